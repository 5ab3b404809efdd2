"""Do two bench runs give the same bins, trial for trial?

Usage: python research/same_bins.py REFERENCE/results.json NEW/results.json

Pairs the trials by (engine, balls, release, repetition, seed) and prints, per cell, how
many trials have the same bin counts, lost and unsettled balls; every trial of NEW must be
in REFERENCE (a run of a subset of the reference's cells is fine). Exits 1 on any
difference or missing trial, printing both trials' bins. Issue 48 checks with it that the
board's materials, carried by the board, give the bins the daemon's former defaults gave
(docs/data/bench-defaults).
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

Key = tuple[str, int, str, int, int]


def trials(path: Path) -> dict[Key, dict[str, Any]]:
    data = json.loads(path.read_text())
    return {(t["engine"], t["balls"], t["release"], t["repetition"], t["seed"]): t
            for t in data["trials"]}


def outcome(trial: dict[str, Any]) -> tuple[list[int], int, int]:
    return list(trial["counts"]), int(trial["lost"]), int(trial["unsettled"])


def main(reference: Path, new: Path) -> int:
    before, after = trials(reference), trials(new)
    same: dict[tuple[str, int, str], list[int]] = defaultdict(lambda: [0, 0])
    problems = []
    for key, trial in sorted(after.items()):
        cell = same[key[:3]]
        cell[1] += 1
        if key not in before:
            problems.append(f"{key}: not in the reference")
        elif outcome(before[key]) == outcome(trial):
            cell[0] += 1
        else:
            problems.append(f"{key}: reference {outcome(before[key])}, new {outcome(trial)}")
    for (engine, balls, release), (equal, total) in sorted(same.items()):
        print(f"{engine:9} {balls:5} balls {release:12} {equal}/{total} trials the same")
    for problem in problems:
        print("DIFFERENT", problem)
    return 1 if problems or not after else 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(Path(sys.argv[1]), Path(sys.argv[2])))
