"""The galton-bridge client: a Python SDK and the ``galton-client`` CLI.

Everything a program using the SDK catches or reads is importable from here: the
``Client``, the body builders, the value types its methods return and every error class
(all rooted at ``GaltonError``).

They are imported on first use (PEP 562), so that ``galton-client --help`` and a
module that needs one name do not load Zenoh, ZeroMQ and numpy for the rest.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from galton.protocol.lazy import lazy_dir, lazy_exports

if TYPE_CHECKING:
    from galton.client.sdk.calibration import (
        CalibrationResult,
        observed_in,
    )
    from galton.client.sdk.client import (
        Client,
        body_group,
        boxes,
        meshes,
        plane,
        spheres,
    )
    from galton.client.sdk.embedded import (
        EmbeddedDaemon,
    )
    from galton.client.sdk.perception import (
        camera,
    )
    from galton.client.sdk.surprise import (
        SurpriseWatch,
    )
    from galton.client.sdk.telemetry import (
        Subscription,
        TelemetryStream,
    )
    from galton.client.sdk.values import (
        Comparison,
        Contacts,
        Image,
        JointStates,
        Prediction,
        RayHits,
        ShapeInfo,
        SnapshotInfo,
        Stamp,
        States,
        WorldInfo,
    )
    from galton.client.sdk.worlds import (
        lockstep,
    )
    from galton.client.transport.credentials import (
        Credentials,
    )
    from galton.client.transport.discovery import (
        DaemonInfo,
        discover,
        discover_at,
        instances,
        wait_for_daemon,
    )
    from galton.client.transport.zmq_keys import (
        ZmqKeys,
    )
    from galton.protocol import (
        AccessDeniedError,
        BodyGroup,
        BodyProperties,
        Capabilities,
        ClientClosedError,
        ControlHeldError,
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
        RoleDeniedError,
        SimState,
        SimStatus,
        Telemetry,
        UnknownOperationError,
        UnsupportedVersionError,
    )

# Where each public name lives, imported when first asked for.
_SOURCES: dict[str, tuple[str, ...]] = {
    "galton.client.transport.credentials": ("Credentials",),
    "galton.client.transport.discovery": (
        "DaemonInfo", "discover", "discover_at", "instances", "wait_for_daemon"),
    "galton.client.sdk.embedded": ("EmbeddedDaemon",),
    "galton.client.sdk.client": ("Client", "body_group", "boxes", "meshes", "plane", "spheres"),
    "galton.client.sdk.perception": ("camera",),
    "galton.client.sdk.worlds": ("lockstep",),
    "galton.client.sdk.telemetry": ("Subscription", "TelemetryStream"),
    "galton.client.sdk.values": (
        "Comparison", "Contacts", "Image", "JointStates", "Prediction", "RayHits",
        "ShapeInfo", "SnapshotInfo", "Stamp", "States", "WorldInfo"),
    "galton.client.transport.zmq_keys": ("ZmqKeys",),
    "galton.client.sdk.calibration": ("CalibrationResult", "observed_in"),
    "galton.client.sdk.surprise": ("SurpriseWatch",),
    "galton.protocol": (
        "AccessDeniedError", "BodyGroup", "BodyProperties", "Capabilities",
        "ClientClosedError", "ControlHeldError", "DaemonUnreachableError", "EntityInfo",
        "FeatureUnsupportedError", "GaltonError", "IncorrectStateError",
        "InvalidArgumentError", "JointInfo", "MalformedRequestError", "NameNotUniqueError",
        "NotFoundError", "OperationFailedError", "PhysicsError", "RemoteError", "Reply",
        "RequestTimeoutError", "ResourceLimitError", "ResultCode", "RoleDeniedError",
        "SimState", "SimStatus", "Telemetry", "UnknownOperationError",
        "UnsupportedVersionError"),
}
__getattr__ = lazy_exports("galton.client", _SOURCES, globals())
__dir__ = lazy_dir(_SOURCES, globals())

__all__ = [
    "AccessDeniedError",
    "BodyGroup",
    "BodyProperties",
    "CalibrationResult",
    "Capabilities",
    "Client",
    "ClientClosedError",
    "Comparison",
    "Contacts",
    "ControlHeldError",
    "Credentials",
    "DaemonInfo",
    "DaemonUnreachableError",
    "EmbeddedDaemon",
    "EntityInfo",
    "FeatureUnsupportedError",
    "GaltonError",
    "Image",
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
    "RayHits",
    "RemoteError",
    "Reply",
    "RequestTimeoutError",
    "ResourceLimitError",
    "ResultCode",
    "RoleDeniedError",
    "ShapeInfo",
    "SimState",
    "SimStatus",
    "SnapshotInfo",
    "Stamp",
    "States",
    "Subscription",
    "SurpriseWatch",
    "Telemetry",
    "TelemetryStream",
    "UnknownOperationError",
    "UnsupportedVersionError",
    "WorldInfo",
    "ZmqKeys",
    "body_group",
    "boxes",
    "camera",
    "discover",
    "discover_at",
    "instances",
    "lockstep",
    "meshes",
    "observed_in",
    "plane",
    "spheres",
    "wait_for_daemon",
]
