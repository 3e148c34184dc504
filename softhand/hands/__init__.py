"""Procedural MuJoCo hands for the handshake scene (stage 3 of softhand; imports softhand.paper only).

- constants: published anthropometry, joint ranges, commercial prosthetic hand specs, with references.
- config: typed, validated dataclasses (SI units) for the hands and the scene.
- layout: the numbers (joint positions, lengths, radii, masses) derived from a HandConfig.
- skeleton: bodies, joints and bones shared by both hands.
- prosthetic: the 6-motor prosthetic right hand with the paper's 18 sensored skin regions.
- partner: the partner's human right hand on a mocap mount, with tissue contact geoms.
- scene: both hands in one spec, facing each other for a handshake.
- mjcf: the generated files in models/mjcf.
"""

from softhand.hands.config import (
    ArmConfig,
    HandConfig,
    PartnerConfig,
    ProstheticConfig,
    SceneConfig,
)
from softhand.hands.grasp import Grasp, partner_contact_pose, partner_start_pose, solve_grasp
from softhand.hands.layout import HandLayout, hand_layout
from softhand.hands.mjcf import write_mjcf
from softhand.hands.partner import (
    add_partner_hand,
    build_partner_hand,
    partner_actuators,
    partner_tissue_geoms,
)
from softhand.hands.prosthetic import (
    RegionInfo,
    add_prosthetic_hand,
    build_prosthetic_hand,
    prosthetic_actuators,
    regions,
)
from softhand.hands.scene import scene_spec

__all__ = [
    "ArmConfig",
    "Grasp",
    "HandConfig",
    "HandLayout",
    "PartnerConfig",
    "ProstheticConfig",
    "RegionInfo",
    "SceneConfig",
    "add_partner_hand",
    "add_prosthetic_hand",
    "build_partner_hand",
    "build_prosthetic_hand",
    "hand_layout",
    "partner_actuators",
    "partner_contact_pose",
    "partner_start_pose",
    "partner_tissue_geoms",
    "prosthetic_actuators",
    "regions",
    "scene_spec",
    "solve_grasp",
    "write_mjcf",
]
