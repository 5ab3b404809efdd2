"""Which daemons a benchmark runs on: remote ones if reachable, else embedded ones."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import ExitStack, contextmanager

from galton.client.discovery import discover, wait_for_daemon
from galton.client.embedded import EmbeddedDaemon
from galton.client.sdk import Client
from galton.client.session import open_session
from galton.protocol import DaemonUnreachableError

START_TIMEOUT_S = 60.0


@contextmanager
def bench_clients(engines: Sequence[str], connect: str | list[str] | None,
                  instances: Sequence[str] | None, timeout: float) -> Iterator[dict[str, Client]]:
    """A client per engine: named instances, daemons found at ``connect``, or, when no
    endpoint was given and none answers on the default one, embedded daemons (one per
    engine, stopped on exit). Any daemon can serve any engine: a trial loads its world."""
    with ExitStack() as stack:
        try:
            session = open_session(connect)
        except DaemonUnreachableError:
            if connect is not None:
                raise
            yield stack.enter_context(_embedded(engines, timeout))
            return
        stack.callback(session.close)
        names = list(instances) if instances else _matching(session, engines, timeout)
        yield {engine: Client(names[min(i, len(names) - 1)], session=session, timeout=timeout)
               for i, engine in enumerate(engines)}


def _matching(session: object, engines: Sequence[str], timeout: float) -> list[str]:
    """Instances to use, in engine order: one running that engine if any, else any."""
    found = discover(session, timeout)  # type: ignore[arg-type]
    if not found:
        raise DaemonUnreachableError("a Zenoh peer answered but no galton daemon is there")
    by_engine = {d.engine: d.instance for d in found}
    return [by_engine.get(engine, found[0].instance) for engine in engines]


@contextmanager
def _embedded(engines: Sequence[str], timeout: float) -> Iterator[dict[str, Client]]:
    """One daemon per engine on free loopback ports, meshed, reached through the first."""
    with ExitStack() as stack:
        daemons: list[EmbeddedDaemon] = []
        for engine in engines:
            extra = ["--connect", daemons[0].endpoint] if daemons else []
            daemon = EmbeddedDaemon(engine, instance=f"bench-{engine}", extra_args=extra)
            daemons.append(stack.enter_context(daemon))
        session = open_session(daemons[0].endpoint)
        stack.callback(session.close)
        for daemon in daemons:
            wait_for_daemon(session, daemon.instance, START_TIMEOUT_S)
        yield {d.engine: Client(d.instance, session=session, timeout=timeout) for d in daemons}
