"""Parsing URDF for the MuJoCo world, keeping every link and what MuJoCo drops of the joints.

MuJoCo reads URDF itself; told (a ``<mujoco><compiler>`` element written into the text)
not to fuse fixed-joint links away, to keep visual geoms (as non-colliding group-1 geoms)
and to keep mesh paths as given (the daemon makes them absolute). What MuJoCo does not keep
is read from the XML here: the joints' effort and velocity limits, and the fixed joints'
names. MuJoCo would take a root link named ``world`` for its world body; it goes by a
stand-in name until attached (``Facts.renamed``), so it stays a link (the model's fixed
root) as in PyBullet.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import mujoco

from galton.daemon.engines.mujoco.model_setup import STAND_IN, WORLD_LINK, Facts
from galton.protocol import InvalidArgumentError

COMPILER = {"fusestatic": "false", "discardvisual": "false", "strippath": "false",
            "autolimits": "true"}


def parse_urdf(text: str | None, path: str | None) -> tuple[mujoco.MjSpec, Facts]:
    """A URDF model as a spec with every link a body, and the facts MuJoCo drops; read from
    its text when given (the path is then for information), else from the path."""
    if text is None and path is None:
        raise InvalidArgumentError("give the URDF model as text or a path")
    folder = None
    if text is None:
        folder = os.path.dirname(os.path.abspath(str(path)))
        text = read_text(str(path))
    try:
        robot = ET.fromstring(text)
    except ET.ParseError as exc:
        raise InvalidArgumentError(f"the URDF model does not parse: {exc}") from exc
    if robot.tag != "robot":
        raise InvalidArgumentError(f"the URDF model's root element is <{robot.tag}>, not "
                                   "<robot>")
    facts = joint_facts(robot)
    set_compiler(robot, folder)
    renamed = rename_links(robot, WORLD_LINK, STAND_IN)
    try:
        child = mujoco.MjSpec.from_string(ET.tostring(robot, encoding="unicode"))
    except ValueError as exc:
        raise InvalidArgumentError(f"the URDF model does not parse: {exc}") from exc
    if renamed:
        facts.renamed[STAND_IN] = WORLD_LINK
    return child, facts


def rename_links(robot: ET.Element, old: str, new: str) -> bool:
    """Rename a link and the joints' references to it; whether there was one."""
    links = [link for link in robot.findall("link") if link.get("name") == old]
    for link in links:
        link.set("name", new)
    for joint in robot.findall("joint"):
        for end in (joint.find("parent"), joint.find("child")):
            if end is not None and end.get("link") == old:
                end.set("link", new)
    return bool(links)


def read_text(path: str) -> str:
    try:
        with open(path, encoding="utf-8") as file:
            return file.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidArgumentError(f"cannot read the URDF model {path!r}: {exc}") from exc


def joint_facts(robot: ET.Element) -> Facts:
    """Effort and velocity limits by joint name, fixed joints' names by child link."""
    facts = Facts()
    for joint in robot.findall("joint"):
        name = joint.get("name", "")
        limit = joint.find("limit")
        if limit is not None:
            for attribute, book in (("effort", facts.effort), ("velocity", facts.velocity)):
                value = number(limit.get(attribute), f"joint {name!r} limit {attribute}")
                if value is not None:
                    book[name] = value
        child = joint.find("child")
        if joint.get("type") == "fixed" and child is not None:
            facts.fixed[child.get("link", "")] = name
    return facts


def number(value: str | None, where: str) -> float | None:
    if value is None:
        return None
    try:
        return float(value)
    except ValueError as exc:
        raise InvalidArgumentError(f"the URDF model's {where} is not a number: "
                                   f"{value!r}") from exc


def set_compiler(robot: ET.Element, folder: str | None) -> None:
    """Write MuJoCo's compiler options into the robot (its own <mujoco> kept otherwise);
    a model read from a file finds its relative meshes in the file's folder."""
    extension = robot.find("mujoco")
    if extension is None:
        extension = ET.SubElement(robot, "mujoco")
    compiler = extension.find("compiler")
    if compiler is None:
        compiler = ET.SubElement(extension, "compiler")
    for key, value in COMPILER.items():
        compiler.set(key, value)
    if folder is not None and compiler.get("meshdir") is None:
        compiler.set("meshdir", folder)
