"""Collision: ODE's space finds the pairs in C, and one near-callback per pair makes their
contact joints, as Webots' ``odeNearCallback`` does (surface as in its
``fillSurfaceParameters``: Coulomb friction, bounce, soft CFM and ERP, ``dContactApprox1``).

What is kept off the per-pair Python path: static-static and sleeping pairs never reach the
callback (collision bits, spawn.py); the callback's arguments are plain addresses looked up
in one dict; the contact buffer and its surface constants are made once and only the pair's
friction and bounce are written per contact. Contact points and forces are recorded only
for the last step of a ``step`` call, the one ``contacts`` reports.
"""

from __future__ import annotations

import ctypes
from typing import Any

import numpy as np

from galton.daemon.engines.ode.native import (
    CONTACT_APPROX1,
    CONTACT_BOUNCE,
    CONTACT_SOFT_CFM,
    CONTACT_SOFT_ERP,
    LIB,
    NEAR_CALLBACK,
    Contact,
    ContactGeom,
    JointFeedback,
)
from galton.daemon.engines.ode.spawn import ASLEEP, AWAKE, Body

BUFFER = 64
BASE_MODE = CONTACT_APPROX1 | CONTACT_SOFT_CFM | CONTACT_SOFT_ERP


class Collider:
    """Makes the contact joints of one step; records the last step's contacts if asked."""

    def __init__(self, world: int, space: int, by_geom: dict[int, Body]) -> None:
        self.world, self.space, self.by_geom = world, space, by_geom
        self.group = int(LIB.dJointGroupCreate(0))
        self.buffer = (Contact * BUFFER)()
        base = ctypes.addressof(self.buffer)
        self.geom_address = base + Contact.geom.offset
        self.addresses = [base + k * ctypes.sizeof(Contact) for k in range(BUFFER)]
        self.stride = ctypes.sizeof(Contact)
        self.max_contacts = 10
        self.recording = False
        self.recorded: list[tuple[str, str, tuple[float, ...], tuple[float, ...], float,
                                  JointFeedback]] = []
        self.callback = NEAR_CALLBACK(self._near)
        self.found: list[tuple[int, int, int]] = []  # (order, geom, geom) of this step
        self.pairs = 0  # candidate pairs seen, for measurements

    def configure(self, values: dict[str, Any]) -> None:
        """Write the surface constants into every slot of the contact buffer once."""
        self.max_contacts = int(values["ode.max_contacts"])
        for contact in self.buffer:
            surface = contact.surface
            surface.bounce_vel = values["ode.bounce_velocity"]
            surface.soft_cfm = soft_cfm(values)
            surface.soft_erp = values["ode.contact_soft_erp"]

    def collide(self, recording: bool) -> None:
        """Forget the previous step's joints, then make this step's: ODE's space lists the
        candidate pairs (the callback only notes them), and their joints are made in the
        bodies' creation order, whatever order the space visited them in (it reorders its
        geoms as they move), so that the same state always gives the same joints."""
        LIB.dJointGroupEmpty(self.group)
        self.recording = recording
        if recording:
            self.recorded = []
        self.found = []
        LIB.dSpaceCollide(self.space, None, self.callback)
        self.pairs += len(self.found)
        self.found.sort()
        by_geom = self.by_geom
        for _, g1, g2 in self.found:
            self._join(by_geom[g1], by_geom[g2])

    def _near(self, _data: Any, g1: int, g2: int) -> None:
        first, second = self.by_geom[g1], self.by_geom[g2]
        if first.serial > second.serial:
            first, second, g1, g2 = second, first, g2, g1
        self.found.append((first.serial << 32 | second.serial, g1, g2))

    def _join(self, first: Body, second: Body) -> None:
        if first.model is not None and first.model == second.model:
            return  # no collisions inside a loaded model (its links touch at the joints)
        count = LIB.dCollide(first.geom, second.geom, self.max_contacts, self.geom_address,
                             self.stride)
        if not count:
            return
        if first.static:
            friction, bounce = first.friction, first.restitution
        elif second.static:
            friction, bounce = second.friction, second.restitution
        else:
            friction = max(first.friction, second.friction)
            bounce = max(first.restitution, second.restitution)
        mode = BASE_MODE | CONTACT_BOUNCE if bounce > 0 else BASE_MODE
        world, group, buffer, b1, b2 = self.world, self.group, self.buffer, first.body, \
            second.body
        for k in range(count):
            surface = buffer[k].surface
            surface.mode, surface.mu, surface.bounce = mode, friction, bounce
            joint = LIB.dJointCreateContact(world, group, self.addresses[k])
            LIB.dJointAttach(joint, b1 or None, b2 or None)
            if self.recording:
                self._record(joint, first, second, buffer[k].geom)

    def _record(self, joint: int, first: Body, second: Body, geom: ContactGeom) -> None:
        feedback = JointFeedback()
        LIB.dJointSetFeedback(joint, ctypes.addressof(feedback))
        self.recorded.append((first.name, second.name, tuple(geom.pos[:3]),
                              tuple(geom.normal[:3]), float(geom.depth), feedback))

    def report(self, names: set[str] | None) -> tuple[list[str], list[str], np.ndarray,
                                                      np.ndarray, np.ndarray, np.ndarray]:
        """The recorded contacts involving ``names`` (None: all). ODE's normal points into
        the first geom; the interface's goes from the first to the second."""
        rows = [r for r in self.recorded
                if names is None or r[0] in names or r[1] in names]
        firsts = [r[0] for r in rows]
        seconds = [r[1] for r in rows]
        points = np.array([r[2] for r in rows], dtype=float).reshape(-1, 3)
        normals = -np.array([r[3] for r in rows], dtype=float).reshape(-1, 3)
        depths = np.array([r[4] for r in rows], dtype=float)
        # The force on the first body, against its normal (ODE's normal points into it).
        forces = np.array([float(np.dot(r[5].f1[:3], r[3])) for r in rows], dtype=float)
        return firsts, seconds, points, normals, np.abs(forces), depths

    def forget(self) -> None:
        LIB.dJointGroupEmpty(self.group)
        self.recorded = []

    def let_go(self, gone: set[str]) -> None:
        """Before bodies are destroyed: their contact joints go (all of the step's: ODE
        empties a group whole), the last step's reports of the others stay until the next
        step (a contact read between steps does not change)."""
        LIB.dJointGroupEmpty(self.group)
        self.recorded = [r for r in self.recorded if r[0] not in gone and r[1] not in gone]

    def close(self) -> None:
        LIB.dJointGroupDestroy(self.group)


def soft_cfm(values: dict[str, Any]) -> float:
    """The contacts' soft CFM at this step (params.py, ``ode.soft_cfm_step``)."""
    reference = values["ode.soft_cfm_step"]
    scale = values["timestep"] / reference if reference > 0 else 1.0
    return float(values["ode.contact_soft_cfm"] * scale)


def sync_sleep(moving: list[Body]) -> None:
    """Collision bits follow ODE's sleep flags: a body that fell asleep (or woke) in the
    step leaves (or rejoins) the pairs that reach the callback."""
    enabled = LIB.dBodyIsEnabled
    for body in moving:
        awake = bool(enabled(body.body))
        if awake != body.awake:
            body.awake = awake
            body.set_bits(AWAKE if awake else ASLEEP)
