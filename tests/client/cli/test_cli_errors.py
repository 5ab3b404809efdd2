"""The console command's errors, run as a user runs it: one line on stderr, exit code 2 for
a bad command line, nothing started (issue 33)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from support.cli import CONSOLE_COMMAND


def console(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([CONSOLE_COMMAND, *args], capture_output=True, text=True,
                          timeout=60, check=False)


@pytest.mark.parametrize(("args", "says"), [
    (["bench", "--balls", "100000"], "at most 2944 do"),
    (["bench", "--engines", "mujoco,bullet"], "did you mean 'pybullet'"),
    (["spawn", "cube", "a"], "'cube' is not one of 'sphere'"),
    (["--timeout", "-1", "status"], "--timeout must be a number of seconds above 0"),
    (["no-such-command"], "No such command 'no-such-command'"),
    (["predict", "-1"], "-1 is read as an option, not a number: put -- before a negative "
                        "argument (galton-client predict -- -1)"),
])
def test_a_bad_command_line_is_one_line_and_exit_2(args: list[str], says: str,
                                                   tmp_path: Path) -> None:
    done = console(*args, *(["--out", str(tmp_path / "run")] if args[0] == "bench" else []))
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("galton-client: ")
    assert says in done.stderr and "Value error" not in done.stderr
    assert "Traceback" not in done.stderr and done.stdout == ""
    assert not (tmp_path / "run").exists()
