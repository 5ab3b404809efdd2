"""Time-control operations of the physics loop: play, pause, stop, step, run_until, reset.

A mixin of ``SimLoop`` so that the state machine reads as one table. Each operation
returns the reply's result map, or None when the reply comes later (a step job).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar

from galton.daemon.calls import Call, RestCheck, StepJob
from galton.daemon.world import World, check_scope
from galton.protocol import (
    IncorrectStateError,
    InvalidArgumentError,
    OperationFailedError,
)
from galton.protocol.errors import brief
from galton.protocol.model import check_fields, check_names, check_type, finite_number

if TYPE_CHECKING:
    from galton.daemon.loop import SimLoop

MAX_RTF = 1e6


def _check_count(value: Any, max_steps: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= max_steps:
        raise InvalidArgumentError(f"step.count must be an integer in [1, {max_steps}], "
                                   f"got {brief(value)}")
    return value


def _check_rtf(value: Any, where: str) -> float:
    return finite_number(value, where, low=0.0, high=MAX_RTF)


def _rest_check(args: dict[str, Any], read: list[str] | None,
                timestep: float) -> RestCheck | None:
    """run_until's optional ``until_rest: {speed, every}``: stop once the read bodies rest."""
    rest = args.get("until_rest")
    if rest is None:
        return None
    check_type(rest, dict, "run_until.until_rest")
    check_fields(rest, ("speed", "every"), "run_until.until_rest")
    if read is None:
        raise InvalidArgumentError("run_until.until_rest needs 'read': the bodies that must rest")
    speed = finite_number(rest.get("speed"), "run_until.until_rest.speed", low=0.0,
                          low_open=True)
    every = finite_number(rest.get("every"), "run_until.until_rest.every", low=0.0,
                          low_open=True)
    return RestCheck(speed, max(1, round(every / timestep)))


class StateOps:
    """The state machine: stopped → playing ⇄ paused, with step jobs while not playing."""

    def op_status(self: SimLoop, call: Call, args: dict[str, Any]) -> dict[str, Any]:
        return self.status().to_wire()

    def op_play(self: SimLoop, call: Call, args: dict[str, Any]) -> dict[str, Any]:
        rtf = args.get("rtf")
        target = self.target_rtf if rtf is None else _check_rtf(rtf, "play.rtf")
        if self.job is not None:
            raise IncorrectStateError("a step request is still running; wait for it or pause")
        self.world.require_valid()
        self.target_rtf = target
        self._set_state("playing")
        return self.status().to_wire()

    def op_set_rtf(self: SimLoop, call: Call, args: dict[str, Any]) -> dict[str, Any]:
        self.target_rtf = _check_rtf(args.get("rtf"), "set_rtf.rtf")
        self.pacer.anchor(time.monotonic(), self.world.sim_time, self.target_rtf)
        return self.status().to_wire()

    def op_pause(self: SimLoop, call: Call, args: dict[str, Any]) -> dict[str, Any]:
        self._cancel_job("paused")
        self._set_state("paused")
        return self.status().to_wire()

    def op_stop(self: SimLoop, call: Call, args: dict[str, Any]) -> dict[str, Any]:
        """Pause and rewind: time to 0 and every entity back to the state it was created in."""
        self._cancel_job("stopped")
        self.world.reset("state")
        self.world.reset("time")
        self._after_reset()
        self._set_state("stopped")
        return self.status().to_wire()

    def op_step(self: SimLoop, call: Call, args: dict[str, Any]) -> None:
        if "until_rest" in args:
            raise InvalidArgumentError("step takes no until_rest: use run_until with "
                                       "until_rest and read to stop once bodies rest")
        count = _check_count(args.get("count", 1), self.limits.max_steps)
        self._start_job(call, count, self._read_list(args, "step"))

    def op_run_until(self: SimLoop, call: Call, args: dict[str, Any]) -> dict[str, Any] | None:
        target = finite_number(args.get("sim_time"), "run_until.sim_time", low=0.0)
        dt = self.world.engine.timestep
        steps = (target - self.world.sim_time) / dt - 1e-9
        limit = self.limits.max_steps
        if steps > limit:
            raise InvalidArgumentError(
                f"run_until.sim_time {target:g} s is {steps:.3g} steps of {dt:g} s away; one "
                f"request takes at most {limit} steps (to sim time "
                f"{self.world.sim_time + limit * dt:g} s)", {"max_steps": limit})
        count = math.ceil(steps)
        if count <= 0:
            raise InvalidArgumentError(
                f"run_until.sim_time {target} is not after the current sim time "
                f"{self.world.sim_time}")
        read = self._read_list(args, "run_until")
        self._start_job(call, count, read, _rest_check(args, read, dt))
        return None

    def op_reset(self: SimLoop, call: Call, args: dict[str, Any]) -> dict[str, Any]:
        scope = check_scope(args.get("scope", "all"))
        self._cancel_job("reset")
        self.world.reset(scope)
        self._after_reset()
        self.emit({"kind": "scene", "op": "reset", "scope": scope,
                   "step": self.world.step_index})
        return self.status().to_wire()

    def op_load_world(self: SimLoop, call: Call, args: dict[str, Any]) -> dict[str, Any]:
        """Replace the world with a fresh one on the named engine, in this process."""
        name = check_type(args.get("engine"), str, "load_world.engine")
        if self.engine_factory is None:
            raise OperationFailedError("this daemon cannot switch engines")
        engine = self.engine_factory(name)
        params = args.get("params")
        if params is not None:
            try:
                engine.set_params(check_type(params, dict, "load_world.params"))
            except Exception:
                engine.close()
                raise
        self._cancel_job("world replaced")
        old, self.world = self.world, World(engine, self.world.name, self.limits)
        old.engine.close()
        self.tune_switch_interval()
        self._after_reset()
        self._set_state("stopped")
        self.emit({"kind": "scene", "op": "load_world", "engine": name, "step": 0})
        return self.status().to_wire()

    # -- helpers ------------------------------------------------------------------------
    def _read_list(self: SimLoop, args: dict[str, Any], where: str) -> list[str] | None:
        """The entities a step request wants read back when done; unknown names reject the
        request before any step is taken."""
        read = args.get("read")
        if read is None:
            return None
        names = check_names(read, f"{where}.read")
        self.world.require_known(names)
        return names

    def _start_job(self: SimLoop, call: Call, count: int, read: list[str] | None = None,
                   rest: RestCheck | None = None) -> None:
        if self.state == "playing":
            raise IncorrectStateError("cannot step while playing: pause first")
        if self.job is not None:
            raise IncorrectStateError("another step request is still running")
        self.world.require_valid()
        if self.state == "stopped":
            self._set_state("paused")
        self.job = StepJob(call, count, count, read, rest)

    def client_gone(self: SimLoop, client: str) -> None:
        """A client's liveliness token vanished: the step request it is waiting for ends
        now (its reply has nowhere to go), the world stays paused where it got to."""
        job = self.job
        if job is None or job.call.client != client:
            return
        self._cancel_job("its client disappeared")
        self.emit({"kind": "job_abandoned", "client": client, "steps_done": job.done,
                   "steps_asked": job.total, "step": self.world.step_index})

    def _cancel_job(self: SimLoop, reason: str) -> None:
        if self.job is None:
            return
        job, self.job = self.job, None
        done = job.total - job.remaining
        self._reply_error(job.call, OperationFailedError(
            f"step request interrupted ({reason}) after {done} of {job.total} steps",
            {"steps_done": done}))

    def _after_reset(self: SimLoop) -> None:
        self.refresh_clock()
        self.rtf_window.clear()
        self.pacer.anchor(time.monotonic(), self.world.sim_time, self.target_rtf)

    def _set_state(self: SimLoop, state: str) -> None:
        if state == "playing":
            self.pacer.anchor(time.monotonic(), self.world.sim_time, self.target_rtf)
        if state != self.state:
            self.state = state
            self.emit({"kind": "state", "state": state, "step": self.world.step_index,
                       "sim_time": self.world.sim_time})

    STATE_OPS: ClassVar[dict[str, Callable[..., dict[str, Any] | None]]] = {
        "status": op_status,
        "play": op_play,
        "set_rtf": op_set_rtf,
        "pause": op_pause,
        "stop": op_stop,
        "step": op_step,
        "run_until": op_run_until,
        "reset": op_reset,
        "load_world": op_load_world,
    }
