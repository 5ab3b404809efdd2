"""simulation_interfaces services onto the daemon's operations (docs/ROS2.md has the
table). Each handler turns a decoded request into native requests (``yield from ask``) and
returns the response; a Refusal becomes the response's Result."""

from __future__ import annotations

import re
from collections.abc import Generator
from typing import Any

import numpy as np

from galton.daemon.fronts.ros2 import codes
from galton.daemon.fronts.ros2.messages import (
    header,
    new,
    packed,
    pose_msg,
    pose_row,
    rows,
    twist_msg,
    twist_row,
    vector,
)
from galton.daemon.fronts.ros2.native import Handler, NativeRequest, Refusal, ask
from galton.daemon.fronts.ros2.spawning import spawn_one
from galton.protocol import Reply, ResultCode

Gen = Generator[NativeRequest, Reply, Any]
PKG = "simulation_interfaces"


def result(code: int = codes.OK, message: str = "") -> Any:
    return new(f"{PKG}/msg/Result", result=code, error_message=message)


def response(service: str, **fields: Any) -> Any:
    return new(f"{PKG}/srv/{service}_Response", **fields)


def get_simulator_features(request: Any) -> Gen:
    found = yield from ask("capabilities")
    features = new(f"{PKG}/msg/SimulatorFeatures",
                   features=np.asarray(codes.FEATURES, dtype=np.uint16),
                   spawn_formats=[*found.get("model_formats", []), "galton"],
                   custom_info=f"galton-bridge on {found.get('engine', '?')} "
                               f"{found.get('engine_version', '')}: docs/ROS2.md")
    return response("GetSimulatorFeatures", features=features)


def get_simulation_state(request: Any) -> Gen:
    status = yield from ask("status")
    state = new(f"{PKG}/msg/SimulationState", state=codes.STATE_OF[status["state"]])
    return response("GetSimulationState", state=state, result=result())


def set_simulation_state(request: Any) -> Gen:
    target = request.state.state
    op = codes.NATIVE_STATE_OP.get(target)
    if target == codes.QUITTING:
        raise Refusal(codes.FEATURE_UNSUPPORTED, "STATE_QUITTING: this front does not end "
                      "the daemon (send it SIGTERM)")
    if op is None:
        raise Refusal(codes.INCORRECT_TRANSITION, f"state {target} cannot be set: set "
                      "STOPPED (0), PLAYING (1) or PAUSED (2)")
    status = yield from ask("status")
    # PAUSED pauses whatever is stepping, as native pause does: a paused world running a
    # step request (StepSimulation, a goal, a native step) is not yet "already paused".
    stepping = target == codes.PAUSED and status.get("stepping", False)
    if codes.STATE_OF[status["state"]] == target and not stepping:
        raise Refusal(codes.ALREADY_IN_TARGET_STATE, f"already {status['state']}")
    yield from ask(op, code_of=lambda reply: codes.STATE_TRANSITION_ERROR)
    return response("SetSimulationState", result=result())


def reset_simulation(request: Any) -> Gen:
    for scope in _reset_scopes(request.scope):
        yield from ask("reset", {"scope": scope})
    return response("ResetSimulation", result=result())


def _reset_scopes(bits: int) -> list[str]:
    """The native scopes of a ResetSimulation scope bit field, spawned ones first."""
    if bits in (codes.SCOPE_DEFAULT, codes.SCOPE_ALL) or bits & 7 == 7:
        return ["all"]
    if bits & ~7:
        raise Refusal(codes.FEATURE_UNSUPPORTED, f"scope {bits}: this simulator resets "
                      "TIME (1), STATE (2), SPAWNED (4), their sums, or ALL (255)")
    return [name for bit, name in ((codes.SCOPE_SPAWNED, "spawned"),
                                   (codes.SCOPE_STATE, "state"), (codes.SCOPE_TIME, "time"))
            if bits & bit]


def step_simulation(request: Any) -> Gen:
    if request.steps < 1:
        raise Refusal(codes.OPERATION_FAILED, "steps must be at least 1")
    status = yield from ask("status")
    if status.get("stepping", False):  # it would wait its turn: say so now, not after it
        raise Refusal(codes.INCORRECT_STATE, "another step request is running (a "
                      "SimulateSteps goal, StepSimulation or a native step): try again when "
                      "it ends, or pause it with SetSimulationState(PAUSED)")
    yield from ask("step", {"count": int(request.steps)},
                   code_of=lambda reply: codes.OPERATION_FAILED)  # the standard's code
    return response("StepSimulation", result=result())


def spawn_entity(request: Any) -> Gen:
    code, message, name = yield from spawn_one(request)
    return response("SpawnEntity", result=result(code, message), entity_name=name)


def spawn_entities(request: Any) -> Gen:
    results = []
    for each in request.spawn_requests:
        code, message, name = yield from spawn_one(each)
        results.append(new(f"{PKG}/msg/SpawnResult", result=result(code, message),
                           entity_name=name))
    failed = [r for r in results if r.result.result != codes.OK]
    overall = (result() if not failed else result(
        codes.ENTITIES_SPAWN_FAILED, f"{len(failed)} of {len(results)} spawn requests "
        "failed: see results"))
    return response("SpawnEntities", result=overall, results=results)


def delete_entity(request: Any) -> Gen:
    yield from ask("delete", {"names": [request.entity]})
    return response("DeleteEntity", result=result())


def _entities(filters: Any) -> Generator[NativeRequest, Reply, list[dict[str, Any]]]:
    """The entities (native ``list`` maps) an EntityFilters lets through."""
    if len(filters.categories):
        raise Refusal(codes.FEATURE_UNSUPPORTED, "category filters are not supported "
                      "(ENTITY_CATEGORIES is not among the features)")
    if filters.bounds.type != codes.BOUNDS_EMPTY:
        raise Refusal(codes.FEATURE_UNSUPPORTED, "bounds filters are not supported")
    try:
        pattern = re.compile(filters.filter)
    except re.error as exc:
        raise Refusal(codes.OPERATION_FAILED, f"filter {filters.filter!r} is not a "
                      f"regular expression: {exc}") from exc
    found = yield from ask("list")
    wanted = set(filters.tags.tags)
    match_all = filters.tags.filter_mode == codes.FILTER_MODE_ALL
    return [entity for entity in found["entities"]
            if pattern.search(entity["name"]) and _tags_match(entity, wanted, match_all)]


def _tags_match(entity: dict[str, Any], wanted: set[str], match_all: bool) -> bool:
    if not wanted:
        return True
    tags = set(entity.get("tags") or [])
    return wanted <= tags if match_all else bool(wanted & tags)


def get_entities(request: Any) -> Gen:
    entities = yield from _entities(request.filters)
    return response("GetEntities", result=result(),
                    entities=[entity["name"] for entity in entities])


def _states(names: list[str]) -> Generator[NativeRequest, Reply, list[Any]]:
    """EntityState messages of these entities, stamped with the sim time they were read."""
    if not names:
        return []
    reply = yield "get_states", {"names": names}
    if not reply.ok:
        raise Refusal(codes.result_code(reply.code), reply.message)
    found = reply.result
    stamp = header(reply.sim_time)
    poses, twists = rows(found["poses"], 7), rows(found["twists"], 6)
    zero = new("geometry_msgs/msg/Accel")
    return [new(f"{PKG}/msg/EntityState", header=stamp, pose=pose_msg(p), twist=twist_msg(t),
                acceleration=zero) for p, t in zip(poses, twists, strict=True)]


def get_entities_states(request: Any) -> Gen:
    entities = yield from _entities(request.filters)
    names = [entity["name"] for entity in entities]
    states = yield from _states(names)
    return response("GetEntitiesStates", result=result(), entities=names, states=states)


def get_entity_state(request: Any) -> Gen:
    states = yield from _states([request.entity])
    return response("GetEntityState", result=result(), state=states[0])


def set_entity_state(request: Any) -> Gen:
    frame = request.state.header.frame_id
    if frame not in ("", "world"):
        raise Refusal(codes.OPERATION_FAILED, f"frame {frame!r} is unknown: states are "
                      "set in the world frame ('' or 'world')")
    args: dict[str, Any] = {"names": [request.entity]}
    if request.set_pose:
        args["poses"] = packed([pose_row(request.state.pose)])
    if request.set_twist:
        args["twists"] = packed([twist_row(request.state.twist)])
    if len(args) > 1:
        yield from ask("set_states", args, code_of=_invalid_pose)
    return response("SetEntityState", result=result())


def _invalid_pose(reply: Reply) -> int | None:
    is_pose = reply.code == ResultCode.INVALID_ARGUMENT and "quaternion" in reply.message
    return codes.SET_STATE_INVALID_POSE if is_pose else None


def _entity(name: str) -> Generator[NativeRequest, Reply, dict[str, Any]]:
    """The native ``list`` map of one entity, or NOT_FOUND."""
    found = yield from ask("list")
    for entity in found["entities"]:
        if entity["name"] == name:
            return dict(entity)
    raise Refusal(codes.NOT_FOUND, f"no entity named {name!r}")


def get_entity_info(request: Any) -> Gen:
    entity = yield from _entity(request.entity)
    category = (codes.CATEGORY_STATIC_OBJECT if entity.get("static")
                else codes.CATEGORY_ROBOT if entity.get("source") == "model"
                else codes.CATEGORY_OBJECT)
    info = new(f"{PKG}/msg/EntityInfo",
               category=new(f"{PKG}/msg/EntityCategory", category=category),
               description=f"{entity.get('shape')} size {entity.get('size')} mass "
                           f"{entity.get('mass')} kg ({entity.get('source')})",
               tags=list(entity.get("tags") or []))
    return response("GetEntityInfo", result=result(), info=info)


def get_entity_bounds(request: Any) -> Gen:
    entity = yield from _entity(request.entity)
    half = _half_extents(entity)
    bounds = new(f"{PKG}/msg/Bounds", type=codes.BOUNDS_EMPTY)
    if half is not None:
        bounds = new(f"{PKG}/msg/Bounds", type=codes.BOUNDS_BOX,
                     points=[vector(*half), vector(*(-h for h in half))])
    return response("GetEntityBounds", result=result(), bounds=bounds)


def _half_extents(entity: dict[str, Any]) -> tuple[float, float, float] | None:
    """The half extents of a primitive's box in its own frame; None for a plane
    (unbounded); a model or link is FEATURE_UNSUPPORTED (its geometry is the engine's)."""
    shape, size = entity.get("shape"), list(entity.get("size") or [])
    if shape == "sphere":
        return (size[0],) * 3
    if shape == "box":
        return size[0], size[1], size[2]
    if shape in ("cylinder", "capsule"):
        cap = size[0] if shape == "capsule" else 0.0
        return size[0], size[0], size[1] + cap
    if shape == "plane":
        return None
    raise Refusal(codes.FEATURE_UNSUPPORTED, f"bounds of a {shape} entity are not "
                  "computed (only of spawned primitives)")


def get_spawnables(request: Any) -> Gen:
    shapes = (yield from ask("capabilities")).get("body_shapes", [])
    spawnables = [new(f"{PKG}/msg/Spawnable",
                      entity_resource=new(f"{PKG}/msg/Resource", uri=f"galton://{shape}"),
                      description=f"a {shape}: galton://{shape}?size=...&mass=...&static="
                                  "...&tags=... (docs/ROS2.md)")
                  for shape in shapes]
    return response("GetSpawnables", result=result(), spawnables=spawnables)


def get_current_world(request: Any) -> Gen:
    """The live world: its name and engine (it is never unloaded; no file loaded it)."""
    status = yield from ask("status")
    world = new(f"{PKG}/msg/WorldResource", name=status["world"],
                description=f"the live {status['engine']} world of daemon "
                            f"{status['instance']}")
    return response("GetCurrentWorld", result=result(), world=world)


HANDLERS: dict[str, Handler] = {
    "GetSimulatorFeatures": get_simulator_features,
    "GetSimulationState": get_simulation_state,
    "SetSimulationState": set_simulation_state,
    "ResetSimulation": reset_simulation,
    "StepSimulation": step_simulation,
    "SpawnEntity": spawn_entity,
    "SpawnEntities": spawn_entities,
    "DeleteEntity": delete_entity,
    "GetEntities": get_entities,
    "GetEntitiesStates": get_entities_states,
    "GetEntityState": get_entity_state,
    "SetEntityState": set_entity_state,
    "GetEntityInfo": get_entity_info,
    "GetEntityBounds": get_entity_bounds,
    "GetSpawnables": get_spawnables,
    "GetCurrentWorld": get_current_world,
}
