"""The handshake scene: both hands in one spec, each on its arm, with softhand's simulation options.

World frame: +Z up, gravity along -Z, no floor. The prosthetic hand (prefix ``pro_``) rides the
free body ``pro_wrist``, held to the fixed anchor ``pro_anchor`` by its arm (SceneConfig.arm: the
prosthesis user's residual limb and socket, or the paper's experimenter's relaxed arm), in a
handshake pose: fingers forward (+X), thumb up, palm facing +Y. The partner hand (prefix
``hum_``) rides the free body ``hum_arm``, held by its arm (SceneConfig.partner_arm) to the mocap
target ``hum_base``, and faces it: palm facing -Y, fingers towards -X. The two long axes cross at
SceneConfig.crossing_angle_deg in the plane of the touching palms, shared equally: each hand's
fingers point down by half of it (prosthetic_quat(), partner_quat()), so each forearm rises gently
towards its elbow and each hand's fingers lie across the other's palm. The env drives
``hum_base``: from its start pose (where the scene places it) to partner_contact_pose() (reach),
shakes it, and takes it back; the shake reaches the sensored hand only through the contacts.

Arms (`add_arm`): a weld between the wrist body and its anchor whose stiffness and damping are
those of the arm's endpoint (softhand.hands.config.ArmConfig), set in MuJoCo's direct format
scaled by the body's inverse weight, so that a force F moves the wrist F / stiffness and a
torque T turns it T / rot_stiffness (tests/test_hands.py pushes both); a sphere of the arm's
moving mass rides the wrist. The arms carry their hands' weight (gravity compensation on every
body of both hands). Each anchor lies ArmConfig.press_n / stiffness beyond its hand's place in the
grasp along its palm normal (the sensored one here, the partner's through its mount,
`press_offset`), so each arm presses its palm towards the other's.

Contact pose: where the handshake's grasp, solved from its contacts, puts the partner
(softhand.hands.grasp: palms pressed, web spaces together, each thumb over the back of the other
hand's index metacarpal, the fingers wrapped round the other's ulnar border).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from softhand.hands.config import ArmConfig, SceneConfig
from softhand.hands.layout import HandLayout
from softhand.hands.partner import add_partner_hand
from softhand.hands.prosthetic import add_prosthetic_hand
from softhand.hands.skeleton import new_spec, quat_from_axes

#: The impedance d of an arm's weld rows, fixed (solimp d0 = dmax): the rows' force is then
#: linear in the offset (`add_arm`).
_ARM_IMPEDANCE = 0.5
#: palm normals in the world: the prosthetic's palm faces +Y, the partner's -Y
PALM_NORMALS = {"pro_": np.array([0.0, 1.0, 0.0]), "hum_": np.array([0.0, -1.0, 0.0])}

__all__ = [
    "PALM_NORMALS",
    "add_arm",
    "partner_quat",
    "press_offset",
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


def press_offset(arm: ArmConfig, prefix: str) -> np.ndarray:
    """Where an arm's anchor lies from its hand's place in the grasp (m, world): press_n /
    stiffness along the hand's palm normal (`PALM_NORMALS`), so that the arm's spring pushes the
    palm towards the other hand's with press_n once the palms meet."""
    return PALM_NORMALS[prefix] * (arm.press_n / arm.stiffness_n_per_m)


def add_arm(spec: mujoco.MjSpec, wrist: str, anchor: str, arm: ArmConfig,
            invweight: tuple[float, float]) -> mujoco.MjsEquality:
    """Hold the free body ``wrist`` to ``anchor`` by the arm's endpoint impedance (module
    docstring): a weld in MuJoCo's direct format with a fixed impedance d = 0.5, whose rows then
    give a force 2 k r / A_t and a torque k s^2 theta / (2 A_r) (measured on this scene's wrists:
    tests/test_hands.py), for the direct stiffness k, the torque scale s and the wrist's
    translational and rotational inverse weights ``invweight`` = (A_t, A_r)
    (MjModel.body_invweight0 of ``wrist``). So k = stiffness A_t / 2, b = damping A_t / 2 and
    s = sqrt(2 rot_stiffness A_r / k)."""
    a_t, a_r = (float(v) for v in invweight)
    k = 0.5 * arm.stiffness_n_per_m * a_t
    b = 0.5 * arm.damping_ns_per_m * a_t
    scale = math.sqrt(2.0 * arm.rot_stiffness_nm_per_rad * a_r / k)
    weld = spec.add_equality(name=f"{wrist}_weld", type=mujoco.mjtEq.mjEQ_WELD,
                             objtype=mujoco.mjtObj.mjOBJ_BODY, name1=wrist, name2=anchor)
    weld.solref = [-k, -b]
    weld.solimp = [_ARM_IMPEDANCE, _ARM_IMPEDANCE, 0.001, 0.5, 2.0]
    # anchor at the wrist body's origin, relative pose the identity: the spring pulls the wrist
    # onto its anchor (the shared numeric default of equalities puts a weld's anchor 1 m along
    # body2's y, and an unset relative pose would take the press offset as the rest pose)
    weld.data[0:10] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    weld.data[10] = scale
    return weld


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
    quat_pro = prosthetic_quat(config.crossing_angle_deg)
    rest = np.asarray(config.prosthetic_wrist_pos_m, float)
    anchor = rest + press_offset(config.arm, "pro_")
    spec.worldbody.add_body(name="pro_anchor", pos=anchor.tolist(), quat=quat_pro.tolist())
    wrist = spec.worldbody.add_body(name="pro_wrist", pos=rest.tolist(), quat=quat_pro.tolist())
    wrist.add_freejoint(name="pro_arm")
    wrist.add_geom(name="pro_arm_mass", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.02, 0, 0],
                   mass=config.arm.mass_kg, contype=0, conaffinity=0, group=4)
    add_prosthetic_hand(spec, wrist, config.prosthetic, "pro_")
    if partner_pose is None:
        from softhand.hands.grasp import partner_start_pose  # the grasp is solved on this scene

        partner_pose = partner_start_pose(config)
    pos, quat = (np.asarray(v, float) for v in partner_pose)
    spec.worldbody.add_body(name="hum_base", mocap=True, pos=pos.tolist(), quat=quat.tolist())
    # The partner's arm: the hand rides a free body held to the mocap target by the arm's
    # impedance, so the scripted reach and shake are compliant (an arm, not a fixture).
    arm = spec.worldbody.add_body(name="hum_arm", pos=pos.tolist(), quat=quat.tolist())
    arm.add_freejoint(name="hum_arm")
    arm.add_geom(name="hum_arm_mass", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.02, 0, 0],
                 mass=config.partner_arm.mass_kg, contype=0, conaffinity=0, group=4)
    add_partner_hand(spec, arm, config.partner, "hum_")
    # what the partner feels is the other hand: its feel sensors match contacts with the sensored
    # hand's subtree only, not its own thumb on its fingers (constants.PARTNER_SELF_BITS)
    for sensor in spec.sensors:
        if sensor.name.startswith("hum_feel_"):
            sensor.reftype, sensor.refname = mujoco.mjtObj.mjOBJ_XBODY, "pro_wrist"
    for body in spec.bodies:
        if body.name.startswith(("hum_", "pro_")):
            body.gravcomp = 1.0  # each arm carries its hand's weight
    # the welds' gains need the wrists' inverse weights, which MuJoCo computes at compile time
    # (3 ms for this scene): compiled once without them
    model = spec.compile()
    for wrist_body, anchor_body, arm_config in (("pro_wrist", "pro_anchor", config.arm),
                                                ("hum_arm", "hum_base", config.partner_arm)):
        add_arm(spec, wrist_body, anchor_body, arm_config,
                tuple(model.body_invweight0[model.body(wrist_body).id]))
    return spec
