"""What the daemon does for each operation: protocol/operations.py declares every operation
(its arguments, whether it mutates, steps or is fast, how long a client waits); this module
binds each one to the function that serves it, and refuses to load when the two drift.

A handler is bound where it is written, marked ``@handles("op")`` or ``@scene_op("op")``
(daemon/ops/binding.py), in one of the modules ``OP_MODULES`` lists; the operations that
predate the marks are still bound in ``_TABLE`` below (the same checks hold for both).

Time-control operations (daemon/core/time_control.py) act on the loop; scene operations
(daemon/ops/scene.py) act on its World and, when they change it, publish a ``scene`` event. The
one ``fast`` operation, status, is answered on the transport's thread from the loop's
atomic snapshot (``SimLoop.handle_readonly``) and never reaches this table's callers; it is
bound here too, so that a status that does reach the physics thread is answered the same.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from types import ModuleType
from typing import Any

from galton.daemon.access import lease
from galton.daemon.core import predict, time_control
from galton.daemon.core.calls import Call
from galton.daemon.core.context import OpContext
from galton.daemon.ops import joints as ops_joints
from galton.daemon.ops import perception as ops_perception
from galton.daemon.ops import scene as ops
from galton.daemon.ops import worlds
from galton.daemon.ops.binding import binding_of
from galton.daemon.world import pose_compare as compare
from galton.daemon.world import state_streams
from galton.protocol.operations import OPERATIONS
from galton.protocol.requests import Args

Result = dict[str, Any] | None  # None: the reply comes later (a step job)
# A handler receives its operation's declared request (protocol/requests.py), decoded and
# checked before it runs.
Handler = Callable[["OpContext", Call, Any], Result]


def _scene(name: str, apply: ops.SceneOp) -> Handler:
    """A scene operation as a handler: applied to the loop's world; a success that changes
    the scene is announced, and a step job reading a deleted entity is answered now."""
    mutates = OPERATIONS[name].mutates

    def handle(loop: OpContext, call: Call, request: Args) -> Result:
        world = loop.world_for(request)
        result = apply(world, request)
        if mutates:
            event = {"kind": "scene", "op": name, "world": world.name,
                     "step": world.step_index}
            if name == "compare" and result is not None:  # the view charts the score
                event.update(score=result["score"], sim_time=world.sim_time)
            loop.emit(event)
            loop.check_job_reads()
        return result
    return handle


def _capabilities(loop: OpContext, call: Call, request: Args) -> Result:
    """The engine's capabilities, with what the daemon adds (its ZeroMQ endpoints)."""
    return {**ops.capabilities(loop.world_for(request), request), **loop.advertised}


_TABLE: dict[str, Handler] = {
    "status": time_control.status,
    "capabilities": _capabilities,
    "play": time_control.play,
    "set_rtf": time_control.set_rtf,
    "pause": time_control.pause,
    "stop": time_control.stop,
    "step": time_control.step,
    "run_until": time_control.run_until,
    "reset": time_control.reset,
    "load_world": time_control.load_world,
    "spawn": _scene("spawn", ops.spawn),
    "load_model": _scene("load_model", ops.load_model),
    "list": _scene("list", ops.list_entities),
    "get_states": _scene("get_states", ops.get_states),
    "get_bounds": _scene("get_bounds", ops.get_bounds),
    "get_shapes": _scene("get_shapes", ops.get_shapes),
    "set_states": _scene("set_states", ops.set_states),
    "update": _scene("update", ops.update),
    "delete": _scene("delete", ops.delete),
    "joints": _scene("joints", ops_joints.joints),
    "get_joint_states": _scene("get_joint_states", ops_joints.get_joint_states),
    "set_joint_states": _scene("set_joint_states", ops_joints.set_joint_states),
    "set_joint_targets": _scene("set_joint_targets", ops_joints.set_joint_targets),
    "apply_wrench": _scene("apply_wrench", ops_joints.apply_wrench),
    "clear_wrenches": _scene("clear_wrenches", ops_joints.clear_wrenches),
    "snapshot": worlds.snapshot,
    "restore": worlds.restore,
    "snapshots": worlds.snapshots,
    "delete_snapshot": worlds.delete_snapshot,
    "list_worlds": worlds.list_worlds,
    "create_world": worlds.create_world,
    "fork_world": worlds.fork_world,
    "delete_world": worlds.delete_world,
    "predict": predict.predict,
    "compare": _scene("compare", compare.compare),
    "render": _scene("render", ops_perception.render),
    "add_camera": _scene("add_camera", ops_perception.add_camera),
    "remove_camera": _scene("remove_camera", ops_perception.remove_camera),
    "cameras": _scene("cameras", ops_perception.cameras),
    "raycast": _scene("raycast", ops_perception.raycast),
    "contacts": _scene("contacts", ops_perception.contacts),
    "get_params": _scene("get_params", ops.get_params),
    "set_params": _scene("set_params", ops.set_params),
    "take_control": lease.take_control,
    "release_control": lease.release_control,
    "stream_states": state_streams.stream_states,
    "close_stream": state_streams.close_stream,
}


# The modules whose marked functions are handlers (daemon/ops/binding.py): a module that
# serves operations is listed here once, then each new handler in it binds itself.
OP_MODULES: tuple[ModuleType, ...] = (ops, ops_joints, ops_perception, worlds, time_control,
                                      predict, compare, lease, state_streams)


def collect(modules: Iterable[ModuleType], table: dict[str, Handler]) -> dict[str, Handler]:
    """``table`` and the functions marked in ``modules`` (each where it is defined), as one
    map; an operation bound twice is refused."""
    found = dict(table)
    for module in modules:
        for value in vars(module).values():
            binding = binding_of(value)
            if binding is None or getattr(value, "__module__", None) != module.__name__:
                continue
            if binding.operation in found:
                raise RuntimeError(f"operation {binding.operation!r} is bound twice (a "
                                   f"marked handler in {module.__name__} and another)")
            found[binding.operation] = (_scene(binding.operation, value) if binding.scene
                                        else value)
    return found


HANDLERS: dict[str, Handler] = collect(OP_MODULES, _TABLE)


# What the transport's thread can answer from the loop's snapshot (SimLoop.handle_readonly).
ANSWERED_FROM_SNAPSHOT = frozenset({"status"})


def check_bindings(handlers: dict[str, Handler]) -> None:
    """Every declared operation has a handler and every handler a declaration; the
    operations declared fast are those the snapshot can answer."""
    unbound = sorted(set(OPERATIONS) - set(handlers))
    undeclared = sorted(set(handlers) - set(OPERATIONS))
    fast = {name for name, op in OPERATIONS.items() if op.fast}
    if unbound or undeclared or fast != ANSWERED_FROM_SNAPSHOT:
        raise RuntimeError(
            f"operations without a handler: {unbound}; handlers without a declaration in "
            f"protocol/operations.py: {undeclared}; declared fast: {sorted(fast)}, answered "
            f"from the snapshot: {sorted(ANSWERED_FROM_SNAPSHOT)}")


check_bindings(HANDLERS)
