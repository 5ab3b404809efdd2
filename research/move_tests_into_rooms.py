"""Move tests/ into the code's rooms (issue 50), in two steps that can be redone after
other branches merge: ``move`` (git mv only: tests/client/<room>/, and the support modules
into the package tests/support/) and ``fix`` (imports, paths of data files, and the pages
and docstrings that name a moved file). Both are idempotent: a file already moved is
skipped, a name already rewritten is not matched again.

    python research/move_tests_into_rooms.py move && git commit -am "tests: move" ...
    python research/move_tests_into_rooms.py fix && git commit -am "tests: imports" ...
    python -m pytest --collect-only -q | tail -1     # the same count as before the move

A test file another branch added to tests/client/ after this script was written lands in
no room: ``move`` lists it (add it to ROOMS, or leave it at tests/client/ beside
test_layout.py).
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "tests"

# tests/client/<file> -> tests/client/<room>/<file>: one folder per room of client/.
ROOMS: dict[str, tuple[str, ...]] = {
    "sdk": ("test_sdk.py", "test_sdk_joints.py", "test_sdk_perception.py",
            "test_sdk_worlds.py"),
    "transport": ("test_credentials.py",),
    "cli": ("test_cli.py", "test_cli_call.py", "test_cli_control.py", "test_cli_errors.py",
            "test_cli_groups.py", "test_cli_help.py", "test_cli_joints.py",
            "test_cli_perception.py", "test_cli_scene.py", "test_cli_startup.py",
            "test_cli_worlds.py", "test_check_cli.py", "test_cli_calibrate.py",
            "test_cli_pipes.py"),
    "bench": ("test_bench.py", "test_bench_figures.py", "test_bench_mesh_board.py",
              "test_bench_pictures.py", "test_pool.py", "test_sweep.py", "test_ray.py",
              "test_ray_cli.py", "test_ray_cluster.py"),
    "laws": ("test_laws.py",),
    "view": ("test_view_browser.py", "test_view_live.py", "test_view_replay.py",
             "test_view_roles.py", "test_view_picture.py"),
    "fuzz": ("test_fuzz.py",),
    "report_card": ("test_report_card.py",),
}
STAYS_IN_CLIENT = ("test_layout.py",)  # about every client room at once

# tests/<old module> -> tests/support/<new module>; support.py becomes the package itself,
# so ``from support import X`` is unchanged.
SUPPORT: dict[str, str] = {
    "support": "__init__",
    "support_browser": "browser",
    "support_certs": "certs",
    "support_daemons": "daemons",
    "support_models": "models",
    "support_mujoco_worlds": "mujoco_worlds",
    "support_perception": "perception",
    "support_pool": "router",  # a galton-client router process ("pool" meant three things)
    "support_pybullet_worlds": "pybullet_worlds",
    "support_urdf": "urdf",
    "support_users": "users",
    "support_worlds": "worlds",
    "support_calibration": "calibration",
    "support_materials": "materials",
    "cli_support": "cli",
    "synthetic_runs": "synthetic_runs",
    "ros2_client": "ros2_client",
    "ros2_rosidl": "ros2_rosidl",
}
DATA = {"ros2_rosidl_hashes.json": "support/ros2_rosidl_hashes.json"}

# Lines the longer paths push past 100 characters, wrapped again.
REWRAPPED = {
    "values rosidl computed (tests/support/ros2_rosidl_hashes.json, made by "
    "tests/support/ros2_rosidl.py), and\n":
    "values rosidl computed (tests/support/ros2_rosidl_hashes.json, made by\n"
    "tests/support/ros2_rosidl.py), and\n",
    "simulation_interfaces 2.1 (tests/support/ros2_rosidl_hashes.json, made by "
    "tests/support/ros2_rosidl.py).\"\"\"\n":
    "simulation_interfaces 2.1 (tests/support/ros2_rosidl_hashes.json, made by\n"
    "tests/support/ros2_rosidl.py).\"\"\"\n",
}

# Where moved files are named (imports, sys.path, docstrings, pages); CHANGELOG.md and the
# notebooks are history and keep the names of their day.
REWRITTEN = ("tests", "benchmarks", "research", "README.md", "docs/ARCHITECTURE.md",
             "docs/SECURITY.md", "docs/ROS2.md", "docs/MULTIHOST.md", "docs/protocol.md",
             "docs/PHYSICS.md", "docs/PERFORMANCE.md", "pyproject.toml")


def git_mv(source: Path, target: Path) -> None:
    if not source.exists() or target.exists():
        return
    target.parent.mkdir(parents=True, exist_ok=True)
    subprocess.run(["git", "mv", str(source), str(target)], cwd=ROOT, check=True)


def move() -> None:
    for room, files in ROOMS.items():
        for name in files:
            git_mv(TESTS / "client" / name, TESTS / "client" / room / name)
    for old, new in SUPPORT.items():
        git_mv(TESTS / f"{old}.py", TESTS / "support" / f"{new}.py")
    for old, new in DATA.items():
        git_mv(TESTS / old, TESTS / new)
    homeless = sorted(p.name for p in (TESTS / "client").glob("test_*.py")
                      if p.name not in STAYS_IN_CLIENT)
    if homeless:
        print(f"tests/client/ files in no room (add them to ROOMS): {homeless}")


def room_of(name: str) -> str | None:
    return next((room for room, files in ROOMS.items() if name in files), None)


def rewrite(text: str, moved_depth: bool) -> str:
    """``text`` with every old module name, path and root depth made the new one."""
    for old, new in SUPPORT.items():
        target = "support" if new == "__init__" else f"support.{new}"
        if old != "support":
            text = re.sub(rf"^(\s*)from {old} import", rf"\1from {target} import", text,
                          flags=re.MULTILINE)
            text = re.sub(rf"^(\s*)import {old}$", rf"\1from support import {new} as {old}",
                          text, flags=re.MULTILINE)
            text = text.replace(f"tests/{old}.py", f"tests/support/{new}.py")
    for old, new in DATA.items():
        text = text.replace(f"tests/{old}", f"tests/{new}")
    for room, files in ROOMS.items():
        for name in files:
            text = re.sub(rf"tests/client/{re.escape(name)}", f"tests/client/{room}/{name}",
                          text)
    for long, wrapped in REWRAPPED.items():
        text = text.replace(long, wrapped)
    if moved_depth:  # one folder deeper: the repository's root is one parent further
        text = re.sub(r"(Path\(__file__\)(?:\.resolve\(\))?\.parents)\[2\]", r"\1[3]", text)
    return text


def fix() -> None:
    changed = []
    for entry in REWRITTEN:
        path = ROOT / entry
        files = [path] if path.is_file() else [*path.rglob("*.py"), *path.rglob("*.md")]
        for file in files:
            if ".venv" in file.parts or file == Path(__file__).resolve():
                continue
            text = file.read_text()
            moved = file.parent.parent == TESTS / "client" and room_of(file.name) is not None
            updated = rewrite(text, moved)
            if file == TESTS / "daemon" / "fronts" / "test_ros2_wire.py":
                updated = updated.replace('parents[2] / "ros2_rosidl_hashes.json"',
                                          'parents[2] / "support" / "ros2_rosidl_hashes.json"')
            if updated != text:
                file.write_text(updated)
                changed.append(file.relative_to(ROOT).as_posix())
    print("\n".join(changed))
    # "support.x" sorts where "support_x" did not: let ruff put the imports back in order.
    subprocess.run([sys.executable, "-m", "ruff", "check", "--fix", "--select", "I", "tests",
                    "benchmarks", "research"], cwd=ROOT, check=False)


if __name__ == "__main__":
    {"move": move, "fix": fix}[sys.argv[1]]()
