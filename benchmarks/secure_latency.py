"""What secure mode costs a control call: status and step(1) over Zenoh, open and secured,
measured in one run.

Usage: python benchmarks/secure_latency.py [--engine mujoco] [--calls 2000] [--json FILE]

Three daemons of one engine run at once, each holding a plane and 20 balls: ``open`` (no
option), ``users`` (``--users``: user/password and access control) and ``users+tls``
(``--users`` and mutual TLS on a ``tls/`` endpoint, the client showing a certificate and a
password). Each round calls status and step(1) on each daemon once, in a shuffled order
(latency.py's ``interleaved``), so that noise falls on all alike. Certificates are made
with the ``openssl`` command (tests/support_certs.py).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

from common import machine, percentiles_ms, write_json
from latency import WARM_UP_ROUNDS, interleaved, scene_groups

from galton.client import Client, Credentials, EmbeddedDaemon, wait_for_daemon
from galton.client.embedded import free_loopback_port

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from support_certs import Certificates, make_certificates

PASSWORD = "bench-password"
MODES = ("open", "users", "users+tls")


def users_file(folder: Path) -> Path:
    path = folder / "users.toml"
    path.write_text(f'[users.bench]\nrole = "operator"\npassword = "{PASSWORD}"\n'
                    'tls_name = "alice.robot"\n')
    path.chmod(0o600)
    return path


def daemon_args(mode: str, folder: Path, certs: Certificates) -> tuple[list[str], str | None]:
    """The daemon's extra options for a mode, and its TLS endpoint (or None)."""
    if mode == "open":
        return [], None
    args = ["--users", str(users_file(folder))]
    if mode == "users":
        return args, None
    tls = f"tls/127.0.0.1:{free_loopback_port()}"
    return [*args, "--listen", tls, "--tls-cert", str(certs.daemon.cert), "--tls-key",
            str(certs.daemon.key), "--tls-ca", str(certs.ca)], tls


def credentials(mode: str, certs: Certificates) -> Credentials | None:
    if mode == "open":
        return None
    if mode == "users":
        return Credentials("bench", PASSWORD)
    return Credentials("bench", PASSWORD, tls_ca=certs.ca, tls_cert=certs.alice.cert,
                       tls_key=certs.alice.key)


@contextmanager
def secured_client(engine: str, mode: str, folder: Path,
                   certs: Certificates) -> Iterator[Client]:
    """A daemon started in ``mode`` and an operator client to it, the scene spawned."""
    args, tls = daemon_args(mode, folder, certs)
    instance = f"bench-{mode.replace('+', '-')}"
    with EmbeddedDaemon(engine, instance=instance, extra_args=args) as daemon, \
            Client(instance, tls or daemon.endpoint, timeout=60.0,
                   credentials=credentials(mode, certs)) as client:
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
