"""An articulated three-link finger whose fingertip skin is pressed by a plate, in any posture.

The check that the soft-contact calibration is a property of the skin, not of the body: the same
skin on the distal link of a finger (hinge joints held by position servos, so the contact's
effective mass depends on the whole chain) must give the rig's force at the same indentation.
The plate is a mocap body that moves along the fingertip skin's normal; indentation is the
contact's penetration, force its normal force. Sizes: an adult index finger (45 / 25 / 20 mm).
"""

from __future__ import annotations

import mujoco
import numpy as np

from softhand.laws.fit import Curve
from softhand.skin.rig import apply_pair_law
from softhand.skin.soft_contact import SoftContactParams

__all__ = ["POSTURES_DEG", "press_finger"]

LINKS_M = (0.045, 0.025, 0.020)
LINK_MASS_KG = (0.020, 0.010, 0.006)
SKIN_HALF_AXES_M = (0.008, 0.007, 0.004)
POSTURES_DEG = {"straight": (0.0, 0.0, 0.0), "hook": (0.0, 60.0, 40.0),
                "grip": (45.0, 45.0, 30.0), "fist": (80.0, 90.0, 60.0)}


def _build(soft: SoftContactParams, posture: tuple[float, float, float], timestep: float
           ) -> mujoco.MjModel:
    spec = mujoco.MjSpec()
    spec.option.timestep = timestep
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    parent = spec.worldbody.add_body(name="palm")
    for i, (length, mass) in enumerate(zip(LINKS_M, LINK_MASS_KG, strict=True)):
        body = parent.add_body(name=f"link{i}", pos=[LINKS_M[i - 1] if i else 0.0, 0.0, 0.0])
        body.add_joint(name=f"j{i}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 1.0, 0.0],
                       damping=[0.01, 0.0, 0.0])
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, fromto=[0, 0, 0, length, 0, 0],
                      size=[0.008, 0, 0], mass=mass, contype=0, conaffinity=0)
        act = spec.add_actuator(name=f"a{i}", target=f"j{i}", trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=5.0, kv=0.05)
        parent = body
    parent.add_geom(name="skin", type=mujoco.mjtGeom.mjGEOM_ELLIPSOID,
                    size=list(SKIN_HALF_AXES_M), pos=[LINKS_M[-1] * 0.6, 0.0, 0.0],
                    contype=0, conaffinity=0)
    plate = spec.worldbody.add_body(name="plate", mocap=True)
    plate.add_geom(name="plate", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.01, 0.01, 0.002],
                   contype=0, conaffinity=0)
    spec.add_pair(name="skin_plate", geomname1="skin", geomname2="plate", condim=3)
    spec.add_key(name="posture", qpos=list(np.deg2rad(posture)), ctrl=list(np.deg2rad(posture)))
    model = spec.compile()
    apply_pair_law(model, "skin_plate", soft)
    return model


def press_finger(soft: SoftContactParams, posture: str, *, depth_mm: float,
                 speed_mm_s: float = 0.5, timestep: float = 1e-3) -> Curve:
    """Hold ``posture`` and press the fingertip skin with a plate along its normal: a simulated
    `Curve` labelled ``posture`` (``displacement_mm``: the skin
    contact's penetration, ``force_N`` its normal force)."""
    if posture not in POSTURES_DEG:
        raise ValueError(f"posture {posture!r} is unknown; allowed: {', '.join(POSTURES_DEG)}")
    model = _build(soft, POSTURES_DEG[posture], timestep)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_forward(model, data)
    skin = model.geom("skin").id
    centre = data.geom_xpos[skin].copy()
    normal = -data.geom_xmat[skin].reshape(3, 3)[:, 2]  # the pad side: the link's -z
    half = SKIN_HALF_AXES_M[2] + 0.002
    rot = np.zeros(4)
    mujoco.mju_mat2Quat(rot, data.geom_xmat[skin])
    data.mocap_quat[0] = rot
    n = int(depth_mm / speed_mm_s / timestep)
    pen = np.zeros(n)
    force = np.zeros(n)
    for k in range(n):
        travel = 1e-3 * speed_mm_s * (k + 1) * timestep
        data.mocap_pos[0] = centre + normal * (half - travel)
        mujoco.mj_step(model, data)
        for i in range(data.ncon):
            c = data.contact[i]
            if skin in (c.geom1, c.geom2):
                pen[k] = -1e3 * c.dist
                force[k] = data.efc_force[c.efc_address]
    return Curve.simulated(timestep * np.arange(1, n + 1), pen, force, label=posture)
