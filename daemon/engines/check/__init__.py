"""An engine checker, as Gymnasium ships ``check_env``: one call tells whether a class
implementing ``galton.daemon.engines.base.Engine`` keeps the interface's promises.

Usage::

    from galton.daemon.engines.check import check_engine

    report = check_engine("mujoco")            # a registered engine, by name
    report = check_engine(MyEngine)            # or any factory of fresh engines
    report = check_engine(MyEngine, params={"timestep": 0.001})  # set on each new engine
    print(report.summary())

``check_engine`` runs every check of ``ENGINE_CHECKS`` on a fresh engine of its own (a
check that needs two, as determinism does, makes a second the same way), and returns a
``CheckReport`` when all pass or are skipped (a skipped check tests a feature the engine
does not list in its capabilities). Otherwise it raises ``EngineCheckError``, whose
message lists every failed check with what was expected and what was seen; the report is
on the error as ``.report``. ``run_check(factory, name)`` runs one check alone, which is
how a test suite parametrizes over ``ENGINE_CHECKS`` with readable ids.

The checks: the interface contract (methods and description; shapes and dtypes of what
they return), spawn of every shape static and dynamic, the get/set states round trip,
effective properties, delete, clear, unknown names, refused parameters, model loading and
refused models, the timestep, free fall, a ball coming to rest on a plane, static bodies,
determinism, the rewind to the created state, edits that keep other bodies' states,
state_within; and for articulated models, links and joints, joint states, the target law,
wrenches and the rewind of joints; snapshots that go on as their source, and independent
clones. Each check's docstring says what it guarantees
(``Check.guarantee``).

Errors, all ``GaltonError`` (the project's root error)::

    GaltonError
    ├── EngineCheckError       check_engine: the engine failed checks (``.report``)
    ├── CheckFailedError       inside a check: what was expected, what was seen
    ├── CheckSkippedError      inside a check: the engine does not list that feature
    └── InvalidArgumentError   no engine or no check of that name ("did you mean")

The runner turns any other exception an engine raises into a failure of that check, never
into a crash of the run. This module and its checks import no engine: they know an engine
only through the interface (and a name only through the registry, which imports lazily).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from galton.daemon.engines import ENGINE_CLASSES, create_engine
from galton.daemon.engines.check import contract, joints, physics, refusals, snapshots
from galton.daemon.engines.check.support import (
    CheckContext,
    CheckFailedError,
    CheckSkippedError,
    EngineFactory,
)
from galton.protocol import GaltonError, InvalidArgumentError
from galton.protocol.errors import did_you_mean

__all__ = ["ENGINE_CHECKS", "Check", "CheckFailedError", "CheckReport", "CheckResult",
           "EngineCheckError", "check_engine", "engine_factory", "run_check"]

PASSED, FAILED, SKIPPED = "passed", "failed", "skipped"


@dataclass(frozen=True)
class Check:
    """One named check: a function that takes a ``CheckContext`` and fails by raising."""

    name: str
    run: Callable[[CheckContext], None]

    @property
    def guarantee(self) -> str:
        """What an engine that passes this check guarantees (the function's docstring)."""
        return " ".join((self.run.__doc__ or "").split())


ENGINE_CHECKS: tuple[Check, ...] = (
    Check("interface", contract.check_interface),
    Check("return-shapes", contract.check_return_shapes),
    Check("spawn-shapes", contract.check_spawn_shapes),
    Check("state-round-trip", contract.check_state_round_trip),
    Check("properties", contract.check_properties),
    Check("delete", contract.check_delete),
    Check("clear", contract.check_clear),
    Check("unknown-names", contract.check_unknown_names),
    Check("bad-params", refusals.check_bad_params),
    Check("load-model", refusals.check_load_model),
    Check("bad-models", refusals.check_bad_models),
    Check("timestep", physics.check_timestep),
    Check("free-fall", physics.check_free_fall),
    Check("resting-contact", physics.check_resting_contact),
    Check("static-bodies", physics.check_static_bodies),
    Check("determinism", physics.check_determinism),
    Check("rewind", physics.check_rewind),
    Check("edits-keep-state", physics.check_edits_keep_state),
    Check("state-within", physics.check_state_within),
    Check("model-links-and-joints", joints.check_model_links_and_joints),
    Check("joint-state-round-trip", joints.check_joint_state_round_trip),
    Check("target-law", joints.check_target_law),
    Check("wrench", joints.check_wrench),
    Check("joint-rewind", joints.check_joint_rewind),
    Check("snapshot-continuation", snapshots.check_snapshot_continuation),
    Check("clone-independent", snapshots.check_clone_independent),
)
_BY_NAME = {check.name: check for check in ENGINE_CHECKS}


@dataclass(frozen=True)
class CheckResult:
    """How one check went: passed, failed or skipped, and why."""

    name: str
    outcome: str
    message: str = ""


@dataclass
class CheckReport:
    """Every check's result for one engine."""

    engine: str
    results: list[CheckResult] = field(default_factory=list)

    @property
    def failures(self) -> list[CheckResult]:
        return [r for r in self.results if r.outcome == FAILED]

    @property
    def ok(self) -> bool:
        return not self.failures

    def summary(self) -> str:
        """One line per check, failed ones with what was expected and seen."""
        counts = {o: sum(r.outcome == o for r in self.results) for o in (PASSED, FAILED,
                                                                           SKIPPED)}
        head = f"{self.engine}: " + ", ".join(f"{n} {o}" for o, n in counts.items())
        lines = [f"  {r.outcome:7} {r.name}" + (f": {r.message}" if r.message else "")
                 for r in self.results]
        return "\n".join([head, *lines])


class EngineCheckError(GaltonError):
    """An engine failed one or more checks; ``report`` holds every result."""

    def __init__(self, report: CheckReport) -> None:
        failed = "\n".join(f"  {r.name}: {r.message}" for r in report.failures)
        super().__init__(f"the {report.engine} engine failed {len(report.failures)} of "
                         f"{len(report.results)} checks:\n{failed}")
        self.report = report


def engine_factory(factory_or_name: EngineFactory | str) -> EngineFactory:
    """A factory of fresh engines: a registered engine's name, or a callable returned as is."""
    if not isinstance(factory_or_name, str):
        return factory_or_name
    name = factory_or_name
    if name not in ENGINE_CLASSES:
        create_engine(name)  # raises InvalidArgumentError, with a "did you mean"
    return lambda: create_engine(name)


def run_check(factory_or_name: EngineFactory | str, name: str, *,
              params: Mapping[str, Any] | None = None) -> CheckResult:
    """Run the check of that name on fresh engines; its result (it never raises for a
    failure of the engine: the result says it)."""
    check = _BY_NAME.get(name)
    if check is None:
        raise InvalidArgumentError(
            f"no engine check named {name!r}{did_you_mean(name, _BY_NAME)}; "
            f"known: {', '.join(_BY_NAME)}")
    context = CheckContext(engine_factory(factory_or_name), dict(params or {}))
    try:
        check.run(context)
    except CheckSkippedError as exc:
        return CheckResult(name, SKIPPED, str(exc))
    except CheckFailedError as exc:
        return CheckResult(name, FAILED, str(exc))
    except Exception as exc:  # an engine's crash is that check's failure
        return CheckResult(name, FAILED, f"raised {type(exc).__name__}: {exc}")
    finally:
        context.close()
    return CheckResult(name, PASSED)


def check_engine(factory_or_name: EngineFactory | str, *,
                 params: Mapping[str, Any] | None = None) -> CheckReport:
    """Run every check of ``ENGINE_CHECKS``; the report, or EngineCheckError naming every
    failure. Parameters an engine refuses are refused here, before any check runs."""
    factory = engine_factory(factory_or_name)
    probe = factory()
    try:
        label = str(getattr(probe, "name", type(probe).__name__))
        if params:
            probe.set_params(dict(params))
    finally:
        probe.close()
    report = CheckReport(label, [run_check(factory, c.name, params=params)
                                 for c in ENGINE_CHECKS])
    if not report.ok:
        raise EngineCheckError(report)
    return report
