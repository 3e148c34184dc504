"""Run one handshake with a controller and collect what a user looks at: forces, motion, contacts."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from softhand import __version__
from softhand.envs.controllers import make_controller
from softhand.envs.handshake import HandshakeEnv
from softhand.envs.partner import HOLDING, SHAKE_HZ
from softhand.envs.physics import DivergenceError, mujoco_warnings_kept
from softhand.envs.skins import skin_of_pair
from softhand.hands.config import HandConfig
from softhand.laws.fit import REFERENCE_FORCE_N
from softhand.paper import paper
from softhand.sensors.device import ASSUMPTIONS
from softhand.skin.local_geometry import (
    LocalGeometry,
    geometry_accounting,
    pair_class,
    surface_point,
)
from softhand.validate import show

__all__ = ["ACCOUNT_CLASSES", "ContactAreas", "HandshakeRun", "check_policy",
           "mean_curvature_radius", "run_handshake", "run_policy"]


#: Time into the motionless hold (s) before its force is read as held: one period of the 4 Hz
#: shake. The shake ends where the hold begins, and its last swing rings on through the arms
#: (the force between the hands swings by about +-1 N for 0.18 s at seed 0); read from the
#: hold's first instant, a "fall" of 1-2 % (and rises of 4-6 % at other seeds) was that swing's
#: phase, not relaxation.
HOLD_SETTLE_S = 1.0 / SHAKE_HZ
OVER_N = REFERENCE_FORCE_N  # the paper's Fig. 4 threshold, 2 N
#: where the normal force between the two hands comes from (force accounting)
ACCOUNT_CLASSES = ("skin_law", "tissue_law_only", "bone_on_bone", "no_law")


@dataclass
class HandshakeRun:
    """One handshake: per physics step (frame) the state, region forces and contacts."""

    region_names: tuple[str, ...]
    skins: dict[str, str]
    time_s: np.ndarray
    qpos: np.ndarray
    mocap_pos: np.ndarray
    mocap_quat: np.ndarray
    region_force_N: np.ndarray
    contacts: list[np.ndarray]
    phase: list[str]
    #: wall time (s) of the env steps after the first and their physics steps: the speed
    wall_s: float
    steps: int
    model: mujoco.MjModel = field(repr=False)
    region_area_mm2: np.ndarray | None = None
    rigid_force_N: np.ndarray | None = None
    accounting: np.ndarray | None = None  # per frame: ContactAreas.accounting
    #: per frame and region: normal force (N) of all the contacts of the region's skin geom
    #: (its sensor zone and the rest), ContactAreas.skin_force
    skin_force_N: np.ndarray | None = None
    #: per frame and region: compression (mm) of the region's relaxation pad (NaN: no pad)
    pad_compression_mm: np.ndarray | None = None
    #: per frame and region: the pad's own force (N), its spline spring and Maxwell branches
    pad_force_N: np.ndarray | None = None
    representations: dict[str, str] = field(default_factory=dict)
    calibration_dir: str = ""
    #: per frame and region: the embedded sensor's reading (N on its patch)
    sensor_reading_N: np.ndarray | None = None
    #: per region: the sensor's placement; the electronics (SensorSpec.to_dict)
    sensor_placements: dict[str, str] = field(default_factory=dict)
    sensor_spec: dict = field(default_factory=dict)
    controller: dict = field(default_factory=dict)
    #: per frame: the partner's summed digit force and its target (N)
    partner_grip_N: np.ndarray | None = None
    #: per frame: normal force between the two palms (thenars included), between the hands, and
    #: between the palms' faces alone (the sensored palm's palmar face on the partner's palm
    #: piece: PALM_FACES) (N)
    palm_force_N: np.ndarray | None = None
    #: the episode: sensored hand, partner's hand size (mm), seed, softhand version
    episode: dict = field(default_factory=dict)
    #: the laws the pairs carried (the accounting's last columns, in this order) and how they
    #: were chosen (softhand.envs.skins.CONTACT_LAWS)
    law_labels: tuple[str, ...] = ()
    contact_laws: str = "geometry"
    #: wall time of the first env step (s), left out of ``wall_s`` and ``steps``: on a machine's
    #: first run it compiles the step's kernels (numba, about 7 s once; then read from its cache)
    first_step_s: float = 0.0
    #: per frame: the deepest penetration (mm) of a law-carrying pair between the hands, and the
    #: pair (its two geoms' names joined by "/"; "" where none touches)
    pair_depth_mm: np.ndarray | None = None
    pair_depth_pair: list[str] = field(default_factory=list)
    #: the episode's first overload (the env's beyond_range_summary: time s and what, N)
    first_overload: dict = field(default_factory=dict)
    #: per frame: the force resisted twice at a skin seam (N, ContactAreas.double_N)
    double_count_N: np.ndarray | None = None
    #: the law-carrying contacts' normal force (N) summed over the recorded frames, by law and
    #: local geometry on each side (ContactAreas.geometry; force_accounting's ``by_geometry``)
    geometry_N: dict | None = None

    def double_count(self) -> dict[str, float]:
        """The force counted twice at skin seams (ContactAreas.double_N) while the hands hold
        each other (grip, shake, hold): N s, and its share of the force between the hands (%)."""
        if self.double_count_N is None or self.palm_force_N is None:
            return {"double_Ns": 0.0, "double_share_pct": 0.0}
        hold = np.array([p in HOLDING for p in self.phase])
        dt = float(np.median(np.diff(self.time_s))) if len(self.time_s) > 1 else 0.0
        double = float(self.double_count_N[hold].sum() * dt)
        total = float(self.palm_force_N[hold, 1].sum() * dt)
        return {"double_Ns": double,
                "double_share_pct": 100.0 * double / total if total > 0 else 0.0}

    def palm_on_palm(self) -> dict[str, float]:
        """How much of the force between the hands the palms exchange while the hands hold each
        other (grip, shake, hold; issue 35's measure): ``palm_share_pct`` between the palms'
        faces alone (the sensored palm's palmar face on the partner's palm piece: not a thumb or
        a finger on a palm, not the thenars, `PALM_FACES`), ``with_thenars_pct`` with the
        thenar pieces of both hands (`PALM_PIECES`), in % of the force between the hands."""
        if self.palm_force_N is None:
            return {"palm_share_pct": 0.0, "with_thenars_pct": 0.0}
        hold = np.array([p in HOLDING for p in self.phase])
        sums = self.palm_force_N[hold].sum(axis=0)
        total = float(sums[1])
        return {"palm_share_pct": 100.0 * float(sums[2]) / total if total > 0 else 0.0,
                "with_thenars_pct": 100.0 * float(sums[0]) / total if total > 0 else 0.0}

    def overload(self) -> dict:
        """Where the episode overloaded: the deepest pair (mm, its geoms, when), the bone-on-bone
        peak (N) and when the first overload began and what (the env's
        ``info["overload_started"]``: a region over the scenario's overload_N, or a bone
        bottoming out under a region)."""
        depth = self.pair_depth_mm if self.pair_depth_mm is not None else np.zeros(1)
        rigid = self.rigid_force_N if self.rigid_force_N is not None else np.zeros(1)
        k, j = int(np.argmax(depth)), int(np.argmax(rigid))
        return {"deepest_pair_mm": float(depth[k]),
                "deepest_pair": self.pair_depth_pair[k] if self.pair_depth_pair else "",
                "deepest_pair_time_s": float(self.time_s[k]),
                "bone_on_bone_peak_N": float(rigid[j]),
                "bone_on_bone_peak_time_s": float(self.time_s[j]),
                "first_overload_time_s": self.first_overload.get("time_s"),
                "first_overload": self.first_overload.get("what")}

    def grasp_checks(self) -> dict:
        """What a hand biomechanist checks (softhand.hands.grasp.grasp_metrics), from the
        recorded frames: at mid-shake, the palm-to-palm share of the force between the hands
        (palms and thenars, %), each thumb pad in the other hand's frame (mm; z > half the
        other's thickness is over its back), the palms' gap (mm); over the episode, the deepest
        self-penetration of each hand (mm) and the partner's smallest joint margin while it holds
        the hand (deg)."""
        from softhand.hands.grasp import grasp_metrics
        from softhand.hands.layout import hand_layout

        m = self.model
        d = mujoco.MjData(m)
        layouts = [hand_layout(HandConfig(hand_length_m=v / 1e3, hand_width_m=w / 1e3))
                   for v, w in ((190.0, 88.0), self.episode.get("partner_size_mm", (190, 88)))]
        shake = [i for i, p in enumerate(self.phase) if p == "shake"]
        mid = shake[len(shake) // 2] if shake else len(self.phase) // 2
        worst = {"prosthetic": 0.0, "partner": 0.0}
        margin = np.inf
        at_mid: dict = {}
        for k in range(len(self.time_s)):
            d.qpos[:] = self.qpos[k]
            d.mocap_pos[:], d.mocap_quat[:] = self.mocap_pos[k], self.mocap_quat[k]
            mujoco.mj_kinematics(m, d)
            g = grasp_metrics(m, d, *layouts)
            for hand, v in g["self_penetration_mm"].items():
                worst[hand] = max(worst[hand], v)
            if self.phase[k] in HOLDING:
                margin = min(margin, g["partner_limit_margin_deg"])
            if k == mid:
                at_mid = g
        palm, total = self.palm_force_N[mid, :2] if self.palm_force_N is not None else (0.0, 0.0)
        return {"t_mid_shake_s": float(self.time_s[mid]),
                "palm_to_palm_share_pct": float(100 * palm / total) if total > 0 else 0.0,
                "palm_gap_mm": at_mid.get("palm_gap_mm", {}),
                "thumb_tip_in_other_mm": at_mid.get("thumb_tip_in_other_mm", {}),
                "self_penetration_mm": worst,
                "partner_limit_margin_deg": float(margin)}

    def grip_tracking(self) -> dict[str, float]:
        """How well the partner's summed digit force followed its target while it held the hand
        (grip and shake, after its first 0.25 s; not the hold, where it keeps its effort instead
        of regulating: softhand.envs.partner.HOLD_KEEPS_EFFORT): mean measured and target (N),
        and the 95th percentile of the relative error (%)."""
        g = self.partner_grip_N
        holding = np.array([p in ("grip", "shake") for p in self.phase])
        if g is None or not holding.any():
            return {"measured_N": 0.0, "target_N": 0.0, "p95_error_pct": float("nan")}
        start = self.time_s[holding][0] + 0.25
        keep = holding & (self.time_s > start)
        measured, target = g[keep, 0], g[keep, 1]
        return {"measured_N": float(measured.mean()), "target_N": float(target.mean()),
                "p95_error_pct": float(100 * np.percentile(np.abs(measured / target - 1), 95))}

    def force_accounting(self) -> dict[str, float]:
        """Where the normal force between the hands came from, over the recorded frames.

        ``skin_law``: a skin x tissue pair law (calibrated skin), or on a relaxation pad the part
        of the force that pushes along the pad's axis; ``tissue_law_only``: a ``rigid`` region
        against tissue (only the tissue law), or the rest of a relaxation pad's force (a contact
        from the side, which the pad's slide does not take);
        ``bone_on_bone``: bones pressed through skin and tissue (no law); ``no_law``: any other
        contact between the hands. ``calibrated_share_pct``: the skin-law force inside its
        calibrated range (the pair's law: `softhand.envs.skins.pair_choices`), in % of all the force
        between the hands (frames of 10 ms; contacts beyond the range count as uncalibrated).
        ``out_of_range_time_pct``: law-carrying contact-frames above their law's range, in % of
        all law-carrying contact-frames. ``unsensed_skin_Ns``: the force through the prosthetic
        skin that no region sensor read (a phalanx's dorsal half, the palm's borders, the
        thenar), i.e. all pair force less the 18 region readings; ``unsensed_share_pct`` its
        share of the pair force. ``by_law_Ns`` / ``by_law_share_pct``: the pair force by the law
        each pair carried (its contact class, ``plate``, a fallback to the plate law, ``tissue``
        or ``plate pad``; `softhand.envs.skins.PairChoice`); ``contact_laws``: how the
        laws were chosen. ``by_geometry`` (where the run classified its contacts): the pair
        force by the local geometry each contact met against the law it carried, and the shares
        whose skin law, tissue law and both were made for that geometry
        (`softhand.skin.local_geometry.geometry_accounting`).
        """
        n = len(ACCOUNT_CLASSES)
        acc = self.accounting if self.accounting is not None else np.zeros((1, n + 3))
        dt = float(np.median(np.diff(self.time_s))) if len(self.time_s) > 1 else 0.0
        integral = {k: float(acc[:, i].sum() * dt) for i, k in enumerate(ACCOUNT_CLASSES)}
        total = sum(integral.values())
        out = {f"{k}_Ns": v for k, v in integral.items()}
        out_in_skin = float(acc[:, n + 2].sum() * dt)
        out.update({
            "total_Ns": total,
            "calibrated_share_pct": 100.0 * (integral["skin_law"] - out_in_skin) / total
            if total > 0 else 100.0,
            "bone_on_bone_peak_N": float(acc[:, 2].max()),
            "bone_on_bone_Ns": integral["bone_on_bone"],
            "out_of_range_time_pct": 100.0 * float(acc[:, n + 1].sum()) / max(1.0, acc[:, n].sum()),
        })
        laws = acc[:, n + 3:]
        by_law = {label: float(laws[:, i].sum() * dt) for i, label in enumerate(self.law_labels)
                  if i < laws.shape[1]}
        law_total = sum(by_law.values())
        out["by_law_Ns"] = by_law
        out["by_law_share_pct"] = {k: 100.0 * v / law_total if law_total > 0 else 0.0
                                   for k, v in by_law.items()}
        out["contact_laws"] = self.contact_laws
        pair = acc[:, 0] + acc[:, 1]  # every pair is a prosthetic skin geom against tissue
        sensed = self.region_force_N.sum(axis=1) if self.region_force_N.size else np.zeros(1)
        unsensed = float(np.maximum(pair - sensed[:pair.size], 0.0).sum() * dt)
        out["unsensed_skin_Ns"] = unsensed
        out["unsensed_share_pct"] = 100.0 * unsensed / max(float(pair.sum() * dt), 1e-12)
        if self.geometry_N is not None:
            out["by_geometry"] = geometry_accounting(self.geometry_N, self.law_labels, dt)
        return out

    def kinematics(self) -> dict:
        """What the hands did: the largest flexion of each prosthetic digit's driven joint and
        of the thumb rotation (deg) while gripping, the regions that touched (> 0.05 N), and the
        partner's largest excursion past a joint's human range (deg; MuJoCo's limits are soft)."""
        m = self.model
        grip = np.array([p in HOLDING for p in self.phase])
        q = self.qpos[grip] if grip.any() else self.qpos
        out: dict = {"prosthetic_flexion_deg": {}, "touched": [
            r for r, v in self.table().items() if v["peak_N"] > 0.05]}
        for digit in ("index", "middle", "ring", "little", "thumb"):
            joint = m.joint(f"pro_{digit}_mcp")
            out["prosthetic_flexion_deg"][digit] = float(np.degrees(q[:, joint.qposadr[0]].max()))
        rot = m.joint("pro_thumb_rot")
        out["prosthetic_thumb_rotation_deg"] = float(np.degrees(q[:, rot.qposadr[0]].max()))
        worst = (0.0, "")
        for j in range(m.njnt):
            name = m.joint(j).name
            if not name.startswith("hum_") or m.jnt_type[j] != mujoco.mjtJoint.mjJNT_HINGE:
                continue
            lo, hi = m.jnt_range[j]
            a = self.qpos[:, m.jnt_qposadr[j]]
            beyond = float(np.degrees(max((a - hi).max(), (lo - a).max(), 0.0)))
            worst = max(worst, (beyond, name))
        out["partner_beyond_range_deg"] = {"max": worst[0], "joint": worst[1]}
        return out

    def relaxation(self, *, min_held_N: float = 1.0) -> dict[str, dict[str, float]]:
        """How the relaxation pads followed the skin's QLV law while the partner held the grip.

        For each region on a relaxation pad whose skin carried more than ``min_held_N`` during
        the grip and shake (the hold), with x(t) the pad's compression (the skin's indentation)
        and F_QLV(x) the skin's QLV law (`softhand.laws.fit.SkinLaw.force`) over the whole
        history x(t), each the largest error over the hold in % of the largest held force
        ``held_N`` of the region's skin (all its contacts):

        * ``pad_error_pct``: the pad's own force (spring + branches) against F_QLV(x): how well the
          pad's mechanics follow QLV;
        * ``qlv_error_pct``: the normal force of the skin's contacts against F_QLV(x): what the
          region's reading makes of it (a contact from the side loads the normal force but
          hardly compresses a pad that slides along the skin's normal);
        * ``soft_contact_error_pct``: the skin's memoryless soft contact (its rest law, fitted
          to the 0.5 mm/s loading curve) at the same x(t) against F_QLV(x): the error a skin
          without relaxation makes on this history.
        """
        if self.pad_compression_mm is None or self.skin_force_N is None:
            return {}
        from softhand.skin.files import load_calibration

        hold = np.array([p in HOLDING for p in self.phase])
        out = {}
        for i, region in enumerate(self.region_names):
            x = self.pad_compression_mm[:, i]
            if not np.isfinite(x).all() or not hold.any():
                continue
            f = self.skin_force_N[:, i]
            held = float(f[hold].max())
            if held < min_held_N:
                continue
            cal = load_calibration(self.skins[region], self.calibration_dir)
            depth = np.maximum(x, 0.0)
            qlv = cal.law.force(self.time_s - self.time_s[0], depth)

            def worst(v: np.ndarray, qlv=qlv, held=held) -> float:
                return float(100 * np.abs(v - qlv)[hold].max() / held)

            out[region] = {"held_N": held, "max_compression_mm": float(depth[hold].max()),
                           "pad_error_pct": worst(self.pad_force_N[:, i]),
                           "qlv_error_pct": worst(f),
                           "soft_contact_error_pct": worst(cal.soft_contact.force(depth))}
        return out

    def hold_relaxation(self, *, window_s: float = 0.05,
                        settle_s: float = HOLD_SETTLE_S) -> dict[str, float]:
        """What the motionless hold shows, once the shake's last swing has died out
        (``settle_s`` into the hold, HOLD_SETTLE_S; a shorter hold, from where its two windows
        still fit; ``settle_s`` in the result): the force between the hands over the first and
        last ``window_s`` after that (N, means) and its fall (``decay_pct``); on relaxation pads,
        the fall the skins' QLV laws give for the pads' own compression histories, weighted by
        the force each pad carries (``qlv_decay_pct``: sum over the pads of F_QLV(t, x(t)) at
        the end against the start), and the share of the hold's force between the hands that went through a
        pad's spring (``pad_share_pct``; the rest meets the tissue's law alone). In the hold the
        partner keeps its grip effort instead of regulating the force
        (softhand.envs.partner.HOLD_KEEPS_EFFORT), so a skin's relaxation can show as a fall of
        the force; the hands still settle after the shake, so the indentation is not constant.
        Empty without a hold."""
        hold = np.array([p == "hold" for p in self.phase])
        if not hold.any() or self.palm_force_N is None:
            return {}
        t = self.time_s
        settled = t[hold][0] + min(settle_s, max(0.0, t[hold][-1] - t[hold][0] - 2 * window_s))
        start = hold & (t >= settled) & (t < settled + window_s)
        end = hold & (t > t[hold][-1] - window_s)
        between = self.palm_force_N[:, 1]
        f0, f1 = float(between[start].mean()), float(between[end].mean())
        out = {"hold_s": float(t[hold][-1] - t[hold][0]), "settle_s": float(settled - t[hold][0]),
               "force_start_N": f0,
               "force_end_N": f1, "decay_pct": 100.0 * (1.0 - f1 / f0) if f0 > 0 else 0.0,
               "qlv_decay_pct": None, "pad_share_pct": 0.0}
        if self.pad_compression_mm is None or self.accounting is None:
            return out
        from softhand.skin.files import load_calibration

        q0 = q1 = 0.0
        for i, region in enumerate(self.region_names):
            x = self.pad_compression_mm[:, i]
            if not np.isfinite(x).all():
                continue
            law = load_calibration(self.skins[region], self.calibration_dir).law
            qlv = law.force(t - t[0], np.maximum(x, 0.0))
            q0 += float(qlv[start].mean())
            q1 += float(qlv[end].mean())
        n = len(ACCOUNT_CLASSES)
        acc = self.accounting[hold, :n]
        out["qlv_decay_pct"] = 100.0 * (1.0 - q1 / q0) if q0 > 0 else None
        out["pad_share_pct"] = 100.0 * float(acc[:, 0].sum() / max(acc.sum(), 1e-12))
        return out

    def table(self) -> dict[str, dict[str, float]]:
        """Per region: peak and mean force (N) and contact area (mm^2) over the handshake, and
        the embedded sensor's peak and mean reading (``sensor_peak``, ``sensor_mean``: N on the
        sensor's patch) with its placement."""
        f = self.region_force_N
        a = self.region_area_mm2 if self.region_area_mm2 is not None else np.zeros_like(f)
        out = {r: {"peak_N": float(f[:, i].max()), "mean_N": float(f[:, i].mean()),
                   "peak_area_mm2": float(a[:, i].max()), "mean_area_mm2": float(a[:, i].mean())}
               for i, r in enumerate(self.region_names)}
        if self.sensor_reading_N is not None:
            s = self.sensor_reading_N
            for i, r in enumerate(self.region_names):
                out[r].update({"sensor_peak": float(s[:, i].max()),
                               "sensor_mean": float(s[:, i].mean()),
                               "sensor_placement": self.sensor_placements.get(r, "")})
        return out

    @property
    def over_2n(self) -> list[str]:
        return [r for r, v in self.table().items() if v["peak_N"] > OVER_N]

    def paper_comparison(self) -> dict[str, list[str]]:
        ref = set(paper()["handshake"]["over_2N"])
        got = set(self.over_2n)
        return {"both": sorted(ref & got), "only_paper": sorted(ref - got),
                "only_softhand": sorted(got - ref)}

    def summary(self) -> dict:
        rigid = self.rigid_force_N if self.rigid_force_N is not None else np.zeros(1)
        out = {"regions": self.table(), "over_2N": self.over_2n,
                "paper_over_2N": self.paper_comparison(), "skins": self.skins,
                "rigid_contact_peak_N": float(rigid.max()),
                "force_accounting": self.force_accounting(),
                "overload": self.overload(),
                "hold": self.hold_relaxation(),
                "double_count": self.double_count(),
                "palm_on_palm": self.palm_on_palm(),
                "kinematics": self.kinematics(),
                "steps_per_s": self.steps / self.wall_s,
                "realtime_factor": self.steps * float(self.model.opt.timestep) / self.wall_s,
                "first_step_s": self.first_step_s,
                "episode": dict(self.episode), "partner_grip": self.grip_tracking(),
                "grasp_checks": self.grasp_checks()}
        if self.representations:
            out["representations"] = dict(self.representations)
        if self.sensor_spec:
            out["sensor"] = {"units": "N on the sensor patch", **self.sensor_spec,
                             "default_sources": ASSUMPTIONS}
        if self.controller:
            out["controller"] = dict(self.controller)
        relax = self.relaxation()
        if relax:
            out["relaxation"] = relax
        return out


#: The palm's surface pieces of each hand, thenar included (the thenar eminence is palm); the
#: prosthetic palm's one surface counts on its palmar face only (PALM_FACE_ZONES), in quarters
#: its palmar ones (the pieces a hand lacks are left out).
PALM_PIECES = {"prosthetic": ("Palm", "Palm1", "Palm2", "Thenar"),
               "partner": ("palm", "thumb_metacarpal")}
#: The palms' faces alone (PALM_PIECES less the thenars): palm on palm, not a thumb on a palm.
PALM_FACES = {"prosthetic": ("Palm", "Palm1", "Palm2"), "partner": ("palm",)}
#: The zones of the prosthetic palm's surface that face the other palm.
PALM_FACE_ZONES = ("Palm1", "Palm2")


#: Two contacts of one geom on two skin geoms closer than this (m) press one indentation: a seam
#: between two skin pieces (the palm's palmar/dorsal and proximal/distal cuts, a joint's crease)
SEAM_M = 0.002


def _palm_to_palm(d: mujoco.MjData, pro: np.ndarray, hum: np.ndarray,
                  palmar: Callable[[int, np.ndarray], bool] | None = None,
                  faces: tuple[np.ndarray, np.ndarray] | None = None
                  ) -> tuple[float, float, float]:
    """Normal force (N) between the two hands' palm pieces, between the hands in all, and
    between the palms' faces alone; ``pro``, ``hum``: per geom, whether it is a palm piece of
    that hand (masks over the geoms); ``faces``: the same masks of the faces alone (default:
    the pieces); ``palmar(geom, point)``: whether a contact at ``point`` on a prosthetic palm
    piece lies on its palmar face (default: all of it)."""
    con = d.contact
    adr = con.efc_address
    live = adr >= 0
    if not live.any():
        return 0.0, 0.0, 0.0
    g, f = con.geom[live], d.efc_force[adr[live]]
    palm = (pro[g[:, 0]] & hum[g[:, 1]]) | (pro[g[:, 1]] & hum[g[:, 0]])
    if palmar is not None:
        pos = con.pos[live]
        for i in np.flatnonzero(palm):
            own = g[i, 0] if pro[g[i, 0]] else g[i, 1]
            palm[i] = palmar(int(own), pos[i])
    fp, fh = faces if faces is not None else (pro, hum)
    face = palm & ((fp[g[:, 0]] & fh[g[:, 1]]) | (fp[g[:, 1]] & fh[g[:, 0]]))
    return float(f[palm].sum()), float(f.sum()), float(f[face].sum())


def mean_curvature_radius(model: mujoco.MjModel, geom: int) -> float:
    """1 / mean curvature (m) of a geom's flattest point: the harmonic mean of its principal radii
    (sphere r; capsule 2r; ellipsoid with semi-axes a1 >= a2 >= a3 at the a3 pole:
    2 / (a3/a1^2 + a3/a2^2)); other types: their largest size."""
    size, kind = model.geom_size[geom], model.geom_type[geom]
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return float(size[0])
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        return 2.0 * float(size[0])
    if kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        a1, a2, a3 = sorted(size, reverse=True)
        return float(2.0 / (a3 / a1**2 + a3 / a2**2))
    return float(max(size))


def sphere_overlap_area(r1: float, r2: float, depth: float) -> float:
    """Area (m^2) of the circle where two sphere surfaces of radii r1, r2 cross when pressed
    ``depth`` into each other (centres r1 + r2 - depth apart); 0 without overlap, the smaller
    cross-section once one sphere lies inside the other."""
    if depth <= 0:
        return 0.0
    d = r1 + r2 - depth
    if d <= abs(r1 - r2):
        return float(np.pi * min(r1, r2) ** 2)
    a2 = (4 * d * d * r1 * r1 - (d * d - r2 * r2 + r1 * r1) ** 2) / (4 * d * d)
    return float(np.pi * max(a2, 0.0))


class ContactAreas:
    """Per-region contact area and the force carried by bone on bone, from MuJoCo's contacts.

    Area estimate: each contact of a region's skin geom adds the area of the circle where the two
    undeformed surfaces, taken as spheres of each geom's mean curvature radius, intersect at the
    contact's penetration depth delta (exact for two spheres: 2 pi R delta, R = R1 R2 / (R1 + R2),
    to first order in delta, never more than the smaller sphere's cross-section). Softer skins
    sink deeper at the same force, so their areas grow (the paper's argument for compliant
    skins); the deformed patch of a real skin is larger still (an estimate, not an FE result).
    With ``zones`` (the regions' sensor sites), only contacts inside a region's zone count, as for
    its force: the area is what the region's sensor sees.
    """

    def __init__(self, model: mujoco.MjModel, region_geoms: list[int],
                 laws: Mapping[tuple[int, int], tuple[int, ...]] | None = None,
                 zones: list[int] | None = None) -> None:
        self.laws = dict(laws or {})
        n_laws = 1 + max((v[2] for v in self.laws.values() if len(v) > 2), default=-1)
        #: per region, the site of its sensor zone (None: every contact of the geom counts)
        self.zones = list(zones) if zones is not None else [None] * len(region_geoms)
        names = [model.geom(g).name or "" for g in range(model.ngeom)]
        self.hand = np.array([0 if n.startswith("pro_") else 1 if n.startswith("hum_") else -1
                              for n in names])
        #: after each call: normal force (N) between the hands per class of ACCOUNT_CLASSES,
        #: the number of law-carrying contacts, of those beyond their calibrated range, and the
        #: skin-law force (N) in contacts beyond it, then the force (N) of the pair contacts
        #: per law they carry (the third entry of each ``laws`` value)
        self.accounting = np.zeros(len(ACCOUNT_CLASSES) + 3 + n_laws)
        #: per geom, the region its skin carries (-1: none; -2: several, as zones of one
        #: surface, the palm's: a contact there belongs to the zone nearest to it, `region_at`)
        self.region_of = -np.ones(model.ngeom, dtype=int)
        self.zones_of: dict[int, list[int]] = {}
        for r, g in enumerate(region_geoms):
            self.zones_of.setdefault(int(g), []).append(r)
        for g, rs in self.zones_of.items():
            self.region_of[g] = rs[0] if len(rs) == 1 else -2
        self.radius = np.array([mean_curvature_radius(model, g) for g in range(model.ngeom)])
        self.bone = np.array(["bone_" in (model.geom(g).name or "") for g in range(model.ngeom)])
        #: per geom, the slide joint of its relaxation pad (-1: none): only the part of a contact
        #: force that pushes along the pad's axis compresses the skin's law; the rest meets the
        #: tissue's law alone (ACCOUNT_CLASSES "tissue_law_only")
        self.pad_joint = np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT,
                                                     f"{model.geom(g).name}_pad")
                                   for g in range(model.ngeom)])
        self.model = model
        self.n_regions = len(region_geoms)
        #: after each call: per region, normal force (N) of all its skin geom's contacts
        self.skin_force = np.zeros(self.n_regions)
        #: after each call: the deepest penetration (m) of a law-carrying pair between the hands
        #: and its two geoms (0, -1, -1: none touching)
        self.deepest: tuple[float, int, int] = (0.0, -1, -1)
        #: after each call: the normal force (N) resisted twice at a seam: where one geom of the
        #: other hand touches two skin geoms at points under SEAM_M apart, the smaller of the two
        #: contacts' forces (one indentation carried by two laws)
        self.double_N = 0.0
        self._force = np.zeros(6)
        #: the law-carrying contacts' normal force (N) summed over the calls that classify
        #: (``geometry=True``), by (law index, *`softhand.skin.local_geometry.pair_class`)
        self.geometry: dict[tuple, float] = {}
        self._local = LocalGeometry(model)

    def __call__(self, data: mujoco.MjData, *, geometry: bool = True
                 ) -> tuple[np.ndarray, float, np.ndarray]:
        """Area per region (mm^2), bone-on-bone force (N), and per active contact a row of
        position xyz (m), normal xyz and normal force (N), as the recording takes them; with
        ``geometry``, each law-carrying contact's local geometry is added to `geometry`."""
        area = np.zeros(self.n_regions)
        rigid = 0.0
        rows = []
        acc = self.accounting
        acc[:] = 0.0
        self.skin_force[:] = 0.0
        deepest = (0.0, -1, -1)
        seam: dict[int, list[tuple[int, np.ndarray, float]]] = {}  # other geom -> skin contacts
        n = len(ACCOUNT_CLASSES)
        for i in range(data.ncon):
            c = data.contact[i]
            if c.efc_address < 0:
                continue
            mujoco.mj_contactForce(self.model, data, i, self._force)
            f = self._force[0]
            rows.append([*c.pos, *c.frame[:3], f])
            g1, g2 = c.geom1, c.geom2
            if self.hand[g1] >= 0 and self.hand[g2] >= 0 and self.hand[g1] != self.hand[g2]:
                law = self.laws.get((min(g1, g2), max(g1, g2)))
                if law is not None and -c.dist > deepest[0]:
                    deepest = (float(-c.dist), min(g1, g2), max(g1, g2))
                if law is not None:
                    skin, other = (g1, g2) if self.hand[g1] == 0 else (g2, g1)
                    seam.setdefault(other, []).append((skin, c.pos.copy(), f))
                if law is not None and len(law) > 2:
                    acc[n + 3 + law[2]] += f
                    if geometry:
                        self._classify(data, c, law[2], f)
                if law is not None and law[0] == 0 and max(self.pad_joint[g1],
                                                           self.pad_joint[g2]) >= 0:
                    share = self._pad_share(data, c)
                    acc[0] += f * share
                    acc[1] += f * (1.0 - share)
                    acc[n] += 1
                    if f > law[1]:
                        acc[n + 1] += 1
                        acc[n + 2] += f * share
                elif law is not None:
                    acc[law[0]] += f
                    acc[n] += 1
                    if f > law[1]:
                        acc[n + 1] += 1
                        acc[n + 2] += f if law[0] == 0 else 0.0
                else:
                    acc[2 if self.bone[g1] and self.bone[g2] else 3] += f
            if self.bone[g1] and self.bone[g2]:
                rigid += f
                continue
            owners = [(g, self.region_at(data, g, c.pos)) for g in (g1, g2)]
            for _, r in owners:
                if r >= 0:
                    self.skin_force[r] += f
            depth = -c.dist
            for _, r in owners:
                if r >= 0 and depth > 0 and self._in_zone(data, r, c.pos):
                    area[r] += sphere_overlap_area(self.radius[g1], self.radius[g2], depth) * 1e6
        self.deepest = deepest
        double = 0.0
        for touches in seam.values():
            for a in range(len(touches)):
                for b in range(a + 1, len(touches)):
                    (sa, pa, fa), (sb, pb, fb) = touches[a], touches[b]
                    if sa != sb and float(np.linalg.norm(pa - pb)) < SEAM_M:
                        double += min(fa, fb)
        self.double_N = double
        return area, rigid, np.asarray(rows, dtype=float).reshape(-1, 7)

    def _classify(self, data: mujoco.MjData, c, law: int, f: float) -> None:
        """Add a law-carrying contact's force to `geometry` under its local geometry."""
        skin, other = (c.geom1, c.geom2) if self.hand[c.geom1] == 0 else (c.geom2, c.geom1)
        key = (law, *pair_class(self._local.shape(data, skin, surface_point(c, skin)),
                                self._local.shape(data, other, surface_point(c, other))))
        self.geometry[key] = self.geometry.get(key, 0.0) + f

    def _pad_share(self, data: mujoco.MjData, c) -> float:
        """The share of a contact's normal force that pushes its pad geom along the pad's axis
        (clipped to [0, 1]; the contact normal points from geom1 to geom2)."""
        g = c.geom1 if self.pad_joint[c.geom1] >= 0 else c.geom2
        axis = data.xaxis[self.pad_joint[g]]  # compression direction
        push = -float(c.frame[:3] @ axis) if g == c.geom1 else float(c.frame[:3] @ axis)
        return min(max(push, 0.0), 1.0)

    def _in_zone(self, data: mujoco.MjData, region: int, point) -> bool:
        site = self.zones[region]
        return True if site is None else _box_contains(data, self.model, site, point)

    def region_at(self, data: mujoco.MjData, geom: int, point) -> int:
        """The region (index) whose skin a contact at ``point`` (world) on ``geom`` presses: the
        geom's own, or on a surface of several zones the zone whose box is nearest (each contact
        belongs to exactly one region: inside a zone, that one; on an unsensed border, the
        nearest); -1 for a geom that carries none."""
        r = int(self.region_of[geom])
        if r != -2:
            return r
        if any(self.zones[z] is None for z in self.zones_of[geom]):
            raise ValueError(f"geom {self.model.geom(geom).name!r} carries several regions: "
                             "ContactAreas needs their zones to tell them apart")
        return min(self.zones_of[geom],
                   key=lambda z: _box_distance(data, self.model, self.zones[z], point))


def _box_contains(data: mujoco.MjData, model: mujoco.MjModel, site: int, point) -> bool:
    """Whether ``point`` (world) lies inside the box site ``site``."""
    return _box_distance(data, model, site, point) <= 1e-12


def _box_distance(data: mujoco.MjData, model: mujoco.MjModel, site: int, point) -> float:
    """Distance (m) from ``point`` (world) to the box site ``site`` (0 inside)."""
    local = data.site_xmat[site].reshape(3, 3).T @ (np.asarray(point) - data.site_xpos[site])
    return float(np.linalg.norm(np.maximum(np.abs(local) - model.site_size[site], 0.0)))


def pair_laws(env: HandshakeEnv) -> dict[tuple[int, int], tuple[int, float, int]]:
    """(geom, geom) of every contact pair -> (class index in ACCOUNT_CLASSES, calibrated range N,
    index of its law in `law_labels`).

    Pairs ``{Skin}__{tissue}`` carry the skin's design in series with tissue (``skin_law``); a
    ``rigid`` region's pairs: ``tissue_law_only``. Which law each carries:
    ``env.pair_laws`` (`softhand.envs.skins.pair_choices`).
    """
    m = env.model
    labels = law_labels(env)
    out = {}
    for pid in range(m.npair):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_PAIR, pid) or ""
        _, skin = skin_of_pair(name, env.skins)
        choice = env.pair_laws[name]
        kind = 0 if skin != "rigid" else 1
        g1, g2 = int(m.pair_geom1[pid]), int(m.pair_geom2[pid])
        out[(min(g1, g2), max(g1, g2))] = (kind, choice.calibrated_max_N,
                                           labels.index(choice.law))
    return out


def law_labels(env: HandshakeEnv) -> list[str]:
    """The distinct laws the env's pairs carry, sorted (the force accounting's ``by_law``)."""
    return sorted({c.law for c in env.pair_laws.values()})


def run_handshake(*, design: str | None = None, skins: Mapping[str, str] | None = None,
                  controller: str = "neutral", seed: int = 0, record_every: int | None = None,
                  env: HandshakeEnv | None = None, signal: str = "contact",
                  controller_settings: Mapping[str, float] | None = None,
                  options: Mapping[str, float] | None = None,
                  **env_kwargs) -> HandshakeRun:
    """Run one episode with a built-in controller (`run_policy`, which keeps every
    ``record_every``-th physics step for the recording; default: the last step of every action,
    100 Hz). ``signal`` and ``controller_settings`` go to
    `make_controller`.

    ``options`` go to the env's reset (the episode's partner: grip, duration, shake phase).

    ``env`` is an environment built already (then ``design``, ``skins`` and ``env_kwargs`` are
    not used): the CLI builds it first, so that every input is checked before the episode.
    """
    if env is None:
        env = HandshakeEnv(design=design, skins=skins, **env_kwargs)
    ctrl = make_controller(controller, signal, **dict(controller_settings or {}))
    about = {"name": controller, "signal": signal if controller != "open-loop" else None,
             **dict(controller_settings or {})}
    return run_policy(env, ctrl, seed=seed, options=options, record_every=record_every,
                      about=about)


def check_policy(env: Any, policy: Any) -> HandshakeEnv:
    """The HandshakeEnv under ``env`` (itself, or the env a Gymnasium wrapper wraps), after
    checking that ``policy`` can be called.

    Raises:
        ValueError: ``env`` is not a HandshakeEnv or a wrapper of one, or ``policy`` is not
            callable, naming the value.
    """
    base = getattr(env, "unwrapped", None)
    if not isinstance(base, HandshakeEnv):
        raise ValueError(f"env = {show(env)}: expected a softhand HandshakeEnv or a Gymnasium "
                         "wrapper of one (gymnasium.make('softhand/Handshake-v0'))")
    if not callable(policy):
        raise ValueError(f"policy = {show(policy)}: expected a callable policy(obs, info) -> "
                         "action")
    return base


def run_policy(env: Any, policy: Callable[[Any, dict], Any], *, seed: int = 0,
               options: Mapping[str, float] | None = None, record_every: int | None = None,
               about: Mapping[str, Any] | None = None) -> HandshakeRun:
    """Run one episode of ``env`` with ``policy(obs, info) -> action`` and collect what a user
    looks at (the `HandshakeRun`: state, forces, readings, contacts and accounting at
    every ``record_every``-th physics step; default the last of every action, 100 Hz).

    ``env`` is a HandshakeEnv or a Gymnasium wrapper of one: the episode steps through the
    wrappers (the policy gets their observation), the state is read from the HandshakeEnv.
    ``seed`` and ``options`` go to its reset. ``about`` is what the run's ``controller`` says
    (default: the policy's name).

    Raises:
        ValueError: a bad ``env`` or ``policy`` (`check_policy`), before any work; a bad
            seed, option or action as the env's reset and step say.
        DivergenceError: the physics diverged.
    """
    base = check_policy(env, policy)
    if about is None:
        about = {"name": getattr(policy, "__name__", type(policy).__name__)}
    record_every = record_every or base.frame_skip
    obs, info = env.reset(seed=seed, options=options)
    m, d = base.model, base.data
    zones = [m.site(f"pro_touch_{r}").id for r in base.region_names]
    areas = ContactAreas(m, [m.geom(g).id for g in base.region_geoms], pair_laws(base), zones)
    def geoms(table: dict) -> list[np.ndarray]:  # per hand, a mask of its pieces in ``table``
        return [np.isin(np.arange(m.ngeom), [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM,
                                                               f"{prefix}{p}") for p in pieces])
                for prefix, pieces in (("pro_skin_", table["prosthetic"]),
                                       ("hum_tissue_", table["partner"]))]
    palms, faces = geoms(PALM_PIECES), tuple(geoms(PALM_FACES))
    face = [base.region_names.index(z) for z in PALM_FACE_ZONES]

    def palmar(geom: int, point: np.ndarray) -> bool:  # the palm's surface: its palmar zones
        return areas.region_of[geom] != -2 or areas.region_at(d, geom, point) in face
    frames: dict[str, list] = {k: [] for k in ("t", "q", "mp", "mq", "f", "c", "ph", "a", "r",
                                                "acc", "sf", "pf", "s", "g", "pp", "dp", "dn", "dc")}
    geom_name = [m.geom(g).name for g in range(m.ngeom)]
    pad_joints = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"{g}_pad")
                  for g in base.region_geoms]
    pads = np.array([m.jnt_qposadr[j] if j >= 0 else -1 for j in pad_joints])
    pad_dofs = np.array([m.jnt_dofadr[j] if j >= 0 else 0 for j in pad_joints])
    has_pads = bool((pads >= 0).any())
    steps, wall, first = 0, 0.0, None  # the speed leaves out the first step (HandshakeRun)
    while True:
        t0 = time.perf_counter()
        with mujoco_warnings_kept():  # a divergence is raised below, not printed by MuJoCo
            obs, _, term, trunc, info = env.step(policy(obs, info))
        if first is None:
            first = time.perf_counter() - t0
        else:
            wall += time.perf_counter() - t0
        steps += base.frame_skip
        if steps % record_every == 0 or term or trunc:
            frames["t"].append(d.time)
            frames["q"].append(d.qpos.copy())
            frames["mp"].append(d.mocap_pos.copy())
            frames["mq"].append(d.mocap_quat.copy())
            frames["f"].append([info["region_forces_N"][r] for r in base.region_names])
            frames["s"].append([info["sensor_readings_N"][r] for r in base.region_names])
            frames["ph"].append(info["phase"])
            frames["g"].append((info["partner_grip_measured_N"], info["partner_grip_N"]))
            frames["pp"].append(_palm_to_palm(d, *palms, palmar, faces))
            area, rigid, rows = areas(d)
            frames["c"].append(rows)
            frames["a"].append(area)
            frames["r"].append(rigid)
            frames["acc"].append(areas.accounting.copy())
            depth, g1, g2 = areas.deepest
            frames["dp"].append(1e3 * depth)
            frames["dc"].append(areas.double_N)
            frames["dn"].append(f"{geom_name[g1]}/{geom_name[g2]}" if g1 >= 0 else "")
            if has_pads:  # the pads' force at this frame's state (mj_step leaves the forces
                # of the state it started from), so that compression and force go together
                mujoco.mj_forward(m, d)
                areas(d, geometry=False)
            frames["sf"].append(areas.skin_force.copy())
            frames["pf"].append(-d.qfrc_passive[pad_dofs])  # the pad's push on its skin
        if term or trunc:
            break
    if term and info.get("unstable"):
        raise DivergenceError(base.physics.divergence, skins=base.skins,
                              representations=base.representations,
                              timestep_s=float(m.opt.timestep))
    summary = info.get("beyond_range_summary") or {}
    first_overload = ({"time_s": summary["first_overload_time_s"],
                       "what": summary["first_overload"]}
                      if summary.get("first_overload") else {})
    timed = steps - base.frame_skip  # the physics steps of the timed env steps
    if timed == 0:  # an episode of one env step: its speed is that step's
        wall, timed, first = first, steps, 0.0
    q = np.array(frames["q"])
    compression = np.where(pads >= 0, 1e3 * q[:, np.maximum(pads, 0)], np.nan)
    return HandshakeRun(base.region_names, dict(base.skins), np.array(frames["t"]), q,
                        np.array(frames["mp"]), np.array(frames["mq"]), np.array(frames["f"]),
                        frames["c"], frames["ph"], wall, timed, m, np.array(frames["a"]),
                        np.array(frames["r"]), np.array(frames["acc"]), np.array(frames["sf"]),
                        compression if has_pads else None,
                        np.array(frames["pf"]) if has_pads else None,
                        dict(base.representations), base.calibration_dir,
                        np.array(frames["s"]), dict(base.sensor_placements),
                        base.sensors.spec.to_dict(), dict(about),
                        np.array(frames["g"]), np.array(frames["pp"]),
                        {"hand": base.hand, "partner_size_mm": list(base.partner_size_mm),
                         "seed": seed, "options": dict(options or {}),
                         "softhand_version": __version__},
                        tuple(law_labels(base)), base.contact_laws, first,
                        np.array(frames["dp"]), frames["dn"], first_overload,
                        np.array(frames["dc"]), dict(areas.geometry))
