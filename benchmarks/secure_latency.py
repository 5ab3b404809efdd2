"""What secure mode costs a control call: status and step(1) over Zenoh and over ZeroMQ,
open and secured, measured in one run.

Usage: python benchmarks/secure_latency.py [--engine mujoco] [--calls 2000] [--json FILE]

Five daemons of one engine run at once, each holding a plane and 20 balls: ``open`` (no
option), ``users`` (``--users``: user/password and access control) and ``users+tls``
(``--users`` and mutual TLS on a ``tls/`` endpoint, the client showing a certificate and a
password), and over ZeroMQ ipc ``zmq`` (no option) and ``zmq+curve`` (``--users`` and
``--zmq-key``: CURVE encryption, the client's key a user's).
Each round calls status and step(1) on each daemon once, in a shuffled order
(latency.py's ``interleaved``), so that noise falls on all alike. Certificates are made
with the ``openssl`` command (tests/support/certs.py).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import zmq.auth
from common import machine, percentiles_ms, write_json
from latency import WARM_UP_ROUNDS, interleaved, scene_groups

from galton.client import Client, Credentials, EmbeddedDaemon, wait_for_daemon
from galton.client.sdk.embedded import free_loopback_port
from galton.client.transport.zmq_keys import ZmqKeys

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from support.certs import Certificates, make_certificates

PASSWORD = "bench-password"
MODES = ("open", "users", "users+tls", "zmq", "zmq+curve")


def users_file(folder: Path) -> Path:
    """The bench user, with a password, a certificate name and a ZeroMQ key."""
    path = folder / "users.toml"
    keys = folder / "zmq"  # beside the TLS files of the same names
    if not keys.exists():
        keys.mkdir()
        for name in ("bench", "daemon"):
            zmq.auth.create_certificates(str(keys), name)
    key = zmq.auth.load_certificate(str(keys / "bench.key"))[0].decode()
    path.write_text(f'[users.bench]\nrole = "operator"\npassword = "{PASSWORD}"\n'
                    f'tls_name = "alice.robot"\nzmq_public_key = "{key}"\n')
    path.chmod(0o600)
    return path


def daemon_args(mode: str, folder: Path, certs: Certificates) -> tuple[list[str], str | None]:
    """The daemon's extra options for a mode, and the endpoint to reach it (None: its
    loopback Zenoh endpoint)."""
    if mode == "open":
        return [], None
    socket = f"ipc://{folder}/{mode.replace('+', '-')}.sock"
    if mode == "zmq":
        return ["--zmq", socket], f"zmq+{socket}"
    args = ["--users", str(users_file(folder))]
    if mode == "zmq+curve":
        return [*args, "--zmq", socket, "--zmq-key", str(folder / "zmq" / "daemon.key_secret")], (
            f"zmq+{socket}")
    if mode == "users":
        return args, None
    tls = f"tls/127.0.0.1:{free_loopback_port()}"
    return [*args, "--listen", tls, "--tls-cert", str(certs.daemon.cert), "--tls-key",
            str(certs.daemon.key), "--tls-ca", str(certs.ca)], tls


def credentials(mode: str, certs: Certificates) -> Credentials | None:
    if mode in ("open", "zmq", "zmq+curve"):
        return None
    if mode == "users":
        return Credentials("bench", PASSWORD)
    return Credentials("bench", PASSWORD, tls_ca=certs.ca, tls_cert=certs.alice.cert,
                       tls_key=certs.alice.key)


@contextmanager
def secured_client(engine: str, mode: str, folder: Path,
                   certs: Certificates) -> Iterator[Client]:
    """A daemon started in ``mode`` and an operator client to it, the scene spawned."""
    args, endpoint = daemon_args(mode, folder, certs)
    instance = f"bench-{mode.replace('+', '-')}"
    keys = (ZmqKeys.load(folder / "zmq" / "bench.key_secret", folder / "zmq" / "daemon.key")
            if mode == "zmq+curve" else None)
    with EmbeddedDaemon(engine, instance=instance, extra_args=args) as daemon, \
            Client(instance, endpoint or daemon.endpoint, timeout=60.0,
                   credentials=credentials(mode, certs), zmq_keys=keys) as client:
        if client.transport.kind == "zenoh":
            wait_for_daemon(client.session, instance, 30)
        client.spawn(*scene_groups())
        client.step(200)
        yield client


def one_step(client: Client) -> Callable[[], object]:
    return lambda: client.step(1)


def measure(engine: str, calls: int) -> dict[str, dict[str, float]]:
    with tempfile.TemporaryDirectory(prefix="galton-secure-bench-") as name, \
            ExitStack() as stack:
        folder = Path(name)
        certs = make_certificates(folder)
        clients = {mode: stack.enter_context(secured_client(engine, mode, folder, certs))
                   for mode in MODES}
        actions: dict[str, Callable[[], object]] = {}
        for mode, client in clients.items():
            actions[f"status {mode}"] = client.status
            actions[f"step(1) {mode}"] = one_step(client)
        interleaved(actions, WARM_UP_ROUNDS)
        samples = interleaved(actions, calls)
    return {name: percentiles_ms(values) for name, values in samples.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco")
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--json")
    args = parser.parse_args()
    result = measure(args.engine, args.calls)
    print(f"# secure-mode latency ({args.engine}) on {machine()}, {args.calls} calls each, "
          f"{time.strftime('%Y-%m-%d')}")
    print("| call | " + " | ".join(f"{mode} p50 / p99" for mode in MODES) + " |")
    print("| --- |" + " --- |" * len(MODES))
    for call in ("status", "step(1)"):
        cells = [f"{result[f'{call} {mode}']['p50']:.3f} / "
                 f"{result[f'{call} {mode}']['p99']:.3f} ms" for mode in MODES]
        print(f"| {call} | " + " | ".join(cells) + " |")
    write_json(args.json, {"engine": args.engine, "calls": args.calls, "results": result})


if __name__ == "__main__":
    main()
