"""The status record and the helpers of flat wire records, without numpy: a command line
that asks a daemon for its status (``galton-client status``) imports only this."""

from __future__ import annotations

from dataclasses import MISSING, dataclass, fields
from typing import Any

import msgspec

from galton.protocol.replies import StatusReply, decode_result
from galton.protocol.vocabulary import SimState


def shallow_dict(record: Any) -> dict[str, Any]:
    """A flat record's fields as a dict, without ``asdict``'s deep copy (hot paths)."""
    return {f.name: getattr(record, f.name) for f in fields(record)}


def older_defaults(cls: type) -> dict[str, Any]:
    """The defaults of a record's fields that an older daemon's reply may leave out."""
    found: dict[str, Any] = {}
    for spec in fields(cls):
        if spec.default is not MISSING:
            found[spec.name] = spec.default
        elif spec.default_factory is not MISSING:
            found[spec.name] = spec.default_factory()
    return found


def known_fields(cls: type, body: dict[str, Any]) -> dict[str, Any]:
    """The fields of ``body`` the dataclass knows: a newer daemon's extra fields (a reply
    that grew, as ``status`` grew ``controller``) are left out, not an error."""
    names = {f.name for f in fields(cls)}
    return {key: value for key, value in body.items() if key in names}


@dataclass
class SimStatus:
    """The simulation's clock and state at one instant."""

    state: SimState
    step: int
    sim_time: float
    timestep: float
    target_rtf: float
    rtf: float
    entity_count: int
    engine: str
    instance: str
    world: str = "default"
    faulted: bool = False
    controller: str | None = None  # who holds control (take_control); absent from old daemons
    # Whether a step request (step, run_until, predict, a ROS 2 goal's chunk) is running:
    # another waits for its turn (issue 46); absent from old daemons.
    stepping: bool = False

    def to_wire(self) -> dict[str, Any]:
        return shallow_dict(self)

    @classmethod
    def from_wire(cls, body: dict[str, Any]) -> SimStatus:
        """A status reply, through its declaration (protocol/replies.py)."""
        status = decode_result(StatusReply, {**older_defaults(cls), **body})
        return cls(**{**msgspec.structs.asdict(status), "state": SimState(status.state)})
