"""The CLI's console and its tables: rich alone (no typer), so that the clock's lean front
can draw the status table in a terminal without building a typer CLI (issue 47)."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

from rich import box
from rich.console import Console, ConsoleDimensions
from rich.table import Table

from galton.client.cli.plain import status_rows, status_title

if TYPE_CHECKING:
    from galton.protocol import SimStatus


class ReadableConsole(Console):
    """A console whose tables keep every character: in a terminal, the first column (the
    names a user types back: joints, links, parameters) as wide as its longest cell (up to
    KEY_WIDTH), the others folded onto more lines instead of cut to "…", light borders;
    into a pipe or a file (no terminal, no COLUMNS), as wide as they are: nothing folded,
    nothing cut (rich would otherwise assume 80 columns)."""

    @property
    def size(self) -> ConsoleDimensions:
        measured = Console.size.fget(self)  # type: ignore[attr-defined]
        if self._width is None and unlimited_width(self.is_terminal):  # no width was set
            return ConsoleDimensions(PIPE_WIDTH, measured.height)
        return measured  # type: ignore[no-any-return]

    @size.setter
    def size(self, new_size: tuple[int, int]) -> None:
        Console.size.fset(self, new_size)  # type: ignore[attr-defined]

    def print(self, *objects: Any, **kwargs: Any) -> None:
        for item in objects:
            if isinstance(item, Table):
                readable(item)
        super().print(*objects, **kwargs)


KEY_WIDTH = 40
PIPE_WIDTH = 10_000  # "unlimited": a table or line is as wide as its text


def unlimited_width(is_terminal: bool) -> bool:
    """Whether output goes where nobody reads it at a terminal's width (a pipe, a file)
    and no width was asked for (COLUMNS)."""
    return not is_terminal and not os.environ.get("COLUMNS")


def readable(table: Table) -> None:
    table.box = box.SIMPLE_HEAD
    for index, column in enumerate(table.columns):
        column.overflow = "fold"
        if index == 0:
            cells = [len(str(cell)) for cell in column.cells]
            column.min_width = min(KEY_WIDTH, max([len(str(column.header)), *cells]))


console = ReadableConsole()


def status_table(status: SimStatus) -> Table:
    """The status as a table of its fields (plain.plain_table draws the same into a pipe)."""
    table = Table(title=status_title(status), show_header=False)
    for key, value in status_rows(status):
        table.add_row(key, value)
    return table
