"""The test session's daemons: one real galton-daemon per engine, started on first use,
serving Zenoh on a free loopback port and ZeroMQ on an ipc socket."""

from __future__ import annotations

from galton.client import Client, EmbeddedDaemon, wait_for_daemon

ENGINES = ("mujoco", "pybullet", "ode", "dart")
# What an engine states it does not do (FEATURE_UNSUPPORTED, and left out of its
# capabilities): a conformance test that meets one of these refusals is skipped, saying so;
# any other refusal fails (tests/conformance/conftest.py).
STATED_GAPS: dict[str, tuple[str, ...]] = {
    "ode": ("loads urdf models, not 'mjcf'", "does not support rendering"),
}
START_TIMEOUT_S = 60.0


def start_daemon(daemons: dict[str, EmbeddedDaemon], engine: str) -> EmbeddedDaemon:
    """The session's daemon of ``engine``, started (and waited for) if it is not yet."""
    if engine not in daemons:
        daemon = EmbeddedDaemon(engine, instance=f"test-{engine}", telemetry_rate=20.0,
                                zmq=True)
        daemons[engine] = daemon.start(START_TIMEOUT_S)
        with Client(daemon.instance, daemon.endpoint) as client:
            wait_for_daemon(client.session, daemon.instance, START_TIMEOUT_S)
    return daemons[engine]
