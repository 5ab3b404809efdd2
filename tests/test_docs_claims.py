"""The lists the docs give are the code's: every place that names the engines a daemon can
host names all of them (the engine registry), and help texts make no unmeasured claim."""

from __future__ import annotations

import re
from pathlib import Path

from support.cli import flat, run

from galton.daemon.access.roles import VIEWER_OPERATIONS
from galton.daemon.engines import ENGINE_CLASSES
from galton.protocol.vocabulary import ENGINE_NAMES

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
PROTOCOL = (ROOT / "docs" / "protocol.md").read_text(encoding="utf-8")
SHOWN = {"mujoco": "MuJoCo", "pybullet": "PyBullet", "ode": "ODE", "dart": "DART"}


def _line(text: str, pattern: str) -> str:
    found = re.search(pattern, text, re.MULTILINE)
    assert found, f"no line matches {pattern!r}"
    return found.group(0)


def test_the_protocol_names_the_engines_of_the_registry() -> None:
    assert tuple(ENGINE_CLASSES) == ENGINE_NAMES and set(SHOWN) == set(ENGINE_NAMES)


def test_every_list_of_engines_in_the_docs_is_whole() -> None:
    intro = _line(README, r"^- \*\*`galton-daemon`\*\* hosts a physics engine.*$")
    assert all(SHOWN[name] in intro for name in ENGINE_NAMES), intro
    for text, pattern in ((README, r"^\| `load-world ENGINE.*$"),
                          (PROTOCOL, r"^\| `engine` \| str \|.*$"),  # capabilities
                          (PROTOCOL, r"^`engine` \(.*default the live world's.*$"),  # create
                          (PROTOCOL, r"^Args: `engine` \(str: .*$")):  # load_world
        line = _line(text, pattern)
        assert all(f"`{name}`" in line for name in ENGINE_NAMES), line


def test_report_card_quick_states_what_was_measured() -> None:
    result = run(["report-card", "--help"])
    assert "about 10 minutes" not in result.output
    assert "5 min 45 s" in flat(result.output)  # docs/PERFORMANCE.md, the retaken card


VIEWER_LIST = re.compile(r"viewer\s+operations\s+\(?((?:`\w+`(?:,|\s|and)*)+)")


def test_every_list_of_the_viewer_operations_is_the_code_s() -> None:
    """Wherever protocol.md or SECURITY.md write out the operations a viewer may ask, they
    are daemon/access/roles.py's VIEWER_OPERATIONS; get_shapes' section says a viewer may
    ask it, and it is one of them."""
    security = (ROOT / "docs" / "SECURITY.md").read_text(encoding="utf-8")
    # protocol.md points at its operations table's viewer column (held by
    # tests/daemon/access/test_viewer_declared.py); any list written out must be whole.
    for text in (PROTOCOL, security):
        lists = [re.findall(r"`(\w+)`", found) for found in VIEWER_LIST.findall(text)]
        for names in lists:
            assert sorted(names) == sorted(VIEWER_OPERATIONS), names
    assert "get_shapes" in VIEWER_OPERATIONS and "A viewer may ask it" in PROTOCOL


def test_the_laws_times_in_the_readme_are_the_stored_run_s() -> None:
    """The README's time for `galton-client laws` is the stored run's own record."""
    import json
    stored = json.loads((ROOT / "docs" / "data" / "laws" / "results.json").read_text())
    said = " ".join(README.split())
    for record in stored["engines"]:
        assert f"{SHOWN[record['engine']]} {record['wall_s']:.1f} s" in said, record["engine"]
    from galton.client.laws import EXPERIMENTS
    words = {13: "thirteen"}
    assert f"{words[len(EXPERIMENTS)]} closed-form experiments" in said
