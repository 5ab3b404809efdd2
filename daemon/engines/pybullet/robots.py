"""The PyBullet engine's records of loaded models' links, joints, targets and held wrenches,
all by name, so that they outlive a rebuild (which gives every body a new PyBullet id).

``uid_of`` turns a root's (or a spawned body's) entity name into its PyBullet id now.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterable, Sequence

import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet.frames import centres
from galton.daemon.engines.pybullet.joints import Articulation
from galton.protocol import JointInfo, NotFoundError
from galton.protocol.errors import did_you_mean

UidOf = Callable[[str], int]
Wrench = tuple[list[float], list[float]]  # force at the centre of mass, torque; world frame
JointStates = dict[str, tuple[np.ndarray, np.ndarray]]  # root -> positions, velocities


class Robots:
    """Every loaded model's articulation, the links' places, the held wrenches."""

    def __init__(self) -> None:
        self.models: dict[str, Articulation] = {}  # by root entity name, in load order
        self.links: dict[str, tuple[str, int]] = {}  # link entity -> root, PyBullet link
        self._joints: dict[str, tuple[str, int]] = {}  # 1-DOF joint -> root, place
        self.wrenches: dict[str, Wrench] = {}  # by entity name: spawned, root or link

    # -- records ------------------------------------------------------------------------
    def check_entities(self, bodies: Collection[str], names: Iterable[str]) -> None:
        """NotFoundError for a name that is neither a body's (spawned or root) nor a link's."""
        for name in names:
            if name not in bodies and name not in self.links:
                known = sorted([*bodies, *self.links])
                raise NotFoundError(f"no entity named {name!r} in the PyBullet world"
                                    f"{did_you_mean(name, known)}")

    def add(self, model: Articulation) -> None:
        self.models[model.root] = model
        self.links.update((name, (model.root, j)) for j, name in enumerate(model.links)
                          if name is not None)
        self._joints.update((name, (model.root, place)) for name, place in model.scalar.items())

    def joint_names(self) -> set[str]:
        return {info.name for model in self.models.values() for info in model.infos}

    def forget(self, names: Iterable[str]) -> None:
        """Entities gone: a root takes its links, joints, targets and wrenches with it."""
        for name in names:
            self.wrenches.pop(name, None)
            model = self.models.pop(name, None)
            if model is None:
                continue
            for link in filter(None, model.links):
                self.links.pop(link, None)
                self.wrenches.pop(link, None)
            for joint in model.scalar:
                self._joints.pop(joint, None)

    def clear(self) -> None:
        self.models.clear()
        self.links.clear()
        self._joints.clear()
        self.wrenches.clear()

    def joints(self) -> list[JointInfo]:
        return [info for model in self.models.values() for info in model.infos]

    def _grouped(self, names: Sequence[str]) -> dict[str, tuple[list[int], list[int]]]:
        """Root -> (places in its arrays, places in ``names``) of these 1-DOF joints."""
        groups: dict[str, tuple[list[int], list[int]]] = {}
        for k, name in enumerate(names):
            ref = self._joints.get(name)
            if ref is None:
                raise NotFoundError(f"no 1-DOF joint named {name!r} in the PyBullet world"
                                    f"{did_you_mean(name, list(self._joints))}")
            places, order = groups.setdefault(ref[0], ([], []))
            places.append(ref[1])
            order.append(k)
        return groups

    # -- joint states -----------------------------------------------------------------
    def read(self, bc: BulletClient, uid_of: UidOf, names: Sequence[str]
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities and last applied efforts of these 1-DOF joints: one
        getJointStates per model."""
        n = len(names)
        out = np.zeros(n), np.zeros(n), np.zeros(n)
        for root, (places, order) in self._grouped(names).items():
            model = self.models[root]
            states = bc.getJointStates(uid_of(root), [model.indices[p] for p in places])
            out[0][order] = [s[0] for s in states]
            out[1][order] = [s[1] for s in states]
            out[2][order] = model.effort[places]
        return out

    def write(self, bc: BulletClient, uid_of: UidOf, names: Sequence[str],
              positions: np.ndarray, velocities: np.ndarray | None) -> None:
        """Teleport these joints (velocities None: each keeps its own)."""
        if velocities is None:
            velocities = self.read(bc, uid_of, names)[1]
        for root, (places, order) in self._grouped(names).items():
            model, uid = self.models[root], uid_of(root)
            for place, k in zip(places, order, strict=True):
                bc.resetJointState(uid, model.indices[place], float(positions[k]),
                                   float(velocities[k]))

    def hold(self, names: Sequence[str], mode: str, targets: np.ndarray, kp: np.ndarray,
             kd: np.ndarray, max_effort: np.ndarray) -> None:
        for root, (places, order) in self._grouped(names).items():
            self.models[root].hold(places, mode, targets[order], kp[order], kd[order],
                                   max_effort[order])

    def snapshot(self, bc: BulletClient, uid_of: UidOf) -> JointStates:
        """Every model's 1-DOF joint states, to carry across a rebuild."""
        out: JointStates = {}
        for root, model in self.models.items():
            if model.indices:
                states = bc.getJointStates(uid_of(root), model.indices)
                out[root] = (np.array([s[0] for s in states]), np.array([s[1] for s in states]))
        return out

    def put_back(self, bc: BulletClient, uid_of: UidOf, states: JointStates) -> None:
        """Joint states carried across a rebuild; a model as loaded is left as loaded, so
        that a rewound world replays bit for bit. Each joint's damping as the books hold it."""
        for root, articulation in self.models.items():
            articulation.apply_damping(bc, uid_of(root))
        for root, (q, qdot) in states.items():
            model = self.models.get(root)
            if model is None:
                continue
            if np.array_equal(q, model.loaded[0]) and np.array_equal(qdot, model.loaded[1]):
                continue
            uid = uid_of(root)
            for j, position, velocity in zip(model.indices, q.tolist(), qdot.tolist(),
                                             strict=True):
                bc.resetJointState(uid, j, position, velocity)

    def restore(self, bc: BulletClient, uid_of: UidOf) -> None:
        """Joints as loaded and at rest, targets none, wrenches gone."""
        for root, model in self.models.items():
            uid = uid_of(root)
            for j, position in zip(model.indices, model.loaded[0].tolist(), strict=True):
                bc.resetJointState(uid, j, position, 0.0)
            model.release()
        self.wrenches.clear()

    # -- every step -------------------------------------------------------------------
    def busy(self) -> bool:
        """Whether a step needs more than stepSimulation."""
        return bool(self.wrenches) or any(m.active for m in self.models.values())

    def actuate(self, bc: BulletClient, uid_of: UidOf, dt: float) -> None:
        """Before one step of ``dt`` s: every model's targets, every held wrench."""
        for root, model in self.models.items():
            if model.active:
                model.actuate(bc, uid_of(root), dt)
        if self.wrenches:
            targets = [self.place(uid_of, name) for name in self.wrenches]
            force_at = centres(bc, targets).tolist()
            for (uid, link), (force, torque), point in zip(
                    targets, self.wrenches.values(), force_at, strict=True):
                bc.applyExternalForce(uid, link, force, point, pybullet.WORLD_FRAME)
                bc.applyExternalTorque(uid, link, torque, pybullet.WORLD_FRAME)

    def place(self, uid_of: UidOf, name: str) -> tuple[int, int]:
        """PyBullet's (body id, link index; -1 for a base) of an entity."""
        ref = self.links.get(name)
        return (uid_of(name), -1) if ref is None else (uid_of(ref[0]), ref[1])

    def hold_wrenches(self, bc: BulletClient, uid_of: UidOf, names: Sequence[str],
                      wrenches: np.ndarray, points: np.ndarray | None) -> None:
        """Force F at the centre of mass c, torque tau + (p - c) x F, with c taken now."""
        forces, torques = wrenches[:, :3], wrenches[:, 3:].copy()
        if points is not None:
            c = centres(bc, [self.place(uid_of, name) for name in names])
            torques += np.cross(points - c, forces)
        for name, force, torque in zip(names, forces.tolist(), torques.tolist(), strict=True):
            self.wrenches[name] = (force, torque)
