"""The clock's commands (``status``, ``play``, ``pause`` ...) without typer, rich or the
protocol's operation table (issue 47: ``status`` took 5 x ``--version``, most of it typer,
rich and pydantic). It reads only a command line it understands whole: the global options
and a clock command with its own options, each value as typer would read it. Anything else
(``--help``, an option it does not know, a value typer would refuse, credentials that do
not load) it leaves to typer's CLI, which answers as it always has; so help, usage and its
errors have one source. tests/client/cli/test_cli_startup.py holds what it reads to what
typer reads from the same line."""

from __future__ import annotations

import json
import math
import os
import sys
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from galton.client.cli.plain import error_line, into_pipe, plain_table, status_rows, status_title
from galton.protocol import RESET_SCOPES, GaltonError
from galton.protocol.vocabulary import MAX_RTF

if TYPE_CHECKING:
    from galton.client.transport.credentials import Credentials
    from galton.client.transport.zmq_keys import ZmqKeys
    from galton.protocol import SimStatus

# Each lean command's word and the operation it sends (what client/cli/time.py and
# world.py register under the same names).
OPERATION_OF = {"status": "status", "play": "play", "set-rtf": "set_rtf", "pause": "pause",
                "stop": "stop", "reset": "reset"}
# root.py's global options that take a value, by the field of LeanLine they fill.
VALUE_OPTIONS = {"--connect": "connect", "--instance": "instance", "--timeout": "timeout",
                 "--user": "user", "--password-file": "password_file", "--tls-ca": "tls_ca",
                 "--tls-cert": "tls_cert", "--tls-key": "tls_key", "--zmq-key": "zmq_key",
                 "--zmq-server-key": "zmq_server_key"}
# Those of them that name a file (typer refuses a directory there).
FILE_OPTIONS = frozenset({"password_file", "tls_ca", "tls_cert", "tls_key", "zmq_key"})


class NotLeanError(Exception):
    """A command line the lean front leaves to typer's CLI."""


@dataclass
class LeanLine:
    """A clock command line read whole: the global options, the operation and its
    arguments."""

    op: str
    args: dict[str, Any]
    as_json: bool = False
    connect: list[str] | None = None
    instance: str = "galton"
    timeout: float = 5.0
    files: dict[str, Path] = field(default_factory=dict)
    user: str | None = None
    zmq_server_key: str | None = None


def parse(argv: Sequence[str]) -> LeanLine | None:
    """The clock command ``argv`` names, as typer would read it; None: leave it to typer."""
    try:
        return _parse(list(argv))
    except NotLeanError:
        return None


def _parse(words: list[str]) -> LeanLine:
    options: dict[str, str | list[str]] = {}
    while words and words[0].startswith("-"):
        name, value = _option(words)
        field_name = VALUE_OPTIONS.get(name)
        if field_name is None:
            raise NotLeanError(name)  # --help, --version, a typo: typer's to answer
        if field_name == "connect":
            connects = options.setdefault("connect", [])
            assert isinstance(connects, list)
            connects.append(value)
        elif field_name in options:
            raise NotLeanError(name)  # given twice
        else:
            options[field_name] = value
    if not words or words[0] not in OPERATION_OF:
        raise NotLeanError("no clock command")
    command, rest = words[0], words[1:]
    line = _global_options(options, OPERATION_OF[command])
    line.as_json, line.args = _command_options(command, rest)
    return line


def _option(words: list[str]) -> tuple[str, str]:
    """Take ``--name value`` or ``--name=value`` off the front of ``words``."""
    word = words.pop(0)
    name, equals, value = word.partition("=")
    if name not in VALUE_OPTIONS:
        raise NotLeanError(name)
    if not equals:
        if not words or words[0].startswith("-"):
            raise NotLeanError(name)  # no value, or one typer might read otherwise
        value = words.pop(0)
    return name, value


def _global_options(options: dict[str, str | list[str]], op: str) -> LeanLine:
    line = LeanLine(op, {})
    for name, value in options.items():
        if name == "connect":
            line.connect = list(value)
        elif name == "timeout":
            line.timeout = _seconds(str(value))
        elif name in FILE_OPTIONS:
            if not value or Path(str(value)).is_dir():
                raise NotLeanError(name)
            line.files[name] = Path(str(value))
        else:
            setattr(line, name, str(value))
    return line


def _seconds(text: str) -> float:
    try:
        seconds = float(text)
    except ValueError:
        raise NotLeanError(text) from None
    if not math.isfinite(seconds) or seconds <= 0:
        raise NotLeanError(text)
    return seconds


def _rtf(text: str) -> float:
    try:
        rtf = float(text)
    except ValueError:
        raise NotLeanError(text) from None
    if not math.isfinite(rtf) or not 0 <= rtf <= MAX_RTF:
        raise NotLeanError(text)
    return rtf


def _command_options(command: str, words: list[str]) -> tuple[bool, dict[str, Any]]:
    """--json and the command's own options and argument, each at most once."""
    as_json, positional = False, False
    args: dict[str, Any] = {}
    while words:
        word = words.pop(0)
        if word == "--json" and not as_json:
            as_json = True
        elif command == "play" and word.partition("=")[0] == "--rtf" and "rtf" not in args:
            args["rtf"] = _rtf(_value(word, words))
        elif command == "reset" and word.partition("=")[0] == "--scope" and "scope" not in args:
            scope = _value(word, words)
            if scope not in RESET_SCOPES:
                raise NotLeanError(scope)
            args["scope"] = scope
        elif command == "set-rtf" and not word.startswith("-") and not positional:
            positional = True
            args["rtf"] = _rtf(word)
        else:
            raise NotLeanError(word)
    if command == "set-rtf" and not positional:
        raise NotLeanError("set-rtf needs RTF")
    if command == "reset":
        args.setdefault("scope", "all")
    return as_json, args


def _value(word: str, words: list[str]) -> str:
    """An option's value: after its ``=``, else the next word."""
    _, equals, value = word.partition("=")
    if equals:
        return value
    if not words or words[0].startswith("-"):
        raise NotLeanError(word)
    return words.pop(0)


def credentials_of(line: LeanLine) -> tuple[Credentials | None, ZmqKeys | None]:
    """The credentials and CURVE keys the line's options and the environment give, as
    root.py's main_options resolves them; NotLeanError where typer would refuse them."""
    from galton.client.transport.credentials import resolve_credentials

    files = line.files
    try:
        credentials = resolve_credentials(line.user, files.get("password_file"),
                                          files.get("tls_ca"), files.get("tls_cert"),
                                          files.get("tls_key"), os.environ)
    except GaltonError as error:
        raise NotLeanError(str(error)) from error
    key, server_key = files.get("zmq_key"), line.zmq_server_key
    if key is None and server_key is None:
        return credentials, None
    if key is None or server_key is None:
        raise NotLeanError("--zmq-key and --zmq-server-key go together")
    from galton.client.transport.zmq_keys import ZmqKeys
    try:
        return credentials, ZmqKeys.load(key, server_key)
    except GaltonError as error:
        raise NotLeanError(str(error)) from error


def ask(connect: list[str] | None, instance: str, timeout_s: float,
        credentials: Credentials | None, zmq_keys: ZmqKeys | None, op: str,
        args: dict[str, Any] | None = None) -> dict[str, Any]:
    """One request and its result map, through the transport alone (neither the SDK's
    Client nor numpy; pyzmq only for a zmq+ endpoint). A refusal raises its typed error."""
    import uuid

    from galton.client.transport.base import transport_for, zmq_endpoint
    from galton.protocol import Keys

    over_zmq = zmq_endpoint(connect) is not None
    client_id = uuid.uuid4().hex  # as the SDK's: a request names its client
    transport = transport_for(Keys(instance), client_id, connect,
                              credentials=None if over_zmq else credentials,
                              zmq_keys=zmq_keys if over_zmq else None)
    try:
        reply = transport.request(op, args, timeout_s, client_id)
    finally:
        transport.close()
    reply.raise_for_code()
    return dict(reply.result)


def run(argv: Sequence[str]) -> int | None:
    """Run a clock command line; its exit code, or None where it is typer's to run."""
    line = parse(argv)
    if line is None:
        return None
    try:
        credentials, zmq_keys = credentials_of(line)
    except NotLeanError:
        return None
    from galton.protocol.status import SimStatus
    try:
        # every clock operation waits the --timeout (their client_timeout; a test holds it)
        status = SimStatus.from_wire(ask(line.connect, line.instance, line.timeout,
                                         credentials, zmq_keys, line.op, line.args))
    except GaltonError as error:
        print(f"galton-client: {error_line(error)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:  # as root.run says it (click's Abort)
        print("\ngalton-client: aborted", file=sys.stderr)
        return 1
    show(status, line.as_json)
    return 0


def show(status: SimStatus, as_json: bool) -> None:
    """The status as JSON, or as its table: plain text into a pipe, else rich's."""
    if as_json:
        print(json.dumps(asdict(status), indent=2, default=str))
        return
    table = plain_table(status_title(status), status_rows(status)) if into_pipe() else None
    if table is None:
        from galton.client.cli.tables import console, status_table
        console.print(status_table(status))
    else:
        sys.stdout.write(table)
