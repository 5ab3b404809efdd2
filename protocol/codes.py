"""Result codes carried by every reply, modelled on ROS 2 simulation_interfaces/Result."""

from enum import IntEnum


class ResultCode(IntEnum):
    """Why a request succeeded or failed; each failure maps to one exception class."""

    OK = 0
    NOT_FOUND = 1
    INCORRECT_STATE = 2
    FEATURE_UNSUPPORTED = 3
    OPERATION_FAILED = 4
    INVALID_ARGUMENT = 5
    NAME_NOT_UNIQUE = 6
    MALFORMED_REQUEST = 7
    UNKNOWN_OPERATION = 8
    UNSUPPORTED_VERSION = 9
    PHYSICS_ERROR = 10
    RESOURCE_LIMIT = 11
    CONTROL_HELD = 12
    ACCESS_DENIED = 13
