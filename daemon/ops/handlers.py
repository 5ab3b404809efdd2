"""What the daemon does for each operation: protocol/operations.py declares every operation
(its arguments, whether it mutates, steps or is fast, how long a client waits); this module
binds each one to the function that serves it, and refuses to load when the two drift.

A handler is bound where it is written, marked ``@handles("op")`` or ``@scene_op("op")``
(daemon/ops/binding.py), in one of the modules ``OP_MODULES`` lists, all in ops/: where
the work lives elsewhere (the time control of daemon/core/time_control.py, the lease of
access/, the state streams and pose comparison of world/), an ops/ module holds a thin
adapter that names the operation.

Time-control operations (daemon/ops/time_control.py) act on the loop; scene operations
(daemon/ops/entities.py) act on its World and, when they change it, publish a ``scene``
event. The one ``fast`` operation, status, is answered on the transport's thread from one
reading of the loop's status values (``StatusBoard.answer``, daemon/core/loop_status.py)
and never reaches this table's callers; it is bound here too, so that a status that does
reach the physics thread (a side world's) is answered the same.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from types import ModuleType
from typing import Any

from galton.daemon.core.calls import Call
from galton.daemon.core.context import OpContext, SceneContext
from galton.daemon.ops import control, look_ahead, streams, time_control, worlds
from galton.daemon.ops import entities as ops
from galton.daemon.ops import joints as ops_joints
from galton.daemon.ops import perception as ops_perception
from galton.daemon.ops.binding import binding_of
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

    def handle(ctx: SceneContext, call: Call, request: Args) -> Result:
        world = ctx.world_for(request)
        result = apply(world, request)
        if mutates:
            ctx.emit({"kind": "scene", "op": name, "world": world.name,
                      "step": world.step_index})
            ctx.check_job_reads()
        return result
    return handle


# The modules whose marked functions are handlers (daemon/ops/binding.py): a module that
# serves operations is listed here once, then each new handler in it binds itself.
OP_MODULES: tuple[ModuleType, ...] = (ops, ops_joints, ops_perception, worlds, time_control,
                                      control, streams, look_ahead)


def collect(modules: Iterable[ModuleType]) -> dict[str, Handler]:
    """The functions marked in ``modules`` (each where it is defined), as one map; an
    operation bound twice is refused."""
    found: dict[str, Handler] = {}
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


HANDLERS: dict[str, Handler] = collect(OP_MODULES)


# What the transport's thread answers from the loop's status values (StatusBoard.answer).
ANSWERED_ON_TRANSPORT_THREAD = frozenset({"status"})


def check_bindings(handlers: dict[str, Handler]) -> None:
    """Every declared operation has a handler and every handler a declaration; the
    operations declared fast are those the transport's thread answers."""
    unbound = sorted(set(OPERATIONS) - set(handlers))
    undeclared = sorted(set(handlers) - set(OPERATIONS))
    fast = {name for name, op in OPERATIONS.items() if op.fast}
    if unbound or undeclared or fast != ANSWERED_ON_TRANSPORT_THREAD:
        raise RuntimeError(
            f"operations without a handler: {unbound}; handlers without a declaration in "
            f"protocol/operations.py: {undeclared}; declared fast: {sorted(fast)}, answered "
            f"on the transport's thread: {sorted(ANSWERED_ON_TRANSPORT_THREAD)}")


check_bindings(HANDLERS)
