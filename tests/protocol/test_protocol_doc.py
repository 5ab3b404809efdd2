"""docs/protocol.md is held to the code: every operation and its arguments, every result
code, every limit and every event kind the daemon publishes are documented."""

from __future__ import annotations

import importlib.util
import re
from dataclasses import fields
from pathlib import Path
from types import ModuleType

import msgspec
import pytest
import typer

from galton.daemon.cli import app as daemon_app
from galton.daemon.core.limits import Limits
from galton.protocol import ResultCode
from galton.protocol.operations import LONG_RUNNING_TIMEOUT_S, OPERATIONS, Operation

PAGE = (Path(__file__).resolve().parents[2] / "docs" / "protocol.md").read_text()
DAEMON = Path(__file__).resolve().parents[2] / "daemon"
CONTENTS_TOOL = Path(__file__).resolve().parents[2] / "docs" / "make_contents.py"


def section(op: str) -> str:
    """The text under the heading that names this operation."""
    match = re.search(rf"^### .*`{op}`.*$", PAGE, re.MULTILINE)
    assert match, f"docs/protocol.md has no section for {op!r}"
    rest = PAGE[match.end():]
    end = re.search(r"^##", rest, re.MULTILINE)
    return rest[:end.start() if end else None]


@pytest.mark.parametrize("op", OPERATIONS.values(), ids=list(OPERATIONS))
def test_every_operation_and_argument_is_documented(op: Operation) -> None:
    text = section(op.name)
    for name in op.arg_names:
        assert f"`{name}`" in text, f"{op.name}: argument {name!r} is not documented"


@pytest.mark.parametrize("op", [op for op in OPERATIONS.values() if op.reply is not None],
                         ids=[name for name, op in OPERATIONS.items() if op.reply is not None])
def test_every_declared_reply_field_is_documented(op: Operation) -> None:
    assert op.reply is not None
    text = section(op.name) + REPLY_SHAPES.get(op.reply.__name__, "")
    for name in msgspec.structs.fields(op.reply):
        assert f"`{name.name}`" in text, f"{op.name}: reply field {name.name!r} is not documented"


# Replies several operations share are described once: status and time control answer a
# status map (docs/protocol.md, "status"), run_until replies as step does, and a world's
# row is list_worlds'.
REPLY_SHAPES = {"StatusReply": section("status"),
                "StepReply": section("step") + section("run_until"),
                "WorldReply": section("list_worlds")}


def test_every_operation_declares_its_reply() -> None:
    assert [name for name, op in OPERATIONS.items() if op.reply is None] == []


def test_every_result_code_is_in_the_table() -> None:
    for code in ResultCode:
        assert re.search(rf"^\| {int(code)} \| {code.name} \|", PAGE, re.MULTILINE), code.name


def test_every_limit_is_in_the_table() -> None:
    for spec in fields(Limits):
        assert f"| `{spec.name}` |" in PAGE, spec.name


def test_every_event_kind_is_documented() -> None:
    source = "".join(p.read_text() for p in DAEMON.rglob("*.py")
                     if "engines" not in p.relative_to(DAEMON).parts)
    kinds = set(re.findall(r'"kind": "(\w+)"', source))
    assert kinds >= {"state", "scene", "physics_error", "job_abandoned"}
    for kind in kinds:
        assert f"| `{kind}` |" in PAGE, kind


def summary_row(op: Operation) -> str:
    """The row the operations table must hold for this operation, from the registry: its
    name linked to its section, its arguments, its flags and how long a client waits."""
    args = ", ".join(f"`{a.name}`" + ("*" if a.required else "") for a in op.args) or "–"
    if op.steps:
        wait = f"{LONG_RUNNING_TIMEOUT_S:g} s"
    else:
        wait = f"≥ {op.timeout_floor_s:g} s" if op.timeout_floor_s else "default"
    flags = " | ".join("yes" if flag else "no"
                       for flag in (op.mutates, op.steps, op.fast, op.viewer))
    return f"| [`{op.name}`](#{section_anchor(op.name)}) | {args} | {flags} | {wait} |"


def section_anchor(op: str) -> str:
    """The anchor of the ``###`` heading that names this operation."""
    found = [anchor for level, title, anchor in contents_tool().headings(PAGE)
             if level == 3 and f"`{op}`" in title]
    assert found, f"docs/protocol.md has no section for {op!r}"
    return found[0]


def contents_tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_contents", CONTENTS_TOOL)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_operations_table_is_the_registry() -> None:
    rows = re.findall(r"^\| \[`\w+`\]\(#[\w-]+\) \| .* \| (?:yes|no) \| (?:yes|no) \| "
                      r"(?:yes|no) \| (?:yes|no) \| .*\|$", PAGE, re.MULTILINE)
    assert rows == [summary_row(op) for op in OPERATIONS.values()]


def test_every_link_of_the_operations_table_reaches_its_section() -> None:
    anchors = {anchor for _, _, anchor in contents_tool().headings(PAGE)}
    linked = dict(re.findall(r"^\| \[`(\w+)`\]\(#([\w-]+)\) \|", PAGE, re.MULTILINE))
    assert set(linked) == set(OPERATIONS)
    for op, anchor in linked.items():
        assert anchor in anchors, f"{op} links to #{anchor}, which no heading has"
        assert anchor == section_anchor(op), f"{op} links to #{anchor}, not its section"


def test_every_daemon_option_the_page_names_exists() -> None:
    options = {opt for param in typer.main.get_command(daemon_app).params
               for opt in param.opts}
    named = set(re.findall(r"(?<![\w#-])(--[a-z][a-z-]*[a-z])(?![\w*-])", PAGE))
    assert named - options == set(), "docs/protocol.md names options galton-daemon lacks"


def documented_default(text: str) -> float | None:
    """A Limits row's default as a number ("16 MiB", "100,000", "10⁹", "10⁶ m", "2,073,600
    (1920 × 1080)"), or None where it is not one ("the cores the daemon may use")."""
    powers = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹", "0123456789")
    if match := re.match(r"10([⁰¹²³⁴⁵⁶⁷⁸⁹]+)", text):
        return 10.0 ** int(match.group(1).translate(powers))
    if match := re.match(r"([\d,.]+)( MiB)?", text):
        return float(match.group(1).replace(",", "")) * (2**20 if match.group(2) else 1)
    return None


def test_every_limit_s_default_is_the_table_s() -> None:
    """Limits: the default column is what a daemon started without --limit holds."""
    rows = dict(re.findall(r"^\| `(\w+)` \| ([^|]+) \|", PAGE, re.MULTILINE))
    defaults = Limits()
    for spec in fields(Limits):
        told = documented_default(rows[spec.name].strip())
        if spec.name == "future_threads":
            assert told is None  # the cores: told in words, not as a number
            continue
        assert told == getattr(defaults, spec.name), (spec.name, rows[spec.name])


@pytest.mark.parametrize(("name", "valid"), [
    ("galton", True), ("x.y-z_1", True), ("a" * 64, True), ("a" * 65, False), ("", False),
    ("-x", False), (".x", False), ("a b", False), ("a/b", False), ("a*", False),
    ("é", False)])
def test_an_instance_name_is_as_the_transport_section_says(name: str, valid: bool) -> None:
    """Transport: a single key chunk of 1-64 characters from A-Z a-z 0-9 _ - . (not
    starting with - or .)."""
    from galton.protocol import InvalidArgumentError, validate_instance_name
    if valid:
        assert validate_instance_name(name) == name
    else:
        with pytest.raises(InvalidArgumentError):
            validate_instance_name(name)
