"""The handshake grasp, solved from what touches: both hands' postures and their relative pose.

A handshake is defined by its contacts, not by a clearance rule. Descriptions used:

- [Cabibihan09/11] the paper (Fig. 1, Fig. 4; "the areas that envelope the handshaking partner's
  hand for a full grasp": palm, back of palm, thumb, the little finger's proximal phalanx and the
  middle phalanges of the little, ring and middle fingers);
- [Napier56] Napier JR (1956). The prehensile movements of the human hand. J Bone Joint Surg Br
  38-B(4):902-913: a power grip wraps the fingers round the object, the palm opposing them and the
  thumb closing over the fingers' side of the object;
- [Chaplin00] Chaplin WF, Phillips JB, Brown JD, Clanton NR, Stein JL (2000). Handshaking, gender,
  personality, and first impressions. J Pers Soc Psychol 79(1):110-117: a full handshake grips the
  whole hand, web to web, rather than the fingers alone (their coders' criteria: completeness of
  grip, strength, duration, vigour, eye contact);
- assumption (no published kinematic description found): each thumb lies over the back of the
  other hand's index metacarpal and first web space, the usual clinical and etiquette description.

Targets (residuals of a least-squares problem, lengths in m; `solve_grasp`):

- palms: each prosthetic palmar piece (Palm1, Palm2) touches the partner's palmar tissue, pressed
  ``press_m``; the two palm normals are opposite (weighted ``palm_align_weight``: at 0.02, the
  weight before, the default grasp rolled the partner's palm 14.5 deg onto one edge of the
  prosthetic palm and the palms carried none of the handshake's force; at the shipped 0.2 they
  lie parallel and pressed, reports/palm-alignment.md)
- web spaces: the two web points (radial border of the index metacarpal, half-way between the
  thumb's CMC and the index MCP) coincide in the plane of the palms
- thumbs: each thumb's pad on the back of the other hand's index metacarpal (60 % of its length from
  the CMC, on the dorsal skin plane)
- fingers: each phalanx touches the other hand (gap penalised beyond ``press_m``); each fingertip
  past the other hand's mid-plane onto its back (one-sided)
- penetration: no soft piece pressed more than ``max_depth_m`` into a piece of the other hand; bones
  of the two hands at least ``bone_clearance_m`` apart
- self-contact: no piece of a hand inside another piece of the same hand (thumb on fingers,
  neighbouring fingers)
- joint limits: hard bounds: the partner's joints stay ``limit_margin_deg`` inside their human range
  ([AAOS65]), the prosthetic's motors inside theirs
- posture prior: a weak pull towards a relaxed mid-flexion posture, so the problem is well posed

The solution is found in two stages: first without the penetration and self-contact terms (the
digits reach their targets through whatever lies between), then with them (each digit settles
on the near side of what it would pass through: the thumbs stay over the other hand's back).
Both stages run from each of five starts, and the grasp is the cheapest (`_solve_starts`): the
targets leave local minima (a finger on one side of a neighbour or the other), and the first
start that met the acceptance could be 20 % dearer and 38 deg away from the cheapest. From the
cheapest start the solver hops to cheaper minima nearby (`_hop`: every other hop moves one digit
alone, the others the whole problem), in two searches of their own seeds (_HOP_SEEDS), and
keeps the cheaper: with the starts alone, finite differences found another minimum 2-10 deg
away on 9 of 34 pairs of hands; reports/grasp-agreement.md says how far the two solvers, and
other hop seeds, now lie apart.

Variables: the partner hand frame's pose relative to the prosthetic hand frame (position, and a
rotation vector about the starting orientation), the partner's 16 digit joints (wrist at 0), the
prosthetic's 6 motors (coupled joints follow their equalities). Solved with
``mujoco.minimize.least_squares`` (box bounds) and an analytic Jacobian: a point's from its body's
Jacobian (mj_jacBody), a distance's from its witness points (the envelope theorem), the partner's
rotation through SO(3)'s left Jacobian. Cached per SceneConfig.

Cost: nearly all the time is geom distances. A pair is measured only where its bounding spheres
can reach the residual's threshold (a convex overlap is at most as deep as its spheres'; the other
pairs' terms are exactly zero: tests/test_grasp.py measures every pair against it). Until the
analytic Jacobian, finite differences took 29 residuals an iteration and a start 1.0-1.6 s; now
about 0.2-0.4 s a start (five starts a grasp), with a cost as low or lower on every hand size
measured.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import mujoco
import numpy as np
from mujoco import minimize

from softhand.hands import constants as const
from softhand.hands.config import SceneConfig
from softhand.hands.envelope import hand_pieces
from softhand.hands.layout import HandLayout, hand_layout
from softhand.hands.partner import PARTNER_JOINTS
from softhand.hands.scene import partner_quat, prosthetic_quat, scene_spec, web_point
from softhand.hands.skeleton import add_piece
from softhand.io import atomic_write_text
from softhand.paths import cache_dir

#: The envelope pieces (palm="quarters") whose shapes measure the palms' target: the palmar face of
#: the prosthetic palm's surface, proximal and distal half
_PALM_PROBES = ("palm_proximal", "palm_distal")

__all__ = [
    "GRASP_SETTINGS",
    "PROSTHETIC_MOTOR_JOINTS",
    "Grasp",
    "GraspSettings",
    "grasp_metrics",
    "partner_contact_pose",
    "partner_start_pose",
    "set_grasp_state",
    "solve_grasp",
]

#: The prosthetic's motor-driven joints (short names), in the order of Grasp.prosthetic_q.
PROSTHETIC_MOTOR_JOINTS: tuple[str, ...] = (
    *(f"{f}_mcp" for f in const.FINGERS), "thumb_mcp", "thumb_rot",
)


@dataclass(frozen=True)
class GraspSettings:
    """Weights and allowances of the grasp's least-squares problem (lengths in m).

    Attributes:
        press_m: how far a touching soft piece is pressed into the other hand at the grasp (light
            touch: the grip presses further).
        max_depth_m: deepest allowed overlap of two soft pieces of the two hands at the grasp.
        bone_clearance_m: smallest distance between the two hands' bones.
        limit_margin_deg: the partner's joints stay this far inside their human range, so that no
            joint holds the grasp at its stop (a fist is a posture at the stops).
        max_iter: iterations per stage.
        palm_align_weight: weight of the palms' parallelism target (its residual: the sum of the
            two palm normals, about the angle between the palms in rad, times this; against
            5 x each palm probe's distance in m, so 0.2 makes 1.4 deg of roll cost about as
            much as 1 mm of press). Shipped 0.2: the default grasp holds the palms parallel
            (1.4 deg) and they press each other through the handshake (palm on palm 4-5 % of
            the force between the hands, seeds 0-4). At 0.02, the weight before, the grasp
            rolled the partner's palm 14.5 deg onto one edge of the prosthetic palm and the
            palms carried 0.0 % (reports/palm-alignment.md compares 0.02 and 0.2; 0.3 in its
            history). With the palms parallel the largest partners' fingers close over their
            own thumb on the other hand's back: the partner's thumb holds its MCP and IP and its
            grip may flex a joint to 7 deg from its stop (softhand.envs.partner.THUMB_HOLDS,
            GRIP_LIMIT_MARGIN_DEG).
    """

    press_m: float = 0.001
    max_depth_m: float = 0.003
    bone_clearance_m: float = 0.004
    limit_margin_deg: float = 10.0
    max_iter: int = 200
    palm_align_weight: float = 0.2


GRASP_SETTINGS = GraspSettings()
#: A grasp whose cost (0.5 |r|^2, m^2) is under this met its targets (the default hands: 3e-4,
#: the posture prior's pull); above it a start was caught in a local minimum (1.6e-2 and 2.3e-2:
#: a partner finger between the palms). The grasp is the cheapest start (`_solve_starts`).
GOOD_COST_M2 = 1e-3
#: Slack of the bounding-sphere pruning (m): a pair is measured unless its spheres' gap exceeds
#: the threshold by this much, so that no rounding in the distance routine changes a residual.
_PRUNE_M = 1e-6
#: Levenberg-Marquardt's regularizer factor per rejected or accepted step (mujoco.minimize's
#: default is 10^0.1): each rejected step costs a residual, and the grasp's cost is flat in the
#: posture (the prior's weak pull), so a coarser factor finds the step in fewer tries; measured on
#: the default hands, the +-2.5 SD corners and 6 sampled partners: 10^0.5 reached a cost as low as
#: or lower than 10^0.1 in each, 0.35-0.5 s a grasp instead of 0.4-0.7 s.
_MU_FACTOR = 10.0 ** 0.5
#: The hops after the starts (`_hop`): each perturbs the best grasp found by a normal draw of
#: these scales (the partner's position, its rotation vector, every joint), times the next of
#: _HOP_TIERS in turn, from a generator of one of _HOP_SEEDS, solves the contact stage from there,
#: and keeps a cheaper answer; the search stops after _HOP_PATIENCE hops in a row find nothing
#: cheaper (by _HOP_GAIN, relative), or at _HOP_MAX. The minima the starts leave lie a few
#: degrees apart (a finger on one side of a neighbour or the other, 0.1-3 % in cost), some up to
#: 10 mm and 8 deg apart in the partner's pose, at the small corners up to 29 deg and 15 % apart:
#: a hop of about 5 deg per joint crosses to the near ones, a wider one to the far. Chosen on the
#: pairs of hands where two solvers or two seeds disagreed (tools/grasp_agreement.py): patience 4
#: left 3 of 11 apart; tiers (1, 3) and patience 16 left 3 of 34 to another seed, 6-10 mm away
#: and 0.2-1.3 % in cost, which tiers (1, 3, 6) and patience 24 reach: all 30 sampled partners
#: within 0.7 deg and 0.3 mm of both checks, the 159 x 73 mm corner still apart (seed 1 stops
#: 2.1 % dearer; finite differences start in a basin 23 % dearer); narrow hops alone missed the
#: 159 x 107 mm corner's minimum 15 % cheaper. A grasp costs about 6-21 s with the two
#: searches of _HOP_SEEDS (1.5-2.5 s with the starts alone; then it is cached).
#: The hop searches of a grasp, one per seed from the same cheapest start; the grasp is the
#: cheapest they reach. With the palms held parallel (palm_align_weight 0.2) the minima lie
#: further apart: one search (seed 0) left two partners near the experimenter's size
#: (190 x 92 and 190 x 97 mm) in minima 45-56 % dearer and 43-57 deg from the one that finite
#: differences and seed 1 both found (reports/grasp-agreement.md).
#: Every other hop moves one digit alone (`_Problem.digits`: a partner digit's joints, or a
#: prosthetic digit's motors), each of its joints by a normal draw of the next of
#: _HOP_DIGIT_RAD in turn: the minima that whole-hand hops could not reach differ in one finger
#: (a 161 x 88 mm partner's ring PIP 40 deg apart, 23 % in cost: finite differences stayed there
#: through 24 whole-hand hops in a row), and the near ties a few degrees apart (204 x 81 and
#: 199 x 85 mm: 2.2-2.5 deg between hop seeds, within 0.03 % in cost) are one finger's posture
#: on either side of a kink (the palms' press is a distance between polyhedra, piecewise in the
#: pose, and the solver stops where it bends). With one width (0.5 rad) and a patience of 24,
#: finite differences and other seeds agreed within 2 deg on 32 of 34 pairs of hands (the
#: 216 x 73 mm corner's seeds 2 and 3 stayed at its cheapest start, 10 % dearer; a 201 x 73 mm
#: partner's finite differences 2.1 deg away); a narrower width beside it (0.1 rad) and a
#: patience of 36 (18 hops of each kind) reach both.
_HOP_SEEDS = (0, 1)
_HOP_POS_M = 0.002
_HOP_TURN_RAD = 0.03
_HOP_JOINT_RAD = 0.08
_HOP_DIGIT_RAD = (0.5, 0.1)
_HOP_PATIENCE = 36
_HOP_MAX = 90
_HOP_TIERS = (1.0, 3.0, 6.0)
_HOP_GAIN = 1e-6
#: Forward-difference step of the finite-difference solver (the check of the analytic one, in
#: units of max(1, |x|)): the distances are accurate to ccd_tolerance (1e-6 m), so
#: mujoco.minimize's default (1.5e-8) differences their noise and stalls short of the minimum
#: (0.1-0.3 % dearer, 2-4 deg away, where the analytic gradient is 3000x the minimum's); 1e-6
#: reaches the analytic solver's minima.
FD_EPS = 1e-6
#: Starts whose costs differ by less than this (relative) reached the same minimum: the first wins
_TIE = 1e-9


@dataclass(frozen=True)
class Grasp:
    """A solved handshake grasp.

    Attributes:
        partner_pos_m, partner_quat: the partner hand frame (its wrist crease, wrist at 0) in the
            world, for the SceneConfig's prosthetic wrist pose.
        partner_q: partner joint angles (rad) in the order of partner.PARTNER_JOINTS.
        prosthetic_q: prosthetic motor joint angles (rad) in the order of PROSTHETIC_MOTOR_JOINTS.
        cost: final cost (0.5 |r|^2, m^2); iterations: per stage.
        metrics: what the grasp achieves (grasp_metrics), in mm and deg.
        touching_phalanges: the partner's phalanges (tissue names without prefix) within
            2 x press_m of the prosthetic hand at the grasp.
        settings: the settings it was solved with.
    """

    partner_pos_m: np.ndarray
    partner_quat: np.ndarray
    partner_q: np.ndarray
    prosthetic_q: np.ndarray
    cost: float
    iterations: tuple[int, ...]
    metrics: dict = field(default_factory=dict)
    touching_phalanges: tuple[str, ...] = ()
    settings: GraspSettings = GRASP_SETTINGS


def _rotvec_quat(rotvec: np.ndarray) -> np.ndarray:
    quat = np.zeros(4)
    mujoco.mju_axisAngle2Quat(quat, rotvec / max(np.linalg.norm(rotvec), 1e-300),
                              float(np.linalg.norm(rotvec)))
    return quat


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, a, b)
    return out


class _Problem:
    """The grasp's model, variables and residuals for one SceneConfig."""

    def __init__(self, config: SceneConfig, settings: GraspSettings) -> None:
        self.config, self.s = config, settings
        if config.prosthetic.palm != "surface":  # the palm's skin does not change the grasp
            config = replace(config, prosthetic=replace(config.prosthetic, palm="surface"))
        self.pro, self.hum = hand_layout(config.prosthetic.hand), hand_layout(config.partner.hand)
        pos0, quat0 = _web_to_web_pose(config, self.pro, self.hum)
        spec = scene_spec(config, partner_pose=(pos0, quat0))
        # the grasp measures the prosthetic palm's surface by its four quarters (their hull is
        # the surface): the palms' target at the two palmar quarters, so that the palms press
        # across their width, and the gaps and penetrations of each quarter. Probe geoms of the
        # quarters' shapes, in this problem's model only (no contact, no pair: the scene has one
        # palm skin), keep the grasp's definition as it was when the palm was four skins
        palm = spec.body("pro_palm")
        for piece in hand_pieces(self.pro, palm="quarters"):
            if piece.body == "palm":
                add_piece(spec, palm, piece, f"pro_probe_{piece.name}", contype=0, conaffinity=0,
                          mass=0.0, group=5)
        m = spec.compile()
        m.opt.ccd_tolerance = 1e-6  # accurate distances and witness points (the Jacobian)
        self.m, self.d = m, mujoco.MjData(m)
        self.pos0, self.quat0 = pos0, quat0
        name = lambda i: m.geom(i).name  # noqa: E731
        geoms = range(m.ngeom)
        self.pro_soft = [g for g in geoms if name(g).startswith(("pro_skin_", "pro_probe_"))
                         and name(g) != "pro_skin_Palm"]
        # the hand's pieces only: the forearm's tissue is not a target of the grasp
        self.hum_soft = [g for g in geoms if name(g).startswith("hum_tissue_")
                         and name(g) != "hum_tissue_forearm"]
        self.pro_bone = [g for g in geoms if name(g).startswith("pro_bone_")]
        self.hum_bone = [g for g in geoms if name(g).startswith("hum_bone_")]
        gid = lambda n: m.geom(n).id  # noqa: E731
        self.pro_palms = [gid(f"pro_probe_{p}") for p in _PALM_PROBES]
        self.hum_palm = gid("hum_tissue_palm")
        self.arm_qpos = int(m.jnt_qposadr[m.joint("hum_arm").id])
        self.hum_qpos = np.array([m.jnt_qposadr[m.joint(f"hum_{j}").id]
                                  for j in PARTNER_JOINTS])
        self.pro_qpos = np.array([m.jnt_qposadr[m.joint(f"pro_{j}").id]
                                  for j in PROSTHETIC_MOTOR_JOINTS])
        self.pro_palm_body = m.body("pro_palm").id
        self.hum_palm_body = m.body("hum_palm").id
        self.couplings = _couplings(m)
        self.pads = {(prefix, digit): _pad_frame(m, prefix, digit, layout)
                     for prefix, layout in (("pro_", self.pro), ("hum_", self.hum))
                     for digit in ("thumb", *const.FINGERS)}
        self.web_pro, self.web_hum = web_point(self.pro), web_point(self.hum)
        self.dorsal_pro, self.dorsal_hum = _dorsal_index(self.pro), _dorsal_index(self.hum)
        # self-contact pairs: thumb pieces x finger phalanges, neighbouring fingers
        self.self_pairs = np.array(_self_pairs(m, "pro_skin_", _PRO_PIECES) + _self_pairs(
            m, "hum_tissue_", _HUM_PIECES))
        self.soft_pairs = np.array([(a, b) for a in self.pro_soft for b in self.hum_soft])
        self.bone_pairs = np.array([(a, b) for a in self.pro_bone for b in self.hum_bone])
        # phalanx pieces of each hand (contact-gap residuals) and fingertip bodies
        self.pro_phalanges = [gid(f"pro_skin_{r}") for r in _PRO_PHALANGES]
        self.hum_phalanges = [gid(f"hum_tissue_{p}") for p in _HUM_PHALANGES]
        self.gap_sets = ((self.pro_phalanges, np.array(self.hum_soft)),
                         (self.hum_phalanges, np.array(self.pro_soft)))
        self.dist = np.zeros(6)
        n_hum, n_pro = len(PARTNER_JOINTS), len(PROSTHETIC_MOTOR_JOINTS)
        margin = math.radians(settings.limit_margin_deg)
        lo = [-0.08] * 3 + [-0.8] * 3
        hi = [0.08] * 3 + [0.8] * 3
        for j in PARTNER_JOINTS:
            jl, jh = m.jnt_range[m.joint(f"hum_{j}").id]
            lo.append(jl + margin)
            hi.append(jh - margin)
        for j in PROSTHETIC_MOTOR_JOINTS:
            jl, jh = m.jnt_range[m.joint(f"pro_{j}").id]
            lo.append(jl)
            hi.append(jh)
        self.bounds = (np.array(lo), np.array(hi))
        # relaxed mid-flexion prior (and starting posture)
        prior_hum = {"thumb_rot": 0.9, "thumb_cmc": 0.0, "thumb_mcp": 0.35, "thumb_ip": 0.35}
        for f in const.FINGERS:
            prior_hum.update({f"{f}_mcp": 0.7, f"{f}_pip": 0.8, f"{f}_dip": 0.5})
        self.prior = np.concatenate([
            np.zeros(6), [prior_hum[j] for j in PARTNER_JOINTS],
            [0.7, 0.7, 0.7, 0.7, 0.4, 0.3]])
        self.prior = np.clip(self.prior, *self.bounds)
        self.n = 6 + n_hum + n_pro
        # each digit's variables (the partner's joints of a digit, the prosthetic's motors of
        # one), in the order they first appear: the digit hops' moves (`_hop`)
        groups: dict[tuple[str, str], list[int]] = {}
        for i, (hand, j) in enumerate([*(("hum", j) for j in PARTNER_JOINTS),
                                       *(("pro", j) for j in PROSTHETIC_MOTOR_JOINTS)]):
            groups.setdefault((hand, j.split("_")[0]), []).append(6 + i)
        self.digits = [np.array(v) for v in groups.values()]
        self.geom_body = m.geom_bodyid.copy()
        self.arm_dof = int(m.jnt_dofadr[m.joint("hum_arm").id])
        self.dq_dx = self._joint_dofs()
        # the distances of the state last set, with their witness points (`_measure`)
        self._measured: tuple[bytes, bool, _Measured] | None = None

    def starts(self):
        """Starting points: the relaxed prior at the configured crossing, then the partner turned
        by -+0.2 rad about the palm normal and shifted -+10 mm along its own axis (a start whose
        cost stays above GOOD_COST_M2 was caught in a local minimum: a finger between the palms).
        The grasp is the cheapest of them (`_solve_starts`)."""
        yield self.prior.copy()
        normal = _rotation(prosthetic_quat(self.config.crossing_angle_deg))[:, 2]
        axis = _rotation(self.quat0)[:, 0]
        for turn, shift in ((0.2, 0.0), (-0.2, 0.0), (0.0, 0.01), (0.0, -0.01)):
            x = self.prior.copy()
            x[:3] = shift * axis
            x[3:6] = turn * normal
            yield np.clip(x, *self.bounds)

    # --- state ---------------------------------------------------------------------------------
    def pose(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.pos0 + x[:3], _quat_mul(_rotvec_quat(x[3:6]), self.quat0)

    def set_state(self, x: np.ndarray) -> None:
        m, d = self.m, self.d
        self._measured = None  # the distances measured belong to the state before
        d.qpos[:] = m.qpos0
        pos, quat = self.pose(x)
        d.qpos[self.arm_qpos:self.arm_qpos + 3] = pos
        d.qpos[self.arm_qpos + 3:self.arm_qpos + 7] = quat
        d.qpos[self.hum_qpos] = x[6:6 + len(self.hum_qpos)]
        d.qpos[self.pro_qpos] = x[6 + len(self.hum_qpos):]
        _couple(m, d, self.couplings)
        mujoco.mj_kinematics(m, d)

    def _joint_dofs(self) -> np.ndarray:
        """d(qvel)/dx (nv x n) of the variables that are joint angles: the partner's hinges, and
        each prosthetic motor with the joints coupled to it (`_couple`'s chain, q1 = c0 + c1 q2);
        the pose columns are filled per state (`_dofs`)."""
        m = self.m
        dof_of = {int(m.jnt_qposadr[j]): int(m.jnt_dofadr[j]) for j in range(m.njnt)
                  if int(m.jnt_type[j]) in (int(mujoco.mjtJoint.mjJNT_HINGE),
                                            int(mujoco.mjtJoint.mjJNT_SLIDE))}
        q = np.zeros((m.nv, self.n))
        arm = self.arm_dof
        q[arm:arm + 3, :3] = np.eye(3)  # a free joint's linear velocity is in the world frame
        n_hum = len(self.hum_qpos)
        for k, a in enumerate(self.hum_qpos):
            q[dof_of[int(a)], 6 + k] = 1.0
        for k, a in enumerate(self.pro_qpos):
            dq = {int(a): 1.0}
            for a1, a2, _, c1 in self.couplings:
                dq[a1] = c1 * dq.get(a2, 0.0)
            for adr, v in dq.items():
                q[dof_of[adr], 6 + n_hum + k] = v
        return q

    def _dofs(self, x: np.ndarray) -> np.ndarray:
        """d(qvel)/dx at ``x`` (the state set): the rotation-vector columns map through SO(3)'s
        left Jacobian to the world angular velocity, which the free joint holds in its own
        frame."""
        q = self.dq_dx.copy()
        rot = _rotation(self.d.qpos[self.arm_qpos + 3:self.arm_qpos + 7])
        q[self.arm_dof + 3:self.arm_dof + 6, 3:6] = rot.T @ _left_jacobian(x[3:6])
        return q

    def distance(self, g1: int, g2: int, cap: float = 0.05) -> float:
        """The pair's signed distance capped at ``cap`` (m); its witness points (from g1 to g2)
        are in ``self.dist`` until the next call."""
        return mujoco.mj_geomDistance(self.m, self.d, g1, g2, cap, self.dist)

    def jacobian(self, x: np.ndarray, r: np.ndarray, contacts: bool) -> np.ndarray:
        """The residual's Jacobian at ``x`` (mujoco.minimize's ``jacobian``), analytic: each
        point's from the bodies' Jacobians (mj_jacBody), each distance's from its witness points
        (the envelope theorem: d dist = n . (v2 - v1), n the unit vector from g1's witness point
        to g2's over the signed distance), each max(0, .) term's on its active side, each
        nearest gap's from its nearest pair; tests/test_grasp.py checks it against central
        differences."""
        return self.residual(np.ravel(x), contacts=contacts, jacobian=True)[1]

    def lower_bounds(self, pairs: np.ndarray) -> np.ndarray:
        """A lower bound of each pair's signed distance: the gap of the geoms' bounding spheres
        (a convex overlap is at most as deep as its bounding spheres')."""
        xpos, rbound = self.d.geom_xpos, self.m.geom_rbound
        a, b = pairs[:, 0], pairs[:, 1]
        return (np.linalg.norm(xpos[a] - xpos[b], axis=1) - rbound[a] - rbound[b])

    def distances(self, pairs: np.ndarray, cap: float, above: float,
                  witness: np.ndarray | None = None) -> np.ndarray:
        """Each pair's distance (capped at ``cap``) where it can be under ``above``; ``cap`` for
        the pairs whose bounding spheres are ``above`` + _PRUNE_M apart or more (their residual
        terms are exactly zero either way: the same residuals as measuring every pair).
        ``witness``: (len(pairs), 6), gets each measured pair's witness points."""
        out = np.full(len(pairs), cap)
        for i in np.flatnonzero(self.lower_bounds(pairs) < above + _PRUNE_M):
            out[i] = mujoco.mj_geomDistance(self.m, self.d, int(pairs[i, 0]), int(pairs[i, 1]),
                                            cap, self.dist)
            if witness is not None:
                witness[i] = self.dist
        return out

    def nearest(self, mine: list[int], others: np.ndarray, cap: float = 0.05,
                witness: list | None = None) -> list[float]:
        """Per geom of ``mine``, the smallest capped distance to ``others``: pairs in the order of
        their bounding spheres' gap, stopping where that gap passes the nearest distance found
        (the same minimum as measuring every pair). ``witness``: a list that gets, per geom, its
        nearest geom of ``others`` and their witness points (None: none within ``cap``)."""
        xpos, rbound = self.d.geom_xpos, self.m.geom_rbound
        bounds = (np.linalg.norm(xpos[mine][:, None] - xpos[others][None], axis=2)
                  - rbound[mine][:, None] - rbound[others][None])
        order = np.argsort(bounds, axis=1, kind="stable").tolist()
        bounds, others = bounds.tolist(), others.tolist()
        out = []
        for k, g in enumerate(mine):
            best, row, arg = cap, bounds[k], None
            for i in order[k]:
                if row[i] >= best + _PRUNE_M:
                    break
                dist = self.distance(g, others[i], cap)
                if dist < best:
                    best = dist
                    if witness is not None:
                        arg = (others[i], self.dist.copy())
            out.append(best)
            if witness is not None:
                witness.append(arg)
        return out

    def hand_point(self, body: int, local: np.ndarray) -> np.ndarray:
        return self.d.xpos[body] + self.d.xmat[body].reshape(3, 3) @ local

    def in_frame(self, body: int, point: np.ndarray) -> np.ndarray:
        return _in_frame(self.d, body, point)

    def pad(self, prefix: str, digit: str) -> np.ndarray:
        """World position of a digit's pad (as `_pad`)."""
        body, local = self.pads[prefix, digit]
        return self.hand_point(body, local)

    # --- residuals -----------------------------------------------------------------------------
    def _pair_terms(self) -> tuple:
        """The overlap terms, weight * max(0, offset - dist) (offset None: -dist): (pairs, cap,
        threshold of the pruning, weight, offset) of soft pieces overlapping deeper than
        max_depth_m, bones closer than bone_clearance_m, pieces of one hand overlapping."""
        s = self.s
        return ((self.soft_pairs, 0.01, -s.max_depth_m, 10.0, -s.max_depth_m),
                (self.bone_pairs, 0.02, s.bone_clearance_m, 10.0, s.bone_clearance_m),
                (self.self_pairs, 0.01, 0.0, 3.0, None))

    def _measure(self, x: np.ndarray, contacts: bool) -> _Measured:
        """The residual's distances at ``x``, with their witness points; the state is set to
        ``x``. Measured once per state: mujoco.minimize asks for the Jacobian at the point whose
        residual it has just evaluated, and the Jacobian is made from the same distances."""
        key = (np.asarray(x, float).tobytes(), contacts)
        if self._measured is not None and self._measured[:2] == key:
            return self._measured[2]
        self.set_state(x)
        palms = []
        for g in self.pro_palms:
            palms.append((self.distance(g, self.hum_palm), self.dist.copy()))
        gaps = []
        for mine, others in self.gap_sets:
            near: list = []
            gaps.append((self.nearest(mine, others, witness=near), near))
        pairs = []
        for pair_set, cap, above, _, _ in self._pair_terms() if contacts else ():
            witness = np.zeros((len(pair_set), 6))
            pairs.append((self.distances(pair_set, cap, above, witness), witness))
        measured = _Measured(palms, gaps, pairs)
        self._measured = (*key, measured)
        return measured

    def residual(self, x: np.ndarray, *, contacts: bool, jacobian: bool = False):
        """The residuals at ``x`` (module docstring's targets); with ``jacobian``, (residuals,
        their Jacobian (len(r), n)) (`jacobian`). Sets the state to ``x``."""
        measured = self._measure(x, contacts)
        s, d = self.s, self.d
        k = _Kinematics(self, x) if jacobian else None
        r: list[float] = []
        rows: list[np.ndarray] = []

        def add(values, grads=None) -> None:
            r.extend(values)
            if k is not None:
                rows.append(np.zeros((len(values), self.n)) if grads is None else grads)

        # palms: both palmar quarters of the prosthetic palm's surface pressed press_m into the
        # partner's palm
        for g, (dist, witness) in zip(self.pro_palms, measured.palms, strict=True):
            add([5.0 * (dist + s.press_m)],
                None if k is None else 5.0 * k.distance(g, self.hum_palm, dist, witness)[None])
        z_pro = d.xmat[self.pro_palm_body].reshape(3, 3)[:, 2]
        z_hum = d.xmat[self.hum_palm_body].reshape(3, 3)[:, 2]
        w_align = self.s.palm_align_weight
        add(list(w_align * (z_pro + z_hum)), None if k is None else w_align * (
            k.axis(self.pro_palm_body, z_pro) + k.axis(self.hum_palm_body, z_hum)))
        # web spaces: together in the plane of the prosthetic palm
        w_pro = self.hand_point(self.pro_palm_body, self.web_pro)
        w_hum = self.hand_point(self.hum_palm_body, self.web_hum)
        web = w_hum + d.xpos[self.pro_palm_body] - w_pro
        add(list(self.in_frame(self.pro_palm_body, web)[:2]), None if k is None else k.in_frame(
            self.pro_palm_body, web, k.point(self.hum_palm_body, w_hum)
            + k.body(self.pro_palm_body)[0] - k.point(self.pro_palm_body, w_pro))[:2])
        # thumbs over the back of the other hand's index metacarpal
        for mine, palm, target in (("hum_", self.pro_palm_body, self.dorsal_pro),
                                   ("pro_", self.hum_palm_body, self.dorsal_hum)):
            pad, point = self.pad(mine, "thumb"), self.hand_point(palm, target)
            add(list(0.5 * (pad - point)), None if k is None else 0.5 * (
                k.point(self.pads[mine, "thumb"][0], pad) - k.point(palm, point)))
        # fingertips past the other hand's mid-plane, onto its back (one-sided)
        for f in const.FINGERS:
            for mine, palm in (("hum_", self.pro_palm_body), ("pro_", self.hum_palm_body)):
                pad = self.pad(mine, f)
                z = self.in_frame(palm, pad)[2]
                add([0.2 * max(0.0, -z)], None if k is None or z >= 0.0 else -0.2 * k.in_frame(
                    palm, pad, k.point(self.pads[mine, f][0], pad))[2:])
        # every phalanx touches the other hand (gap beyond the press is penalised)
        for (mine, _), (gaps, near) in zip(self.gap_sets, measured.gaps, strict=True):
            for g, gap, arg in zip(mine, gaps, near, strict=True):
                active = gap + s.press_m > 0.0 and arg is not None
                add([0.3 * max(0.0, gap + s.press_m)], 0.3 * k.distance(
                    g, arg[0], gap, arg[1])[None] if k is not None and active else None)
        for (pairs, _, _, weight, offset), (dist, witness) in zip(  # none without contacts
                self._pair_terms() if measured.pairs else (), measured.pairs, strict=True):
            values = -dist if offset is None else offset - dist
            active = values > 0.0
            add(list(weight * np.maximum(0.0, values)), None if k is None else
                -weight * active[:, None] * k.distances(pairs, dist, witness, active))
        add(list(0.01 * (x[6:] - self.prior[6:])),
            None if k is None else 0.01 * np.eye(self.n)[6:])
        add(list(0.005 * x[3:6]), None if k is None else 0.005 * np.eye(self.n)[3:6])
        if k is None:
            return np.asarray(r)
        return np.asarray(r), np.concatenate(rows)


@dataclass
class _Measured:
    """The distances of one state of `_Problem`, with their witness points (6: on the first geom,
    on the second): the palms' (distance, witness); per gap set, (the nearest gaps, per geom its
    nearest geom and witness or None); per overlap term (`_Problem._pair_terms`, with contacts),
    (distances, witness rows)."""

    palms: list[tuple[float, np.ndarray]]
    gaps: list[tuple[list[float], list]]
    pairs: list[tuple[np.ndarray, np.ndarray]]


class _Kinematics:
    """Jacobians (d/dx, through `_Problem._dofs`) of points, axes and distances at the state that
    `_Problem.set_state` set; each body's Jacobian is computed once."""

    def __init__(self, problem: _Problem, x: np.ndarray) -> None:
        self.p = problem
        mujoco.mj_comPos(problem.m, problem.d)  # the motion subspaces mj_jacBody needs
        self.dofs = problem._dofs(x)
        self._bodies: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._jp, self._jr = np.zeros((3, problem.m.nv)), np.zeros((3, problem.m.nv))

    def body(self, b: int) -> tuple[np.ndarray, np.ndarray]:
        """(d origin / dx, d angle / dx): 3 x n each, the angle's in the world frame."""
        if b not in self._bodies:
            mujoco.mj_jacBody(self.p.m, self.p.d, self._jp, self._jr, b)
            self._bodies[b] = (self._jp @ self.dofs, self._jr @ self.dofs)
        return self._bodies[b]

    def point(self, b: int, point: np.ndarray) -> np.ndarray:
        """d point / dx of a point fixed to body ``b`` (v = v_origin + w x r)."""
        jp, jr = self.body(b)
        return jp - _skew(point - self.p.d.xpos[b]) @ jr

    def axis(self, b: int, axis: np.ndarray) -> np.ndarray:
        """d axis / dx of a unit vector fixed to body ``b`` (w x axis)."""
        return -_skew(axis) @ self.body(b)[1]

    def in_frame(self, b: int, point: np.ndarray, dpoint: np.ndarray) -> np.ndarray:
        """d/dx of `_in_frame`(b, point), ``dpoint`` the point's d/dx: R^T (dpoint - the
        velocity of the point of b that lies there)."""
        return self.p.d.xmat[b].reshape(3, 3).T @ (dpoint - self.point(b, point))

    def distance(self, g1: int, g2: int, dist: float, witness: np.ndarray) -> np.ndarray:
        """d dist / dx of the signed distance of geoms g1, g2 with its witness points (zero where
        the points coincide: no direction)."""
        gap = witness[3:] - witness[:3]
        if abs(dist) < 1e-12:
            return np.zeros(self.p.n)
        body = self.p.geom_body
        return (gap / dist) @ (self.point(body[g2], witness[3:])
                               - self.point(body[g1], witness[:3]))

    def distances(self, pairs: np.ndarray, dist: np.ndarray, witness: np.ndarray,
                  active: np.ndarray) -> np.ndarray:
        """d dist / dx of each pair (rows; zero where not ``active``)."""
        out = np.zeros((len(pairs), self.p.n))
        for i in np.flatnonzero(active):
            out[i] = self.distance(int(pairs[i, 0]), int(pairs[i, 1]), float(dist[i]), witness[i])
        return out


def _skew(v: np.ndarray) -> np.ndarray:
    """[v]x: _skew(v) @ w = v x w."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _left_jacobian(rotvec: np.ndarray) -> np.ndarray:
    """SO(3)'s left Jacobian at ``rotvec``: exp(rotvec + du) = exp(J du) exp(rotvec) to first
    order, so J du is the world-frame rotation of a step du (Sola, Deray, Atchuthan 2018, "A
    micro Lie theory for state estimation in robotics", arXiv:1812.01537, eq. 145)."""
    theta = float(np.linalg.norm(rotvec))
    k = _skew(rotvec)
    if theta < 1e-6:  # series: I + K/2 + K^2/6
        return np.eye(3) + 0.5 * k + k @ k / 6.0
    return (np.eye(3) + (1.0 - math.cos(theta)) / theta ** 2 * k
            + (theta - math.sin(theta)) / theta ** 3 * k @ k)


#: The prosthetic's skin pieces by digit (self-contact pairs) and its phalanx regions.
_PRO_PIECES = {"thumb": ("Thenar", "Thumb1", "Thumb2"),
               **{f: tuple(f"{f.capitalize()}{i}" for i in (1, 2, 3)) for f in const.FINGERS}}
_HUM_PIECES = {"thumb": ("thumb_metacarpal", "thumb_proximal", "thumb_distal"),
               **{f: tuple(f"{f}_{s}" for s in ("proximal", "middle", "distal"))
                  for f in const.FINGERS}}
_PRO_PHALANGES = tuple(p for k, v in _PRO_PIECES.items() for p in v if p != "Thenar")
_HUM_PHALANGES = tuple(p for k, v in _HUM_PIECES.items() for p in v if p != "thumb_metacarpal")


def _self_pairs(m: mujoco.MjModel, prefix: str, pieces: dict) -> list[tuple[int, int]]:
    """Geom pairs of one hand that must not overlap: thumb x finger pieces, neighbouring fingers."""
    gid = lambda n: m.geom(f"{prefix}{n}").id  # noqa: E731
    pairs = [(gid(a), gid(b)) for a in pieces["thumb"] for f in const.FINGERS for b in pieces[f]]
    for f1, f2 in zip(const.FINGERS[:-1], const.FINGERS[1:], strict=True):
        pairs += [(gid(a), gid(b)) for a in pieces[f1] for b in pieces[f2]]
    return pairs


def _dorsal_index(layout: HandLayout) -> np.ndarray:
    """Target of the other thumb's pad in a hand's frame: on the dorsal skin plane over the index
    metacarpal, 60 % of its length from the CMC (near the first web space)."""
    idx = layout.digits["index"]
    cmc, base = np.asarray(idx.cmc_m, float), np.asarray(idx.base_m, float)
    p = cmc + 0.6 * (base - cmc)
    return np.array([p[0], p[1], 0.5 * layout.thickness_m])


def _web_to_web_pose(config: SceneConfig, pro: HandLayout,
                     hum: HandLayout) -> tuple[np.ndarray, np.ndarray]:
    """Starting pose of the partner hand frame: web points together, palmar planes touching, the
    hands crossed at SceneConfig.crossing_angle_deg."""
    quat = partner_quat(config.crossing_angle_deg)
    r_pro, r_hum = _rotation(prosthetic_quat(config.crossing_angle_deg)), _rotation(quat)
    wrist = np.asarray(config.prosthetic_wrist_pos_m, float)
    pos = wrist + r_pro @ web_point(pro) - r_hum @ web_point(hum)
    # palmar planes touching: the partner's mid-plane half a thickness beyond each palm surface
    normal = r_pro[:, 2]  # prosthetic dorsal direction; its palm faces -normal
    offset = float(normal @ (pos - wrist))
    pos += normal * (-0.5 * (pro.thickness_m + hum.thickness_m) - offset)
    return pos, quat


def _rotation(quat: np.ndarray) -> np.ndarray:
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat, float))
    return mat.reshape(3, 3)


def _solve(problem: _Problem, x0: np.ndarray, contacts: bool, max_iter: int, *,
           finite_differences: bool = False):
    """One stage of the grasp from ``x0``: mujoco.minimize.least_squares with the analytic
    Jacobian (`_Problem.jacobian`), or, with ``finite_differences``, mujoco.minimize's own
    forward differences (the check that the analytic one changes no answer)."""
    def fun(x: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(x.T).T
        return np.stack([problem.residual(x[:, k], contacts=contacts)
                         for k in range(x.shape[1])], axis=1)

    jac = {"eps": FD_EPS} if finite_differences else {
        "jacobian": lambda x, r: problem.jacobian(x, r, contacts)}
    return minimize.least_squares(
        x0, fun, bounds=problem.bounds, mu_factor=_MU_FACTOR, max_iter=max_iter, verbose=0,
        xtol=1e-6, **jac)


def solve_grasp(config: SceneConfig | None = None,
                settings: GraspSettings | None = None) -> Grasp:
    """Solve the handshake grasp of the scene's two hands (cached per config and settings, in
    this process and on disk: a solution in softhand.paths.cache_dir() is read back instead of
    solved, bit for bit the same; a population's partners, or a sweep over skins and controllers,
    solve each hand size once per machine).

    Args:
        config: the scene (both hands' sizes, the prosthetic wrist pose, the starting crossing
            angle); default SceneConfig().
        settings: weights and allowances; None: the module's `GRASP_SETTINGS` as it is at the
            call (an experiment may replace it, as tools/palm_alignment.py does: the cache key
            holds the settings, so no other setting's grasp is read back).

    Returns:
        The grasp: the partner's pose and posture, the prosthetic's motor posture, and
        grasp_metrics() of the solution.
    """
    return _solve_grasp(config or SceneConfig(), settings or GRASP_SETTINGS)


@functools.lru_cache(maxsize=64)
def _solve_grasp(config: SceneConfig, settings: GraspSettings) -> Grasp:
    """`solve_grasp` of a given config and settings, cached in this process (its
    ``__wrapped__`` reads and writes the disk cache only)."""
    problem = _Problem(config, settings)
    path = _cache_path(config, settings)
    known = _read_cached(path, problem.n)
    if known is not None and not _cached_cost_holds(problem, *known[:2]):
        known = None  # an entry whose variables do not give its cost: solved again, rewritten
    if known is not None:
        cost, x, iterations = known
    else:
        cost, x, iterations = _solve_starts(problem, settings)
        _write_cached(path, cost, x, iterations)
    problem.set_state(x)
    pos, quat = problem.pose(x)
    n_hum = len(PARTNER_JOINTS)
    metrics = grasp_metrics(problem.m, problem.d, problem.pro, problem.hum)
    touching = tuple(
        problem.m.geom(g).name.removeprefix("hum_tissue_") for g in problem.hum_phalanges
        if min(problem.distance(g, o) for o in problem.pro_soft) < 2 * settings.press_m)
    return Grasp(partner_pos_m=pos, partner_quat=quat, partner_q=x[6:6 + n_hum].copy(),
                 prosthetic_q=x[6 + n_hum:].copy(), cost=cost, iterations=tuple(iterations),
                 metrics=metrics, touching_phalanges=touching, settings=settings)


def _start_runs(problem: _Problem, settings: GraspSettings, *,
                finite_differences: bool = False) -> list[tuple[float, np.ndarray, list[int]]]:
    """Every start (`_Problem.starts`) solved to the end, both stages: per start (cost,
    variables, iterations per stage), in the order of the starts."""
    runs = []
    for start in problem.starts():
        x, iterations = start, []
        for contacts in (False, True):
            x, trace = _solve(problem, x, contacts, settings.max_iter,
                              finite_differences=finite_differences)
            iterations.append(len(trace))
        runs.append((0.5 * float(np.sum(problem.residual(x, contacts=True) ** 2)), x,
                     iterations))
    return runs


def _solve_starts(problem: _Problem, settings: GraspSettings, *,
                  finite_differences: bool = False, seeds: tuple[int, ...] = _HOP_SEEDS,
                  ) -> tuple[float, np.ndarray, list[int]]:
    """The grasp: the cheapest of all starts (`_start_runs`), then hops from it to any cheaper
    minimum nearby (`_hop`), one search per seed of ``seeds``, the cheapest kept (the first of
    ties): (cost, variables, iterations per stage).

    The cheapest, not the first that meets GOOD_COST_M2: the targets leave local minima a few
    per cent apart in cost (a finger on one side of a neighbour or the other) whose postures
    differ by up to 38 deg, and a grasp that depends on the order of the starts is not one
    answer. The starts alone left it to the solver: on 9 of 34 pairs of hands the
    finite-difference solver's cheapest start lay 2-10 deg from the analytic one's; the hops
    close most of that (tools/grasp_agreement.py, reports/grasp-agreement.md: the pairs where
    a solver or a seed still lands elsewhere)."""
    runs = _start_runs(problem, settings, finite_differences=finite_differences)
    # starts that reach the same minimum tie to rounding (1e-13 of the cost): the first of them
    lowest = min(r[0] for r in runs)
    best = next(r for r in runs if r[0] <= lowest * (1.0 + _TIE))
    found = [_hop(problem, settings, best, finite_differences=finite_differences, seed=seed)
             for seed in seeds]
    cheapest = min(f[0] for f in found)
    return next(f for f in found if f[0] <= cheapest * (1.0 + _TIE))


def _hop(problem: _Problem, settings: GraspSettings, best: tuple[float, np.ndarray, list[int]],
         *, seed: int, finite_differences: bool = False,
         ) -> tuple[float, np.ndarray, list[int]]:
    """From the cheapest start, hops to cheaper minima nearby (the constants' comment): odd
    hops move one digit, even ones the whole problem by the next of _HOP_TIERS; (cost,
    variables, iterations per stage: the starts' two, then the last kept hop's)."""
    rng = np.random.default_rng(seed)
    scale = np.concatenate([np.full(3, _HOP_POS_M), np.full(3, _HOP_TURN_RAD),
                            np.full(problem.n - 6, _HOP_JOINT_RAD)])
    cost, x, iterations = best
    fails = hops = 0
    while fails < _HOP_PATIENCE and hops < _HOP_MAX:
        hops += 1
        if hops % 2:
            digit = problem.digits[int(rng.integers(len(problem.digits)))]
            x0 = x.copy()
            wide = _HOP_DIGIT_RAD[(hops // 2) % len(_HOP_DIGIT_RAD)]
            x0[digit] += wide * rng.standard_normal(len(digit))
            x0 = np.clip(x0, *problem.bounds)
        else:
            wide = _HOP_TIERS[(hops // 2) % len(_HOP_TIERS)]
            x0 = np.clip(x + wide * scale * rng.standard_normal(problem.n), *problem.bounds)
        y, trace = _solve(problem, x0, True, settings.max_iter,
                          finite_differences=finite_differences)
        c = 0.5 * float(np.sum(problem.residual(y, contacts=True) ** 2))
        if c < cost * (1.0 - _HOP_GAIN):
            cost, x, iterations, fails = c, y, [*iterations[:2], len(trace)], 0
        else:
            fails += 1
    return cost, x, iterations


@functools.lru_cache(maxsize=1)
def _code_digest() -> str:
    """What a grasp depends on besides its config and settings: the source of softhand.hands
    (the hands, the scene, this solver), the paper's data file, and the MuJoCo and NumPy that
    compute it."""
    h = hashlib.sha256(f"mujoco {mujoco.__version__} numpy {np.__version__}".encode())
    here = Path(__file__).resolve().parent
    for path in (*sorted(here.glob("*.py")), here.parent / "data" / "paper.json"):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def _cache_path(config: SceneConfig, settings: GraspSettings) -> Path | None:
    """Where the grasp of ``config`` and ``settings`` is cached (softhand.paths.cache_dir), keyed
    by both (their repr: every field, floats exactly) and by `_code_digest`; None: no
    cache."""
    root = cache_dir()
    if root is None:
        return None
    key = hashlib.sha256(f"{config!r}|{settings!r}|{_code_digest()}".encode()).hexdigest()
    return root / "grasps" / f"{key[:32]}.json"


def _read_cached(path: Path | None, n: int) -> tuple[float, np.ndarray, list[int]] | None:
    """A cached solution (cost, variables, iterations), or None when there is none or it cannot
    be read (then the grasp is solved again and the entry rewritten)."""
    if path is None:
        return None
    try:
        entry = json.loads(path.read_text())
        x = np.array(entry["x"], dtype=float)
        if x.shape != (n,) or not np.all(np.isfinite(x)):
            return None
        return float(entry["cost"]), x, [int(i) for i in entry["iterations"]]
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _cached_cost_holds(problem: _Problem, cost: float, x: np.ndarray) -> bool:
    """Whether a cached solution's variables give its recorded cost (one residual, a few ms):
    an entry edited or damaged into other finite numbers is not used."""
    got = 0.5 * float(np.sum(problem.residual(x, contacts=True) ** 2))
    return bool(np.isfinite(cost)) and abs(got - cost) <= 1e-9 + 1e-6 * abs(cost)


def _write_cached(path: Path | None, cost: float, x: np.ndarray, iterations: list[int]) -> None:
    """Keep a solution for the next process (JSON floats round-trip exactly); a cache that
    cannot be written is skipped: it only saves time."""
    if path is None:
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(path, json.dumps({"cost": cost, "x": x.tolist(),
                                            "iterations": list(iterations)}))
    except OSError:
        pass


def set_grasp_state(model: mujoco.MjModel, data: mujoco.MjData, grasp: Grasp, *,
                    prosthetic: bool = True) -> None:
    """Write the grasp into ``data.qpos`` (partner arm and joints; the prosthetic's motors and
    their coupled joints when ``prosthetic``) and run mj_kinematics. The model is a handshake scene
    (prefixes ``pro_``, ``hum_``, the partner on the free joint ``hum_arm``)."""
    arm = int(model.jnt_qposadr[model.joint("hum_arm").id])
    data.qpos[arm:arm + 3] = grasp.partner_pos_m
    data.qpos[arm + 3:arm + 7] = grasp.partner_quat
    for j, q in zip(PARTNER_JOINTS, grasp.partner_q, strict=True):
        data.qpos[model.jnt_qposadr[model.joint(f"hum_{j}").id]] = q
    if prosthetic:
        for j, q in zip(PROSTHETIC_MOTOR_JOINTS, grasp.prosthetic_q, strict=True):
            data.qpos[model.jnt_qposadr[model.joint(f"pro_{j}").id]] = q
        _couple(model, data)
    mujoco.mj_kinematics(model, data)


def _couple(model: mujoco.MjModel, data: mujoco.MjData,
            couplings: list[tuple[int, int, float, float]] | None = None) -> None:
    """Set every joint coupled by a joint equality (q1 = c0 + c1 q2, the prosthetic's couplings)
    from its driver in ``data.qpos``, in the equalities' order (a coupled joint may drive
    another); ``couplings``: `_couplings` of the model, when known."""
    qpos = data.qpos
    for a1, a2, c0, c1 in _couplings(model) if couplings is None else couplings:
        qpos[a1] = c0 + c1 * qpos[a2]


def _couplings(model: mujoco.MjModel) -> list[tuple[int, int, float, float]]:
    """The model's joint equalities as (qpos address of q1, of q2, c0, c1), in order."""
    return [(int(model.jnt_qposadr[model.eq_obj1id[e]]),
             int(model.jnt_qposadr[model.eq_obj2id[e]]),
             float(model.eq_data[e, 0]), float(model.eq_data[e, 1]))
            for e in range(model.neq) if model.eq_type[e] == mujoco.mjtEq.mjEQ_JOINT]


def _in_frame(data: mujoco.MjData, body: int, point: np.ndarray) -> np.ndarray:
    """``point`` (world) in ``body``'s frame."""
    return data.xmat[body].reshape(3, 3).T @ (point - data.xpos[body])


def _pad(model: mujoco.MjModel, data: mujoco.MjData, prefix: str, digit: str,
         layout: HandLayout) -> np.ndarray:
    """World position of the pad (palmar surface, mid-length) of a digit's distal phalanx."""
    body, local = _pad_frame(model, prefix, digit, layout)
    return data.xpos[body] + data.xmat[body].reshape(3, 3) @ local


def _pad_frame(model: mujoco.MjModel, prefix: str, digit: str,
               layout: HandLayout) -> tuple[int, np.ndarray]:
    """The body of a digit's distal phalanx and its pad in that body's frame."""
    dl = layout.digits[digit]
    return model.body(f"{prefix}{digit}_distal").id, np.array(
        [0.5 * dl.lengths_m["distal"], 0.0, -dl.radii_m["distal"]])


def grasp_metrics(model: mujoco.MjModel, data: mujoco.MjData, pro: HandLayout,
                  hum: HandLayout) -> dict:
    """What a biomechanist checks in a handshake state (kinematics already computed):

    ``palm_gap_mm``: signed distance between the prosthetic palm's surface and the partner's
    palm (negative: pressed), keyed ``Palm``; ``palm_angle_deg``: the angle between the two palms
    (between one palm's normal and the other's reversed; 0: facing each other, parallel);
    ``thumb_tip_in_other_mm``: each thumb's pad in the other hand's frame
    (x distal, y radial, z dorsal; z > 0 is over the back); ``fingertip_z_in_other_mm``: each
    fingertip's height in the other hand's frame (z > 0: past its mid-plane, onto its back);
    ``self_penetration_mm``: the deepest overlap of two pieces of the same hand (thumb on fingers,
    neighbouring fingers), per hand; ``partner_limit_margin_deg``: the smallest distance of a
    partner digit joint to its range's ends.
    """
    dist = np.zeros(6)

    def gd(a: str, b: str) -> float:
        return mujoco.mj_geomDistance(model, data, model.geom(a).id, model.geom(b).id, 0.05, dist)

    def pad(prefix: str, digit: str, layout: HandLayout) -> np.ndarray:
        return _pad(model, data, prefix, digit, layout)

    def local(body: str, point: np.ndarray) -> np.ndarray:
        return _in_frame(data, model.body(body).id, point)

    out: dict = {
        "palm_gap_mm": {"Palm": 1e3 * gd("pro_skin_Palm", "hum_tissue_palm")},
        "palm_angle_deg": math.degrees(math.acos(float(np.clip(
            -data.xmat[model.body("pro_palm").id].reshape(3, 3)[:, 2]
            @ data.xmat[model.body("hum_palm").id].reshape(3, 3)[:, 2], -1.0, 1.0)))),
        "thumb_tip_in_other_mm": {
            "partner_on_prosthetic": (1e3 * local("pro_palm", pad("hum_", "thumb", hum))).tolist(),
            "prosthetic_on_partner": (1e3 * local("hum_palm", pad("pro_", "thumb", pro))).tolist(),
        },
        "fingertip_z_in_other_mm": {
            "partner": {f: float(1e3 * local("pro_palm", pad("hum_", f, hum))[2])
                        for f in const.FINGERS},
            "prosthetic": {f: float(1e3 * local("hum_palm", pad("pro_", f, pro))[2])
                           for f in const.FINGERS},
        },
    }
    depth = {}
    for hand, prefix, pieces in (("prosthetic", "pro_skin_", _PRO_PIECES),
                                 ("partner", "hum_tissue_", _HUM_PIECES)):
        worst = 0.0
        for a, b in _self_pairs(model, prefix, pieces):
            worst = max(worst, -mujoco.mj_geomDistance(model, data, a, b, 0.01, dist))
        depth[hand] = 1e3 * worst
    out["self_penetration_mm"] = depth
    margin = np.inf
    for j in PARTNER_JOINTS:
        jid = model.joint(f"hum_{j}").id
        q = data.qpos[model.jnt_qposadr[jid]]
        lo, hi = model.jnt_range[jid]
        margin = min(margin, q - lo, hi - q)
    out["partner_limit_margin_deg"] = float(np.degrees(margin))
    return out


def partner_contact_pose(config: SceneConfig | None = None) -> tuple[np.ndarray, np.ndarray]:
    """World position (m) and quaternion of the partner's mount (its hand frame, wrist at 0) at
    the grasp: where solve_grasp() puts it."""
    grasp = solve_grasp(config or SceneConfig())
    return grasp.partner_pos_m.copy(), grasp.partner_quat.copy()


def partner_start_pose(config: SceneConfig | None = None) -> tuple[np.ndarray, np.ndarray]:
    """World position (m) and quaternion of the partner's mount at the start of a handshake:
    SceneConfig.partner_start_offset_m from the grasp pose, in the partner's hand frame."""
    config = config or SceneConfig()
    pos, quat = partner_contact_pose(config)
    return pos + _rotation(quat) @ np.asarray(config.partner_start_offset_m, float), quat
