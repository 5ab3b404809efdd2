"""The simulation_interfaces 2.1 types, written from the standard's .msg/.srv field lists,
in a rosbags type store beside ROS 2 Kilted's own messages.

Only fields matter on the wire and in the RIHS01 hash (constants and comments do not), so
the definitions below hold fields only; the constants the front uses are in
``daemon/fronts/ros2/codes.py``. A service ``Name`` is four types, as rosidl makes them:
``Name_Request``, ``Name_Response``, ``Name_Event`` (``service_msgs/ServiceEventInfo info``
and the request and response as sequences of at most one) and ``Name`` itself
(``request_message``, ``response_message``, ``event_message``): the hash of ``Name`` is the
one rmw_zenoh puts in a service's key expression, not the request's.
"""

from __future__ import annotations

from functools import cache
from typing import Any

from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

PACKAGE = "simulation_interfaces"
# An empty structure gets this one member in rosidl (and so on the wire: one byte).
EMPTY_MEMBER = "uint8 structure_needs_at_least_one_member"

MESSAGES: dict[str, str] = {
    "Bounds": "uint8 type\ngeometry_msgs/Vector3[] points",
    "EntityCategory": "uint8 category",
    "EntityFilters": "string filter\nEntityCategory[] categories\nTagsFilter tags\n"
                     "Bounds bounds",
    "EntityInfo": "EntityCategory category\nstring description\nstring[] tags",
    "EntityState": "std_msgs/Header header\ngeometry_msgs/Pose pose\n"
                   "geometry_msgs/Twist twist\ngeometry_msgs/Accel acceleration",
    "NamedPose": "string name\nstring description\nstring[] tags\ngeometry_msgs/Pose pose",
    "Resource": "string uri\nstring resource_string",
    "Result": "uint8 result\nstring error_message",
    "SimulationState": "uint8 state",
    "SimulatorFeatures": "uint16[] features\nstring[] spawn_formats\nstring custom_info",
    "SpawnEntity": "string name\nbool allow_renaming\nResource entity_resource\n"
                   "string entity_namespace\ngeometry_msgs/PoseStamped initial_pose",
    "SpawnResult": "Result result\nstring entity_name",
    "Spawnable": "Resource entity_resource\nstring description\nBounds spawn_bounds",
    "TagsFilter": "string[] tags\nuint8 filter_mode",
    "WorldResource": "string name\nResource world_resource\nstring description\n"
                     "string[] tags",
}

# Service name -> (request fields, response fields).
SERVICES: dict[str, tuple[str, str]] = {
    "DeleteEntity": ("string entity", "Result result"),
    "GetAvailableWorlds": ("string[] additional_sources\nTagsFilter filter\n"
                           "bool offline_only\nbool continue_on_error",
                           "Result result\nWorldResource[] worlds"),
    "GetCurrentWorld": ("", "Result result\nWorldResource world"),
    "GetEntities": ("EntityFilters filters", "Result result\nstring[] entities"),
    "GetEntitiesStates": ("EntityFilters filters",
                          "Result result\nstring[] entities\nEntityState[] states"),
    "GetEntityBounds": ("string entity", "Result result\nBounds bounds"),
    "GetEntityInfo": ("string entity", "Result result\nEntityInfo info"),
    "GetEntityState": ("string entity", "Result result\nEntityState state"),
    "GetNamedPoseBounds": ("string name", "Result result\nBounds bounds"),
    "GetNamedPoses": ("TagsFilter tags", "Result result\nNamedPose[] poses"),
    "GetSimulationState": ("", "SimulationState state\nResult result"),
    "GetSimulatorFeatures": ("", "SimulatorFeatures features"),
    "GetSpawnables": ("string[] sources", "Result result\nSpawnable[] spawnables"),
    "LoadWorld": ("Resource world_resource\nbool fail_on_unsupported_element\n"
                  "bool ignore_missing_or_unsupported_assets",
                  "Result result\nWorldResource world"),
    "ResetSimulation": ("uint8 scope", "Result result"),
    "SetEntityInfo": ("string entity\nEntityInfo info", "Result result"),
    "SetEntityState": ("string entity\nEntityState state\nbool set_pose\nbool set_twist\n"
                       "bool set_acceleration", "Result result"),
    "SetSimulationState": ("SimulationState state", "Result result"),
    "SpawnEntities": ("SpawnEntity[] spawn_requests", "Result result\nSpawnResult[] results"),
    "SpawnEntity": ("string name\nbool allow_renaming\nResource entity_resource\n"
                    "string entity_namespace\ngeometry_msgs/PoseStamped initial_pose",
                    "Result result\nstring entity_name"),
    "StepSimulation": ("uint64 steps", "Result result"),
    "UnloadWorld": ("", "Result result"),
}

# The SimulateSteps action, as rosidl makes an action: its goal, result and feedback, the
# SendGoal and GetResult services and the FeedbackMessage (names fully qualified).
ACTION = f"{PACKAGE}/action/SimulateSteps"
ACTION_MESSAGES: dict[str, str] = {
    f"{ACTION}_Goal": "uint64 steps",
    f"{ACTION}_Result": f"{PACKAGE}/Result result",
    f"{ACTION}_Feedback": "uint64 completed_steps\nuint64 remaining_steps",
    f"{ACTION}_FeedbackMessage": f"unique_identifier_msgs/UUID goal_id\n"
                                 f"{ACTION}_Feedback feedback",
}
ACTION_SERVICES: dict[str, tuple[str, str]] = {
    f"{ACTION}_SendGoal": (f"unique_identifier_msgs/UUID goal_id\n{ACTION}_Goal goal",
                           "bool accepted\nbuiltin_interfaces/Time stamp"),
    f"{ACTION}_GetResult": ("unique_identifier_msgs/UUID goal_id",
                            f"int8 status\n{ACTION}_Result result"),
    "action_msgs/srv/CancelGoal": ("action_msgs/GoalInfo goal_info",
                                   "int8 return_code\naction_msgs/GoalInfo[] goals_canceling"),
}
GOAL_STATUS_ARRAY = "action_msgs/msg/GoalStatusArray"

# Standard messages of ROS 2 the front publishes or subscribes to (in rosbags' Kilted store).
CLOCK = "rosgraph_msgs/msg/Clock"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
JOINT_STATE = "sensor_msgs/msg/JointState"
EVENT_INFO = "service_msgs/msg/ServiceEventInfo"


def service_type(name: str) -> str:
    """``simulation_interfaces/srv/<name>``: the ROS type name of a service."""
    return f"{PACKAGE}/srv/{name}"


def dds_type_name(ros_type: str) -> str:
    """The DDS type name rmw_zenoh puts in keys: ``pkg/srv/Name`` -> ``pkg::srv::dds_::Name_``."""
    package, kind, name = ros_type.split("/")
    return f"{package}::{kind}::dds_::{name}_"


def _fields(text: str) -> Any:
    """The rosbags field list of a .msg text, short nested names resolved in our package."""
    return get_types_from_msg(text or EMPTY_MEMBER, f"{PACKAGE}/msg/Parsed")[
        f"{PACKAGE}/msg/Parsed"]


def _service_types(name: str, request: str, response: str) -> dict[str, Any]:
    """The four types rosidl makes of one service (see the module docstring); ``name`` is
    a service of our package, or a full type name (an action's services)."""
    base = name if "/" in name else service_type(name)
    types = {f"{base}_Request": _fields(request), f"{base}_Response": _fields(response)}

    def at_most_one(typ: str) -> Any:
        return (Nodetype.SEQUENCE, ((Nodetype.NAME, typ), 1))

    types[f"{base}_Event"] = ([], [
        ("info", (Nodetype.NAME, EVENT_INFO)),
        ("request", at_most_one(f"{base}_Request")),
        ("response", at_most_one(f"{base}_Response"))])
    types[base] = ([], [
        ("request_message", (Nodetype.NAME, f"{base}_Request")),
        ("response_message", (Nodetype.NAME, f"{base}_Response")),
        ("event_message", (Nodetype.NAME, f"{base}_Event"))])
    return types


@cache
def typestore() -> Typestore:
    """Kilted's standard messages plus every simulation_interfaces message and service."""
    store = get_typestore(Stores.ROS2_KILTED)
    _gid_as_uint8(store)
    types: dict[str, Any] = {}
    for name, text in MESSAGES.items():
        types.update(get_types_from_msg(text, f"{PACKAGE}/msg/{name}"))
    for name, (request, response) in (SERVICES | ACTION_SERVICES).items():
        types.update(_service_types(name, request, response))
    types.update({name: _fields(text) for name, text in ACTION_MESSAGES.items()})
    store.register(types)
    return store


def _gid_as_uint8(store: Typestore) -> None:
    """rosbags keeps ServiceEventInfo's ``char[16] client_gid`` as char (type id 13), but
    rosidl turns a .msg ``char`` into ``uint8`` (3): with char, every service hash differs
    from rosidl's (the design document's AddTwoInts example shows it). Same bytes on the
    wire; only the hash reads it."""
    consts, fields = store.fielddefs[EVENT_INFO]
    store.fielddefs[EVENT_INFO] = (consts, [
        (name, (Nodetype.ARRAY, ((Nodetype.BASE, ("uint8", 0)), 16)))
        if name == "client_gid" else (name, desc) for name, desc in fields])


def type_hash(ros_type: str) -> str:
    """The RIHS01 hash of a message or service type, as rosidl computes it."""
    return typestore().hash_rihs01(ros_type)
