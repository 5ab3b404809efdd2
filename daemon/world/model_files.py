"""The files a model names (meshes, textures, height fields), made absolute before an
engine sees the model, so that both engines load the same files and a missing one is
refused with its name, never half-loaded.

A reference is looked up, in order: as an absolute path; relative to the model's own
folder (for MJCF, under the compiler's ``meshdir``/``texturedir``/``assetdir`` when set);
then in each folder of the request's search path. ``package://PKG/rest`` is looked up as
``rest`` and as ``PKG/rest`` in the model's folder, its parent, and each search folder, as
ROS tools do without a ROS install. The rewritten text names every file absolutely (and
MJCF's directory settings are dropped, since they no longer apply).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from collections.abc import Iterator, Sequence
from pathlib import Path

from galton.protocol import InvalidArgumentError
from galton.protocol.errors import brief

# The attributes that name files, per format: (element tag, attribute, MJCF directory key).
URDF_REFERENCES = (("mesh", "filename", None), ("texture", "filename", None))
MJCF_REFERENCES = (("mesh", "file", "meshdir"), ("texture", "file", "texturedir"),
                   ("hfield", "file", "assetdir"), ("skin", "file", "assetdir"),
                   ("include", "file", None))
MJCF_DIRECTORIES = ("meshdir", "texturedir", "assetdir")
MAX_SEARCH_FOLDERS = 32


def search_folders(value: str | None) -> list[Path]:
    """A load_model search path: folders joined by the OS path separator (":")."""
    if not value:
        return []
    folders = [Path(part) for part in value.split(os.pathsep) if part]
    if len(folders) > MAX_SEARCH_FOLDERS:
        raise InvalidArgumentError(f"load_model.search_path names {len(folders)} folders; at "
                                   f"most {MAX_SEARCH_FOLDERS}")
    for folder in folders:
        if not folder.is_absolute() or not folder.is_dir():
            raise InvalidArgumentError(
                f"load_model.search_path: {brief(str(folder))} is not an absolute path to a "
                "folder")
    return folders


def resolve_model(fmt: str, text: str, path: str | None, search: Sequence[Path]) -> str:
    """The model's text with every file it names made absolute (InvalidArgumentError naming
    the first file that cannot be found, and where it was looked for)."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise InvalidArgumentError(f"the {fmt.upper()} model is not well-formed XML: {exc}"
                                   ) from exc
    base = Path(path).resolve().parent if path else None
    changed = False
    for element, attribute, directory in _references(fmt, root):
        named = element.get(attribute, "")
        found = _find(named, base, _subfolder(root, directory), search)
        if found is None:
            where = [str(f) for f in _candidates(named, base, _subfolder(root, directory),
                                                 search)]
            raise InvalidArgumentError(
                f"the model names a file that cannot be found: {brief(named)} (looked in "
                f"{', '.join(where[:6]) or 'no folder: give the model as a path, or a '}"
                f"{'' if where else 'search_path'})", {"missing_file": named[:200]})
        if str(found) != named:
            element.set(attribute, str(found))
            changed = True
    if fmt == "mjcf":
        for compiler in root.iter("compiler"):
            for key in MJCF_DIRECTORIES:
                if key in compiler.attrib:
                    del compiler.attrib[key]
                    changed = True
    return ET.tostring(root, encoding="unicode") if changed else text


def _references(fmt: str, root: ET.Element) -> Iterator[tuple[ET.Element, str, str | None]]:
    table = URDF_REFERENCES if fmt == "urdf" else MJCF_REFERENCES
    for tag, attribute, directory in table:
        for element in root.iter(tag):
            if element.get(attribute):
                yield element, attribute, directory


def _subfolder(root: ET.Element, key: str | None) -> str:
    """MJCF's compiler folder for this kind of file ('' when none is set)."""
    if key is None:
        return ""
    for compiler in root.iter("compiler"):
        value = compiler.get(key) or compiler.get("assetdir")
        if value:
            return value
    return ""


def _candidates(named: str, base: Path | None, subfolder: str,
                search: Sequence[Path]) -> list[Path]:
    if named.startswith("package://"):
        rest = named[len("package://"):]
        _package, _, inner = rest.partition("/")
        tails = [Path(inner), Path(rest)] if inner else [Path(rest)]
        folders = [*([base, base.parent] if base else []), *search]
        return [folder / tail for folder in folders for tail in tails]
    if named.startswith("file://"):
        named = named[len("file://"):]
    reference = Path(named)
    if reference.is_absolute():
        return [reference]
    folders = ([base / subfolder, base] if base else []) + [
        f / subfolder for f in search if subfolder] + list(search)
    return [folder / reference for folder in folders]


def _find(named: str, base: Path | None, subfolder: str,
          search: Sequence[Path]) -> Path | None:
    for candidate in _candidates(named, base, subfolder, search):
        if candidate.is_file():
            return candidate.resolve()
    return None
