"""galton-client: find, watch and drive galton daemons; run the Galton benchmark.

Every operation of the wire protocol has a command; "call OP JSON" sends any request as is.
Lists: several entity names are separate arguments (delete a b c); a list given to one
option is comma-separated in that one value (--pos 0,0,1 or --read a,b). Errors print one
line naming the wire code and exit 1; bad command lines exit 2 before anything is sent.
"""

from __future__ import annotations

import typer

from galton.client.cli import (
    auth,
    bench,
    calibrate,
    call,
    check,
    control,
    entities,
    fuzz,
    joints,
    laws,
    perception,
    report_card,
    router,
    states,
    streams,
    time,
    view,
    world,
    worlds,
    zmq_keys,
)
from galton.client.cli.root import make_app, run

# Every command group, in the order `galton-client --help` lists them: the one place
# where commands join the CLI (each group's module declares its own).
COMMAND_GROUPS: tuple[typer.Typer, ...] = (
    auth.commands,
    bench.commands,
    calibrate.commands,
    call.commands,
    check.commands,
    control.commands,
    fuzz.commands,
    states.commands,
    joints.commands,
    laws.commands,
    perception.commands,
    report_card.commands,
    router.commands,
    entities.commands,
    streams.commands,
    worlds.commands,
    time.commands,
    view.commands,
    world.commands,
    zmq_keys.commands,
)


app = make_app(COMMAND_GROUPS, __doc__ or "")


def main() -> None:
    """The console command (galton.client.cli.root.run: one line per error)."""
    run(app)
