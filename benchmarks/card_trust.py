"""Bar `card-trust` (issue 49): two report cards taken on different seeds agree.

    galton-client report-card --quick --engines mujoco,pybullet --seed 1 --out /tmp/card-1
    galton-client report-card --quick --engines mujoco,pybullet --seed 2 --out /tmp/card-2
    python benchmarks/card_trust.py /tmp/card-1 /tmp/card-2

Checks, and prints each: every measure in each card.json has value/low/high/n; engines
whose measures tie on a criterion share its rank; each use's recommendation is the same
engine in both cards, or both say no clear winner; each card's Markdown names every failed
law of every engine. Exit code 1 when one fails.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

KEYS = {"value", "low", "high", "n"}


def load(folder: Path) -> tuple[dict[str, Any], str]:
    return (json.loads((folder / "card.json").read_text()),
            (folder / "report-card.md").read_text())


def measures_whole(card: dict[str, Any]) -> list[str]:
    bad = [f"{e}.{k}" for e, ms in card["measures"].items() for k, m in ms.items()
           if m is not None and set(m) != KEYS]
    bad += [f"criteria.{c}.{e}" for c, body in card["criteria"].items()
            for e, m in body["measures"].items() if m is not None and set(m) != KEYS]
    return bad


def ties_shared(card: dict[str, Any]) -> list[str]:
    """Equal values, or overlapping intervals with nobody between, must share a rank."""
    bad = []
    for key, body in card["criteria"].items():
        measured = {e: m for e, m in body["measures"].items() if m is not None}
        for a, ma in measured.items():
            for b, mb in measured.items():
                overlap = ma["low"] <= mb["high"] and mb["low"] <= ma["high"]
                if a < b and (ma["value"] == mb["value"] or (overlap and len(measured) == 2)) \
                        and body["ranks"][a] != body["ranks"][b]:
                    bad.append(f"{key}: {a} #{body['ranks'][a]} vs {b} #{body['ranks'][b]}")
    return bad


def failures_named(card: dict[str, Any], text: str) -> list[str]:
    return [f"{e}: {c['law']} ({c['quantity']})" for e, checks in card["laws"].items()
            for c in checks if not c["passed"]
            and f"| {e} | {c['law']} | {c['quantity']} |" not in text]


def main(first: Path, second: Path) -> int:
    (one, one_md), (two, two_md) = load(first), load(second)
    problems: dict[str, list[str]] = {
        "every measure has value/low/high/n": measures_whole(one) + measures_whole(two),
        "ties share ranks": ties_shared(one) + ties_shared(two),
        "failed laws named in the Markdown": failures_named(one, one_md)
        + failures_named(two, two_md)}
    seeds = (one["config"].get("seed"), two["config"].get("seed"))
    problems["the seeds differ"] = [] if seeds[0] != seeds[1] else [f"both seed {seeds[0]}"]
    answers = []
    for use, body in one["uses"].items():
        theirs = two["uses"].get(use, {}).get("engine", "missing")
        answers.append(f"{use}: {body['engine'] or 'no clear winner'} / "
                       f"{theirs or 'no clear winner'}")
        if body["engine"] != theirs:
            problems.setdefault("each use's answer agrees", []).append(answers[-1])
    problems.setdefault("each use's answer agrees", [])
    print("answers (first card / second card):", *answers, sep="\n  ")
    for name, found in problems.items():
        print(f"{'ok  ' if not found else 'FAIL'} {name}" + "".join(f"\n     {p}" for p in found))
    return 1 if any(problems.values()) else 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(Path(sys.argv[1]), Path(sys.argv[2])))
