"""The handshake scene: both hands in one spec, with softhand's simulation options.

World frame: +Z up, gravity along -Z, no floor. The prosthetic hand (prefix ``pro_``) is fixed to
the world through the body ``pro_wrist`` in a handshake pose: fingers along +X, thumb up (+Z), palm
facing +Y. The partner hand (prefix ``hum_``) rides the free body ``hum_arm``, held by a soft weld
(the arm's compliance) to the mocap target ``hum_base``, and faces it:
fingers along -X, thumb up, palm facing -Y. The env drives ``hum_base``: from its start pose
(where the scene places it) to partner_contact_pose() (reach), shakes it, and takes it back.

Contact pose: the palmar surfaces touch (along Y) and the hands overlap along X so that each hand's
wrist crease lies at the other hand's PIP line (middle finger): each hand's proximal phalanges lie
across the other's palm heel, around which its fingers wrap onto the back of the other hand when
they flex, as in a full-enclosure handshake (paper: forces > 2 N on palm, back of palm, thumb and
the proximal/middle phalanges). An approximation of an antiparallel handshake; real hands cross at
an angle.
"""

from __future__ import annotations

import mujoco
import numpy as np

from softhand.hands.config import SceneConfig
from softhand.hands.layout import hand_layout
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
    "PARTNER_QUAT",
    "PROSTHETIC_QUAT",
    "partner_contact_pose",
    "partner_start_pose",
    "scene_spec",
]

#: Hand frame -> world: prosthetic x -> +X, y (radial) -> +Z, z (dorsal) -> -Y.
PROSTHETIC_QUAT: tuple[float, ...] = tuple(
    quat_from_axes(np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), np.array([0, -1.0, 0]))
)
#: Hand frame -> world: partner x -> -X, y (radial) -> +Z, z (dorsal) -> +Y.
PARTNER_QUAT: tuple[float, ...] = tuple(
    quat_from_axes(np.array([-1.0, 0, 0]), np.array([0, 0, 1.0]), np.array([0, 1.0, 0]))
)


def partner_contact_pose(config: SceneConfig | None = None) -> tuple[np.ndarray, np.ndarray]:
    """World position (m) and quaternion of ``hum_base`` when the two hands are in full contact."""
    config = config or SceneConfig()
    pro = hand_layout(config.prosthetic.hand)
    hum = hand_layout(config.partner.hand)
    offset = np.array(
        [
            0.5 * (pro.pip_x_m() + hum.pip_x_m()),  # each wrist crease at the other's PIP line
            0.5 * (pro.thickness_m + hum.thickness_m),  # palmar surfaces touch along Y
            0.0,
        ]
    )
    return np.asarray(config.prosthetic_wrist_pos_m, float) + offset, np.array(PARTNER_QUAT)


def partner_start_pose(config: SceneConfig | None = None) -> tuple[np.ndarray, np.ndarray]:
    """World position (m) and quaternion of ``hum_base`` at the start of a handshake."""
    config = config or SceneConfig()
    pos, quat = partner_contact_pose(config)
    return pos + np.asarray(config.partner_start_offset_m, float), quat


def scene_spec(config: SceneConfig | None = None) -> mujoco.MjSpec:
    """Build the handshake scene: options, both hands, the partner at its start pose.

    Args:
        config: the scene; default SceneConfig().

    Returns:
        A new MjSpec (not compiled).
    """
    config = config or SceneConfig()
    if not isinstance(config, SceneConfig):
        raise ValueError(f"config = {config!r}: expected a SceneConfig")
    spec = new_spec(
        "softhand_handshake", timestep_s=config.timestep_s, gravity_m_s2=config.gravity_m_s2
    )
    spec.worldbody.add_light(name="key_light", pos=[0.1, -0.5, 1.8], dir=[0.0, 0.5, -1.0])
    wrist = spec.worldbody.add_body(
        name="pro_wrist",
        pos=[float(v) for v in config.prosthetic_wrist_pos_m],
        quat=list(PROSTHETIC_QUAT),
    )
    add_prosthetic_hand(spec, wrist, config.prosthetic, "pro_")
    pos, quat = partner_start_pose(config)
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
    for body in spec.bodies:
        if body.name.startswith("hum_"):
            body.gravcomp = 1.0  # the arm carries the hand's weight
    return spec
