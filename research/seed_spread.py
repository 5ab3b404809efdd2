"""How a fidelity verdict depends on the seed, and how far each engine is from the binomial.

Usage: python research/seed_spread.py [--summary] [--exact EXACT_FILE] FILE [FILE ...]

Each FILE holds JSON lines printed by ``research/fidelity_inprocess.py`` (other lines are
skipped). Runs are grouped by engine, balls, release mode and parameters; for each group the
script prints every seed's pooled Monte Carlo p (recomputed with the bench's 200,000
draws), width and effect size w (Cohen's w, see
``galton.analysis.stats.effect_size``), then w over all its seeds' balls together, beside
the w that one run of that size detects half the time (``detectable_effect``), and the
standardised residual of each bin over all seeds (where the law departs), how flat the law
is (excess kurtosis, read as a number of independent rows: ``galton.analysis.shape``), and
how each trial's width follows its board shift. A group
whose w is near that line passes or fails with the seed; one well below it passes.

``--exact EXACT_FILE`` (JSON lines of ``research/exact_lone_ball.py``) adds, to each
group, the test of homogeneity of all its balls against the exact lone ball's balls on the
``paper`` board at ``--restitution`` and ``--friction`` (constant laws only;
``galton.analysis.same_law.homogeneity``): the reference a faithful simulator should match.

``--summary`` prints one line per group instead: how many of its seeds pass the pooled
test, with that rate's 95 % interval beside the rate the group's pooled law predicts for a
run of its size (``galton.analysis.stats.pass_rate``), w and excess kurtosis over all its
balls, the width, and lost and unsettled balls.
Groups are told apart by engine, balls, release mode, parameters and per-role surfaces.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats as sps

from galton.analysis import same_law, shape, stats
from galton.analysis.board import BoardSpec
from galton.analysis.board_release import perturbation


def read_runs(paths: list[str]) -> list[dict[str, Any]]:
    runs = []
    for path in paths:
        for line in Path(path).read_text().splitlines():
            if line.startswith("{") and '"pooled"' in line:
                runs.append(json.loads(line))
    return runs


def group_key(run: dict[str, Any]) -> tuple[str, int, str, str]:
    settings = json.dumps(run.get("params", {}), sort_keys=True)
    if run.get("surfaces"):
        settings += " surfaces " + json.dumps(run["surfaces"], sort_keys=True)
    return (run["engine"], run["balls"], run["mode"], settings)


def pooled_p(run: dict[str, Any]) -> float:
    """A run's pooled Monte Carlo p, with the bench's own number of draws."""
    return stats.p_monte_carlo(run["pooled"],
                               draws=stats.DEFAULT_DRAWS * stats.POOLED_DRAWS_FACTOR)


def exact_counts(path: str, restitution: float, friction: float) -> np.ndarray:
    """All the exact lone balls on the ``paper`` board with this constant contact law."""
    law = {"restitution": restitution, "friction": friction}
    tables = []
    for line in Path(path).read_text().splitlines():
        run = json.loads(line) if line.startswith("{") else {}
        contact = run.get("contact", {})
        constant = set(contact) <= {"restitution", "friction", "threshold"}
        if (run.get("board") == "paper" and constant
                and {k: contact.get(k) for k in law} == law):
            tables.append(run["bins"]["counts"])
    if not tables:
        raise SystemExit(f"{path}: no exact paper-board run at restitution {restitution}, "
                         f"friction {friction}")
    return np.sum(tables, axis=0)


def exact_line(together: np.ndarray, exact: np.ndarray) -> str:
    """Whether a group's balls and the exact lone ball's come from one law."""
    same = same_law.homogeneity(together, exact)
    return (f"  against {int(exact.sum())} exact lone balls: chi2 {same.chi2:.1f}, "
            f"{same.dof} df, p {same.p_value:.3f} (homogeneity, outer two bins merged)")


def describe(key: tuple[str, int, str, str], runs: list[dict[str, Any]],
             exact: np.ndarray | None = None) -> str:
    engine, balls, mode, params = key
    runs = sorted(runs, key=lambda r: r["seed"])
    per_run = int(sum(runs[0]["pooled"]))
    lines = [f"{engine} {mode} {balls} x {runs[0]['reps']} {params}"]
    ps = [pooled_p(run) for run in runs]
    for run, p in zip(runs, ps, strict=True):
        lines.append(f"  seed {run['seed']}: p {p:.3f}  width {run['width']:.3f}  "
                     f"w {stats.effect_size(run['pooled']):.3f}  "
                     f"kurtosis {shape.excess_kurtosis(run['pooled']):+.3f}  "
                     f"({run.get('source', '')})")
    together = np.sum([r["pooled"] for r in runs], axis=0)
    lines.append(f"  all {len(runs)} seeds ({int(together.sum())} balls): "
                 f"w {stats.effect_size(together):.3f}; one run of {per_run} balls detects "
                 f"w {stats.detectable_effect(per_run):.3f} half the time")
    passed = sum(p > stats.ALPHA for p in ps)
    lines.append(f"  {passed}/{len(runs)} seeds pass ({pass_rate_line(runs, passed, together)})")
    lines.append(flatness_line(together))
    if exact is not None:
        lines.append(exact_line(together, exact))
    lines.extend(shift_line(runs))
    expected = stats.expected_counts(int(together.sum()))
    residuals = (together - expected) / np.sqrt(expected)
    lines.append("  residuals (O - E) / sqrt(E) by bin: "
                 + " ".join(f"{r:+.1f}" for r in residuals))
    return "\n".join(lines)


def summary_line(key: tuple[str, int, str, str], runs: list[dict[str, Any]]) -> str:
    """One group in one line: its seeds' pass count and how far all its balls are from the
    binomial (w, kurtosis with the binomial's 95 % range at as many balls, width)."""
    engine, balls, mode, settings = key
    passed = sum(pooled_p(run) > stats.ALPHA for run in runs)
    together = np.sum([r["pooled"] for r in runs], axis=0)
    flat = shape.flatness(together)
    return (f"{engine:8s} {mode:11s} {balls:4d} x {runs[0]['reps']:2d}  {settings}: "
            f"{passed}/{len(runs)} seeds pass ({pass_rate_line(runs, passed, together)}); "
            f"{int(together.sum())} balls: "
            f"w {stats.effect_size(together):.3f}, kurtosis {flat.excess_kurtosis:+.2f} "
            f"[{flat.null_low:+.2f}, {flat.null_high:+.2f}], width {shape.width(together):.3f}, "
            f"lost {sum(r['lost'] for r in runs)}, "
            f"unsettled {sum(r['unsettled'] for r in runs)}")


def pass_rate_line(runs: list[dict[str, Any]], passed: int, together: np.ndarray) -> str:
    """The observed pass rate's 95 % interval beside the rate the group's pooled law
    predicts for one run (``stats.pass_rate``): if the interval holds the prediction, the
    seeds only resample one law, and that rate is the law's, not luck's."""
    interval = sps.binomtest(passed, len(runs)).proportion_ci(confidence_level=0.95)
    predicted = stats.pass_rate(together, int(sum(runs[0]["pooled"])))
    return (f"95 % interval {100 * interval.low:.0f}-{100 * interval.high:.0f} %; "
            f"its pooled law predicts {100 * predicted:.0f} %")


def flatness_line(together: np.ndarray) -> str:
    """How flat the law of all seeds' balls is, read as a number of independent rows."""
    flat = shape.flatness(together)
    return (f"  excess kurtosis {flat.excess_kurtosis:+.3f} (binomial "
            f"{flat.binomial_excess_kurtosis:+.3f}; a binomial board with as many balls gives "
            f"{flat.null_low:+.3f}..{flat.null_high:+.3f}): as flat as "
            f"{flat.effective_rows:.1f} independent rows")


def shift_line(runs: list[dict[str, Any]]) -> list[str]:
    """How the trials' widths follow their board shifts (runs that list trial widths)."""
    shifts, widths = [], []
    for run in runs:
        board = BoardSpec.load("paper")
        board = board.replace(release=dataclasses.replace(board.release, mode=run["mode"]))
        for rep, trial_width in enumerate(run.get("trial_widths", [])):
            shake = perturbation(board, rep, run["seed"], run["balls"])
            shifts.append(1000 * shake.board_offset_x)
            widths.append(trial_width)
    if len(widths) < 3:
        return []
    slope = np.polyfit(shifts, widths, 1)[0]
    r = np.corrcoef(shifts, widths)[0, 1]
    return [f"  trial width against board shift: {slope:+.4f} per mm, r {r:+.2f} over "
            f"{len(widths)} trials"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="+")
    parser.add_argument("--summary", action="store_true",
                        help="one line per group: pass count over seeds, w, kurtosis, width")
    parser.add_argument("--exact", metavar="EXACT_FILE",
                        help="exact_lone_ball.py runs to test each group's law against")
    parser.add_argument("--restitution", type=float, default=0.72,
                        help="the exact runs' restitution (default 0.72)")
    parser.add_argument("--friction", type=float, default=0.25,
                        help="the exact runs' friction (default 0.25)")
    args = parser.parse_args()
    exact = exact_counts(args.exact, args.restitution, args.friction) if args.exact else None
    groups: dict[tuple[str, int, str, str], list[dict[str, Any]]] = defaultdict(list)
    for run in read_runs(args.files):
        groups[group_key(run)].append(run)
    for key in sorted(groups):
        runs = sorted(groups[key], key=lambda r: r["seed"])
        print(summary_line(key, runs) if args.summary else describe(key, runs, exact))


if __name__ == "__main__":
    main()
