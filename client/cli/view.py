"""galton-client view: the live world in a browser page (the ``[view]`` extra, viser), or a
bench trial's recording replayed in the same page."""

from __future__ import annotations

import importlib.util
import json
import math
import signal
import sys
import threading
import uuid
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from galton.client.cli.common import JsonOpt, Target, run_guarded
from galton.client.cli.streams import until_interrupted

if TYPE_CHECKING:  # numpy, the SDK and viser load when a command runs, not for --help
    from galton.client.sdk.client import Client, StateSample

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

PANEL = "Streams"
RECORDING_SUFFIX = ".npz"  # galton.client.view.recording.SUFFIX
Point = tuple[float, float, float]


def _point(text: str | None, option: str) -> Point | None:
    if text is None:
        return None
    try:
        values = [float(part) for part in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise typer.BadParameter(f"{option} takes three numbers, x,y,z; got {text!r}")
    return values[0], values[1], values[2]


def _require_viser() -> None:
    from galton.protocol import InvalidArgumentError
    if importlib.util.find_spec("viser") is None:
        raise InvalidArgumentError(
            "galton-client view needs the [view] extra: pip install 'galton-bridge[view]'")


@commands.command(rich_help_panel=PANEL)
def view(ctx: typer.Context,
         source: Annotated[Path | None, typer.Argument(
             help="A bench results directory or a recording (.npz) to replay, instead of a "
                  "live daemon.")] = None,
         port: Annotated[int, typer.Option(help="The page's port.", min=1, max=65535)] = 8080,
         host: Annotated[str, typer.Option(
             help="The address the page is served on (0.0.0.0: every interface).")
         ] = "127.0.0.1",
         rate: Annotated[float, typer.Option(
             help="State samples a second, 1-60.", min=1.0, max=60.0)] = 20.0,
         read_only: Annotated[bool, typer.Option(
             "--read-only", help="No operator buttons, whatever this client's role.")
         ] = False,
         camera: Annotated[str | None, typer.Option(
             help="Camera position x,y,z (default: framing the bodies from the front).")
         ] = None,
         look_at: Annotated[str | None, typer.Option(help="Camera target x,y,z.")] = None,
         ) -> None:
    """Serve a live 3-D view of the daemon's world at http://HOST:PORT: every body as its
    shape coloured by tag, side worlds as translucent ghosts, the clock, compare's anomaly
    score, contacts on demand, and play/pause/step/reset for an operator (a viewer's page
    has none). Opening the page never changes the world. With SOURCE, replay a bench
    trial's recording instead."""
    target: Target = ctx.obj
    position, aim = _point(camera, "--camera"), _point(look_at, "--look-at")
    framed = (position, aim) if position is not None and aim is not None else None
    if (position is None) != (aim is None):
        raise typer.BadParameter("--camera and --look-at go together")
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())

    def serve() -> None:
        _require_viser()
        import numpy as np
        import viser

        from galton.protocol.keys import VIEWER_ID_PREFIX
        framed_arrays = (None if framed is None else
                         (np.asarray(framed[0]), np.asarray(framed[1])))
        server = viser.ViserServer(host=host, port=port, verbose=False)
        try:
            if source is not None:
                from galton.client.view.replay import ReplayView
                replay = ReplayView.open(source, server, framed_arrays)
                _ready(host, port)
                replay.run(stop)
                return
            from galton.client.view.live import LiveView, may_operate
            with target.client() as probe:
                operator = not read_only and may_operate(probe)
            # A viewer's id is one a viewer may hold a token for under --users.
            client_id = None if operator else f"{VIEWER_ID_PREFIX}{uuid.uuid4().hex}"
            with target.client(client_id) as client:
                page = LiveView(client, server, rate, operator, framed_arrays)
                _ready(host, port)
                try:
                    page.run(stop)
                finally:
                    page.close()
        finally:
            server.stop()
    run_guarded(serve)


def _ready(host: str, port: int) -> None:
    """The readiness line a script (or a test) waits for."""
    typer.echo(f"galton-client view: serving http://{host}:{port}", err=True)


@commands.command(rich_help_panel=PANEL)
def record(ctx: typer.Context,
           out: Annotated[Path, typer.Argument(help="The recording to write (.npz).")],
           rate: Annotated[float, typer.Option(
               help="State samples a second, 1-60.", min=1.0, max=60.0)] = 60.0,
           seconds: Annotated[float, typer.Option(
               help="Stop after this many seconds of wall time (0: at Ctrl-C).", min=0.0)
           ] = 0.0) -> None:
    """Record the daemon's world (a bench trial as it runs) for ``galton-client view OUT``:
    the entities and their poses at RATE samples a second. Recording reads the world and
    never changes it."""
    target: Target = ctx.obj
    if out.suffix != RECORDING_SUFFIX:
        raise typer.BadParameter(
            f"the recording is a {RECORDING_SUFFIX} file, got {str(out)!r}")
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())

    def go() -> None:
        from galton.client.view.recording import Recorder
        with target.client() as client, Recorder(client, out, rate) as recorder:
            typer.echo(f"galton-client record: recording to {out}", err=True)
            stop.wait(seconds if seconds > 0 else None)
        typer.echo(f"galton-client record: {len(recorder.samples)} samples saved to {out}",
                   err=True)
    run_guarded(go)


@commands.command("stream-states", rich_help_panel=PANEL)
def stream_states(ctx: typer.Context,
                  names: Annotated[list[str] | None, typer.Argument(
                      help="Entities to stream (default: every one).")] = None,
                  rate: Annotated[float, typer.Option(
                      help="Samples a second, 1-60.", min=1.0, max=60.0)] = 10.0,
                  count: Annotated[int, typer.Option(
                      help="Stop after N samples (0 = run until Ctrl-C).", min=0)] = 0,
                  as_json: JsonOpt = False) -> None:
    """Print a state stream's samples: the poses of every entity (or NAMEs) at RATE Hz, one
    line each (JSON: step, sim_time, names, poses as lists). The stream is closed
    (close_stream) when the command ends."""
    def go(client: Client) -> None:
        with client.stream_states(rate, names or None, timeout=max(10.0, 3 / rate)) as stream:
            typer.echo(f"streaming {stream.key} at {stream.rate:g} Hz", err=True)
            for seen, sample in enumerate(stream, start=1):
                _print_sample(sample, as_json)
                if count and seen >= count:
                    return
    until_interrupted(ctx, go)


def _print_sample(sample: StateSample, as_json: bool) -> None:
    if as_json:
        typer.echo(json.dumps({"seq": sample.seq, "world": sample.world, "step": sample.step,
                               "sim_time": sample.sim_time, "state": sample.state,
                               "names": list(sample.names),
                               "poses": sample.poses.tolist()}))
        sys.stdout.flush()
        return
    typer.echo(f"#{sample.seq:<6} {sample.state:<8} t={sample.sim_time:10.3f}s "
               f"step={sample.step:<9} bodies={len(sample.names)}")
