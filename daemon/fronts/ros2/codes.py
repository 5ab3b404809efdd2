"""The simulation_interfaces constants the front uses (msg/Result, SimulationState,
SimulatorFeatures, ResetSimulation, Bounds, EntityCategory and the per-service codes)."""

from __future__ import annotations

from galton.protocol import ResultCode

# msg/Result
FEATURE_UNSUPPORTED, OK, NOT_FOUND, INCORRECT_STATE, OPERATION_FAILED = 0, 1, 2, 3, 4
# msg/SimulationState
STOPPED, PLAYING, PAUSED, QUITTING, NO_WORLD, LOADING_WORLD = 0, 1, 2, 3, 4, 5
STATE_OF = {"stopped": STOPPED, "playing": PLAYING, "paused": PAUSED}
NATIVE_STATE_OP = {STOPPED: "stop", PLAYING: "play", PAUSED: "pause"}
# srv/SetSimulationState
ALREADY_IN_TARGET_STATE, STATE_TRANSITION_ERROR, INCORRECT_TRANSITION = 101, 102, 103
# srv/SpawnEntity and msg/SpawnResult
NAME_NOT_UNIQUE, NAME_INVALID, UNSUPPORTED_FORMAT, NO_RESOURCE = 101, 102, 103, 104
RESOURCE_PARSE_ERROR, MISSING_ASSETS, SPAWN_INVALID_POSE = 106, 107, 109
ENTITIES_SPAWN_FAILED = 150  # srv/SpawnEntities
SET_STATE_INVALID_POSE = 101  # srv/SetEntityState
# srv/ResetSimulation scope bits
SCOPE_DEFAULT, SCOPE_TIME, SCOPE_STATE, SCOPE_SPAWNED, SCOPE_ALL = 0, 1, 2, 4, 255
# msg/Bounds
BOUNDS_EMPTY, BOUNDS_BOX = 0, 1
# msg/EntityCategory
CATEGORY_OBJECT, CATEGORY_ROBOT, CATEGORY_STATIC_OBJECT = 0, 1, 5
# msg/TagsFilter
FILTER_MODE_ANY, FILTER_MODE_ALL = 0, 1

# msg/SimulatorFeatures: what this front serves.
FEATURES = (
    0,  # SPAWNING
    1,  # DELETING
    4,  # ENTITY_TAGS
    5,  # ENTITY_BOUNDS
    9,  # SPAWNING_RESOURCE_STRING
    10,  # ENTITY_STATE_GETTING
    11,  # ENTITY_STATE_SETTING
    12,  # ENTITY_INFO_GETTING
    14,  # SPAWNABLES
    20, 21, 22, 23,  # SIMULATION_RESET and its TIME, STATE and SPAWNED scopes
    24, 25, 26,  # SIMULATION_STATE_GETTING, _SETTING, _PAUSE
    31, 32, 33,  # STEP_SIMULATION_SINGLE, _MULTIPLE, _ACTION (SimulateSteps)
    44,  # WORLD_INFO_GETTING (GetCurrentWorld)
    50,  # SPAWNING_ENTITIES
)

# The daemon's result codes as msg/Result codes: the standard has no INVALID_ARGUMENT, so
# a refused argument is OPERATION_FAILED with the daemon's message.
RESULT_OF_CODE = {
    ResultCode.OK: OK,
    ResultCode.NOT_FOUND: NOT_FOUND,
    ResultCode.INCORRECT_STATE: INCORRECT_STATE,
    ResultCode.FEATURE_UNSUPPORTED: FEATURE_UNSUPPORTED,
}


def result_code(code: int) -> int:
    """The msg/Result code for one of the daemon's result codes."""
    return RESULT_OF_CODE.get(ResultCode(code), OPERATION_FAILED)
