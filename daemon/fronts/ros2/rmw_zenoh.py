"""rmw_zenoh's wire format (ros2/rmw_zenoh, docs/design.md): key expressions, the request
and reply attachment, liveliness tokens and the CDR encapsulation header.

- Key expression of a topic or service: ``<domain>/<fully qualified name without the
  leading slash>/<DDS type name>/<RIHS01 hash>``; a service's type name and hash are the
  service type's (``pkg::srv::dds_::Name_``), never its request's.
- Attachment: int64 LE sequence number, int64 LE source timestamp (ns since the epoch),
  uint8 GID length (16), the 16-byte GID: 33 bytes. A reply echoes the request's sequence
  number and GID with its own timestamp.
- Liveliness token of an entity: ``@ros2_lv/<domain>/<zid>/<node id>/<entity id>/<kind>/
  <enclave>/<namespace>/<node>/<name>/<type>/<hash>/<qos>``, each ``/`` inside a field
  mangled to ``%``, an empty field written ``%``; a node's token stops after its name.
"""

from __future__ import annotations

import os
import struct
import time
from dataclasses import dataclass

from galton.protocol import InvalidArgumentError

ADMIN_SPACE = "@ros2_lv"
GID_LENGTH = 16
ATTACHMENT_LENGTH = 8 + 8 + 1 + GID_LENGTH
CDR_LE_HEADER = b"\x00\x01\x00\x00"
# Entity kinds of a liveliness token.
NODE, PUBLISHER, SUBSCRIPTION, SERVICE_SERVER, SERVICE_CLIENT = "NN", "MP", "MS", "SS", "SC"
# Compact QoS of a token (rmw_zenoh's qos_to_keyexpr): reliability:durability:history,depth:
# deadline:lifespan:liveliness; empty means the default. These are the design document's.
SERVICE_QOS = "::,10:,:,:,,"
TOPIC_QOS = "::,10:,:,:,,"


@dataclass(frozen=True)
class Attachment:
    """The 33 bytes rmw_zenoh attaches to every sample, query and reply."""

    sequence: int
    timestamp_ns: int
    gid: bytes

    def encode(self) -> bytes:
        return (struct.pack("<qqB", self.sequence, self.timestamp_ns, len(self.gid))
                + self.gid)

    @classmethod
    def decode(cls, data: bytes) -> Attachment:
        """Parse an attachment; anything but 33 well-formed bytes is INVALID_ARGUMENT."""
        if len(data) != ATTACHMENT_LENGTH or data[16] != GID_LENGTH:
            raise InvalidArgumentError(
                f"an rmw_zenoh attachment is {ATTACHMENT_LENGTH} bytes (sequence, timestamp, "
                f"GID length 16, GID); got {len(data)} bytes")
        sequence, stamp = struct.unpack_from("<qq", data)
        return cls(sequence, stamp, bytes(data[17:]))

    def reply(self) -> Attachment:
        """The reply's attachment: this sequence number and GID, a fresh timestamp."""
        return Attachment(self.sequence, time.time_ns(), self.gid)


def new_gid() -> bytes:
    """A random 16-byte GID for one publisher (rmw_zenoh hashes its entity's identity)."""
    return os.urandom(GID_LENGTH)


def mangle(name: str) -> str:
    """A name as a single key chunk: ``/`` becomes ``%``; empty becomes ``%``."""
    return name.replace("/", "%") or "%"


def qualified_name(namespace: str, name: str) -> str:
    """``/ns/name`` from a namespace (``""``, ``/`` or ``/ns``) and a relative name; an
    absolute name (``/clock``) ignores the namespace."""
    if name.startswith("/"):
        return name
    return f"{namespace.rstrip('/')}/{name}"


def check_namespace(namespace: str) -> str:
    """A ROS namespace: empty, or ``/`` followed by ``/``-separated tokens of letters,
    digits and ``_`` not starting with a digit; it is normalised without a trailing ``/``."""
    text = namespace.rstrip("/")
    if text and not text.startswith("/"):
        text = "/" + text
    for token in text.split("/")[1:]:
        if not token or not (token[0].isalpha() or token[0] == "_") or not all(
                c.isalnum() or c == "_" for c in token) or not token.isascii():
            raise InvalidArgumentError(
                f"--ros-namespace {namespace!r} is not a ROS namespace: tokens of letters, "
                "digits and '_', not starting with a digit, separated by '/' (e.g. /sim)")
    return text


def key_expr(domain: int, qualified: str, dds_type: str, type_hash: str) -> str:
    """The key of a topic or service: ``0/galton/step_simulation/<type>/<hash>``."""
    return f"{domain}/{qualified.lstrip('/')}/{dds_type}/{type_hash}"


@dataclass(frozen=True)
class NodeIdentity:
    """Who a token says an entity belongs to: the session's zid, the node and its names."""

    domain: int
    zid: str
    node_id: int
    namespace: str
    node: str
    enclave: str = ""

    def node_token(self) -> str:
        return "/".join((ADMIN_SPACE, str(self.domain), self.zid, str(self.node_id),
                          str(self.node_id), NODE, mangle(self.enclave),
                          mangle(self.namespace), self.node))

    def entity_token(self, entity_id: int, kind: str, qualified: str, dds_type: str,
                     type_hash: str, qos: str) -> str:
        return "/".join((ADMIN_SPACE, str(self.domain), self.zid, str(self.node_id),
                         str(entity_id), kind, mangle(self.enclave), mangle(self.namespace),
                         self.node, mangle(qualified), dds_type, type_hash, qos))
