"""``galton-daemon``: serve one physics world over Zenoh until SIGINT/SIGTERM."""

from __future__ import annotations

import hashlib
import json
import logging
import os
import sys
from pathlib import Path
from typing import Annotated, Any

import typer
import zenoh

from galton.daemon.access.users import User, load_users, readable_by_others
from galton.daemon.access.zenoh_security import TlsFiles
from galton.daemon.core.limits import Limits, describe_limits, parse_limits
from galton.daemon.fronts.ros2.options import Ros2Options, ros2_options
from galton.daemon.fronts.zenoh_config import DEFAULT_LISTEN, DEFAULT_TLS_LISTEN
from galton.daemon.server import DaemonOptions, run_daemon
from galton.protocol import GaltonError, InvalidArgumentError, validate_instance_name

MIN_SNAPSHOT_KEY_BYTES = 16

app = typer.Typer(add_completion=False, help=__doc__)


def _parse_params(text: str | None) -> dict[str, Any]:
    if not text:
        return {}
    try:
        params = json.loads(text)
    except json.JSONDecodeError as exc:
        raise typer.BadParameter(f"--params must be a JSON object: {exc}") from exc
    if not isinstance(params, dict):
        raise typer.BadParameter("--params must be a JSON object of name to value")
    return params


def _parse_limits(items: list[str]) -> Limits:
    try:
        return parse_limits(items)
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from exc


def _tls_files(cert: Path | None, key: Path | None, ca: Path | None) -> TlsFiles | None:
    """--tls-cert and --tls-key go together; --tls-ca (mutual TLS) needs them."""
    if cert is None and key is None:
        if ca is not None:
            raise InvalidArgumentError("--tls-ca needs --tls-cert and --tls-key (the daemon's "
                                       "own certificate and key)")
        return None
    if cert is None or key is None:
        raise InvalidArgumentError("--tls-cert and --tls-key go together: give both")
    return TlsFiles(cert, key, ca)


def _users(path: Path | None) -> dict[str, User] | None:
    """The users of --users; a file other accounts can read gets a warning line."""
    if path is None:
        return None
    found = load_users(path)
    if readable_by_others(path):
        typer.echo(f"galton-daemon: warning: other accounts can read {path}; its password "
                   f"hashes are password-equivalent: chmod 600 {path}", err=True)
    return found


ROS2_WITH_USERS = (
    "--ros2 cannot be used with --users: a ROS 2 caller (rmw_zenoh) sends no user name, "
    "password or certificate the daemon could give a role to, so under --users every ROS 2 "
    "request would be refused (the Zenoh ACL admits only its users' keys). Serve ROS 2 from "
    "a daemon without --users on a network you trust, or reach this one through the native "
    "protocol (docs/SECURITY.md, \"The ROS 2 front\")")


def _ros2(on: bool, domain: int, namespace: str, mirrors: list[str],
          users: Path | None = None) -> Ros2Options | None:
    """--ros2's options; its sub-options without --ros2 are refused, not ignored, and so is
    --ros2 with --users (``ROS2_WITH_USERS`` says why)."""
    if on and users is not None:
        raise InvalidArgumentError(ROS2_WITH_USERS)
    if not on:
        if mirrors or namespace or domain:
            raise InvalidArgumentError("--ros-domain-id, --ros-namespace and --ros2-mirror "
                                       "need --ros2")
        return None
    return ros2_options(domain, namespace, mirrors)


@app.command()
def serve(
    engine: Annotated[str, typer.Option(
        help="Physics engine: mujoco, pybullet, ode or dart.")] = "mujoco",
    instance: Annotated[str, typer.Option(help="Instance name, one key chunk.")] = "galton",
    listen: Annotated[list[str] | None, typer.Option(
        help=f"Zenoh endpoint to listen on (repeatable). Default: the --zenoh-config "
             f"file's, else {DEFAULT_LISTEN}.")] = None,
    connect: Annotated[list[str] | None, typer.Option(
        help="Zenoh endpoint of a peer or router to join (repeatable).")] = None,
    zenoh_config: Annotated[Path | None, typer.Option(
        help="A Zenoh JSON5 config file: its mode, endpoints and scouting are honoured; "
             "--listen/--connect/--multicast given here override it.",
        exists=True, dir_okay=False)] = None,
    users: Annotated[Path | None, typer.Option(
        help="A TOML users file (docs/SECURITY.md): turns on Zenoh authentication and "
             "access control by role (operator, viewer), default deny.",
        dir_okay=False)] = None,
    tls_cert: Annotated[Path | None, typer.Option(
        help=f"The daemon's TLS certificate (PEM): serve TLS too, on the tls/ --listen "
             f"endpoint, else {DEFAULT_TLS_LISTEN}.", dir_okay=False)] = None,
    tls_key: Annotated[Path | None, typer.Option(
        help="The private key (PEM) of --tls-cert.", dir_okay=False)] = None,
    tls_ca: Annotated[Path | None, typer.Option(
        help="A CA certificate (PEM): mutual TLS, clients must show a certificate it signed; "
             "with --users, a user's tls_name gives that certificate its role.",
        dir_okay=False)] = None,
    zmq: Annotated[list[str] | None, typer.Option(
        help="Also serve over ZeroMQ at this endpoint (repeatable): ipc:///path, "
             "tcp://HOST:PORT, or a port (loopback). Telemetry and events are published "
             "at ipc:///path.pub or the next port.")] = None,
    zmq_key: Annotated[Path | None, typer.Option(
        help="The daemon's ZeroMQ CURVE key pair (a .key_secret file; `galton-client "
             "zmq-keys DIR` makes one): ZeroMQ encrypted and, with --users, authenticated "
             "by each user's zmq_public_key. Required for --zmq with --users.",
        dir_okay=False)] = None,
    multicast: Annotated[bool, typer.Option(
        help="Enable Zenoh multicast scouting (off by default).")] = False,
    telemetry_rate: Annotated[float, typer.Option(
        help="Telemetry publications per second (0 = none).", min=0.0, max=1000.0)] = 10.0,
    params: Annotated[str | None, typer.Option(
        help='Engine parameters as JSON, e.g. \'{"timestep": 0.001}\'.')] = None,
    limit: Annotated[list[str] | None, typer.Option(
        help=f"A limit as NAME=VALUE (repeatable); defaults: {describe_limits()}.")] = None,
    state_dir: Annotated[Path | None, typer.Option(
        help="Folder where the live world is checkpointed (every --checkpoint-every seconds "
             "and on SIGTERM) and restored from when the daemon starts again.")] = None,
    checkpoint_every: Annotated[float, typer.Option(
        help="Seconds between checkpoints with --state-dir.", min=0.1)] = 10.0,
    ros2: Annotated[bool, typer.Option(
        help="Also serve ROS 2 nodes on rmw_zenoh: simulation_interfaces services, /clock, "
             "/tf (docs/ROS2.md; needs the \\[ros2] extra).")] = False,
    ros_domain_id: Annotated[int, typer.Option(
        help="The ROS_DOMAIN_ID of --ros2's keys.")] = 0,
    ros_namespace: Annotated[str, typer.Option(
        help="The ROS namespace of --ros2's node, e.g. /sim.")] = "",
    ros2_mirror: Annotated[list[str] | None, typer.Option(
        help="MODEL=TOPIC (repeatable): with --ros2, set the loaded model's joints from "
             "each sensor_msgs/JointState on TOPIC, e.g. arm=/joint_states.")] = None,
    snapshot_key: Annotated[Path | None, typer.Option(
        help="A file of secret bytes (16 at least) that seals snapshot blobs: the daemon "
             "then restores only blobs a daemon with the same file sealed.",
        dir_okay=False)] = None,
    log_level: Annotated[str, typer.Option(help="Logging level.")] = "warning",
) -> None:
    """Serve one world on ENGINE as INSTANCE until SIGINT or SIGTERM."""
    logging.basicConfig(level=log_level.upper(), format="%(asctime)s %(name)s %(message)s")
    zenoh.init_log_from_env_or("error")
    try:
        validate_instance_name(instance)
        options = DaemonOptions(
            engine=engine, instance=instance, listen=listen or [],
            connect=connect or [], zenoh_config=zenoh_config, multicast=multicast,
            telemetry_rate_hz=telemetry_rate, params=_parse_params(params),
            limits=_parse_limits(limit or []), state_dir=state_dir,
            checkpoint_period_s=checkpoint_every, zmq=zmq or [],
            users=_users(users), zmq_key=zmq_key,
            tls=_tls_files(tls_cert, tls_key, tls_ca),
            ros2=_ros2(ros2, ros_domain_id, ros_namespace, ros2_mirror or [], users),
            snapshot_key=_snapshot_key(snapshot_key))
        code = run_daemon(options, announce=lambda line: print(line, flush=True))
    except GaltonError as error:
        typer.echo(f"galton-daemon: {error}", err=True)
        raise typer.Exit(2) from error
    except zenoh.ZError as error:
        typer.echo(f"galton-daemon: zenoh could not start: {error}", err=True)
        raise typer.Exit(2) from error
    raise typer.Exit(code)


def _snapshot_key(path: Path | None) -> bytes | None:
    """The --snapshot-key file's bytes, hashed to a BLAKE2b key (any length of 16 up)."""
    if path is None:
        return None
    try:
        secret = path.read_bytes()
    except OSError as error:
        raise InvalidArgumentError(f"--snapshot-key {path}: {error.strerror}") from error
    if len(secret) < MIN_SNAPSHOT_KEY_BYTES:
        raise InvalidArgumentError(f"--snapshot-key {path} holds {len(secret)} bytes; give at "
                                   f"least {MIN_SNAPSHOT_KEY_BYTES} secret ones")
    return hashlib.blake2b(secret, digest_size=32).digest()


HELP_PIPE_WIDTH = 160  # --help into a pipe: wide enough that no cell is cut to "…"


def widen_help_when_piped(args: list[str]) -> None:
    """--help into a pipe or a file at HELP_PIPE_WIDTH columns instead of rich's 80, which
    cut the options' help to "…" (issue 47; COLUMNS or TERMINAL_WIDTH, when set, decide).
    Only for --help: a serving daemon's environment is left as it was."""
    if "--help" not in args or sys.stdout.isatty():
        return
    if not os.environ.get("COLUMNS") and not os.environ.get("TERMINAL_WIDTH"):
        os.environ["TERMINAL_WIDTH"] = str(HELP_PIPE_WIDTH)
        rich_utils = sys.modules.get("typer.rich_utils")
        if rich_utils is not None:
            rich_utils.MAX_WIDTH = HELP_PIPE_WIDTH  # type: ignore[attr-defined]


def main() -> None:
    widen_help_when_piped(sys.argv[1:])
    app()
