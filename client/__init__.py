"""The galton-bridge client: a Python SDK and the ``galton-client`` CLI.

Everything a program using the SDK catches or reads is importable from here: the
``Client``, the body builders, the value types its methods return and every error class
(all rooted at ``GaltonError``).
"""

from galton.client.discovery import DaemonInfo, discover, discover_at, instances, wait_for_daemon
from galton.client.embedded import EmbeddedDaemon
from galton.client.sdk import Client, body_group, boxes, plane, spheres
from galton.client.sdk_worlds import lockstep
from galton.client.telemetry import Subscription, TelemetryStream
from galton.client.values import (
    Comparison,
    JointStates,
    Prediction,
    SnapshotInfo,
    Stamp,
    States,
    WorldInfo,
)
from galton.protocol import (
    BodyGroup,
    BodyProperties,
    Capabilities,
    ClientClosedError,
    DaemonUnreachableError,
    EntityInfo,
    FeatureUnsupportedError,
    GaltonError,
    IncorrectStateError,
    InvalidArgumentError,
    JointInfo,
    MalformedRequestError,
    NameNotUniqueError,
    NotFoundError,
    OperationFailedError,
    PhysicsError,
    RemoteError,
    Reply,
    RequestTimeoutError,
    ResourceLimitError,
    ResultCode,
    SimState,
    SimStatus,
    Telemetry,
    UnknownOperationError,
    UnsupportedVersionError,
)

__all__ = [
    "BodyGroup",
    "BodyProperties",
    "Capabilities",
    "Client",
    "ClientClosedError",
    "Comparison",
    "DaemonInfo",
    "DaemonUnreachableError",
    "EmbeddedDaemon",
    "EntityInfo",
    "FeatureUnsupportedError",
    "GaltonError",
    "IncorrectStateError",
    "InvalidArgumentError",
    "JointInfo",
    "JointStates",
    "MalformedRequestError",
    "NameNotUniqueError",
    "NotFoundError",
    "OperationFailedError",
    "PhysicsError",
    "Prediction",
    "RemoteError",
    "Reply",
    "RequestTimeoutError",
    "ResourceLimitError",
    "ResultCode",
    "SimState",
    "SimStatus",
    "SnapshotInfo",
    "Stamp",
    "States",
    "Subscription",
    "Telemetry",
    "TelemetryStream",
    "UnknownOperationError",
    "UnsupportedVersionError",
    "WorldInfo",
    "body_group",
    "boxes",
    "discover",
    "discover_at",
    "instances",
    "lockstep",
    "plane",
    "spheres",
    "wait_for_daemon",
]
