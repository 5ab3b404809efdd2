"""Who may call an operation is part of its declaration (``Operation(viewer=True)``): the
fronts' role checks and the pages that name a viewer's operations follow it, so adding a
viewer operation is one edit, and a page that drifts (as SECURITY.md once did on
``get_shapes``) fails here."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from galton.daemon.access.roles import VIEWER_OPERATIONS, may_ask
from galton.daemon.access.users import OPERATOR, VIEWER
from galton.protocol.operations import OPERATIONS, Operation
from galton.protocol.requests import NoArgs

DOCS = Path(__file__).resolve().parents[3] / "docs"
DECLARED = {name for name, op in OPERATIONS.items() if op.viewer}


def test_the_roles_follow_the_declarations() -> None:
    assert set(VIEWER_OPERATIONS) == DECLARED
    assert {"status", "capabilities", "get_shapes"} <= DECLARED
    for name, op in OPERATIONS.items():
        assert may_ask(VIEWER, name) is op.viewer, name
        assert may_ask(OPERATOR, name) and may_ask(None, name)


def test_no_operation_that_changes_a_world_is_a_viewers() -> None:
    assert [name for name in DECLARED if OPERATIONS[name].mutates] == []
    with pytest.raises(ValueError, match="viewer may not ask one that mutates"):
        Operation("paint", NoArgs, mutates=True, viewer=True)


def named_operations(line: str) -> set[str]:
    return {name for name in re.findall(r"`(\w+)`", line) if name in OPERATIONS}


def test_security_md_names_the_viewer_operations() -> None:
    page = (DOCS / "SECURITY.md").read_text()
    zenoh_row = next(line for line in page.splitlines() if line.startswith("| `viewer` |"))
    inbound = zenoh_row.split(" | ")[1]
    assert named_operations(inbound) == DECLARED, "docs/SECURITY.md, the viewer's Zenoh row"
    zmq_row = next(line for line in page.splitlines()
                   if line.startswith("| `--zmq-key FILE` with `--users`"))
    assert named_operations(zmq_row.split("anything else")[0]) == DECLARED, (
        "docs/SECURITY.md, the ZeroMQ row")


def test_protocol_md_marks_the_viewer_operations() -> None:
    page = (DOCS / "protocol.md").read_text()
    marked = set(re.findall(r"^\| \[`(\w+)`\]\(#[\w-]+\) \| .* \| (?:yes|no) \| (?:yes|no) \| "
                            r"(?:yes|no) \| yes \| [^|]*\|$", page, re.MULTILINE))
    assert marked == DECLARED
