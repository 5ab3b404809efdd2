"""The galton-bridge client: a Python SDK and the ``galton-client`` CLI."""

from galton.client.discovery import DaemonInfo, discover, discover_at, instances, wait_for_daemon
from galton.client.embedded import EmbeddedDaemon
from galton.client.sdk import Client, Stamp, States, body_group, boxes, plane, spheres

__all__ = [
    "Client",
    "DaemonInfo",
    "EmbeddedDaemon",
    "Stamp",
    "States",
    "body_group",
    "boxes",
    "discover",
    "discover_at",
    "instances",
    "plane",
    "spheres",
    "wait_for_daemon",
]
