"""The handshake scene: both hands in one spec, with softhand's simulation options.

World frame: +Z up, gravity along -Z, no floor. The prosthetic hand (prefix ``pro_``) is fixed to
the world through the body ``pro_wrist`` in a handshake pose: fingers forward (+X), thumb up, palm
facing +Y. The partner hand (prefix ``hum_``) rides the free body ``hum_arm``, held by a soft weld
(the arm's compliance) to the mocap target ``hum_base``, and faces it: palm facing -Y, fingers
towards -X. The two long axes cross at SceneConfig.crossing_angle_deg in the plane of the touching
palms, shared equally: each hand's fingers point down by half of it (prosthetic_quat(),
partner_quat()), so each forearm rises gently towards its elbow and each hand's fingers lie across
the other's palm. The env drives ``hum_base``: from its start
pose (where the scene places it) to partner_contact_pose() (reach), shakes it, and takes it back.

Contact pose: where the handshake's grasp, solved from its contacts, puts the partner
(softhand.hands.grasp: palms pressed, web spaces together, each thumb over the back of the other
hand's index metacarpal, the fingers wrapped round the other's ulnar border).
"""

from __future__ import annotations

import mujoco
import numpy as np

from softhand.hands.config import SceneConfig
from softhand.hands.layout import HandLayout
from softhand.hands.partner import add_partner_hand
from softhand.hands.prosthetic import add_prosthetic_hand
from softhand.hands.skeleton import new_spec, quat_from_axes

#: Time constant of the weld holding the partner's hand to its target (s): with the hand's
#: ~0.4 kg it gives an endpoint stiffness of a few hundred N/m, the order of the human arm's
#: postural hand stiffness (Mussa-Ivaldi, Hogan & Bizzi 1985, J Neurosci 5(10):2732-2743).
ARM_TIMECONST_S = 0.035
#: Mass moving with the partner's wrist (kg): the distal forearm (assumption, ~1/4 of a 1.2 kg
#: forearm, Winter 2009 Table 4.1: forearm 0.016 x body mass).
ARM_MASS_KG = 0.3

__all__ = [
    "ARM_MASS_KG",
    "ARM_TIMECONST_S",
    "partner_quat",
    "prosthetic_quat",
    "scene_spec",
    "web_point",
]

def prosthetic_quat(crossing_angle_deg: float) -> np.ndarray:
    """Prosthetic hand frame -> world: palm facing +Y, fingers turned down by half the crossing
    angle (the other half is the partner's, partner_quat), thumb side up.

    At 0 the fingers point along +X and the thumb up (+Z); at angle b the fingers point along
    (cos b/2, 0, -sin b/2) and the radial side along (sin b/2, 0, cos b/2); the back faces -Y.
    """
    h = np.radians(0.5 * crossing_angle_deg)
    fingers = np.array([np.cos(h), 0.0, -np.sin(h)])
    radial = np.array([np.sin(h), 0.0, np.cos(h)])
    return np.array(quat_from_axes(fingers, radial, np.array([0.0, -1.0, 0.0])))


def partner_quat(crossing_angle_deg: float) -> np.ndarray:
    """Partner hand frame -> world: palm facing -Y, fingers turned down by half the crossing angle.

    At 0 the fingers point along -X and the thumb up (+Z); at angle b the fingers point along
    (-cos b/2, 0, -sin b/2) and the radial side along (-sin b/2, 0, cos b/2); the back faces +Y.
    Both forearms are then inclined by b/2, rising towards their elbows.
    """
    h = np.radians(0.5 * crossing_angle_deg)
    fingers = np.array([-np.cos(h), 0.0, -np.sin(h)])
    radial = np.array([-np.sin(h), 0.0, np.cos(h)])
    return np.array(quat_from_axes(fingers, radial, np.array([0.0, 1.0, 0.0])))


def web_point(layout: HandLayout) -> np.ndarray:
    """The web space between thumb and index in the hand frame (mid-thickness of the palm): the
    radial border of the index metacarpal, half-way between the thumb's CMC and the index MCP."""
    thumb, index = layout.digits["thumb"], layout.digits["index"]
    return np.array([0.5 * (thumb.cmc_m[0] + index.base_m[0]),
                     index.base_m[1] + index.radii_m["metacarpal"], 0.0])


def _rotation(quat: np.ndarray) -> np.ndarray:
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat, float))
    return mat.reshape(3, 3)


def scene_spec(config: SceneConfig | None = None, *,
               partner_pose: tuple[np.ndarray, np.ndarray] | None = None) -> mujoco.MjSpec:
    """Build the handshake scene: options, both hands, the partner at its start pose.

    Args:
        config: the scene; default SceneConfig().
        partner_pose: world position and quaternion of the partner's mount (its hand frame);
            default: its start pose, SceneConfig.partner_start_offset_m from the solved grasp
            (softhand.hands.grasp.partner_start_pose).

    Returns:
        A new MjSpec (not compiled).
    """
    config = config or SceneConfig()
    if not isinstance(config, SceneConfig):
        raise ValueError(f"config = {config!r}: expected a SceneConfig")
    spec = new_spec(
        "softhand_handshake", timestep_s=config.timestep_s, gravity_m_s2=config.gravity_m_s2
    )
    # Two hands in contact are one constraint island; finding islands every step cost more than
    # solving them apart saved: 4-5 % of a handshake step, region forces equal to 1e-4 N.
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_ISLAND)
    spec.worldbody.add_light(name="key_light", pos=[0.1, -0.5, 1.8], dir=[0.0, 0.5, -1.0])
    wrist = spec.worldbody.add_body(
        name="pro_wrist",
        pos=[float(v) for v in config.prosthetic_wrist_pos_m],
        quat=prosthetic_quat(config.crossing_angle_deg).tolist(),
    )
    add_prosthetic_hand(spec, wrist, config.prosthetic, "pro_")
    if partner_pose is None:
        from softhand.hands.grasp import partner_start_pose  # the grasp is solved on this scene

        partner_pose = partner_start_pose(config)
    pos, quat = (np.asarray(v, float) for v in partner_pose)
    spec.worldbody.add_body(name="hum_base", mocap=True, pos=pos.tolist(), quat=quat.tolist())
    # The partner's arm: the hand rides a free body held to the mocap target by a soft weld, so
    # the scripted reach and shake are compliant (an arm, not an infinitely strong fixture).
    arm = spec.worldbody.add_body(name="hum_arm", pos=pos.tolist(), quat=quat.tolist())
    arm.add_freejoint(name="hum_arm")
    arm.add_geom(name="hum_arm_mass", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.02, 0, 0],
                 mass=ARM_MASS_KG, contype=0, conaffinity=0, group=4)
    add_partner_hand(spec, arm, config.partner, "hum_")
    weld = spec.add_equality(name="hum_arm_weld", type=mujoco.mjtEq.mjEQ_WELD,
                             objtype=mujoco.mjtObj.mjOBJ_BODY, name1="hum_arm", name2="hum_base")
    weld.solref = [ARM_TIMECONST_S, 1.0]
    # anchor at the arm body's origin: the shared numeric default of equalities puts a weld's
    # anchor 1 m along body2's y, where a small wrist rotation satisfies it with the hand far away
    weld.data[0:3] = 0.0
    for body in spec.bodies:
        if body.name.startswith("hum_"):
            body.gravcomp = 1.0  # the arm carries the hand's weight
    return spec
