"""The partner's scripted handshake: reach, grip, shake, hold, release and return.

Timeline (Cabibihan et al., "Guidelines for robot-to-human handshake from the movement nuances
in human-to-human handshake", Front. Robot. AI 9:758519, 2022: a handshake lasts 3.63 +/- 0.45 s:
reach 0.92 s, contact 1.96 s, return 0.75 s; the contact divides into a preshake of 0.06 s, a main
shake of 1.31 s, a postshake of 0.06 s and 0.52 s of no movement just before the hands are
retracted):

| phase | what the partner does |
|---|---|
| reach | mount moves from its start pose to the contact pose (minimum-jerk), 0.92 s |
| grip | fingers and thumb close until the grip force reaches its target, 0.30 s |
| shake | mount oscillates at 4 Hz (Melnyk et al., IEEE AIM 2014), 1.31 s |
| hold | mount still, grip held: the published 0.52 s of no movement (relaxation shows here) |
| release | fingers open, 0.35 s |
| return | mount goes back to its start pose, 0.75 s |

The closing and the opening are phases of their own here (0.30 + 0.35 s), where the published
contact phase has 0.06 s of pre- and postshake and the closing overlaps the reach: the contact
lasts 2.48 s against the published 1.96 s, the handshake 4.15 s (assumption: a hand cannot
close over another in 0.06 s; the published 0.52 s hold is kept whole). Population durations
scale this timeline by the published spread (softhand.envs.population).

Grip: the partner reaches with an open hand, closes to its grasp posture (solved from the
handshake's contacts, softhand.hands.grasp) and adds a grip effort (joint impedance towards the
grasp plus a flexion offset on the fingers' joints and the thumb's CMC, THUMB_HOLDS keeping
the thumb's MCP and IP at the grasp): a PI regulator (GRIP_KP, GRIP_TI_S) sets the effort so
that the summed force its
phalanges feel (contact sensors ``hum_feel_*`` on the phalanx tissues, as the data-glove sensors
on the subjects' fingers; the palm and thenar are left out, so that a push on the palm does not
open the fingers) follows GRIP_FORCE_N times ``squeeze`` times GRIP_PHALANGES (GRIP_FORCE_N
says what Melnyk et al. 2014 published and what is read into it). Shake amplitude: +-5 mm
vertically (assumption: only the *relative* motion of the two hands is modelled; the arm's gross
shake moves both hands together and is left out, "a scene models only what it needs").
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numba import njit, vectorize

from softhand.hands.grasp import Grasp
from softhand.hands.partner import PARTNER_JOINTS
from softhand.paper import paper

__all__ = [
    "CLOSE_S",
    "GRIP_FORCE_N",
    "GRIP_PHALANGES",
    "HOLDING",
    "MAX_EFFORT_RAD",
    "MAX_SQUEEZE",
    "PARTNER_SD_RANGE",
    "PHASES",
    "RELEASING",
    "PartnerScript",
    "RelaxedHand",
    "Timeline",
    "check_partner_size",
    "check_reset_options",
    "partner_postures",
    "partner_size_range",
    "phase_at",
    "phase_index",
]

PHASES = ("reach", "grip", "shake", "hold", "release", "return", "done")
#: Phases in which the hands hold each other: the partner grips, the reward's grip and contact
#: terms count, the controllers close (everything of the handshake written once here)
HOLDING = ("grip", "shake", "hold")
#: Phases in which the hands let go
RELEASING = ("release", "return", "done")
#: Grip per phalanx (N). Melnyk, Borysenko & Henaff (2014, IEEE/ASME AIM, pp. 1753-1758) measured
#: handshakes between people with "a special pair of data gloves" and report that the "average
#: strength of the grip is 2.5 N" (their abstract, the only part of the paper this project could
#: read): not how many sensors, where on the hand, or whether per sensor or for the whole grip.
#: assumption: per sensor, one sensor a phalanx, so the grip is this per touching phalanx
#: (GRIP_PHALANGES). No other handshake between two people with a published grip force was
#: found (Orefice et al. 2018, RO-MAN, and Knoop et al. 2017, IROS, measured pressures whose
#: numbers could not be read; Cabibihan et al. 2011 give where the force is high, not how high).
GRIP_FORCE_N = 2.5
#: Phalanges the grip force is summed over (its target is GRIP_FORCE_N x this). assumption: the
#: partner phalanges that touch the other hand in the grasp of two 190 x 88 mm hands (the paper's
#: experimenter's size); a person's grip does not grow with how many phalanges happen to touch.
GRIP_PHALANGES = 8
SHAKE_HZ = 4.0  # Melnyk et al. 2014
SHAKE_AMPLITUDE_M = 0.005  # assumption, see the module docstring


@dataclass(frozen=True)
class Timeline:
    """Phase durations (s) after Cabibihan et al. 2022 (module docstring)."""

    reach_s: float = 0.92
    grip_s: float = 0.30
    shake_s: float = 1.31
    hold_s: float = 0.52
    release_s: float = 0.35
    return_s: float = 0.75

    def __post_init__(self) -> None:
        for name in ("reach_s", "grip_s", "shake_s", "hold_s", "release_s", "return_s"):
            v = getattr(self, name)
            if not (np.isfinite(v) and 0 < v <= 10):
                raise ValueError(f"{name} = {v!r} s must be in (0, 10]")

    @cached_property
    def ends(self) -> tuple[float, ...]:
        """End time (s) of each phase but ``done``; computed once (the env asks every step)."""
        return tuple(float(x) for x in np.cumsum([self.reach_s, self.grip_s, self.shake_s,
                                                  self.hold_s, self.release_s, self.return_s]))

    @property
    def total_s(self) -> float:
        return self.ends[-1]

    def phase(self, t: float) -> str:
        return PHASES[int(phase_index(np.array([self.ends]), np.array([t], float))[0])]

    def scaled(self, factor: float) -> Timeline:
        return Timeline(*(factor * v for v in (self.reach_s, self.grip_s, self.shake_s,
                                                self.hold_s, self.release_s, self.return_s)))


@njit(cache=True, inline="always")
def _clip(x: float, lo: float, hi: float) -> float:
    """min(max(x, lo), hi), NaN kept (as np.minimum(np.maximum(x, lo), hi))."""
    if x != x:
        return x
    return min(max(x, lo), hi)


@vectorize(["float64(float64)"], cache=True)
def _min_jerk(s):
    """Minimum-jerk blend 0 -> 1 of s in [0, 1] (clipped): a ufunc, for a number or an array,
    and for the compiled per-step kernels."""
    s = _clip(s, 0.0, 1.0)
    # C's pow, as Python's s**3 on a float (numpy's s**3 differs in the last bit for about 5 % of
    # an array's entries, and a handshake amplifies that to 1e-9 N)
    return math.pow(s, 3.0) * (10.0 - 15.0 * s + 6.0 * s * s)


#: Slack (s) of every comparison of the simulation clock with a scripted time. MuJoCo's clock is
#: a sum of timesteps and lands on a scripted time from either side, by the timestep (the
#: open-loop close, 0.8 s from the grip's start, measured 0.8000000000000006 s at 2 ms and
#: 0.7999999999999184 s at 1 ms): without the slack a phase, or a command that lasts a scripted
#: time, ended one action apart at two timesteps (the open-loop close: one action more at 1 ms,
#: every motor 0.5 deg further closed, the middle phalanges 8-10 % apart in the shake and the
#: hold).
CLOCK_SLACK_S = 1e-9


@njit(cache=True, inline="always")
def phase_at(ends: np.ndarray, t: float) -> int:
    """Index in PHASES at time ``t`` (s) of one world whose phases but ``done`` end at ``ends``
    (its Timeline.ends; compiled, for the per-step kernels and the single env)."""
    k = 0
    for e in ends:
        k += e <= t + CLOCK_SLACK_S
    return min(k, len(PHASES) - 1)


def phase_index(ends: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Index in PHASES of each world's phase at its time: ``ends`` (W, 6) the end of each phase
    but ``done`` (Timeline.ends per world), ``t`` (W,) (s)."""
    return _phase_index(ends, np.asarray(t, float).reshape(-1))


@njit(cache=True)
def _phase_index(ends: np.ndarray, t: np.ndarray) -> np.ndarray:
    out = np.empty(t.size, np.int64)
    for w in range(t.size):
        out[w] = phase_at(ends[w], t[w])
    return out


#: Time from the end of the reach to the grasp posture (s): the digits close over the other hand
#: in the first part of the grip phase. assumption.
CLOSE_S = 0.2
#: In the hold (the published 0.52 s of no movement) the partner keeps its grip effort, the
#: flexion offset its regulator had at the end of the shake, instead of regulating the force:
#: the hands hold still (assumption: a person holds the posture, not the force, for half a
#: second), so the skins' relaxation shows as a fall of the force.
HOLD_KEEPS_EFFORT = True
#: Largest grip effort (rad of extra flexion target on every flexing digit joint). With the
#: impedance of softhand.hands.partner it presses a phalanx with a few newtons: the regulator
#: never needs it whole in a light handshake, so it does not saturate into a fist.
MAX_EFFORT_RAD = 1.0
#: The grip regulator's gains (`_grips`): the proportional part gives GRIP_KP of the whole
#: effort at 100 % force error, the integral part takes the whole effort in GRIP_TI_S. Chosen on
#: the default run (seeds 0-4, three controllers), the four +-2.5 SD corner partners and 30
#: sampled partners (reports/palm-alignment.md): with the palms held parallel the gains before
#: (0.5, 0.1 s) let the integral charge while the fingers closed and the grip overshot; a
#: proportional gain of 1.0 stepped the digits' targets by a whole effort at the grip's first
#: step, the partner's index slammed onto the other palm and the 1 and 2 ms runs parted by 33 %
#: on that peak.
GRIP_KP = 0.7
GRIP_TI_S = 0.12


class PartnerScript:
    """Mount pose and digit joint targets of the partner at time t, with a grip-force regulator,
    for one world or for W worlds at once (arrays with a leading world axis: the vector env's
    worlds; one world is W = 1, and the single env runs the same code).

    The partner reaches with an open hand (``open_q``), closes to its grasp posture (``grasp_q``,
    solved from the handshake's contacts, softhand.hands.grasp) in CLOSE_S, then adds a grip
    effort, a flexion offset on every flexing joint (``effort_dir``) that an integral controller
    sets so that the force its digits feel follows ``grip_force_N``; on release the effort goes
    and the hand opens.

    Args (one world's plan; `stack` makes W worlds of W one-world scripts):
        timeline: phase durations.
        start_pos, contact_pos: mount positions (m); the orientation stays fixed.
        grip_force_N: target of the grip measure the env feeds grip(): the summed normal force
            on the partner's phalanges, > 0.
        shake_phase: shake phase offset (rad).
        open_q, grasp_q: joint targets (rad) of the open hand and of the grasp, one per digit servo.
        effort_dir: per servo, 1 where the grip effort flexes the joint, 0 where it does not.
        q_max: per servo, the largest target (rad): the joint's upper limit less the grasp's
            margin, so that a digit that meets nothing does not curl onto its stop (a fist).
    """

    def __init__(self, timeline: Timeline, start_pos: np.ndarray, contact_pos: np.ndarray, *,
                 grip_force_N: float = GRIP_FORCE_N, shake_phase: float = 0.0,
                 open_q: np.ndarray, grasp_q: np.ndarray, effort_dir: np.ndarray,
                 q_max: np.ndarray) -> None:
        if not (np.isfinite(grip_force_N) and grip_force_N > 0):
            raise ValueError(f"grip_force_N = {grip_force_N!r} must be finite and > 0")
        #: each world's timeline
        self.timelines = [timeline]
        self.ends = np.array([timeline.ends])  # (W, 6) end of each phase but done (s)
        self.reach_s = np.array([timeline.reach_s])
        self.return_s = np.array([timeline.return_s])
        self.starts = np.asarray(start_pos, float)[None].copy()  # (W, 3)
        self.contacts = np.asarray(contact_pos, float)[None].copy()
        self.grip_forces_N = np.array([float(grip_force_N)])  # (W,)
        self.shake_phases = np.array([float(shake_phase)])
        self.open = np.asarray(open_q, float)[None].copy()  # (W, servos)
        self.grasp = np.asarray(grasp_q, float)[None].copy()
        self.effort_dir = np.asarray(effort_dir, float)[None].copy()
        self.q_max = np.asarray(q_max, float)[None].copy()
        #: the grip effort (rad) of each world, the regulator's state
        self.efforts = np.zeros(1)
        self._integral = np.zeros(1)
        self._release_from = self.grasp.copy()  # the targets the release starts from
        self._released = np.zeros(1, bool)  # whether _release_from was set by a grip

    _ROWS = ("ends", "reach_s", "return_s", "starts", "contacts", "grip_forces_N", "shake_phases",
             "open", "grasp", "effort_dir", "q_max", "efforts", "_integral", "_release_from",
             "_released")

    @classmethod
    def stack(cls, scripts: list[PartnerScript]) -> PartnerScript:
        """One script of the worlds of ``scripts`` (in order), their states included."""
        out = cls.__new__(cls)
        out.timelines = [tl for s in scripts for tl in s.timelines]
        for name in cls._ROWS:
            setattr(out, name, np.concatenate([getattr(s, name) for s in scripts]))
        return out

    def set_world(self, i: int, script: PartnerScript) -> None:
        """Make world ``i`` the one world of ``script`` (a new episode's plan and state)."""
        self.timelines[i] = script.timelines[0]
        for name in self._ROWS:
            getattr(self, name)[i] = getattr(script, name)[0]

    # one world's view (W = 1), as the single env and its scenario read it
    @property
    def timeline(self) -> Timeline:
        return self.timelines[0]

    @property
    def start(self) -> np.ndarray:
        return self.starts[0]

    @property
    def contact(self) -> np.ndarray:
        return self.contacts[0]

    @property
    def grip_force_N(self) -> float:  # noqa: N802 (the one-world name it always had)
        return float(self.grip_forces_N[0])

    @property
    def shake_phase(self) -> float:
        return float(self.shake_phases[0])

    @property
    def effort(self) -> float:
        return float(self.efforts[0])

    def mount(self, t: float) -> np.ndarray:
        """One world's mount position (m) at ``t`` (s)."""
        return self.mounts(np.array([t], float))[0]

    def grip(self, t: float, grip_force_N: float, dt: float) -> np.ndarray:
        """One world's digit joint targets (`grips`)."""
        return self.grips(np.array([t], float), np.array([grip_force_N], float), dt)[0]

    def mounts(self, t: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        """Every world's mount position (m), shape (W, 3), at its time ``t`` (s, shape (W,));
        with ``rows``, the mount of world ``rows[k]`` at ``t[k]`` (k entries)."""
        r = slice(None) if rows is None else rows
        e, starts, contacts = self.ends[r], self.starts[r], self.contacts[r]
        t = np.asarray(t, float)
        reach = starts + _min_jerk(t / self.reach_s[r])[:, None] * (contacts - starts)
        held = contacts.copy()
        ramp = np.minimum(1.0, np.minimum((t - e[:, 1]) / 0.1, (e[:, 2] - t) / 0.1))  # 0.1 s fades
        shaking = (e[:, 1] <= t) & (t < e[:, 2])
        held[:, 2] += np.where(shaking, ramp * SHAKE_AMPLITUDE_M * np.sin(
            2 * np.pi * SHAKE_HZ * (t - e[:, 1]) + self.shake_phases[r]), 0.0)
        back = contacts + (_min_jerk((t - e[:, 4]) / self.return_s[r])[:, None]
                           * (starts - contacts))
        return np.where((t < e[:, 0])[:, None], reach, np.where((t < e[:, 4])[:, None], held, back))

    def mount_path(self, times: np.ndarray, world: int = 0) -> np.ndarray:
        """World ``world``'s mount positions (m) at ``times`` (s), shape (len(times), 3)."""
        times = np.asarray(times, float)
        return self.mounts(times, np.full(times.shape, world))

    def grips(self, t: np.ndarray, grip_force_N: np.ndarray, dt: float) -> np.ndarray:
        """Every world's digit joint targets (W, servos) at its time ``t`` (W,) from the summed
        force its phalanges feel (``grip_force_N``, (W,)): open on the reach, close to the grasp,
        regulate, then open."""
        return _grips(np.asarray(t, float).reshape(-1),
                      np.asarray(grip_force_N, float).reshape(-1), float(dt), self.ends,
                      self.open, self.grasp, self.effort_dir, self.q_max, self.grip_forces_N,
                      self._integral, self.efforts, self._release_from, self._released)


@njit(cache=True)
def _grips(t, feel_N, dt, ends, open_q, grasp_q, effort_dir, q_max, grip_N, integral, efforts,
           release_from, released):
    """`PartnerScript.grips` of every world, compiled (a few microseconds a step, where numpy's
    calls on one world's dozen numbers took tens); updates the regulator's state arrays in place.
    """
    out = open_q.copy()  # the reach
    for w in range(t.size):
        phase = phase_at(ends[w], t[w])
        if phase == 1 or phase == 2 or phase == 3:  # HOLDING
            s = _min_jerk((t[w] - ends[w, 0]) / CLOSE_S)
            if phase != 3 or not HOLD_KEEPS_EFFORT:  # the hold keeps the shake's last effort
                target = grip_N[w]
                error = _clip((target - feel_N[w]) / target, -1.0, 1.0)
                # PI (GRIP_KP, GRIP_TI_S)
                integral[w] = _clip(integral[w] + MAX_EFFORT_RAD * error * dt / GRIP_TI_S, 0.0,
                                    MAX_EFFORT_RAD)
                efforts[w] = _clip(integral[w] + GRIP_KP * MAX_EFFORT_RAD * error, 0.0,
                                   MAX_EFFORT_RAD)
            for j in range(out.shape[1]):
                q = (open_q[w, j] + s * (grasp_q[w, j] - open_q[w, j])
                     + efforts[w] * effort_dir[w, j])
                q = q if q != q else min(q, q_max[w, j])  # np.minimum: NaN kept
                release_from[w, j] = out[w, j] = q
            released[w] = True
        elif phase >= 4:  # RELEASING: the effort goes and the hand opens in 0.2 s
            efforts[w] = integral[w] = 0.0
            s = _min_jerk((t[w] - ends[w, 3]) / 0.2)
            for j in range(out.shape[1]):
                held = release_from[w, j] if released[w] else grasp_q[w, j]
                out[w, j] = held + s * (open_q[w, j] - held)
    return out


#: How far inside its range the open hand holds a joint whose range starts at 0 (PIP, thumb MCP):
#: a relaxed open hand is slightly flexed, not pressed on its extension stops (deg; assumption).
OPEN_MARGIN_DEG = 5.0


#: The thumb joints that hold the grasp's posture instead of taking the grip effort: the thumb
#: presses onto the other hand's back from its base (the CMC), its MCP and IP keep their angles
#: (assumption). With the flexion offset on all three, the fingers of the largest partners
#: (216 mm long) closed over the thumb's tip and pushed its MCP and IP onto their stops, 1-1.5 mm
#: into the fingers, once the palms lie parallel (reports/palm-alignment.md).
THUMB_HOLDS = ("thumb_mcp", "thumb_ip")
#: How far inside its range the grip effort may flex a digit joint (deg; ``q_max``): a digit that
#: meets nothing does not curl onto its stop (a fist). Assumption, 7 deg: with the grasp's own
#: 10 deg (GraspSettings.limit_margin_deg) the longest, narrowest partner (216 x 73 mm), whose
#: fingers wrap the other hand to that bound, held its grip 16 % short at full effort.
GRIP_LIMIT_MARGIN_DEG = 7.0


def partner_postures(grasp: Grasp, lower_rad: np.ndarray,
                     upper_rad: np.ndarray) -> dict[str, np.ndarray]:
    """PartnerScript's postures for a grasp: ``grasp_q`` the solved posture; ``open_q`` the
    reaching hand, fingers straight (OPEN_MARGIN_DEG off the stops of joints whose range starts at
    0) and the thumb extended at its grasp abduction (it passes over
    the other hand's web space and closes onto its back); ``effort_dir`` 1 on every flexing joint
    (all but the thumb's abduction); ``q_max`` the joints' upper limits ``upper_rad`` less the
    grasp's limit margin (GraspSettings.limit_margin_deg)."""
    grasp_q = np.asarray(grasp.partner_q, float)
    open_q = np.maximum(0.0, np.asarray(lower_rad, float) + np.radians(OPEN_MARGIN_DEG))
    rot = PARTNER_JOINTS.index("thumb_rot")
    open_q[rot] = grasp_q[rot]
    effort_dir = np.ones_like(grasp_q)
    for joint in ("thumb_rot", *THUMB_HOLDS):
        effort_dir[PARTNER_JOINTS.index(joint)] = 0.0
    q_max = np.asarray(upper_rad, float) - np.radians(GRIP_LIMIT_MARGIN_DEG)
    return {"open_q": open_q, "grasp_q": grasp_q, "effort_dir": effort_dir, "q_max": q_max}


#: How far from the paper's subjects' mean a partner's hand may be, in standard deviations (Table 1).
PARTNER_SD_RANGE = 2.5


def partner_size_range() -> dict[str, tuple[float, float]]:
    """Allowed partner hand length and width (mm): the paper's 30 subjects (Table 1, read from
    softhand.paper) +- PARTNER_SD_RANGE standard deviations."""
    subjects = paper()["anthropometry"]
    out = {}
    for key in ("length", "width"):
        mean, sd = subjects[f"subjects_hand_{key}_mm"]
        out[key] = (mean - PARTNER_SD_RANGE * sd, mean + PARTNER_SD_RANGE * sd)
    return out


def check_partner_size(size) -> tuple[float, float]:
    """``size`` as (length_mm, width_mm) within partner_size_range(); None: the experimenter's
    190 x 88 mm (Table 1).

    Raises:
        ValueError: naming the value and the allowed range.
    """
    subjects = paper()["anthropometry"]
    if size is None:
        return (float(subjects["experimenter_hand_length_mm"]),
                float(subjects["experimenter_hand_width_mm"]))
    ranges = partner_size_range()
    allowed = ", ".join(f"{k} {lo:g}-{hi:g} mm" for k, (lo, hi) in ranges.items())
    try:  # a sequence of two numbers: not a mapping (its keys) nor a string (its characters)
        values = () if isinstance(size, (Mapping, str, bytes)) else tuple(float(v) for v in size)
    except (TypeError, ValueError):
        values = ()
    if len(values) != 2 or not all(np.isfinite(values)):
        raise ValueError(f"partner_size = {size!r}: expected (length_mm, width_mm); allowed "
                         f"{allowed} (+-{PARTNER_SD_RANGE:g} SD of the paper's subjects)")
    for key, value in zip(("length", "width"), values, strict=True):
        lo, hi = ranges[key]
        if not lo - 1e-9 <= value <= hi + 1e-9:
            raise ValueError(f"partner_size {key} = {value!r} mm: allowed {lo:g}-{hi:g} mm "
                             f"(+-{PARTNER_SD_RANGE:g} SD of the paper's subjects, Table 1)")
    return values


#: Largest ``squeeze`` (the partner's grip per phalanx as a multiple of GRIP_FORCE_N): the
#: partner's hardest grip, the hard case of the tests. Measured (one episode each, seed 0, no
#: randomization; the default scene with the neutral and open-loop controllers, and with rigid
#: skins, the human hand and the smallest and largest partners): the summed phalanx force follows
#: its target up to squeeze 2.5 (50 N over GRIP_PHALANGES); from 3 the grip effort sits at
#: MAX_EFFORT_RAD for a growing share of the grip and shake (up to 89 % at 3.5, 92-96 % at 4-5),
#: and above that the forces stop following the squeeze: in the default scene the largest region
#: force is 24.2 N (neutral) and 25.0 N (open loop) at every squeeze from 4 to 1e6, and in the
#: other scenes the partner's mean grip moved by 0.1-9 % from 5 to 8 while its target grew 60 %.
#: A larger squeeze would ask for a grip the partner's hand cannot give: refused.
MAX_SQUEEZE = 5.0

#: reset() options that set the episode's partner, with their allowed closed ranges: the grip per
#: phalanx up to GRIP_FORCE_N x MAX_SQUEEZE (the partner's hardest grip, as ``squeeze``); the
#: duration around the published 3.63 +- 0.45 s; the shake's phase within one turn either way
#: (every other angle is one of these).
RESET_OPTIONS = {"grip_N": (1e-6, GRIP_FORCE_N * MAX_SQUEEZE), "duration_s": (2.0, 6.0),
                 "shake_phase_rad": (-2 * np.pi, 2 * np.pi)}


def check_reset_options(options) -> dict[str, float]:
    """reset()'s ``options``: None or a mapping of RESET_OPTIONS keys to numbers in range.

    Raises:
        ValueError: an unknown key or a value out of range, naming it and the range.
    """
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise ValueError(f"options = {options!r}: expected None or a mapping with keys "
                         f"{', '.join(RESET_OPTIONS)}")
    out = {}
    for key, value in options.items():
        if key not in RESET_OPTIONS:
            raise ValueError(f"options key {key!r} is unknown; allowed: {', '.join(RESET_OPTIONS)}")
        lo, hi = RESET_OPTIONS[key]
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
            raise ValueError(f"options[{key!r}] = {value!r}: expected a number in [{lo:g}, {hi:g}]")
        if not (np.isfinite(value) and lo <= value <= hi):
            raise ValueError(f"options[{key!r}] = {value!r}: allowed [{lo:g}, {hi:g}]")
        out[key] = float(value)
    return out


class RelaxedHand:
    """The paper's experimenter's hand in a neutral handshake ("kept his grasping force at a
    minimum and waited for the handshake partner to initiate the contact"): targets of the 6 soft
    drives of a ``relaxed-human`` hand. Open on the reach with the thumb rotated to the grasp,
    closing to the grasp posture (``grasp_q``, solved from the handshake's contacts) in CLOSE_S
    once the partner arrives, holding it through the shake, opening in 0.2 s from the release; the
    thumb keeps its rotation. One world, or W worlds at once (`stack`, `targets_at`).

    Args:
        timeline: the episode's phases.
        grasp_q: the drives' grasp angles (rad), in the order of the hand's actuators.
        rotation: index of the thumb's rotation drive in ``grasp_q``.
    """

    def __init__(self, timeline: Timeline, grasp_q: np.ndarray, rotation: int) -> None:
        self.ends = np.array([timeline.ends])  # (W, 6)
        self.grasp = np.asarray(grasp_q, float)[None].copy()  # (W, drives)
        self.open = np.zeros_like(self.grasp)
        self.open[:, rotation] = self.grasp[:, rotation]

    @classmethod
    def stack(cls, hands: list[RelaxedHand]) -> RelaxedHand:
        out = cls.__new__(cls)
        for name in ("ends", "grasp", "open"):
            setattr(out, name, np.concatenate([getattr(h, name) for h in hands]))
        return out

    def set_world(self, i: int, hand: RelaxedHand) -> None:
        for name in ("ends", "grasp", "open"):
            getattr(self, name)[i] = getattr(hand, name)[0]

    def targets(self, t: float) -> np.ndarray:
        """One world's targets at ``t`` (s)."""
        return self.targets_at(np.array([t], float))[0]

    def targets_at(self, t: np.ndarray) -> np.ndarray:
        """Every world's targets (W, drives) at its time ``t`` (W,)."""
        t = np.asarray(t, float)
        phase = phase_index(self.ends, t)[:, None]
        closing = self.open + _min_jerk((t - self.ends[:, 0]) / CLOSE_S)[:, None] * (
            self.grasp - self.open)
        opening = self.grasp + _min_jerk((t - self.ends[:, 3]) / 0.2)[:, None] * (
            self.open - self.grasp)
        return np.where(phase == 0, self.open, np.where(phase <= 3, closing, opening))
