"""What the CLI prints without typer or rich: an error's one line, and the status table as
rich draws it into a pipe. The clock's lean front (``lean.py``) prints with these alone, so
that ``status`` into a pipe or a file imports neither (issue 47); ``common.py`` prints the
same through rich, and tests/client/cli/test_cli_startup.py holds the two to one text."""

from __future__ import annotations

import os
import sys
from dataclasses import asdict
from typing import TYPE_CHECKING

from galton.protocol import (
    AccessDeniedError,
    DaemonUnreachableError,
    GaltonError,
    RemoteError,
    RequestTimeoutError,
)

if TYPE_CHECKING:
    from galton.protocol import SimStatus

# What makes rich draw for a terminal (or at a set width) though stdout is not one: with
# any of these set, the table is left to rich.
TERMINAL_HINTS = ("COLUMNS", "FORCE_COLOR", "TTY_COMPATIBLE")
# Characters rich might read as markup (``[bold]``) or draw wider than one column.
PLAIN_CHARACTERS = frozenset(chr(code) for code in range(0x20, 0x7F)) - {"[", "]", "\\"}


def error_line(error: GaltonError) -> str:
    """What went wrong in one line: the wire code for a daemon's refusal, else which side."""
    if isinstance(error, RemoteError):
        return f"{error.code.name} ({int(error.code)}): {error.message}"
    if isinstance(error, DaemonUnreachableError):
        return f"unreachable (client side): {error}"
    if isinstance(error, RequestTimeoutError):
        return f"timed out (client side): {error}"
    if isinstance(error, AccessDeniedError):
        return f"access denied (client side): {error}"
    return f"{type(error).__name__}: {error}"


def status_title(status: SimStatus) -> str:
    return f"daemon {status.instance}"


def status_rows(status: SimStatus) -> list[tuple[str, str]]:
    """The status table's rows: each field and its value (floats to 4 significant digits)."""
    return [(key, f"{value:.4g}" if isinstance(value, float) else str(value))
            for key, value in asdict(status).items()]


def into_pipe() -> bool:
    """Whether stdout is no terminal and nothing asks rich to draw as for one."""
    return not sys.stdout.isatty() and not any(os.environ.get(h) is not None
                                               for h in TERMINAL_HINTS)


def plain_table(title: str, rows: list[tuple[str, str]]) -> str | None:
    """A title over two columns without a header, as rich draws ``common.ReadableConsole``'s
    tables into a pipe (light box: blank lines above and below, a space at each edge, one of
    padding each side of a cell); None where rich could draw it otherwise (markup, wide or
    control characters, a title wider than the table)."""
    cells = [title, *(cell for row in rows for cell in row)]
    if not rows or not all(set(cell) <= PLAIN_CHARACTERS for cell in cells):
        return None
    key_width = max(len(key) for key, _ in rows)
    value_width = max(len(value) for _, value in rows)
    width = key_width + value_width + 7  # 2 at each edge, 3 between (SIMPLE_HEAD: spaces)
    if len(title) > width or min(key_width, value_width) == 0:
        return None
    left = (width - len(title)) // 2
    lines = [" " * left + title + " " * (width - left - len(title)), " " * width]
    lines += [f"  {key.ljust(key_width)}   {value.ljust(value_width)}  " for key, value in rows]
    lines.append(" " * width)
    return "\n".join(lines) + "\n"
