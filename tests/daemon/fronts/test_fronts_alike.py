"""Fronts alike: the composition root names no front when it wires the loop or writes the
ready line; each front says its own words, and a new front writes only what it serves
(``Front``'s defaults cover the rest)."""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

import galton.daemon
from galton.client.sdk.embedded import free_loopback_port
from galton.daemon.core.calls import CallPort
from galton.daemon.engines import ENGINE_CLASSES
from galton.daemon.fronts.base import Front, Fronts
from galton.daemon.server import Daemon, DaemonOptions

SERVER = Path(galton.daemon.__file__).parent / "server.py"


class LineFront(Front):
    """The least a front writes: open, publish, close."""

    def __init__(self) -> None:
        self.lines: list[tuple[str, bytes]] = []

    def open(self, core: CallPort) -> None:
        return None

    def publish(self, topic: str, data: bytes) -> None:
        self.lines.append((topic, data))

    def close(self) -> None:
        return None


@pytest.fixture
def daemon() -> Iterator[Daemon]:
    """A real daemon with Zenoh (on a loopback port) and ZeroMQ, built but not serving."""
    options = DaemonOptions(instance="alike", listen=[f"tcp/127.0.0.1:{free_loopback_port()}"],
                            zmq=["tcp://127.0.0.1:*"])
    built = Daemon(options)
    yield built
    built.close()


def test_the_ready_line_is_the_fronts_words_in_order(daemon: Daemon) -> None:
    control = daemon.loop.advertised["zmq"]["control"]
    assert daemon.ready_line() == (
        f"galton-daemon ready: instance=alike engine=mujoco "
        f"listen={daemon.options.listen[0]} zmq={control[0]} "
        f"engines={','.join(ENGINE_CLASSES)}")


def test_the_polled_front_is_found_among_the_fronts(daemon: Daemon) -> None:
    polled = daemon.loop.wiring.polled
    assert polled is not None and polled in daemon.fronts.fronts
    assert daemon.fronts.polled() is polled


def test_a_front_that_writes_only_what_it_serves_gets_the_defaults() -> None:
    fronts = Fronts([LineFront(), LineFront()])
    assert (fronts.ready_words(), fronts.advertised(), fronts.client_alive("c"),
            fronts.polled()) == ("", {}, None, None)
    fronts.withdraw()
    fronts.publish("events", b"x")
    assert [front.lines for front in fronts.fronts] == [[("events", b"x")]] * 2  # type: ignore[attr-defined]


def test_two_polled_fronts_are_refused(daemon: Daemon) -> None:
    with pytest.raises(ValueError, match="at most one"):
        Fronts([*daemon.fronts.fronts, *daemon.fronts.fronts]).polled()


def test_the_composition_root_names_no_front_class_outside_its_factories() -> None:
    """Only a factory (``_zmq_front``, ``_ros2_front``, ``_fronts``) names a front class."""
    tree = ast.parse(SERVER.read_text())
    outside = [node.name for node in tree.body
               if isinstance(node, (ast.FunctionDef, ast.ClassDef))
               and not node.name.endswith("_front") and node.name != "_fronts"
               and any(isinstance(n, ast.Name) and n.id in {"ZenohFront", "ZmqFront",
                                                              "Ros2Front"}
                       for n in ast.walk(node))]
    assert outside == []
