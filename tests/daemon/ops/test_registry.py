"""One registry: every operation declared in protocol/operations.py is served by exactly one
handler, the fast ones are those the daemon answers from its snapshot, and a client's
default timeouts come from the same declarations."""

from __future__ import annotations

import inspect
import types
from pathlib import Path

import pytest

from galton.daemon.ops import entities, handlers
from galton.daemon.ops.binding import binding_of
from galton.daemon.ops.handlers import HANDLERS, OP_MODULES, check_bindings, collect
from galton.protocol.operations import LONG_RUNNING_TIMEOUT_S, OPERATIONS, Operation, operation


def test_every_declared_operation_has_one_handler() -> None:
    check_bindings(HANDLERS)
    assert set(HANDLERS) == set(OPERATIONS)


def test_a_declaration_without_a_handler_stops_the_daemon_loading() -> None:
    partial = {name: handler for name, handler in HANDLERS.items() if name != "spawn"}
    with pytest.raises(RuntimeError, match=r"without a handler: \['spawn'\]"):
        check_bindings(partial)


def test_a_handler_without_a_declaration_stops_the_daemon_loading() -> None:
    extra = {**HANDLERS, "teleport": HANDLERS["set_states"]}
    with pytest.raises(RuntimeError, match=r"without a declaration .*\['teleport'\]"):
        check_bindings(extra)


def test_a_marked_handler_binds_itself_and_twice_is_refused() -> None:
    assert HANDLERS["get_entities"] is not HANDLERS["get_bounds"]  # collected from entities.py
    module = types.ModuleType("marked_ops")
    exec("from galton.daemon.ops.binding import handles\n"
         "@handles('get_bounds')\ndef bounds_again(context, call, request): return None",
         module.__dict__)
    with pytest.raises(RuntimeError, match="'get_bounds' is bound twice"):
        collect([entities, module])
    assert collect([module])["get_bounds"] is module.bounds_again


# Every operation's handler is bound in ops/ (thin adapters where the work lives elsewhere).
BOUND_OUTSIDE_OPS: set[str] = set()


def test_every_handler_is_bound_in_ops() -> None:
    ops_folder = Path(handlers.__file__).parent
    where = {binding.operation: Path(inspect.getfile(value)).parent
             for module in OP_MODULES for value in vars(module).values()
             if (binding := binding_of(value)) is not None
             and value.__module__ == module.__name__}
    assert set(where) == set(OPERATIONS)
    assert {name for name, folder in where.items() if folder != ops_folder} == BOUND_OUTSIDE_OPS
    assert not hasattr(handlers, "_TABLE")


@pytest.mark.parametrize("op", OPERATIONS.values(), ids=list(OPERATIONS))
def test_client_timeouts_follow_the_declaration(op: Operation) -> None:
    waited = op.client_timeout(5.0)
    if op.steps:
        assert waited == LONG_RUNNING_TIMEOUT_S
    else:
        assert waited == max(5.0, op.timeout_floor_s)
        assert op.client_timeout(100.0) == 100.0  # a longer default is never shortened


def test_only_status_is_fast_and_only_stepping_operations_are_long_running() -> None:
    assert [name for name, op in OPERATIONS.items() if op.fast] == ["status"]
    assert [name for name, op in OPERATIONS.items() if op.steps] == ["step", "run_until",
                                                                      "predict", "calibrate"]
    assert all(op.mutates for op in OPERATIONS.values() if op.steps and op.name != "predict")
    assert operation("spawn").timeout_floor_s >= 30
