"""A relaxation pad as the hand uses it, pressed by a plate through human tissue (shared by the
tests of the pad's law, tests/test_representations.py, and of its stability, tests/test_divergence.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from softhand.hands.skeleton import new_spec
from softhand.laws.references import HUMAN
from softhand.skin.files import load_calibration
from softhand.skin.representations import HandPad, add_hand_pad
from softhand.skin.rig import apply_pair_law


@dataclass(frozen=True)
class PadPress:
    """One press: ``t`` (s), the pad's compression ``x`` (mm) and contact force ``f`` (N) per
    step, how many times MuJoCo reset the run (its time went back) and its bad-acceleration
    warning count."""

    law: object
    t: np.ndarray
    x: np.ndarray
    f: np.ndarray
    resets: int
    badqacc: int


def press_pad(design: str, *, timestep: float = 0.002, force_N: float = 2.0,
              hold_s: float = 2.0, segment_kg: float = 0.05, behind: bool = False,
              settings: HandPad | None = None) -> PadPress:
    """A hand pad of ``design`` on a segment of ``segment_kg`` held by a stiff spring, pressed in
    0.3 s by a plate through human tissue (the tissue's calibrated soft contact) to the depth of
    about ``force_N`` and held ``hold_s``, under the hands' options (implicitfast); ``behind``: the
    plate presses from the bone's side, pushing the pad past its rest, as a partner's finger
    curled round a phalanx does."""
    cal, tissue = load_calibration(design), load_calibration(HUMAN)
    spec = new_spec("hand_pad", timestep_s=timestep, gravity_m_s2=0.0)
    seg = spec.worldbody.add_body(name="segment")
    seg.add_geom(name="bone", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.004, 0.006, 0.001],
                 mass=segment_kg, contype=0, conaffinity=0)
    joint = seg.add_joint(name="mount", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
    joint.stiffness, joint.damping = [1e5, 0.0, 0.0], [50.0, 0.0, 0.0]
    seg.add_geom(name="skin", type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[0.009, 0.01, 0],
                 quat=[0.7071068, 0.7071068, 0, 0], contype=0, conaffinity=0, mass=0.0)
    add_hand_pad(spec, "skin", cal.law, outward=(0.0, 0.0, -1.0 if behind else 1.0),
                 settings=settings or HandPad())
    plate = spec.worldbody.add_body(name="plate", pos=[0, 0, 0.011], mocap=True)
    plate.add_geom(name="plate", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.02, 0.02, 0.002],
                   contype=0, conaffinity=0)
    spec.add_pair(name="skin_plate", geomname1="skin", geomname2="plate", condim=3)
    model = spec.compile()
    apply_pair_law(model, "skin_plate", tissue.soft_contact)
    data = mujoco.MjData(model)
    depth = 1e-3 * (tissue.law.elastic.displacement_at(force_N)
                    + (0.0 if behind else cal.law.elastic.displacement_at(force_N)))
    q = model.joint("skin_pad").qposadr[0]
    z0 = model.body_pos[model.body("plate").id, 2]
    n = int((0.3 + hold_s) / timestep)
    t, x, f = np.empty(n), np.empty(n), np.zeros(n)
    resets, f6 = 0, np.zeros(6)
    for k in range(n):
        t[k] = (k + 1) * timestep
        data.mocap_pos[0, 2] = z0 - depth * min(t[k] / 0.3, 1.0)
        before = data.time
        mujoco.mj_step(model, data)
        resets += data.time < before
        x[k] = 1e3 * data.qpos[q]
        for i in range(data.ncon):
            mujoco.mj_contactForce(model, data, i, f6)
            f[k] += f6[0]
    return PadPress(cal.law, t, x, f, resets,
                    int(data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number))
