"""Every SDK method sends its operation's wire map, written out here. They were written as
the SDK sent them before its methods were built on the declared request types (issue 50),
and held since: a field left None is not sent. Where a method took None for "the daemon's
default", the declared default is now sent (``before`` holds what was sent then), and the
daemon decodes both to the same request. Every operation has a method here.

The requests are caught at the transport, packed and unpacked as the daemon receives them,
and go no further (a method's reply is not the point); a stream's requests are forwarded
to the real daemon, so that a stream really opens and closes. A bad argument is refused
before it is sent, in the words the daemon answers the same map with."""

from __future__ import annotations

import ast
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from support.daemons import start_daemon

import galton.client.sdk
from galton.client import Client, EmbeddedDaemon, InvalidArgumentError, spheres
from galton.client.transport.base import Transport
from galton.protocol import Reply, pack_f64
from galton.protocol import requests as rq
from galton.protocol.envelope import decode_request, encode_request
from galton.protocol.operations import OPERATIONS
from galton.protocol.vocabulary import (
    DEFAULT_MAX_LENGTH,
    DEFAULT_SIGMA_ANGLE,
    DEFAULT_SIGMA_POSITION,
    DEFAULT_SIGMA_SPEED,
)


class SentError(Exception):
    """A request caught on its way to the wire."""


class Catching:
    """A transport that records each request's (op, args) and stops it there, unless its
    op is one of ``forward`` (then the real transport sends it)."""

    def __init__(self, real: Transport, forward: frozenset[str] = frozenset()) -> None:
        self.real, self.forward, self.kind = real, forward, real.kind
        self.sent: list[tuple[str, dict[str, Any]]] = []

    def request(self, op: str, args: dict[str, Any] | None, timeout: float,
                client: str | None) -> Reply:
        # What the daemon receives: the request packed and unpacked as the envelope does.
        self.sent.append((op, decode_request(encode_request(op, args, client)).args))
        if op in self.forward:
            return self.real.request(op, args, timeout, client)
        raise SentError(op)

    def send_raw(self, op: str, payload: bytes, timeout: float) -> list[bytes]:
        return self.real.send_raw(op, payload, timeout)

    def subscribe(self, topic: Any, callback: Callable[[bytes], None],
                  key: str | None = None) -> Any:
        return self.real.subscribe(topic, callback, key)

    def close(self) -> None:
        self.real.close()


@pytest.fixture(scope="module")
def catching(daemons: dict[str, EmbeddedDaemon]) -> Iterator[tuple[Client, Catching]]:
    daemon = start_daemon(daemons, "mujoco")
    with Client(daemon.instance, daemon.endpoint, timeout=20.0) as client:
        caught = Catching(client.transport)
        client.transport = caught
        yield client, caught


def rows(*values: Any) -> bytes:
    return pack_f64(np.asarray(values, dtype=float))


def tiled(row: list[float], count: int) -> bytes:
    return pack_f64(np.tile(np.asarray(row, dtype=float), (count, 1)))


POSE = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
TWIST = [0.0, 0.0, 0.5, 0.0, 0.0, 0.0]
WRENCH = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]
GROUP = spheres(["b0", "b1"], [[0, 0, 1], [0, 0, 2]], radius=0.05, mass=0.2)
CAMERA = {"eye": [1.0, 0.0, 1.0], "target": [0.0, 0.0, 0.0], "width": 32, "height": 24}
JOINT_TARGETS = {"names": ["j1", "j2"], "mode": "position", "targets": [0.1, 0.2]}
WRENCHES = {"names": ["a"], "wrenches": WRENCH, "duration": 0.5}
PLANS = [[{"at": 0.0, "joint_targets": {"names": ["j1", "j2"], "mode": "position",
                                        "targets": rows(0.1, 0.2)}}],
         [{"at": 0.5, "wrenches": {"names": ["a"], "wrenches": rows(*WRENCH),
                                   "duration": 0.5}}]]
NO_NOISE = {"position": 0.0, "orientation": 0.0, "velocity": 0.0}
SIGMAS = {"sigma_position": DEFAULT_SIGMA_POSITION, "sigma_angle": DEFAULT_SIGMA_ANGLE,
          "sigma_speed": DEFAULT_SIGMA_SPEED}


@dataclass(frozen=True)
class Case:
    """An SDK call and the (op, args) it sends (``before``: before issue 50, if other)."""

    call: Callable[[Client], Any]
    op: str
    wire: dict[str, Any]
    before: dict[str, Any] | None = None


CASES: dict[str, Case] = {
    "capabilities": Case(lambda c: c.capabilities(), "capabilities", {}),
    "status": Case(lambda c: c.status(), "status", {}),
    "play": Case(lambda c: c.play(), "play", {}),
    "play-rtf": Case(lambda c: c.play(2.5), "play", {"rtf": 2.5}),
    "play-flat-out": Case(lambda c: c.play(0), "play", {"rtf": 0}),
    "set_rtf": Case(lambda c: c.set_rtf(3.0), "set_rtf", {"rtf": 3.0}),
    "pause": Case(lambda c: c.pause(), "pause", {}),
    "stop": Case(lambda c: c.stop(), "stop", {}),
    "step": Case(lambda c: c.step(), "step", {"count": 1}),
    "step-10": Case(lambda c: c.step(10), "step", {"count": 10}),
    "step_and_read": Case(lambda c: c.step_and_read(5, ["a", "b"]), "step",
                          {"count": 5, "read": ["a", "b"]}),
    "step_and_read_joints": Case(lambda c: c.step_and_read_joints(5, ("j",)), "step",
                                 {"count": 5, "read_joints": ["j"]}),
    "step_and_read_both": Case(lambda c: c.step_and_read_both(2, ["a"], ["j"]), "step",
                               {"count": 2, "read": ["a"], "read_joints": ["j"]}),
    "run_until": Case(lambda c: c.run_until(1.5), "run_until", {"sim_time": 1.5}),
    # msgspec takes no numpy float where msgpack sends it as a float: the daemon's check
    "run_until-numpy": Case(lambda c: c.run_until(np.float64(1.5)), "run_until",
                            {"sim_time": 1.5}),
    "run_until_and_read": Case(lambda c: c.run_until_and_read(1.0, ["a"]), "run_until",
                               {"sim_time": 1.0, "read": ["a"]}),
    "run_until_and_read_joints": Case(lambda c: c.run_until_and_read_joints(1.0, ["j"]),
                                      "run_until", {"sim_time": 1.0, "read_joints": ["j"]}),
    "run_until_rest": Case(lambda c: c.run_until_rest(2.0, ["a"], 0.01, 0.1), "run_until",
                           {"sim_time": 2.0, "read": ["a"],
                            "until_rest": {"speed": 0.01, "every": 0.1}}),
    "reset": Case(lambda c: c.reset(), "reset", {"scope": "all"}),
    "reset-time": Case(lambda c: c.reset("time"), "reset", {"scope": "time"}),
    "load_world": Case(lambda c: c.load_world("pybullet"), "load_world",
                       {"engine": "pybullet"}),
    "load_world-params": Case(lambda c: c.load_world("mujoco", {"timestep": 0.001}),
                              "load_world", {"engine": "mujoco",
                                             "params": {"timestep": 0.001}}),
    "load_world-no-params": Case(lambda c: c.load_world("mujoco", {}), "load_world",
                                 {"engine": "mujoco"}),
    "get_params": Case(lambda c: c.get_params(), "get_params", {}),
    "set_params": Case(lambda c: c.set_params({"gravity": [0.0, 0.0, -9.0]}), "set_params",
                       {"params": {"gravity": [0.0, 0.0, -9.0]}}),
    "spawn": Case(lambda c: c.spawn(GROUP), "spawn", {"groups": [GROUP.to_wire()]}),
    "load_model": Case(lambda c: c.load_model("urdf", text="<robot/>"), "load_model",
                       {"format": "urdf", "prefix": "", "text": "<robot/>",
                        "fixed_base": True},
                       before={"format": "urdf", "prefix": "", "text": "<robot/>"}),
    "load_model-path": Case(
        lambda c: c.load_model("mjcf", path=Path("/m/arm.xml"), prefix="p_",
                               fixed_base=False, search_path=["/a", Path("/b")]),
        "load_model", {"format": "mjcf", "prefix": "p_", "path": "/m/arm.xml",
                       "fixed_base": False, "search_path": "/a:/b"}),
    "list": Case(lambda c: c.list(), "list", {}),
    "list-filtered": Case(lambda c: c.list("b*", tag="t", kind="dynamic"), "list",
                          {"name": "b*", "tag": "t", "kind": "dynamic"}),
    "get_states": Case(lambda c: c.get_states(), "get_states", {}),
    "get_states-named": Case(lambda c: c.get_states(("a", "b")), "get_states",
                             {"names": ["a", "b"]}),
    "get_bounds": Case(lambda c: c.get_bounds(["a"]), "get_bounds", {"names": ["a"]}),
    "get_shapes": Case(lambda c: c.get_shapes(), "get_shapes", {}),
    "get_entities": Case(lambda c: c.get_entities(), "get_entities", {}),
    "get_entities-filtered": Case(
        lambda c: c.get_entities("b*", [[0, 0, 0], [1, 1, 1]]), "get_entities",
        {"pattern": "b*", "region": rows(0, 0, 0, 1, 1, 1)}),
    "set_states": Case(lambda c: c.set_states(["a", "b"], poses=POSE), "set_states",
                       {"names": ["a", "b"], "poses": tiled(POSE, 2)}),
    "set_states-twists": Case(lambda c: c.set_states(["a"], twists=[TWIST]), "set_states",
                              {"names": ["a"], "twists": rows(*TWIST)}),
    "update": Case(lambda c: c.update(["a"], mass=2.0, rgba=(1, 0, 0, 1), tags=("t",)),
                   "update", {"names": ["a"], "properties": {
                       "mass": 2.0, "rgba": [1, 0, 0, 1], "tags": ["t"]}}),
    "delete": Case(lambda c: c.delete(["a"]), "delete", {"names": ["a"]}),
    "joints": Case(lambda c: c.joints(), "joints", {}),
    "joints-filtered": Case(lambda c: c.joints("arm", ["j1"]), "joints",
                            {"model": "arm", "names": ["j1"]}),
    "get_joint_states": Case(lambda c: c.get_joint_states(["j"]), "get_joint_states",
                             {"names": ["j"]}),
    "set_joint_states": Case(lambda c: c.set_joint_states(["j1", "j2"], 0.5),
                             "set_joint_states", {"names": ["j1", "j2"],
                                                  "positions": rows(0.5, 0.5)}),
    "set_joint_states-velocities": Case(
        lambda c: c.set_joint_states(["j1", "j2"], [0.1, 0.2], [1, 2]), "set_joint_states",
        {"names": ["j1", "j2"], "positions": rows(0.1, 0.2), "velocities": rows(1, 2)}),
    "set_joint_states_and_read": Case(
        lambda c: c.set_joint_states_and_read(["j"], [0.1], ["a"]), "set_joint_states",
        {"names": ["j"], "positions": rows(0.1), "read": ["a"]}),
    "set_joint_targets": Case(
        lambda c: c.set_joint_targets(["j1", "j2"], "position", [0.1, 0.2], kp=10, kd=1,
                                      max_effort=5),
        "set_joint_targets", {"names": ["j1", "j2"], "mode": "position",
                              "targets": rows(0.1, 0.2), "kp": rows(10, 10),
                              "kd": rows(1, 1), "max_effort": rows(5, 5)}),
    "set_joint_targets-none": Case(lambda c: c.set_joint_targets(["j"], "none"),
                                   "set_joint_targets", {"names": ["j"], "mode": "none"}),
    "apply_wrench": Case(lambda c: c.apply_wrench(["a", "b"], WRENCH), "apply_wrench",
                         {"names": ["a", "b"], "wrenches": tiled(WRENCH, 2)}),
    "apply_wrench-at": Case(
        lambda c: c.apply_wrench(["a"], [WRENCH], points=[0, 0, 1], duration=0.5),
        "apply_wrench", {"names": ["a"], "wrenches": rows(*WRENCH), "points": rows(0, 0, 1),
                         "duration": 0.5}),
    "clear_wrenches": Case(lambda c: c.clear_wrenches(), "clear_wrenches", {}),
    "clear_wrenches-named": Case(lambda c: c.clear_wrenches(["a"]), "clear_wrenches",
                                 {"names": ["a"]}),
    "list_worlds": Case(lambda c: c.list_worlds(), "list_worlds", {}),
    "create_world": Case(lambda c: c.create_world("w"), "create_world", {"name": "w"}),
    "create_world-all": Case(lambda c: c.create_world("w", "ode", {"timestep": 0.01}),
                             "create_world", {"name": "w", "engine": "ode",
                                              "params": {"timestep": 0.01}}),
    "create_world-no-params": Case(lambda c: c.create_world("w", params={}), "create_world",
                                   {"name": "w"}),
    "fork_world": Case(lambda c: c.fork_world("w"), "fork_world", {"name": "w"}),
    "fork_world-source": Case(lambda c: c.fork_world("w", "other"), "fork_world",
                              {"name": "w", "source": "other"}),
    "delete_world": Case(lambda c: c.delete_world("w"), "delete_world", {"name": "w"}),
    "snapshot": Case(lambda c: c.snapshot(), "snapshot", {"blob": False}),
    "snapshot-slot-blob": Case(lambda c: c.snapshot("s", blob=True), "snapshot",
                               {"slot": "s", "blob": True}),
    "restore": Case(lambda c: c.restore("s"), "restore", {"slot": "s"}),
    "restore-blob": Case(lambda c: c.restore(blob=bytearray(b"xy")), "restore",
                         {"blob": b"xy"}),
    "snapshots": Case(lambda c: c.snapshots(), "snapshots", {}),
    "delete_snapshot": Case(lambda c: c.delete_snapshot("s"), "delete_snapshot",
                            {"slot": "s"}),
    "predict": Case(lambda c: c.predict(1.0), "predict", {"horizon": 1.0, "first_future": 0},
                    before={"horizon": 1.0}),
    "predict-all": Case(
        lambda c: c.predict(
            1.0, every=0.1, read=("a",), read_joints=["j1"], slot="s",
            set_states={"names": ["a"], "poses": POSE}, joint_targets=JOINT_TARGETS,
            wrenches=WRENCHES, futures=4, seed=7, first_future=3,
            perturb={"position": 0.01, "velocity": 0.0},
            plans=[[{"at": 0, "joint_targets": JOINT_TARGETS}], [{"at": 0.5,
                                                                  "wrenches": WRENCHES}]],
            score={"body": "a", "target": (1, 2, 3)}),
        "predict", {
            "horizon": 1.0, "every": 0.1, "read": ["a"], "read_joints": ["j1"], "slot": "s",
            "set_states": {"names": ["a"], "poses": rows(*POSE)},
            "joint_targets": {"names": ["j1", "j2"], "mode": "position",
                              "targets": rows(0.1, 0.2)},
            "wrenches": {"names": ["a"], "wrenches": rows(*WRENCH), "duration": 0.5},
            "futures": 4, "seed": 7, "first_future": 3,
            "perturb": {"position": 0.01, "orientation": 0.0, "velocity": 0.0},
            "plans": PLANS, "score": {"body": "a", "target": [1.0, 2.0, 3.0]}},
        before={
            "horizon": 1.0, "every": 0.1, "read": ["a"], "read_joints": ["j1"], "slot": "s",
            "set_states": {"names": ["a"], "poses": rows(*POSE)},
            "joint_targets": {"names": ["j1", "j2"], "mode": "position",
                              "targets": rows(0.1, 0.2)},
            "wrenches": {"names": ["a"], "wrenches": rows(*WRENCH), "duration": 0.5},
            "futures": 4, "seed": 7, "first_future": 3,
            "perturb": {"position": 0.01, "velocity": 0.0},
            "plans": PLANS, "score": {"body": "a", "target": [1.0, 2.0, 3.0]}}),
    "predict-bodies": Case(
        lambda c: c.predict(0.5, futures=2, perturb={"bodies": {"a": {"position": 0.1}}}),
        "predict", {"horizon": 0.5, "futures": 2, "first_future": 0, "perturb": {
            **NO_NOISE, "bodies": {"a": {**NO_NOISE, "position": 0.1}}}},
        before={"horizon": 0.5, "futures": 2, "perturb": {"bodies": {"a": {"position": 0.1}}}}),
    "compare": Case(lambda c: c.compare(["a", "b"], POSE), "compare",
                    {"names": ["a", "b"], "poses": tiled(POSE, 2), "correct": False,
                     **SIGMAS},
                    before={"names": ["a", "b"], "poses": tiled(POSE, 2), "correct": False}),
    "compare-all": Case(
        lambda c: c.compare(["a"], [POSE], twists=TWIST, sigma_position=0.01,
                            sigma_angle=0.1, sigma_speed=0.2, correct=True, spread=0.05,
                            trigger=(3, 4)),
        "compare", {"names": ["a"], "poses": rows(*POSE), "twists": rows(*TWIST),
                    "sigma_position": 0.01, "sigma_angle": 0.1, "sigma_speed": 0.2,
                    "correct": True, "spread": 0.05,
                    "trigger": {"threshold": 3.0, "window": 4}}),
    "compare-calibrating": Case(
        lambda c: c.compare(["a"], POSE, trigger=(3.0, 4), calibrate={
            "fit": {"a.friction": (0.1, 1)}, "apply": True}),
        "compare", {"names": ["a"], "poses": rows(*POSE), "correct": False, **SIGMAS,
                    "trigger": {"threshold": 3.0, "window": 4, "calibrate": {
                        "fit": {"a.friction": [0.1, 1.0]}, "apply": True,
                        "max_predictions": 200, "seed": 0}}},
        before={"names": ["a"], "poses": rows(*POSE), "correct": False,
                "trigger": {"threshold": 3.0, "window": 4, "calibrate": {
                    "fit": {"a.friction": [0.1, 1.0]}, "apply": True}}}),
    "compare-spreads": Case(lambda c: c.compare(["a", "b"], POSE, spread=[0.1, 0.2]),
                            "compare", {"names": ["a", "b"], "poses": tiled(POSE, 2),
                                        "correct": False, "spread": rows(0.1, 0.2), **SIGMAS},
                            before={"names": ["a", "b"], "poses": tiled(POSE, 2),
                                    "correct": False, "spread": rows(0.1, 0.2)}),
    "calibrate": Case(
        lambda c: c.calibrate({"a.friction": (0.1, 1)}, ["a"], [0.0, 0.1],
                              [POSE, POSE]),
        "calibrate", {"names": ["a"], "times": rows(0.0, 0.1), "poses": tiled(POSE, 2),
                      "fit": {"a.friction": [0.1, 1.0]}, "apply": False,
                      "max_predictions": 200, "seed": 0},
        before={"names": ["a"], "times": rows(0.0, 0.1), "poses": tiled(POSE, 2),
                "fit": {"a.friction": [0.1, 1.0]}, "apply": False}),
    "calibrate-all": Case(
        lambda c: c.calibrate({"gravity": [5, 15]}, ["a"], [0.0], [POSE], twists=[TWIST],
                              slot="s", apply=True, max_predictions=40, population=8,
                              seed=3),
        "calibrate", {"names": ["a"], "times": rows(0.0), "poses": rows(*POSE),
                      "fit": {"gravity": [5.0, 15.0]}, "twists": rows(*TWIST), "slot": "s",
                      "apply": True, "max_predictions": 40, "population": 8, "seed": 3}),
    "render": Case(lambda c: c.render(CAMERA), "render",
                   {"cameras": [CAMERA], "format": "raw"}),
    "render-png": Case(lambda c: c.render([CAMERA, {"camera": "top"}], format="png"),
                       "render", {"cameras": [CAMERA, {"camera": "top"}], "format": "png"}),
    "add_camera": Case(lambda c: c.add_camera("top", CAMERA), "add_camera",
                       {"name": "top", "camera": CAMERA}),
    "remove_camera": Case(lambda c: c.remove_camera("top"), "remove_camera",
                          {"name": "top"}),
    "cameras": Case(lambda c: c.cameras(), "cameras", {}),
    "raycast": Case(lambda c: c.raycast([0, 0, 1], directions=[0, 0, -1]), "raycast",
                    {"origins": rows(0, 0, 1), "directions": rows(0, 0, -1),
                     "max_length": DEFAULT_MAX_LENGTH},
                    before={"origins": rows(0, 0, 1), "directions": rows(0, 0, -1)}),
    "raycast-ends": Case(lambda c: c.raycast([[0, 0, 1], [1, 0, 1]], ends=[[0, 0, 0],
                                                                           [1, 0, 0]],
                                             max_length=5),
                         "raycast", {"origins": rows(0, 0, 1, 1, 0, 1),
                                     "ends": rows(0, 0, 0, 1, 0, 0), "max_length": 5.0}),
    "contacts": Case(lambda c: c.contacts(), "contacts", {}),
    "contacts-named": Case(lambda c: c.contacts(["a"]), "contacts", {"names": ["a"]}),
    "contacts-one-name": Case(lambda c: c.contacts("a"), "contacts", {"names": ["a"]}),  # type: ignore[arg-type]
    "take_control": Case(lambda c: c.take_control(), "take_control", {}),
    "release_control": Case(lambda c: c.release_control(), "release_control", {}),
}


def sent_by(case: Case, client: Client, caught: Catching) -> tuple[str, dict[str, Any]]:
    caught.sent.clear()
    with pytest.raises(SentError):
        case.call(client)
    assert len(caught.sent) == 1
    return caught.sent[0]


@pytest.mark.parametrize("name", CASES)
def test_each_method_sends_its_wire_map(
        name: str, catching: tuple[Client, Catching]) -> None:
    case = CASES[name]
    op, args = sent_by(case, *catching)
    assert (op, args) == (case.op, case.wire)
    sent = OPERATIONS[op].decode(args)  # the daemon takes it
    if case.before is not None:
        assert OPERATIONS[op].decode(case.before) == sent


def test_a_stream_opens_and_closes_with_its_declared_requests(
        catching: tuple[Client, Catching]) -> None:
    client, caught = catching
    caught.forward = frozenset({"load_world", "spawn", "stream_states", "close_stream"})
    try:
        client.load_world("mujoco")
        client.spawn(GROUP)
        caught.sent.clear()
        with client.stream_states(rate=5, names=["b1"]) as stream:
            assert stream.rate == 5
        client.stream_states().close()
    finally:
        caught.forward = frozenset()
    assert caught.sent == [("stream_states", {"rate": 5, "names": ["b1"]}),
                           ("close_stream", {"stream": stream.stream_id}),
                           ("stream_states", {"rate": 10.0}),
                           ("close_stream", {"stream": caught.sent[3][1]["stream"]})]
    for op, args in caught.sent:
        OPERATIONS[op].decode(args)


def test_every_operation_has_an_sdk_method() -> None:
    streams = {"stream_states", "close_stream"}  # the test above
    assert {case.op for case in CASES.values()} | streams == set(OPERATIONS)


SDK = Path(galton.client.sdk.__file__).parent
RAW_SENDERS = frozenset({"_ok", "call", "request"})  # raw maps: the CLI's call, the fuzzer
TYPED_SENDERS = frozenset({"_send", "_status"})  # the clock's status replies go by _status


def sdk_sends() -> Iterator[tuple[str, ast.Call]]:
    """Every call in the SDK's modules that names an operation by a literal: (module, call)."""
    for module in sorted(SDK.glob("*.py")):
        for node in ast.walk(ast.parse(module.read_text())):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                    and node.args and isinstance(node.args[0], ast.Constant)
                    and isinstance(node.args[0].value, str)):
                yield module.name, node


def test_every_sdk_method_sends_through_the_typed_helper() -> None:
    """No SDK method hands a raw map to the transport: each names its operation to
    ``Client._send`` (or ``_status``, which sends by it), which takes only the operation's
    declared request type (a request built right there is checked here too, by name)."""
    raw, sent = [], set()
    for module, node in sdk_sends():
        assert isinstance(node.func, ast.Attribute) and isinstance(node.args[0], ast.Constant)
        op, how = node.args[0].value, node.func.attr
        if how in RAW_SENDERS:
            raw.append(f"{module}:{node.lineno} {how}({op!r}, ...)")
        if how not in TYPED_SENDERS:
            continue
        sent.add(op)
        built = node.args[1] if len(node.args) > 1 else None
        if isinstance(built, ast.Call):
            name = built.func.attr if isinstance(built.func, ast.Attribute) else getattr(
                built.func, "id", None)
            if name and name[0].isupper():  # a Struct built in place
                assert name == OPERATIONS[op].request.__name__, f"{module}:{node.lineno}"
    assert raw == []
    assert sent == set(OPERATIONS)


def test_a_request_of_another_type_is_refused_before_it_is_sent(
        catching: tuple[Client, Catching]) -> None:
    client, caught = catching
    caught.sent.clear()
    with pytest.raises(TypeError, match="get_states takes a NamesOrAll request, not NamedOnly"):
        client._send("get_states", rq.NamedOnly(names=["a"]))
    with pytest.raises(TypeError, match="pause takes a NoArgs"):
        client._send("pause", rq.Play())
    assert caught.sent == []


# A bad argument, as an SDK call and as the raw map the SDK would have sent for it.
BAD: dict[str, tuple[Callable[[Client], Any], str, dict[str, Any]]] = {
    "step-0": (lambda c: c.step(0), "step", {"count": 0}),
    "negative-rtf": (lambda c: c.play(-1.0), "play", {"rtf": -1.0}),
    "nan-rtf": (lambda c: c.set_rtf(math.nan), "set_rtf", {"rtf": math.nan}),
    "scope": (lambda c: c.reset("everything"), "reset", {"scope": "everything"}),
    "engine": (lambda c: c.load_world("bullet"), "load_world", {"engine": "bullet"}),
    "empty-names": (lambda c: c.delete([]), "delete", {"names": []}),
    "rate": (lambda c: c.stream_states(rate=100), "stream_states", {"rate": 100}),
    "mode": (lambda c: c.set_joint_targets(["j"], "positon"), "set_joint_targets",
             {"names": ["j"], "mode": "positon"}),
    "world-name": (lambda c: c.create_world(""), "create_world", {"name": ""}),
    "image": (lambda c: c.render(CAMERA, format="jpg"), "render",
              {"cameras": [CAMERA], "format": "jpg"}),
    "until-rest": (lambda c: c.run_until_rest(1.0, ["a"], -1.0, 0.1), "run_until",
                   {"sim_time": 1.0, "read": ["a"], "until_rest": {"speed": -1.0,
                                                                   "every": 0.1}}),
    "perturb-field": (lambda c: c.predict(1.0, perturb={"postion": 0.1}), "predict",
                      {"horizon": 1.0, "perturb": {"postion": 0.1}}),
    "perturb-body": (lambda c: c.predict(1.0, perturb={"bodies": {"a": {"velocity": -1}}}),
                     "predict", {"horizon": 1.0, "perturb": {"bodies": {"a": {
                         "velocity": -1}}}}),
    "inner-request": (lambda c: c.predict(1.0, joint_targets={"names": ["j"], "mode": "pos"}),
                      "predict", {"horizon": 1.0, "joint_targets": {"names": ["j"],
                                                                    "mode": "pos"}}),
    "inner-plan": (lambda c: c.predict(1.0, plans=[[{"at": 0, "wrenches": {
        "names": ["a"], "wrenches": WRENCH, "duration": -1}}]]), "predict",
        {"horizon": 1.0, "plans": [[{"at": 0.0, "wrenches": {
            "names": ["a"], "wrenches": rows(*WRENCH), "duration": -1.0}}]]}),
    "trigger-calibrate": (
        lambda c: c.compare(["a"], POSE, trigger=(3.0, 4), calibrate={
            "fit": {"a.friction": (0.1, 1)}, "population": 1}),
        "compare", {"names": ["a"], "poses": rows(*POSE), "trigger": {
            "threshold": 3.0, "window": 4, "calibrate": {"fit": {"a.friction": [0.1, 1.0]},
                                                         "population": 1}}}),
    "numpy-nan": (lambda c: c.set_rtf(np.float64("nan")), "set_rtf", {"rtf": math.nan}),
    "trigger": (lambda c: c.compare(["a"], POSE, trigger=(3.0, 0)), "compare",
                {"names": ["a"], "poses": rows(*POSE), "trigger": {"threshold": 3.0,
                                                                   "window": 0}}),
}


@pytest.mark.parametrize("name", BAD)
def test_a_bad_argument_is_refused_here_as_the_daemon_refuses_it(
        name: str, catching: tuple[Client, Catching], mujoco_sim: Client) -> None:
    """The SDK's refusal says, word for word, what the daemon answers the raw map; and
    nothing was sent."""
    call, op, args = BAD[name]
    client, caught = catching
    caught.sent.clear()
    with pytest.raises(InvalidArgumentError) as here:
        call(client)
    assert caught.sent == []
    with pytest.raises(InvalidArgumentError) as there:
        mujoco_sim.call(op, args)
    assert str(here.value) == str(there.value)


def test_a_number_msgpack_cannot_send_is_refused_naming_its_type(
        catching: tuple[Client, Catching]) -> None:
    client, caught = catching
    caught.sent.clear()
    with pytest.raises(InvalidArgumentError, match=r"step\.count must be int, got np\.int64"):
        client.step(np.int64(3))  # type: ignore[arg-type]
    assert caught.sent == []
