"""The galton-bridge wire protocol, shared by the daemon and every client.

It imports nothing else of galton: anyone can implement it with zenoh and msgpack alone,
following ``docs/protocol.md``.

The names below are imported on first use (PEP 562): a command line that needs a few
of them does not load numpy, Zenoh or ZeroMQ for the rest.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from galton.protocol.lazy import lazy_dir, lazy_exports

if TYPE_CHECKING:
    from galton.protocol.arrays import (
        pack_f64,
        unpack_f64,
    )
    from galton.protocol.codes import (
        ResultCode,
    )
    from galton.protocol.envelope import (
        PROTOCOL_VERSION,
        DecodeLimits,
        Reply,
        Request,
        decode_reply,
        decode_request,
        encode_reply,
        encode_request,
        error_reply,
    )
    from galton.protocol.errors import (
        AccessDeniedError,
        ClientClosedError,
        ControlHeldError,
        DaemonUnreachableError,
        FeatureUnsupportedError,
        GaltonError,
        IncorrectStateError,
        InvalidArgumentError,
        MalformedRequestError,
        NameNotUniqueError,
        NotFoundError,
        OperationFailedError,
        PhysicsError,
        RemoteError,
        RequestTimeoutError,
        ResourceLimitError,
        RoleDeniedError,
        UnknownOperationError,
        UnsupportedVersionError,
        error_for_code,
    )
    from galton.protocol.keys import (
        DEFAULT_PORT,
        Keys,
        instance_from_liveliness_key,
        validate_instance_name,
    )
    from galton.protocol.model import (
        BodyGroup,
        BodyProperties,
        Capabilities,
        EntityInfo,
        JointInfo,
        Telemetry,
    )
    from galton.protocol.status import SimStatus
    from galton.protocol.vocabulary import (
        BODY_SHAPES,
        ENGINE_NAMES,
        JOINT_TYPES,
        MODEL_SHAPES,
        POSE_WIDTH,
        RESET_SCOPES,
        SCALAR_JOINT_TYPES,
        SIM_STATES,
        TARGET_MODES,
        TWIST_WIDTH,
        WRENCH_WIDTH,
        SimState,
    )

# Where each public name lives, imported when first asked for.
_SOURCES: dict[str, tuple[str, ...]] = {
    "galton.protocol.arrays": ("pack_f64", "unpack_f64"),
    "galton.protocol.codes": ("ResultCode",),
    "galton.protocol.envelope": (
        "PROTOCOL_VERSION", "DecodeLimits", "Reply", "Request", "decode_reply",
        "decode_request", "encode_reply", "encode_request", "error_reply"),
    "galton.protocol.errors": (
        "AccessDeniedError", "ClientClosedError", "ControlHeldError",
        "DaemonUnreachableError", "FeatureUnsupportedError", "GaltonError",
        "IncorrectStateError", "InvalidArgumentError", "MalformedRequestError",
        "NameNotUniqueError", "NotFoundError", "OperationFailedError", "PhysicsError",
        "RemoteError", "RequestTimeoutError", "ResourceLimitError", "RoleDeniedError",
        "UnknownOperationError", "UnsupportedVersionError", "error_for_code"),
    "galton.protocol.keys": (
        "DEFAULT_PORT", "Keys", "instance_from_liveliness_key", "validate_instance_name"),
    "galton.protocol.model": (
        "BodyGroup", "BodyProperties", "Capabilities", "EntityInfo", "JointInfo",
        "Telemetry"),
    "galton.protocol.status": ("SimStatus",),
    "galton.protocol.vocabulary": (
        "BODY_SHAPES", "ENGINE_NAMES", "JOINT_TYPES", "MODEL_SHAPES", "POSE_WIDTH",
        "RESET_SCOPES", "SCALAR_JOINT_TYPES", "SIM_STATES", "TARGET_MODES", "TWIST_WIDTH",
        "WRENCH_WIDTH", "SimState"),
}
__getattr__ = lazy_exports("galton.protocol", _SOURCES, globals())
__dir__ = lazy_dir(_SOURCES, globals())

__all__ = [
    "BODY_SHAPES",
    "DEFAULT_PORT",
    "ENGINE_NAMES",
    "JOINT_TYPES",
    "MODEL_SHAPES",
    "POSE_WIDTH",
    "PROTOCOL_VERSION",
    "RESET_SCOPES",
    "SCALAR_JOINT_TYPES",
    "SIM_STATES",
    "TARGET_MODES",
    "TWIST_WIDTH",
    "WRENCH_WIDTH",
    "AccessDeniedError",
    "BodyGroup",
    "BodyProperties",
    "Capabilities",
    "ClientClosedError",
    "ControlHeldError",
    "DaemonUnreachableError",
    "DecodeLimits",
    "EntityInfo",
    "FeatureUnsupportedError",
    "GaltonError",
    "IncorrectStateError",
    "InvalidArgumentError",
    "JointInfo",
    "Keys",
    "MalformedRequestError",
    "NameNotUniqueError",
    "NotFoundError",
    "OperationFailedError",
    "PhysicsError",
    "RemoteError",
    "Reply",
    "Request",
    "RequestTimeoutError",
    "ResourceLimitError",
    "ResultCode",
    "RoleDeniedError",
    "SimState",
    "SimStatus",
    "Telemetry",
    "UnknownOperationError",
    "UnsupportedVersionError",
    "decode_reply",
    "decode_request",
    "encode_reply",
    "encode_request",
    "error_for_code",
    "error_reply",
    "instance_from_liveliness_key",
    "pack_f64",
    "unpack_f64",
    "validate_instance_name",
]
