"""A flex pad on one region of the prosthetic hand, pressed by a plate: contact area and pressure.

The ``flex`` representation cannot join the handshake: MuJoCo 4 integrates flex elasticity only
under the ``discrete`` integrator, under which the hand's calibrated soft contacts do not hold
(`softhand.skin.representations`). So a flex region lives in a scene that models only what
it needs: the prosthetic hand alone, fixed at the wrist, one digit held in a posture by its
motor, a flex pad on one phalanx region and a rigid plate pressing it along the pad's normal.
No other contact exists in the scene, so every newton on the plate comes from the pad.

The pad is the calibrated flex of the skin (`softhand.skin.flex.FlexPadParams`, fitted to
the design's FE loading curve on a world-fixed base): the paper's phalanx, 16 mm wide, 9 mm high
and 10 mm long, its flat base on the plane through the phalanx's axis (the capsule skins of the
prosthetic phalanges are 15-20 mm across, so the pad is the palmar half of the segment; its apex
stands 1 mm proud of an 8 mm capsule), centred on the region's skin, width across the finger,
length along it. Its base nodes are pinned to the phalanx body and every other node rides it
on three slide joints, so the pad follows the finger (MuJoCo's articulated flex attachment, Newton
solver). The region's own skin geom is hidden. Gravity is off, as in the FE and the rig.

Indentation is what the pad feels: its height minus the distance from the pad's base plane (on
the phalanx) to the plate's face, so the finger's give under the motor does not enter it (the
rig's convention). Force: the plate's normal contact forces. Contact area and pressure:
`softhand.skin.flex.contact_patch`. Postures: ``extended`` (every joint of the digit at 0)
and ``flexed`` (the digit's motor at half its range, the coupled joints following).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np

from softhand.hands import constants as const
from softhand.hands.prosthetic import REGION_SEGMENTS, build_prosthetic_hand, regions
from softhand.laws.fit import Curve
from softhand.skin.flex import (
    ContactPatch,
    FlexPadParams,
    add_flex_pad,
    add_plate,
    contact_patch,
    set_flex_options,
)

__all__ = ["FLEX_REGIONS", "POSTURES", "FlexPress", "build_flex_region", "press_flex_region"]

#: regions whose skin is a capsule round a phalanx (the palm and back are meshes)
FLEX_REGIONS: tuple[str, ...] = tuple(r for r, seg in REGION_SEGMENTS.items() if seg != "palm")
POSTURES: tuple[str, ...] = ("extended", "flexed")
_PAD = "flexpad"
_PLATE_MASS_KG = 0.02


def _digit(region: str) -> str:
    return REGION_SEGMENTS[region].split("_")[0]


def _motor_joint(digit: str) -> str:
    return "thumb_mcp" if digit == "thumb" else "mcp"


def _check_choice(name: str, value: str, allowed: tuple[str, ...]) -> None:
    if value not in allowed:
        raise ValueError(f"{name} = {value!r}: allowed {', '.join(allowed)}")


def build_flex_region(params: FlexPadParams, region: str = "Index3", *,
                      timestep: float = 1e-3, prefix: str = "pro_") -> mujoco.MjModel:
    """Compile the hand with the flex pad (``flexpad``) on ``region`` and the plate (body
    ``plate``, slide joint ``plate_z`` along the pad's outward normal, servo ``plate_servo``),
    the plate's face on the pad's apex in the extended posture (`press_flex_region`
    re-places it for the posture).

    Raises:
        ValueError: ``region`` is not a phalanx region, or a parameter is out of range.
    """
    _check_choice("region", region, FLEX_REGIONS)
    if not (math.isfinite(timestep) and 1e-5 <= timestep <= 5e-3):
        raise ValueError(f"timestep = {timestep!r} s: allowed range [1e-05, 0.005] s")
    params.validate()
    spec = build_prosthetic_hand(prefix=prefix)
    set_flex_options(spec, timestep)
    spec.option.gravity = [0.0, 0.0, 0.0]
    info = regions(spec, prefix)[region]
    # the skin capsule's centre in the phalanx's frame (the spec holds its fromto, not its pos)
    centre = spec.compile().geom(info.geom).pos.copy()
    skin = spec.geom(info.geom)
    skin.rgba = [0.0, 0.0, 0.0, 0.0]  # the pad is this region's skin now
    body = spec.body(info.body)
    # pad frame in the phalanx's frame: width across (y), length along (x), height palmar (-z)
    rot = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    add_flex_pad(spec, body, params, timestep=timestep, pos=centre, rot=rot, name=_PAD)
    add_plate(spec, pos=[0.0, 0.0, 0.0], plate_mass_kg=_PLATE_MASS_KG, timestep=timestep)
    body.add_site(name="flexpad_base", pos=centre.tolist(),
                  quat=_quat_of(rot).tolist(), group=4)
    return spec.compile()


def _quat_of(rot: np.ndarray) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(rot, dtype=float).ravel())
    return q


def _set_posture(model: mujoco.MjModel, data: mujoco.MjData, region: str, posture: str,
                 prefix: str) -> None:
    """Put the region's digit in ``posture``: its motor's setpoint and joints, couplings solved."""
    digit = _digit(region)
    joint = _motor_joint(digit)
    lo, hi = const.PROSTHETIC_RANGE_DEG[joint]
    angle = 0.0 if posture == "extended" else math.radians(0.5 * (lo + hi))
    motor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR,
                              f"{prefix}{digit}_{'flex_' if digit == 'thumb' else ''}motor")
    driver = model.joint(f"{prefix}{digit}_{joint.split('_')[-1]}").id
    data.qpos[model.jnt_qposadr[driver]] = angle
    for e in range(model.neq):  # joint couplings, in build order (a follower's lead comes first)
        if model.eq_type[e] != mujoco.mjtEq.mjEQ_JOINT:
            continue
        follower, lead = model.eq_obj1id[e], model.eq_obj2id[e]
        if model.joint(follower).name.startswith(f"{prefix}{digit}_"):
            q = data.qpos[model.jnt_qposadr[lead]]
            data.qpos[model.jnt_qposadr[follower]] = np.polyval(model.eq_data[e, 4::-1], q)
    data.act[model.actuator_actadr[motor]] = angle
    mujoco.mj_forward(model, data)


@dataclass(frozen=True)
class FlexPress:
    """One press of a flex region.

    Attributes:
        region, posture: where and how the hand was held.
        curve: simulated `Curve` (indentation the pad feels, plate
            force; ``stats``: ``steps``, ``step_us`` in ``mj_step`` alone, ``nv``).
        area_mm2, inner_area_mm2: the contact patch's area bounds at each curve sample.
        patch: the contact patch at the last sample (the peak force).
        model, qpos: the scene (the plate placed for the posture) and its state at the last
            sample, for a picture (`softhand.viz.render.render_state`).
        lookat_m: the pad's base centre in the world at the last sample.
    """

    region: str
    posture: str
    curve: Curve
    area_mm2: np.ndarray = field(repr=False)
    inner_area_mm2: np.ndarray = field(repr=False)
    patch: ContactPatch = field(repr=False)
    model: mujoco.MjModel = field(repr=False)
    qpos: np.ndarray = field(repr=False)
    lookat_m: np.ndarray = field(repr=False)

    def area_at(self, force_N: float) -> tuple[float, float]:
        """(inner, outer) contact area bounds where the force first reaches ``force_N``."""
        i = int(np.argmax(self.curve.force_N >= force_N))
        if self.curve.force_N[i] < force_N:
            raise ValueError(f"force_N = {force_N!r}: the press peaked at "
                             f"{self.curve.force_N.max():.3g} N")
        return float(self.inner_area_mm2[i]), float(self.area_mm2[i])


def press_flex_region(params: FlexPadParams, region: str = "Index3", posture: str = "extended",
                      *, speed_mm_s: float = 0.5, max_force_N: float = 2.0,
                      max_depth_mm: float | None = None, timestep: float = 1e-3,
                      prefix: str = "pro_",
                      progress: Callable[[float], None] | None = None) -> FlexPress:
    """Hold the hand in ``posture`` and press the plate into the region's flex pad along its
    normal at ``speed_mm_s`` until ``max_force_N`` (or ``max_depth_mm``, default 60 % of the pad
    height) of indentation; see the module docstring for what is measured.

    Raises:
        ValueError: a region, posture or number outside its allowed range (before any work).
        FloatingPointError: the simulation produced a bad acceleration.
    """
    _check_choice("posture", posture, POSTURES)
    for name, value, lo, hi in (("speed_mm_s", speed_mm_s, 0.01, 100.0),
                                ("max_force_N", max_force_N, 1e-3, 20.0)):
        if not (math.isfinite(value) and lo <= value <= hi):
            raise ValueError(f"{name} = {value!r}: allowed range [{lo}, {hi}]")
    depth_cap = 0.6 * params.height_mm
    max_depth_mm = depth_cap if max_depth_mm is None else max_depth_mm
    if not (math.isfinite(max_depth_mm) and 0 < max_depth_mm <= depth_cap):
        raise ValueError(f"max_depth_mm = {max_depth_mm!r}: allowed range (0, {depth_cap:g}] "
                         "(60 % of the pad height)")
    model = build_flex_region(params, region, timestep=timestep, prefix=prefix)
    data = mujoco.MjData(model)
    _set_posture(model, data, region, posture, prefix)
    base = model.site("flexpad_base").id
    frame = data.site_xmat[base].reshape(3, 3)
    apex = data.site_xpos[base] + frame[:, 2] * params.height_mm * 1e-3
    plate = model.body("plate").id
    model.body_pos[plate] = apex  # the plate's face on the apex, its z the pad's normal
    model.body_quat[plate] = _quat_of(frame)
    mujoco.mj_forward(model, data)
    servo = model.actuator("plate_servo").id
    n_max = int(np.ceil(max_depth_mm / speed_mm_s / timestep)) + 1
    t, depth, force = np.zeros(n_max), np.zeros(n_max), np.zeros(n_max)
    area, inner = np.zeros(n_max), np.zeros(n_max)
    patch = contact_patch(model, data, pad=_PAD)
    h = params.height_mm * 1e-3
    step_s, k = 0.0, 0
    for k in range(1, n_max):
        data.ctrl[servo] = -speed_mm_s * 1e-3 * k * timestep
        t0 = time.perf_counter()
        mujoco.mj_step(model, data)
        step_s += time.perf_counter() - t0
        if data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number or not np.isfinite(
                data.qpos).all():
            raise FloatingPointError(f"{region} flex press diverged at t = {data.time:.4f} s "
                                     f"(timestep {timestep} s)")
        frame = data.site_xmat[base].reshape(3, 3)
        gap = float(frame[:, 2] @ (data.xpos[plate] - data.site_xpos[base]))
        patch = contact_patch(model, data, pad=_PAD)
        t[k], depth[k], force[k] = data.time, (h - gap) * 1e3, patch.force_N
        area[k], inner[k] = patch.area_mm2, patch.inner_area_mm2
        if progress:
            progress(min(1.0, max(patch.force_N / max_force_N, depth[k] / max_depth_mm)))
        if patch.force_N >= max_force_N or depth[k] >= max_depth_mm:
            break
    n = k + 1
    curve = Curve.simulated(t[:n], depth[:n], force[:n], label=f"{region} {posture}",
                            steps=n - 1, step_us=1e6 * step_s / max(n - 1, 1), nv=int(model.nv))
    return FlexPress(region, posture, curve, area[:n], inner[:n], patch, model,
                     data.qpos.copy(), data.site_xpos[base].copy())
