"""Output into a pipe keeps every character: tables as wide as their text (rich would
assume 80 columns and fold or cut them), --help never cut to "…". Each check reads the
real console's output through a real pipe (a subprocess whose stdout is not a terminal)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from galton.client.cli.common import HELP_PIPE_WIDTH

DATA = Path(__file__).resolve().parents[3] / "docs" / "data"
CLI = str(Path(sys.executable).with_name("galton-client"))
# What a terminal-less run of a command prints, as the CLI prints it.
SHOW_TABLE2 = """
import sys
from galton.analysis.records import ExperimentResults
from galton.analysis.summary import summarise
from galton.client.cli.bench import table2
from galton.client.cli.common import console
trials = ExperimentResults.from_json(sys.argv[1]).trials
console.print(table2(summarise([t for t in trials if t.repetition < 2 and t.balls == 100])))
"""
SHOW_LAWS = """
import sys
from pathlib import Path
from galton.analysis.laws import LawResults
from galton.client.cli.laws import _show
_show(LawResults.load(Path(sys.argv[1])), {})
"""


def _piped(*command: str) -> str:
    """What ``command`` writes into a pipe (no terminal, no COLUMNS)."""
    env = {k: v for k, v in os.environ.items() if k not in ("COLUMNS", "TERMINAL_WIDTH")}
    done = subprocess.run(command, capture_output=True, text=True, env=env, timeout=120,
                          check=False)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_the_report_table_keeps_its_title_and_every_column_in_a_pipe() -> None:
    out = _piped(sys.executable, "-c", SHOW_TABLE2,
                 str(DATA / "bench-defaults" / "all-at-once" / "results.json"))
    lines = out.splitlines()
    title = ("Galton board, 11 d.o.f., critical value 19.68 at 5 % (published rows: the "
             "paper's 11-row board)")
    assert any(line.strip() == title for line in lines), out
    header = next(line for line in lines if "simulator" in line)
    assert "lost balls (%)" in header and "real-time factor" in header, header
    rows = [line for line in lines if "(this run)" in line]
    assert len(rows) == 2 and all("[" in row and "]" in row for row in rows), out  # RTF
    assert "…" not in out


def test_the_laws_table_keeps_every_engine_in_a_pipe() -> None:
    out = _piped(sys.executable, "-c", SHOW_LAWS, str(DATA / "laws" / "results.json"))
    header = next(line for line in out.splitlines() if "quantity" in line)
    assert header.split()[-4:] == ["mujoco", "pybullet", "ode", "dart"], header
    assert "…" not in out


def test_help_into_a_pipe_is_whole() -> None:
    out = _piped(CLI, "bench", "--help")
    assert "…" not in out
    assert "--connect/--instances" in out  # cut to "--connect/--insta…" at 80 columns
    assert max(len(line) for line in out.splitlines()) <= HELP_PIPE_WIDTH
