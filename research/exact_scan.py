"""Run exact_lone_ball trials over a grid of contact laws and seeds, in parallel.

Why: one exact trial of 1,000 balls takes about 25 s on one core, and a bounce law is judged
on many seeds; this spreads (law, seed) pairs over processes and prints one JSON line each,
with the spread of the approach speeds at impact so a speed-dependent law can be read
against the speeds the board really sees.

    python research/exact_scan.py --laws '[{"restitution": 0.8, "plastic_exponent": 0.25}]' \
        --seeds 0-7 --balls 1000 --jobs 2 >> docs/data/exact_bounce_laws.jsonl
    python research/exact_scan.py --summary docs/data/exact_bounce_laws.jsonl

``--summary`` pools the seeds of each law: width, excess kurtosis, effect size w and the
Monte Carlo p of the pooled counts against the binomial, and how many single seeds pass.
"""

from __future__ import annotations

import argparse
import json
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field

import exact_lone_ball as exact
import numpy as np

from galton.analysis import shape, stats

DEFAULTS = {"restitution": 0.72, "friction": 0.25, "threshold": 0.2, "cap": 0.95,
            "whole_speed": False}


def seed_range(text: str) -> list[int]:
    """'0-7' or '0,3,5' as a list of seeds."""
    if "-" in text:
        first, last = text.split("-")
        return list(range(int(first), int(last) + 1))
    return [int(part) for part in text.split(",")]


@dataclass(frozen=True)
class RecordedContact(exact.Contact):
    """A contact law that also notes every approach speed it is asked for e at."""

    speeds: list[float] = field(default_factory=list, compare=False, repr=False)

    def bounce(self, approach: float, speed: float | None = None) -> float:
        self.speeds.append(approach)
        return super().bounce(approach, speed)


def one(board: str, balls: int, seed: int, law: dict) -> dict:
    """One trial, with the percentiles of the approach speeds at which the law was asked for e."""
    contact = RecordedContact(**{**DEFAULTS, **law})
    result = exact.trial(board, balls, seed, contact)
    result["contact"] = {**DEFAULTS, **law}
    fast = np.array([s for s in contact.speeds if s >= contact.threshold])
    result["approach_speed_percentiles"] = {
        str(q): round(float(np.percentile(fast, q)), 3) for q in (10, 50, 90, 99)}
    return result


def law_key(contact: dict) -> str:
    """e and the fields of a law that differ from the defaults, as a sortable label."""
    varied = {k: v for k, v in contact.items()
              if v is not None and (k == "restitution" or DEFAULTS.get(k) != v)}
    return json.dumps(varied, sort_keys=True)


def summary_line(key: str, runs: list[dict]) -> str:
    """Pooled fidelity of one law's seeds, and how many seeds pass on their own."""
    counts = np.sum([run["bins"]["counts"] for run in runs], axis=0)
    passing = sum(stats.p_monte_carlo(run["bins"]["counts"]) > stats.ALPHA for run in runs)
    caught = sum(run["caught"] for run in runs)
    return (f"{key:52s} balls {counts.sum():6d}  width {shape.width(counts):.3f}  "
            f"kurtosis {shape.excess_kurtosis(counts):+.3f}  w {stats.effect_size(counts):.3f}  "
            f"p {stats.p_monte_carlo(counts):.4f}  seeds passing {passing}/{len(runs)}  "
            f"caught {caught}")


def summarise(paths: list[str]) -> None:
    """One line per law over every run in these files."""
    groups: dict[str, list[dict]] = {}
    for path in paths:
        with open(path) as lines:
            for line in lines:
                run = json.loads(line)
                groups.setdefault(law_key(run["contact"]), []).append(run)
    for key in sorted(groups):
        print(summary_line(key, groups[key]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--laws", help="JSON list of Contact fields to vary")
    parser.add_argument("--summary", nargs="+", metavar="FILE", help="pool stored runs instead")
    parser.add_argument("--seeds", default="0-7")
    parser.add_argument("--balls", type=int, default=1000)
    parser.add_argument("--board", default="paper")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    args = parser.parse_args()
    if args.summary:
        summarise(args.summary)
        return
    if not args.laws:
        parser.error("give --laws to run, or --summary FILE to pool stored runs")
    tasks = [(law, seed) for law in json.loads(args.laws) for seed in seed_range(args.seeds)]
    with ProcessPoolExecutor(args.jobs) as pool:
        futures = [pool.submit(one, args.board, args.balls, seed, law) for law, seed in tasks]
        for future in futures:
            print(json.dumps(future.result()), flush=True)


if __name__ == "__main__":
    main()
