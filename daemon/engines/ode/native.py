"""The ODE library through ctypes: the few functions and structures the engine calls.

Debian's ``libode8`` (0.16.2, double precision) is loaded by name. Every handle travels as a
plain integer address (``c_void_p``), so the near-callback receives two ints it can look up
in a dict, with no pointer objects made per pair (``ode-python``'s typed bindings would make
several per call, and it edits ``os.environ`` when imported; this module does neither).

``BODY_STATE`` is the layout of the dynamic state inside ODE's ``dxBody``: position, rotation
matrix, quaternion and the two velocities lie in one run of 28 doubles. ``check_layout``
proves it on the loaded library before the engine reads or writes states through it.
"""

from __future__ import annotations

import ctypes
import ctypes.util
from ctypes import POINTER, Structure, c_char_p, c_double, c_int, c_uint, c_ulong, c_void_p
from typing import Any

from galton.protocol import FeatureUnsupportedError

REAL = c_double
VECTOR3 = REAL * 4  # ODE pads 3-vectors to 4
# Offsets (in doubles) into a body's state run, from the address of its position.
POS, ROT, QUAT, LVEL, AVEL, STATE_LENGTH = 0, 4, 16, 20, 24, 28

CONTACT_BOUNCE, CONTACT_SOFT_ERP, CONTACT_SOFT_CFM, CONTACT_APPROX1 = 4, 8, 16, 0x7000
RAY_CLASS = 5
SAP_AXES_XZY = 0 | (2 << 2) | (1 << 4)  # dSAP_AXES_XZY: sort along x (the board's width) first
SPHERE, BOX, CAPSULE, CYLINDER, PLANE, TRIMESH = 0, 1, 2, 3, 4, 8  # ODE's geom classes
JOINT_TYPE_CONTACT = 4


class ContactGeom(Structure):
    _fields_ = [("pos", VECTOR3), ("normal", VECTOR3), ("depth", REAL), ("g1", c_void_p),
                ("g2", c_void_p), ("side1", c_int), ("side2", c_int)]


class SurfaceParameters(Structure):
    _fields_ = [("mode", c_int), ("mu", REAL), ("mu2", REAL), ("rho", REAL), ("rho2", REAL),
                ("rhoN", REAL), ("bounce", REAL), ("bounce_vel", REAL), ("soft_erp", REAL),
                ("soft_cfm", REAL), ("motion1", REAL), ("motion2", REAL), ("motionN", REAL),
                ("slip1", REAL), ("slip2", REAL)]


class Contact(Structure):
    _fields_ = [("surface", SurfaceParameters), ("geom", ContactGeom), ("fdir1", VECTOR3)]


class Mass(Structure):
    _fields_ = [("mass", REAL), ("c", VECTOR3), ("I", REAL * 12)]


class JointFeedback(Structure):
    _fields_ = [("f1", VECTOR3), ("t1", VECTOR3), ("f2", VECTOR3), ("t2", VECTOR3)]


NEAR_CALLBACK = ctypes.CFUNCTYPE(None, c_void_p, c_void_p, c_void_p)
P, D, N = c_void_p, REAL, c_int  # pointer, real, integer
# name: (result, argument types)
_SIGNATURES: dict[str, tuple[Any, tuple[Any, ...]]] = {
    "dInitODE2": (c_int, (c_uint,)), "dGetConfiguration": (c_char_p, ()),
    "dRandSetSeed": (None, (c_ulong,)),
    "dWorldCreate": (P, ()), "dWorldDestroy": (None, (P,)),
    "dWorldSetGravity": (None, (P, D, D, D)), "dWorldSetCFM": (None, (P, D)),
    "dWorldSetERP": (None, (P, D)), "dWorldStep": (N, (P, D)),
    "dWorldSetMaxAngularSpeed": (None, (P, D)),
    "dWorldQuickStep": (N, (P, D)), "dWorldSetQuickStepNumIterations": (None, (P, N)),
    "dWorldSetAutoDisableFlag": (None, (P, N)), "dWorldSetAutoDisableTime": (None, (P, D)),
    "dWorldSetAutoDisableSteps": (None, (P, N)),
    "dWorldSetAutoDisableLinearThreshold": (None, (P, D)),
    "dWorldSetAutoDisableAngularThreshold": (None, (P, D)),
    "dWorldSetLinearDampingThreshold": (None, (P, D)),
    "dWorldSetAngularDampingThreshold": (None, (P, D)),
    "dHashSpaceCreate": (P, (P,)), "dSpaceDestroy": (None, (P,)),
    "dSweepAndPruneSpaceCreate": (P, (P, N)),
    "dSpaceCollide": (None, (P, P, NEAR_CALLBACK)),
    "dSpaceCollide2": (None, (P, P, P, NEAR_CALLBACK)),
    "dCollide": (N, (P, P, N, P, N)),
    "dCreateSphere": (P, (P, D)), "dCreateBox": (P, (P, D, D, D)),
    "dCreateCylinder": (P, (P, D, D)), "dCreateCapsule": (P, (P, D, D)),
    "dCreatePlane": (P, (P, D, D, D, D)), "dCreateRay": (P, (P, D)),
    "dGeomRaySet": (None, (P, D, D, D, D, D, D)), "dGeomRaySetLength": (None, (P, D)),
    "dGeomRaySetClosestHit": (None, (P, N)),
    "dGeomDestroy": (None, (P,)), "dGeomSetBody": (None, (P, P)),
    "dGeomGetClass": (N, (P,)), "dGeomSpherePointDepth": (D, (P, D, D, D)),
    "dGeomBoxPointDepth": (D, (P, D, D, D)), "dGeomCapsulePointDepth": (D, (P, D, D, D)),
    "dGeomPlanePointDepth": (D, (P, D, D, D)), "dGeomGetPosRelPoint": (None, (P, D, D, D, P)),
    "dGeomCylinderGetParams": (None, (P, P, P)),
    "dGeomSetPosition": (None, (P, D, D, D)), "dGeomSetQuaternion": (None, (P, P)),
    "dGeomPlaneSetParams": (None, (P, D, D, D, D)),
    "dGeomSetCategoryBits": (None, (P, c_ulong)), "dGeomSetCollideBits": (None, (P, c_ulong)),
    "dGeomSetOffsetPosition": (None, (P, D, D, D)),
    "dGeomSetOffsetQuaternion": (None, (P, P)),
    "dBodyCreate": (P, (P,)), "dBodyDestroy": (None, (P,)),
    "dBodySetPosition": (None, (P, D, D, D)), "dBodySetQuaternion": (None, (P, P)),
    "dBodySetLinearVel": (None, (P, D, D, D)), "dBodySetAngularVel": (None, (P, D, D, D)),
    "dBodyGetPosition": (P, (P,)), "dBodyGetQuaternion": (P, (P,)),
    "dBodyGetRotation": (P, (P,)), "dBodyGetLinearVel": (P, (P,)),
    "dBodyGetAngularVel": (P, (P,)),
    "dBodySetMass": (None, (P, P)), "dBodyGetMass": (None, (P, P)),
    "dBodyAddForce": (None, (P, D, D, D)), "dBodyAddTorque": (None, (P, D, D, D)),
    "dBodyEnable": (None, (P,)), "dBodyDisable": (None, (P,)),
    "dBodyIsEnabled": (N, (P,)), "dBodySetGravityMode": (None, (P, N)),
    "dBodySetAutoDisableDefaults": (None, (P,)), "dBodySetKinematic": (None, (P,)),
    "dBodySetAutoDisableFlag": (None, (P, N)),
    "dMassSetSphereTotal": (None, (P, D, D)), "dMassSetBoxTotal": (None, (P, D, D, D, D)),
    "dMassSetCylinderTotal": (None, (P, D, N, D, D)),
    "dMassSetCapsuleTotal": (None, (P, D, N, D, D)),
    "dMassSetZero": (None, (P,)), "dMassAdd": (None, (P, P)),
    "dMassTranslate": (None, (P, D, D, D)), "dMassRotate": (None, (P, P)),
    "dMassSetParameters": (None, (P, D, D, D, D, D, D, D, D, D, D)),
    "dJointGroupCreate": (P, (N,)), "dJointGroupDestroy": (None, (P,)),
    "dJointGroupEmpty": (None, (P,)), "dJointCreateContact": (P, (P, P, P)),
    "dJointAttach": (None, (P, P, P)), "dJointSetFeedback": (None, (P, P)),
    "dJointDestroy": (None, (P,)),
    "dJointCreateHinge": (P, (P, P)), "dJointCreateSlider": (P, (P, P)),
    "dJointCreateFixed": (P, (P, P)), "dJointSetFixed": (None, (P,)),
    "dJointSetHingeAnchor": (None, (P, D, D, D)), "dJointSetHingeAxis": (None, (P, D, D, D)),
    "dJointGetHingeAngle": (D, (P,)), "dJointGetHingeAngleRate": (D, (P,)),
    "dJointSetHingeParam": (None, (P, N, D)), "dJointAddHingeTorque": (None, (P, D)),
    "dJointSetSliderAxis": (None, (P, D, D, D)), "dJointGetSliderPosition": (D, (P,)),
    "dJointGetSliderPositionRate": (D, (P,)), "dJointSetSliderParam": (None, (P, N, D)),
    "dJointAddSliderForce": (None, (P, D)),
    "dAreConnectedExcluding": (N, (P, P, N)),
    "dGeomTriMeshDataCreate": (P, ()), "dGeomTriMeshDataDestroy": (None, (P,)),
    "dGeomTriMeshDataBuildDouble": (None, (P, P, N, N, P, N, N)),
    "dCreateTriMesh": (P, (P, P, P, P, P)), "dMassSetTrimeshTotal": (None, (P, D, P)),
    "dMassAdjust": (None, (P, D)),
}


def _load() -> ctypes.CDLL:
    name = ctypes.util.find_library("ode")
    if name is None:
        raise FeatureUnsupportedError(
            "the ODE library (libode) is not installed here: apt-get install libode8")
    lib = ctypes.CDLL(name)
    for function, (result, arguments) in _SIGNATURES.items():
        call = getattr(lib, function)
        call.restype, call.argtypes = result, list(arguments)
    lib.dInitODE2(0)
    return lib


LIB = _load()


def version() -> str:
    """What the loaded library says of itself (its configuration string)."""
    return "0.16 (" + (LIB.dGetConfiguration() or b"").decode() + ")"


def quaternion(xyzw: Any) -> ctypes.Array[c_double]:
    """An ODE quaternion (w, x, y, z) from the protocol's (x, y, z, w)."""
    x, y, z, w = (float(v) for v in xyzw)
    return (REAL * 4)(w, x, y, z)


def body_state(body: int) -> ctypes.Array[c_double]:
    """The body's 28-double state run, as a ctypes array over ODE's own memory."""
    return (REAL * STATE_LENGTH).from_address(LIB.dBodyGetPosition(body))


def check_layout() -> None:
    """Prove on the loaded library that a body's state lies as ``BODY_STATE`` says."""
    world = LIB.dWorldCreate()
    try:
        body = LIB.dBodyCreate(world)
        base = LIB.dBodyGetPosition(body)
        size = ctypes.sizeof(REAL)
        offsets = {"quaternion": (LIB.dBodyGetQuaternion(body), QUAT),
                   "rotation": (LIB.dBodyGetRotation(body), ROT),
                   "linear velocity": (LIB.dBodyGetLinearVel(body), LVEL),
                   "angular velocity": (LIB.dBodyGetAngularVel(body), AVEL)}
        for what, (address, offset) in offsets.items():
            if address - base != offset * size:
                raise FeatureUnsupportedError(
                    f"this libode keeps a body's {what} where the engine does not expect it")
    finally:
        LIB.dWorldDestroy(world)


check_layout()
POINTER_TO_CONTACT = POINTER(Contact)
