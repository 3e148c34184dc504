"""Controllers of the prosthetic hand, for testing grasp control in the handshake.

Each maps an observation and the env's ``info`` to an action in ``[-1, 1]^6`` (finger motors,
thumb flexion, thumb rotation; positive closes): ``ctrl(obs, info)`` for a single env, and
``ctrl.actions(obs, info, region_names)`` for W worlds of the vector env (softhand.envs.vector)
at once, with per-world state; both are the same array code (one world for a single env):

* `OpenLoopClose`: rotate the thumb to its handshake posture, close every digit at a fixed
  speed for a fixed time once the partner grips, hold, open when it lets go (what a myoelectric
  user does with one short "close" signal).
* `ForceRegulating`: per digit, close until the force of that digit's most loaded region
  reaches a target grip force, open a little when over it (a proportional force loop on the region
  forces); the thumb rotates to its handshake posture.
* `Neutral`: the paper's sensored hand (the experimenter's "neutral handshake: minimal grip,
  waiting for the partner"): per digit, close until the digit first touches the partner, then hold
  that posture (the motors are not back-drivable) until the partner lets go; the thumb rotates to
  the grasp's rotation and closes over the back of the partner's index metacarpal. The default of
  ``softhand handshake``, since it is the scenario of the paper's Fig. 4.

The force-feedback controllers take ``signal``: ``contact`` (default) feeds them the true region
forces (``info["region_forces_N"]``), ``sensor`` what the embedded sensors let a calibrated
read-out infer (``info["sensor_load_estimate_N"]``: the transfer law inverted, with the sensor's
latency, noise, threshold and quantization, and nothing inside a pocket's dead band).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields

import numpy as np

from softhand.envs.partner import CLOCK_SLACK_S, HOLDING, RELEASING
from softhand.validate import check_number

__all__ = ["CONTROLLERS", "SIGNALS", "ForceRegulating", "Neutral", "OpenLoopClose",
           "make_controller"]

#: what a force-feedback controller reads: the true contact forces, or the embedded sensors
SIGNALS = {"contact": "region_forces_N", "sensor": "sensor_load_estimate_N"}


#: Allowed ranges of the controllers' settings (closed unless marked open), with why:
#: a speed is a fraction of the motors' maximum; the longest episode is 6 s (reset option
#: duration_s); a force target or touch threshold lies between the 0.05 N at which a region
#: counts as touched and the 20 N the pair laws are fitted to; at a gain of 10 per N a 0.1 N
#: error already commands full speed (a larger gain only makes the loop bang-bang).
SPEED_RANGE = (0.0, 1.0)  # open at 0
CLOSE_S_RANGE = (0.0, 6.0)  # open at 0
FORCE_RANGE_N = (0.05, 20.0)
GAIN_RANGE_PER_N = (0.0, 10.0)  # open at 0


def _check_signal(signal: str) -> None:
    if not isinstance(signal, str) or signal not in SIGNALS:
        raise ValueError(f"signal = {signal!r} is unknown; allowed: {', '.join(SIGNALS)}")

_DIGITS = ("Index", "Middle", "Ring", "Little", "Thumb")
_GRIPPING = HOLDING
#: Phases in which the controllers open the digits. The thumb keeps its rotation: turning it back
#: while the partner's hand still lies under it swept it through that hand (14-18 N on Thumb1-2
#: and 1.4 N bone on bone in the release of the default handshake).
_RELEASE = RELEASING


class _Worlds:
    """What the controllers read, over W worlds: phases (W,), times (s), region forces (W,
    regions) from the chosen signal, thumb rotation and the grasp's (rad). Built from a single
    env's ``info`` (W = 1, dicts keyed by region) or from the vector env's (arrays; its
    ``region_names``)."""

    def __init__(self, info: Mapping, key: str | None,
                 region_names: Sequence[str] | None = None) -> None:
        single = isinstance(info["phase"], str)
        if single:  # one world: numbers and a dict keyed by region
            self.phase = np.array([info["phase"]])
            self.time_s = np.array([info["time_s"]], float)
            self.thumb = np.array([info["thumb_rotation_rad"]], float)
            self.grasp_thumb = np.array([info["grasp_thumb_rotation_rad"]], float)
        else:
            self.phase = np.asarray(info["phase"]).astype(str)
            self.time_s = np.asarray(info["time_s"], float)
            self.thumb = np.asarray(info["thumb_rotation_rad"], float)
            self.grasp_thumb = np.asarray(info["grasp_thumb_rotation_rad"], float)
        self.n = self.phase.size
        phases = self.phase.tolist()
        self.gripping = np.array([p in _GRIPPING for p in phases], bool)
        self.releasing = np.array([p in _RELEASE for p in phases], bool)
        if key is not None:
            forces = info[key]
            if single:
                self.regions = tuple(forces)
                self.forces = np.array([list(forces.values())], float)
            else:
                self.regions = tuple(region_names)
                self.forces = np.asarray(forces, float)

    def digit(self, name: str, only: tuple[str, ...] | None = None) -> np.ndarray:
        """(W,) the largest force over a digit's regions (``only``: those regions)."""
        return self.forces[:, _digit_columns(self.regions, name, only)].max(axis=1)


@functools.lru_cache(maxsize=64)
def _digit_columns(regions: tuple[str, ...], name: str,
                   only: tuple[str, ...] | None) -> list[int]:
    """The columns of a digit's regions (``only``: those regions) among ``regions``."""
    return [i for i, r in enumerate(regions) if (r in only if only else r.startswith(name))]


def _thumb_to_handshake(w: _Worlds) -> np.ndarray:
    """Thumb-rotation speed command (in [-1, 1]) towards the grasp's thumb rotation
    (``info["grasp_thumb_rotation_rad"]``, solved from the handshake's contacts, so that the thumb
    lies over the back of the partner's index metacarpal instead of pointing into its palm)."""
    return np.clip(4.0 * (w.grasp_thumb - w.thumb), -1.0, 1.0)


class _Controller:
    """A controller's two entries: ``ctrl(obs, info)`` for a single env (one action (6,)), and
    ``ctrl.actions(obs, info, region_names)`` for the vector env (W actions (W, 6), ``info`` its
    arrays); both run `_act` over arrays of worlds, which keeps each world's state."""

    signal: str | None = None

    def __call__(self, obs: np.ndarray, info: dict) -> np.ndarray:
        return self._act(_Worlds(info, self._key()))[0]

    def actions(self, obs: np.ndarray, info: Mapping,
                region_names: Sequence[str]) -> np.ndarray:
        return self._act(_Worlds(info, self._key(), region_names))

    def _key(self) -> str | None:
        return SIGNALS[self.signal] if self.signal is not None else None

    def _state(self, name: str, shape: tuple[int, ...], fill) -> np.ndarray:
        """Per-world state, (re)made when the number of worlds changes."""
        x = getattr(self, name, None)
        if x is None or x.shape != shape:
            x = np.full(shape, fill)
            setattr(self, name, x)
        return x

    def _act(self, w: _Worlds) -> np.ndarray:
        raise NotImplementedError


@dataclass
class OpenLoopClose(_Controller):
    """Close at ``speed`` (fraction of the maximum) for ``close_s`` from the start of the grip,
    hold (the motors are not back-drivable), open afterwards; the thumb goes to its handshake
    rotation. Open loop: the closure does not depend on the forces. The default closes each
    digit by 0.6 x 0.8 s / 1 s = 48 % of its range beyond where it started (43 deg at the MCP):
    far enough for the index and middle fingers to wrap the partner's hand, as the force
    controller's fingers do at 38-51 deg; a digit that meets the partner before then drives on
    into it until the command stops (up to its stall torque), which is what an open loop does
    (0.35 s, the earlier default, stopped every finger 19 deg in, short of the partner).

    Settings: ``speed`` in (0, 1], ``close_s`` in (0, 6] s (`CLOSE_S_RANGE`)."""

    speed: float = 0.6
    close_s: float = 0.8

    def __post_init__(self) -> None:
        check_number("speed", self.speed, lo=SPEED_RANGE[0], hi=SPEED_RANGE[1], lo_open=True)
        check_number("close_s", self.close_s, lo=CLOSE_S_RANGE[0], hi=CLOSE_S_RANGE[1],
                     lo_open=True, why="s")
        self._start: np.ndarray | None = None  # per world: the grip's start (s), nan before

    def _act(self, w: _Worlds) -> np.ndarray:
        start = self._state("_start", (w.n,), np.nan)
        a = np.zeros((w.n, 6))
        g, r = w.gripping, w.releasing
        start[g & np.isnan(start)] = w.time_s[g & np.isnan(start)]
        a[g, :5] = np.where(w.time_s[g] - start[g] < self.close_s - CLOCK_SLACK_S, self.speed,
                            0.0)[:, None]
        a[g, 5] = _thumb_to_handshake(w)[g]
        start[r] = np.nan
        a[r, :5] = -1.0  # open; the thumb keeps its rotation (_RELEASE)
        return a


@dataclass
class ForceRegulating(_Controller):
    """Hold ``target_N`` on each digit's most loaded region with a proportional speed command.

    Settings: ``target_N`` in [0.05, 20] N, ``gain_per_N`` in (0, 10] per N, ``signal``
    ``contact`` or ``sensor`` (module constants: the ranges and why)."""

    target_N: float = 2.5
    gain_per_N: float = 0.5
    signal: str = "contact"

    def __post_init__(self) -> None:
        _check_signal(self.signal)
        check_number("target_N", self.target_N, lo=FORCE_RANGE_N[0], hi=FORCE_RANGE_N[1],
                     why="N")
        check_number("gain_per_N", self.gain_per_N, lo=GAIN_RANGE_PER_N[0],
                     hi=GAIN_RANGE_PER_N[1], lo_open=True, why="per N")

    def _act(self, w: _Worlds) -> np.ndarray:
        a = np.zeros((w.n, 6))
        a[w.releasing, :5] = -1.0  # the thumb keeps its rotation
        g = w.gripping
        for i, digit in enumerate(_DIGITS):
            a[g, i] = np.clip(self.gain_per_N * (self.target_N - w.digit(digit)[g]), -1.0, 1.0)
        # the thumb swings to its handshake rotation only while it holds less than the target
        a[g, 5] = np.where(w.digit("Thumb")[g] < self.target_N, _thumb_to_handshake(w)[g], 0.0)
        return a


@dataclass
class Neutral(_Controller):
    """Close each digit at ``speed`` until its most loaded region (the thumb: its pad, Thumb2)
    exceeds ``touch_N``, then hold; the thumb rotates to the grasp's rotation.

    Settings: ``speed`` in (0, 1], ``touch_N`` in [0.05, 20] N, ``signal`` ``contact`` or
    ``sensor``."""

    speed: float = 0.5
    touch_N: float = 0.3
    signal: str = "contact"

    def __post_init__(self) -> None:
        _check_signal(self.signal)
        check_number("speed", self.speed, lo=SPEED_RANGE[0], hi=SPEED_RANGE[1], lo_open=True)
        check_number("touch_N", self.touch_N, lo=FORCE_RANGE_N[0], hi=FORCE_RANGE_N[1],
                     why="N")
        self._held: np.ndarray | None = None  # per world and digit: touched, held since

    def _act(self, w: _Worlds) -> np.ndarray:
        held = self._state("_held", (w.n, 5), False)
        a = np.zeros((w.n, 6))
        g = w.gripping
        held[~g] = False
        a[w.releasing, :5] = -1.0  # the thumb keeps its rotation
        for i, digit in enumerate(_DIGITS):
            # the thumb closes until its pad (Thumb2) touches: its proximal phalanx lies in the
            # partner's web space from the start and would stop it in the air over the back
            force = w.digit(digit, ("Thumb2",) if digit == "Thumb" else None)
            held[g, i] |= force[g] > self.touch_N
            a[g, i] = np.where(held[g, i], 0.0, self.speed)
        # the thumb rotates towards the back of the partner's index metacarpal until it touches
        a[g, 5] = np.where(held[g, 4], 0.0, _thumb_to_handshake(w)[g])
        return a


CONTROLLERS = {"neutral": Neutral, "open-loop": OpenLoopClose, "force": ForceRegulating}


def make_controller(name: str, signal: str = "contact", **settings):
    """``neutral``, ``open-loop`` or ``force``, fed ``signal`` (the feedback controllers; the open
    loop reads nothing), with ``settings`` (e.g. ``target_N``) over the defaults.

    Raises:
        ValueError: an unknown controller or signal, or a setting outside its range (each
            class's docstring), naming it, the value and the range."""
    if not isinstance(name, str) or name not in CONTROLLERS:
        raise ValueError(f"controller {name!r} is unknown; allowed: {', '.join(CONTROLLERS)}")
    _check_signal(signal)
    allowed = [f.name for f in fields(CONTROLLERS[name]) if f.name != "signal"]
    for key in settings:
        if key not in allowed:
            raise ValueError(f"controller {name!r}: setting {key!r} is unknown; allowed: "
                             f"{', '.join(allowed)}")
    if name != "open-loop":
        settings["signal"] = signal
    return CONTROLLERS[name](**settings)
