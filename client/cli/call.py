"""galton-client call OP JSON: any request of the protocol, for scripts.

Arguments are JSON; poses and twists (of set_states, or of spawn's groups), joint values,
wrenches and points may be (nested) lists of numbers, packed here as the wire's float64
bins. Bins of the result are unpacked
back into lists of rows. The result prints as JSON; a failure prints its wire code and
exits 1.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Annotated, Any

import typer

from galton.client.cli.common import Target, fail, run_guarded
from galton.protocol import POSE_WIDTH, TWIST_WIDTH, GaltonError
from galton.protocol.operations import OPERATIONS

if TYPE_CHECKING:
    from galton.protocol import Reply

if TYPE_CHECKING:
    pass

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

BIN_WIDTHS = {"poses": POSE_WIDTH, "twists": TWIST_WIDTH}
# Argument kinds sent as float64 bins (a single number of kind "values" stays a number).
PACKED_KINDS = (*BIN_WIDTHS, "values", "wrenches", "points")


def parse_args(text: str) -> dict[str, Any]:
    try:
        args = json.loads(text)
    except json.JSONDecodeError as error:
        raise typer.BadParameter(f"ARGS is not JSON: {error}") from None
    if not isinstance(args, dict):
        raise typer.BadParameter(f"ARGS must be a JSON object, got {type(args).__name__}")
    return args


def packed(value: Any) -> Any:
    """Rows of numbers as a float64 bin; anything else as it is (the daemon judges it)."""
    import numpy as np

    from galton.protocol import pack_f64
    if not isinstance(value, list):
        return value
    try:
        return pack_f64(np.asarray(value, dtype=float))
    except (TypeError, ValueError):
        return value


def pack_args(op: str, args: dict[str, Any]) -> dict[str, Any]:
    """Pack the numeric arrays of an operation's arguments (and of spawn's groups)."""
    declared = OPERATIONS.get(op)
    if declared is None:
        return args
    out = dict(args)
    for arg in declared.args:
        if arg.name not in out:
            continue
        if arg.kind in PACKED_KINDS:
            out[arg.name] = packed(out[arg.name])
        elif arg.kind == "groups" and isinstance(out[arg.name], list):
            out[arg.name] = [pack_group(group) for group in out[arg.name]]
    return out


def pack_group(group: Any) -> Any:
    if not isinstance(group, dict):
        return group
    return {key: packed(value) if key in BIN_WIDTHS else value for key, value in group.items()}


def unpacked(value: Any, key: str = "") -> Any:
    """A result with every bin as numbers: rows for poses and twists, a flat list for another
    bin of float64, hex for one that is not."""
    from galton.protocol import unpack_f64
    if isinstance(value, dict):
        return {k: unpacked(v, str(k)) for k, v in value.items()}
    if isinstance(value, list):
        return [unpacked(v, key) for v in value]
    if isinstance(value, bytes | bytearray):
        width = BIN_WIDTHS.get(key, 1)
        if len(value) % (8 * width):
            return value.hex()
        flat = unpack_f64(value, width).tolist()
        return flat if key in BIN_WIDTHS else [row[0] for row in flat]
    return value


def reply_dict(reply: Reply) -> dict[str, Any]:
    return {"code": int(reply.code), "code_name": reply.code.name, "message": reply.message,
            "result": unpacked(reply.result), "step": reply.step, "sim_time": reply.sim_time,
            "details": unpacked(reply.details)}


@commands.command(rich_help_panel="Scripts")
def call(
    ctx: typer.Context,
    op: Annotated[str, typer.Argument(
        help=f"Operation: {', '.join(OPERATIONS)} (others are sent as they are).",
        show_default=False)],
    args: Annotated[str, typer.Argument(help="Its arguments, a JSON object.")] = "{}",
    whole: Annotated[bool, typer.Option(
        "--reply", help="Print the whole reply (code, message, result, step, sim_time, "
                        "details), also on failure.")] = False,
) -> None:
    """Send one request as JSON and print its result as JSON (exit 1 on a failure code).

    Example: call set_states '{"names": ["ball"], "poses": [[0, 0, 1, 0, 0, 0, 1]]}'
    """
    wire_args = pack_args(op, parse_args(args))
    target: Target = ctx.obj

    def send() -> Reply:  # waits as long as the operation's declaration asks
        with target.client() as client:
            return client.request(op, wire_args)
    reply = run_guarded(send)
    shown = reply_dict(reply) if whole else unpacked(reply.result)
    if whole or reply.ok:
        typer.echo(json.dumps(shown, indent=2, default=str))
    try:
        reply.raise_for_code()
    except GaltonError as error:
        raise fail(error) from error


@commands.command(rich_help_panel="Scripts")
def schema() -> None:
    """Print the JSON Schema of every operation's request and reply (no daemon needed).

    Under "operations", each operation's "request" and "reply" refer to "$defs"; a reply
    not yet declared is {} (any map). Msgpack bins appear as base64 strings."""
    from galton.protocol.operations import json_schema

    typer.echo(json.dumps(json_schema(), indent=2))
