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
  ``press_m``; the two palm normals are opposite
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

Variables: the partner hand frame's pose relative to the prosthetic hand frame (position, and a
rotation vector about the starting orientation), the partner's 16 digit joints (wrist at 0), the
prosthetic's 6 motors (coupled joints follow their equalities). Solved with
``mujoco.minimize.least_squares`` (box bounds, finite differences). Cached per SceneConfig.

Cost: nearly all the time is geom distances inside finite differences. Two shortcuts that leave
every floating-point number as it was (tests/test_grasp.py measures every pair against them): a
pair is measured only where its bounding spheres can reach the residual's threshold (a convex
overlap is at most as deep as its spheres'; the other pairs' terms are exactly zero), and a
Jacobian column, whose step turns one joint or moves the partner, measures only the pairs with a
geom that moved (the others keep the distance they have at the column's base point).
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
from mujoco import minimize

from softhand.hands import constants as const
from softhand.hands.config import SceneConfig
from softhand.hands.layout import HandLayout, hand_layout
from softhand.hands.partner import PARTNER_JOINTS
from softhand.hands.scene import partner_quat, prosthetic_quat, scene_spec, web_point
from softhand.io import atomic_write_text
from softhand.paths import cache_dir

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
    """

    press_m: float = 0.001
    max_depth_m: float = 0.003
    bone_clearance_m: float = 0.004
    limit_margin_deg: float = 10.0
    max_iter: int = 60


GRASP_SETTINGS = GraspSettings()
#: A grasp whose cost (0.5 |r|^2, m^2) is under this met its targets (the default hands: 3e-4,
#: the posture prior's pull); above it the solver tries the next start (local minima were 1.6e-2
#: and 2.3e-2: a partner finger between the palms).
GOOD_COST_M2 = 1e-3
#: Slack of the bounding-sphere pruning (m): a pair is measured unless its spheres' gap exceeds
#: the threshold by this much, so that no rounding in the distance routine changes a residual.
_PRUNE_M = 1e-6
#: Finite-difference step of the grasp's Jacobian (relative, as mujoco.minimize scales it).
_FD_EPS = 1e-5


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
        self.pro, self.hum = hand_layout(config.prosthetic.hand), hand_layout(config.partner.hand)
        pos0, quat0 = _web_to_web_pose(config, self.pro, self.hum)
        spec = scene_spec(config, partner_pose=(pos0, quat0))
        m = spec.compile()
        m.opt.ccd_tolerance = 1e-6  # smooth distances for finite differences
        self.m, self.d = m, mujoco.MjData(m)
        self.pos0, self.quat0 = pos0, quat0
        name = lambda i: m.geom(i).name  # noqa: E731
        geoms = range(m.ngeom)
        self.pro_soft = [g for g in geoms if name(g).startswith("pro_skin_")]
        self.hum_soft = [g for g in geoms if name(g).startswith("hum_tissue_")]
        self.pro_bone = [g for g in geoms if name(g).startswith("pro_bone_")]
        self.hum_bone = [g for g in geoms if name(g).startswith("hum_bone_")]
        gid = lambda n: m.geom(n).id  # noqa: E731
        self.pro_palms = [gid("pro_skin_Palm1"), gid("pro_skin_Palm2")]
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
        # the reference state of jacobian(), which geoms moved from it, the distances measured
        self._ref: tuple[np.ndarray, np.ndarray] | None = None
        self._moved: np.ndarray | None = None
        self._known: dict = {}

    def starts(self):
        """Starting points: the relaxed prior at the configured crossing, then the partner turned
        by -+0.2 rad about the palm normal and shifted -+10 mm along its own axis (a grasp whose
        cost stays above GOOD_COST_M2 was caught in a local minimum: a finger between the palms)."""
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
        d.qpos[:] = m.qpos0
        pos, quat = self.pose(x)
        d.qpos[self.arm_qpos:self.arm_qpos + 3] = pos
        d.qpos[self.arm_qpos + 3:self.arm_qpos + 7] = quat
        d.qpos[self.hum_qpos] = x[6:6 + len(self.hum_qpos)]
        d.qpos[self.pro_qpos] = x[6 + len(self.hum_qpos):]
        _couple(m, d, self.couplings)
        mujoco.mj_kinematics(m, d)
        if self._ref is not None:  # inside jacobian(): which geoms this state moved
            xpos, xmat = self._ref
            self._moved = (d.geom_xpos != xpos).any(axis=1) | (d.geom_xmat != xmat).any(axis=1)

    def distance(self, g1: int, g2: int, cap: float = 0.05) -> float:
        """The pair's signed distance capped at ``cap`` (m). Inside `jacobian` a pair
        whose two geoms have not moved from the reference state is measured once."""
        if self._moved is None or self._moved[g1] or self._moved[g2]:
            return mujoco.mj_geomDistance(self.m, self.d, g1, g2, cap, self.dist)
        key = (g1, g2, cap)
        value = self._known.get(key)
        if value is None:
            value = self._known[key] = mujoco.mj_geomDistance(self.m, self.d, g1, g2, cap,
                                                              self.dist)
        return value

    def jacobian(self, x: np.ndarray, r: np.ndarray, contacts: bool) -> np.ndarray:
        """mujoco.minimize's finite-difference Jacobian at ``x`` (the same steps and columns),
        with each column measuring only the pairs that its step moved: a step of one joint moves
        one digit, and a pair with neither geom moved has the distance it has at ``x`` (the
        same floating-point result: forward kinematics of unchanged joints is unchanged)."""
        self.set_state(np.ravel(x))
        self._ref = (self.d.geom_xpos.copy(), self.d.geom_xmat.copy())
        self._known = {}
        try:
            jac, _ = minimize.jacobian_fd(
                lambda xh: np.stack([self.residual(xh[:, k], contacts=contacts)
                                     for k in range(xh.shape[1])], axis=1),
                x, r, _FD_EPS, 0, [b.reshape(-1, 1) for b in self.bounds])
        finally:
            self._ref, self._moved, self._known = None, None, {}
        return jac

    def lower_bounds(self, pairs: np.ndarray) -> np.ndarray:
        """A lower bound of each pair's signed distance: the gap of the geoms' bounding spheres
        (a convex overlap is at most as deep as its bounding spheres')."""
        xpos, rbound = self.d.geom_xpos, self.m.geom_rbound
        a, b = pairs[:, 0], pairs[:, 1]
        return (np.linalg.norm(xpos[a] - xpos[b], axis=1) - rbound[a] - rbound[b])

    def distances(self, pairs: np.ndarray, cap: float, above: float) -> np.ndarray:
        """Each pair's distance (capped at ``cap``) where it can be under ``above``; ``cap`` for
        the pairs whose bounding spheres are ``above`` + _PRUNE_M apart or more (their residual
        terms are exactly zero either way: the same residuals as measuring every pair)."""
        out = np.full(len(pairs), cap)
        candidates = self.lower_bounds(pairs) < above + _PRUNE_M
        if self._moved is None:
            fixed, known = np.zeros(len(pairs), bool), None  # nothing kept
        else:  # inside jacobian(): pairs that did not move keep their measured distance
            known = self._known.setdefault((id(pairs), cap), np.full(len(pairs), np.nan))
            fixed = ~(self._moved[pairs[:, 0]] | self._moved[pairs[:, 1]])
            reuse = candidates & fixed & ~np.isnan(known)
            out[reuse] = known[reuse]
            candidates &= ~reuse
        for i in np.flatnonzero(candidates):
            out[i] = mujoco.mj_geomDistance(self.m, self.d, int(pairs[i, 0]), int(pairs[i, 1]),
                                            cap, self.dist)
            if fixed[i]:
                known[i] = out[i]
        return out

    def nearest(self, mine: list[int], others: np.ndarray, cap: float = 0.05) -> list[float]:
        """Per geom of ``mine``, the smallest capped distance to ``others``: pairs in the order of
        their bounding spheres' gap, stopping where that gap passes the nearest distance found
        (the same minimum as measuring every pair)."""
        xpos, rbound = self.d.geom_xpos, self.m.geom_rbound
        bounds = (np.linalg.norm(xpos[mine][:, None] - xpos[others][None], axis=2)
                  - rbound[mine][:, None] - rbound[others][None])
        order = np.argsort(bounds, axis=1, kind="stable").tolist()
        # inside jacobian(): a geom that did not move, among others that did not, keeps its gap
        known = None if self._moved is None or self._moved[others].any() else \
            self._known.setdefault((id(others), cap), {})
        bounds, others = bounds.tolist(), others.tolist()
        out = []
        for k, g in enumerate(mine):
            if known is not None and not self._moved[g] and g in known:
                out.append(known[g])
                continue
            best, row = cap, bounds[k]
            for i in order[k]:
                if row[i] >= best + _PRUNE_M:
                    break
                best = min(best, self.distance(g, others[i], cap))
            out.append(best)
            if known is not None and not self._moved[g]:
                known[g] = best
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
    def residual(self, x: np.ndarray, *, contacts: bool) -> np.ndarray:
        self.set_state(x)
        s, d = self.s, self.d
        r: list[float] = []
        # palms: both prosthetic palmar quarters pressed press_m into the partner's palm
        r += [5.0 * (self.distance(g, self.hum_palm) + s.press_m) for g in self.pro_palms]
        z_pro = d.xmat[self.pro_palm_body].reshape(3, 3)[:, 2]
        z_hum = d.xmat[self.hum_palm_body].reshape(3, 3)[:, 2]
        r += list(0.02 * (z_pro + z_hum))
        # web spaces: together in the plane of the prosthetic palm
        w_pro = self.hand_point(self.pro_palm_body, self.web_pro)
        w_hum = self.hand_point(self.hum_palm_body, self.web_hum)
        r += list(self.in_frame(self.pro_palm_body, w_hum + d.xpos[self.pro_palm_body]
                                - w_pro)[:2])
        # thumbs over the back of the other hand's index metacarpal
        r += list(0.5 * (self.pad("hum_", "thumb")
                         - self.hand_point(self.pro_palm_body, self.dorsal_pro)))
        r += list(0.5 * (self.pad("pro_", "thumb")
                         - self.hand_point(self.hum_palm_body, self.dorsal_hum)))
        # fingertips past the other hand's mid-plane, onto its back (one-sided)
        for f in const.FINGERS:
            z = self.in_frame(self.pro_palm_body, self.pad("hum_", f))[2]
            r.append(0.2 * max(0.0, -z))
            z = self.in_frame(self.hum_palm_body, self.pad("pro_", f))[2]
            r.append(0.2 * max(0.0, -z))
        # every phalanx touches the other hand (gap beyond the press is penalised)
        for mine, others in self.gap_sets:
            r += [0.3 * max(0.0, gap + s.press_m) for gap in self.nearest(mine, others)]
        if contacts:
            r += list(10.0 * np.maximum(0.0, -self.distances(
                self.soft_pairs, 0.01, -s.max_depth_m) - s.max_depth_m))
            r += list(10.0 * np.maximum(0.0, s.bone_clearance_m - self.distances(
                self.bone_pairs, 0.02, s.bone_clearance_m)))
            r += list(3.0 * np.maximum(0.0, -self.distances(self.self_pairs, 0.01, 0.0)))
        r += list(0.01 * (x[6:] - self.prior[6:]))
        r += list(0.005 * x[3:6])
        return np.asarray(r)


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


def _solve(problem: _Problem, x0: np.ndarray, contacts: bool, max_iter: int):
    def fun(x: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(x.T).T
        return np.stack([problem.residual(x[:, k], contacts=contacts)
                         for k in range(x.shape[1])], axis=1)

    return minimize.least_squares(
        x0, fun, bounds=problem.bounds, jacobian=lambda x, r: problem.jacobian(x, r, contacts),
        eps=_FD_EPS, max_iter=max_iter, verbose=0, xtol=1e-6)


@functools.lru_cache(maxsize=64)
def solve_grasp(config: SceneConfig | None = None,
                settings: GraspSettings = GRASP_SETTINGS) -> Grasp:
    """Solve the handshake grasp of the scene's two hands (cached per config and settings, in
    this process and on disk: a solution in softhand.paths.cache_dir() is read back instead of
    solved, bit for bit the same; a population's partners, or a sweep over skins and controllers,
    solve each hand size once per machine).

    Args:
        config: the scene (both hands' sizes, the prosthetic wrist pose, the starting crossing
            angle); default SceneConfig().
        settings: weights and allowances.

    Returns:
        The grasp: the partner's pose and posture, the prosthetic's motor posture, and
        grasp_metrics() of the solution.
    """
    config = config or SceneConfig()
    problem = _Problem(config, settings)
    path = _cache_path(config, settings)
    known = _read_cached(path, problem.n)
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


def _solve_starts(problem: _Problem, settings: GraspSettings
                  ) -> tuple[float, np.ndarray, list[int]]:
    """The grasp from the first start whose cost meets GOOD_COST_M2, else the cheapest:
    (cost, variables, iterations per stage)."""
    best = None
    for start in problem.starts():
        x, iterations = start, []
        for contacts in (False, True):
            x, trace = _solve(problem, x, contacts, settings.max_iter)
            iterations.append(len(trace))
        cost = 0.5 * float(np.sum(problem.residual(x, contacts=True) ** 2))
        if best is None or cost < best[0]:
            best = (cost, x, iterations)
        if cost < GOOD_COST_M2:  # a grasp that meets its targets: no other start needed
            break
    return best


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

    ``palm_gap_mm``: signed distance between the prosthetic's palmar quarters and the partner's
    palm (negative: pressed); ``thumb_tip_in_other_mm``: each thumb's pad in the other hand's frame
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
        "palm_gap_mm": {p: 1e3 * gd(f"pro_skin_{p}", "hum_tissue_palm") for p in ("Palm1", "Palm2")},
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
