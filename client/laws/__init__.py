"""The physical-law suite: experiments with closed-form answers, run through the bridge on
every engine a daemon offers (``galton-client laws``).

Each experiment spawns a small scene on a fresh world, runs it with the SDK and returns
``galton.analysis.laws.Check`` records: the measured value beside the closed form of
``galton.analysis.laws_theory``, a tolerance and why. Nothing names an engine, so an engine
a daemon adds joins the suite as it is.
"""

from __future__ import annotations

from galton.client.laws.registry import EXPERIMENTS, KEYS, Experiment
from galton.client.laws.runner import choose, engines_of, run_engine, run_law, run_laws

__all__ = ["EXPERIMENTS", "KEYS", "Experiment", "choose", "engines_of", "run_engine",
           "run_law", "run_laws"]
