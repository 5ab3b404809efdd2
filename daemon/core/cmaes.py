"""A small CMA-ES (Hansen's "The CMA Evolution Strategy: A Tutorial", 2016) in ask/tell
form, over the unit box: calibrate (daemon/core/calibrate.py) asks for a generation of
candidates, evaluates them one prediction at a time between the live world's steps, and
tells the errors back. Why CMA-ES and not scipy's differential evolution: scipy drives its
own loop (the daemon's physics thread cannot), and the daemon does not depend on scipy;
CMA-ES needs few generations of few candidates (4 + 3 ln n) for a handful of parameters,
and its final distribution gives each value's spread. calibrate starts it from the best of
a Latin hypercube over the bounds (contact makes the error landscape rugged)."""

from __future__ import annotations

import math

import numpy as np

# The distribution's step size (in units of each parameter's range) below which the search
# has converged: a thousandth of the bounds.
CONVERGED_SIGMA = 1e-3


def default_population(dimensions: int) -> int:
    """Hansen's population for ``dimensions`` parameters, at least 6."""
    return max(6, 4 + int(3 * math.log(dimensions)))


class CmaEs:
    """Minimise over [0, 1]^n from ``mean`` with step ``sigma``; samples outside the box are
    moved onto it (and learnt from there)."""

    def __init__(self, mean: np.ndarray, sigma: float, population: int,
                 rng: np.random.Generator) -> None:
        n = len(mean)
        self.n, self.lam, self.rng = n, population, rng
        self.mean = np.clip(np.asarray(mean, float), 0.0, 1.0)
        self.sigma = sigma
        mu = population // 2
        weights = np.log(mu + 0.5) - np.log(np.arange(1, mu + 1))
        self.weights = weights / weights.sum()
        self.mueff = 1.0 / float(np.sum(self.weights ** 2))
        self.cc = (4 + self.mueff / n) / (n + 4 + 2 * self.mueff / n)
        self.cs = (self.mueff + 2) / (n + self.mueff + 5)
        self.c1 = 2 / ((n + 1.3) ** 2 + self.mueff)
        self.cmu = min(1 - self.c1, 2 * (self.mueff - 2 + 1 / self.mueff)
                       / ((n + 2) ** 2 + self.mueff))
        self.damps = 1 + 2 * max(0.0, math.sqrt((self.mueff - 1) / (n + 1)) - 1) + self.cs
        self.chi_n = math.sqrt(n) * (1 - 1 / (4 * n) + 1 / (21 * n * n))
        self.pc, self.ps = np.zeros(n), np.zeros(n)
        self.cov = np.eye(n)
        self.generation = 0
        self.selected = self.mean[None, :].copy()  # the last generation's best half

    def ask(self) -> np.ndarray:
        """A generation: (population, n) points in the unit box."""
        values, vectors = np.linalg.eigh(self.cov)
        scale = vectors * np.sqrt(np.maximum(values, 1e-20))
        steps = self.rng.standard_normal((self.lam, self.n)) @ scale.T
        points: np.ndarray = np.clip(self.mean + self.sigma * steps, 0.0, 1.0)
        return points

    def tell(self, points: np.ndarray, errors: np.ndarray) -> None:
        """Move the distribution towards the generation's better half."""
        order = np.argsort(errors, kind="stable")
        best = points[order[: len(self.weights)]]
        self.selected = best
        old = self.mean
        self.mean = self.weights @ best
        shift = (self.mean - old) / self.sigma
        values, vectors = np.linalg.eigh(self.cov)
        inv_sqrt = vectors @ np.diag(1 / np.sqrt(np.maximum(values, 1e-20))) @ vectors.T
        self.ps = ((1 - self.cs) * self.ps
                   + math.sqrt(self.cs * (2 - self.cs) * self.mueff) * inv_sqrt @ shift)
        self.generation += 1
        norm = float(np.linalg.norm(self.ps))
        stalled = norm / math.sqrt(1 - (1 - self.cs) ** (2 * self.generation)) / self.chi_n
        hsig = float(stalled < 1.4 + 2 / (self.n + 1))
        self.pc = (1 - self.cc) * self.pc + hsig * math.sqrt(
            self.cc * (2 - self.cc) * self.mueff) * shift
        rel = (best - old) / self.sigma
        self.cov = ((1 - self.c1 - self.cmu) * self.cov
                    + self.c1 * (np.outer(self.pc, self.pc)
                                 + (1 - hsig) * self.cc * (2 - self.cc) * self.cov)
                    + self.cmu * (rel.T * self.weights) @ rel)
        self.cov = (self.cov + self.cov.T) / 2
        self.sigma *= math.exp((self.cs / self.damps) * (norm / self.chi_n - 1))
        self.sigma = min(self.sigma, 1.0)

    @property
    def spread(self) -> float:
        """The distribution's largest step now, in units of the ranges."""
        return self.sigma * math.sqrt(float(np.max(np.linalg.eigvalsh(self.cov))))

    @property
    def converged(self) -> bool:
        return self.spread < CONVERGED_SIGMA
