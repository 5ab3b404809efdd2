"""Which daemons a benchmark runs on: remote ones if reachable, else embedded ones; for
``--pool``, every daemon found (or a few embedded ones) with the host each runs on."""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from typing import Any

import zenoh

from galton.client.sdk.client import Client
from galton.client.sdk.embedded import EmbeddedDaemon
from galton.client.transport.credentials import Credentials
from galton.client.transport.discovery import DaemonInfo, discover, wait_for_daemon
from galton.client.transport.session import close_session, open_session
from galton.protocol import DaemonUnreachableError

START_TIMEOUT_S = 60.0
DISCOVERY_TIMEOUT_S = 5.0


@contextmanager
def bench_clients(engines: Sequence[str], connect: str | list[str] | None,
                  instances: Sequence[str] | None, timeout: float,
                  credentials: Credentials | None = None,
                  use_running: bool = False) -> Iterator[dict[str, Client]]:
    """A client per engine. A trial loads its own world, replacing the daemon's, so a daemon
    already running is used only when the caller named it: ``connect`` (with these
    credentials), ``instances``, or ``use_running`` (any daemon on the default endpoint).
    Otherwise embedded daemons are started (one per engine, stopped on exit), whatever runs
    here, and no world the bench did not create is touched."""
    with ExitStack() as stack:
        if not names_running(connect, instances, use_running):
            yield stack.enter_context(_embedded(engines, timeout))
            return
        session = open_session(connect, credentials=credentials)
        stack.callback(session.close)
        names = list(instances) if instances else _matching(session, engines, timeout)
        yield {engine: Client(names[min(i, len(names) - 1)], session=session, timeout=timeout)
               for i, engine in enumerate(engines)}


def names_running(connect: str | list[str] | None, instances: Sequence[str] | None,
                  use_running: bool) -> bool:
    """Whether the command line asked for daemons that already run (their worlds will be
    replaced), rather than daemons of the bench's own."""
    return connect is not None or bool(instances) or use_running


def _matching(session: zenoh.Session, engines: Sequence[str], timeout: float) -> list[str]:
    """Instances to use, in engine order: one running that engine if any, else any."""
    found = discover(session, timeout)
    if not found:
        raise DaemonUnreachableError("a Zenoh peer answered but no galton daemon is there")
    by_engine = {d.engine: d.instance for d in found}
    return [by_engine.get(engine, found[0].instance) for engine in engines]


@contextmanager
def _embedded(engines: Sequence[str], timeout: float) -> Iterator[dict[str, Client]]:
    """One daemon per engine on free loopback ports, meshed, reached through the first."""
    with embedded_mesh({f"bench-{engine}": engine for engine in engines}) as session:
        yield {engine: Client(f"bench-{engine}", session=session, timeout=timeout)
               for engine in engines}


@dataclass
class PoolDaemons:
    """The daemons of a pool: a Client each (one shared session), and their hosts."""

    clients: dict[str, Client]
    hosts: dict[str, dict[str, Any]]


@contextmanager
def pool_clients(connect: str | list[str] | None, instances: Sequence[str] | None,
                 timeout: float, size: int, engine: str,
                 credentials: Credentials | None = None,
                 use_running: bool = False) -> Iterator[PoolDaemons]:
    """Every daemon found at ``connect`` (or the named ``instances``, or with
    ``use_running`` every daemon on the default endpoint), or else ``size`` embedded
    daemons (started with ``engine``: any daemon serves any engine), stopped on exit; as for
    ``bench_clients``, a running daemon's world is replaced only when it was asked for."""
    with ExitStack() as stack:
        if names_running(connect, instances, use_running):
            session = open_session(connect, credentials=credentials)
            stack.callback(close_session, session)
        else:
            session = stack.enter_context(
                embedded_mesh({f"pool-{i + 1}": engine for i in range(size)}))
        found = _pool_members(session, instances, timeout)
        clients = {d.instance: Client(d.instance, session=session, timeout=timeout)
                   for d in found}
        for client in clients.values():
            stack.callback(client.close)
        yield PoolDaemons(clients, {d.instance: d.host for d in found})


def _pool_members(session: zenoh.Session, instances: Sequence[str] | None,
                  timeout: float) -> list[DaemonInfo]:
    """The reachable daemons (the named ones, each of which must be there)."""
    found = [d for d in discover(session, min(timeout, DISCOVERY_TIMEOUT_S)) if d.reachable]
    if instances:
        missing = sorted(set(instances) - {d.instance for d in found})
        if missing:
            raise DaemonUnreachableError(
                f"--instances {', '.join(missing)}: no such daemon answers; found "
                f"{', '.join(d.instance for d in found) or 'none'}")
        found = [d for d in found if d.instance in instances]
    if not found:
        raise DaemonUnreachableError(
            "a Zenoh peer answered but no galton daemon is there to pool (start some with "
            "`galton-daemon --connect ENDPOINT`, or leave out --connect to start them here)")
    return found


@contextmanager
def embedded_mesh(members: Mapping[str, str]) -> Iterator[zenoh.Session]:
    """Daemons (instance name -> engine) on free loopback ports, meshed through the first,
    and a session that sees them all; the session is closed and the daemons stopped on exit."""
    with ExitStack() as stack:
        daemons: list[EmbeddedDaemon] = []
        for name, engine in members.items():
            extra = ["--connect", daemons[0].endpoint] if daemons else []
            daemons.append(stack.enter_context(
                EmbeddedDaemon(engine, instance=name, extra_args=extra)))
        session = open_session(daemons[0].endpoint)
        stack.callback(close_session, session)
        for daemon in daemons:
            wait_for_daemon(session, daemon.instance, START_TIMEOUT_S)
        yield session
