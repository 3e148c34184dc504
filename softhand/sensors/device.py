"""A real sensor's behaviour after the skin: sampling, latency, noise, threshold, saturation,
quantization and hysteresis, applied to the transfer law's reading.

Default: `FLEXIFORCE_A101`, a Tekscan FlexiForce A101 thin-film piezoresistive force sensor
(a 3.8 mm sensing circle, the size of the FE's 4 x 4 mm patch; `softhand.fem.sensors`). From
Tekscan's public A101 datasheet: standard force range 0-44 N (10 lbf, the saturation), hysteresis
< 4.5 % of full scale, linearity within +-3 % (the FlexiForce user manual; not modelled: the
read-out is taken as calibrated), response time < 5 us (so the electronics, not the sensor, set
the sampling). These datasheet values were not re-checked against the current PDF (this project
is built offline); each is a parameter of `SensorSpec`.
The electronics are named assumptions (`ASSUMPTIONS`): a 10-bit ADC over the full range
(quantum 44.5 / 1024 = 0.043 N), 100 Hz sampling, one sample of latency, a noise of half a quantum
(0.02 N RMS), a threshold of 0.1 N (the reading is 0 below it). Hysteresis is off by default (the
datasheet's bound is a worst case); `SensorSpec` takes any of them.

The chain, per sensing region, at every env step (``step_s`` = frame_skip x timestep):

1. the transfer law's reading R(t) of the region's load (`TransferBank`);
2. hysteresis: a play operator of width ``hysteresis_pct`` of full scale (the reading lags the
   load by up to half of it, low while loading, high while unloading), its band narrowing to 0
   at no load so that an unloaded sensor reads 0;
3. sampling every ``period_s``: the sample adds Gaussian noise (``noise_N`` RMS, drawn from the
   env's seeded generator), reads 0 below ``threshold_N``, is clipped to ``full_scale_N`` and
   rounded to ``resolution_N``;
4. latency: the sample is available ``latency_s`` after it was taken; between samples the reading
   holds (zero-order hold).

Why not MuJoCo's own sensor ``noise``/``interval``/``delay``: the reading is a hereditary
function of the load (the transfer law) computed on the host, and MuJoCo's ``noise`` attribute is
stored but never applied; MuJoCo's delay buffers need the sensor computed at every physics step,
while the scene computes its contact sensors once per env step (the skins' forces do not need
more). Time is therefore resolved to the env step: ``period_s`` and ``latency_s`` are rounded to
whole env steps, and a latency between 0 and one env step is refused.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from softhand.laws.elastic import MonotoneInverse
from softhand.sensors.transfer import TransferLaw
from softhand.validate import check_number

__all__ = ["ASSUMPTIONS", "FLEXIFORCE_A101", "SensorChain", "SensorSpec", "TransferBank"]

FULL_SCALE_N = 44.5  # 10 lbf


@dataclass(frozen=True)
class SensorSpec:
    """A sensor's electronics (see the module docstring for the defaults' sources).

    Attributes:
        name: what it stands for.
        full_scale_N: saturation, > 0.
        resolution_N: quantum of the reading, >= 0 (0: no quantization), < full scale.
        noise_N: RMS of the Gaussian noise per sample, >= 0.
        threshold_N: readings below it are 0, in [0, full scale).
        period_s: sampling period, > 0.
        latency_s: from a sample to its availability, >= 0.
        hysteresis_pct: play-operator width in % of full scale, in [0, 50].
    """

    name: str = "FlexiForce A101 (Tekscan) + 10-bit ADC at 100 Hz"
    full_scale_N: float = FULL_SCALE_N
    resolution_N: float = FULL_SCALE_N / 1024
    noise_N: float = 0.5 * FULL_SCALE_N / 1024
    threshold_N: float = 0.1
    period_s: float = 0.01
    latency_s: float = 0.01
    hysteresis_pct: float = 0.0

    def __post_init__(self) -> None:
        fs = check_number("sensor full_scale_N", self.full_scale_N, lo=0.0, lo_open=True)
        check_number("sensor resolution_N", self.resolution_N, lo=0.0, hi=fs, hi_open=True)
        check_number("sensor noise_N", self.noise_N, lo=0.0)
        check_number("sensor threshold_N", self.threshold_N, lo=0.0, hi=fs, hi_open=True)
        check_number("sensor period_s", self.period_s, lo=0.0, lo_open=True, hi=1.0)
        check_number("sensor latency_s", self.latency_s, lo=0.0, hi=1.0)
        check_number("sensor hysteresis_pct", self.hysteresis_pct, lo=0.0, hi=50.0)

    def on_grid(self, step_s: float) -> SensorSpec:
        """The spec with period and latency in whole env steps; ValueError names the value when
        the period is shorter than a step or the latency is between 0 and one step."""
        tol = 1e-9
        if self.period_s < step_s - tol:
            raise ValueError(f"sensor period_s = {self.period_s:g} s is shorter than the env step "
                             f"{step_s:g} s (frame_skip x timestep_s), the finest time the sensor "
                             f"model resolves; allowed >= {step_s:g} s")
        if 0 < self.latency_s < step_s - tol:
            raise ValueError(f"sensor latency_s = {self.latency_s:g} s is shorter than the env "
                             f"step {step_s:g} s (frame_skip x timestep_s), the finest time the "
                             f"sensor model resolves; allowed 0 or >= {step_s:g} s")
        return replace(self, period_s=round(self.period_s / step_s) * step_s,
                       latency_s=round(self.latency_s / step_s) * step_s)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


FLEXIFORCE_A101 = SensorSpec()

#: What each default stands on.
ASSUMPTIONS = {
    "full_scale_N": "datasheet: FlexiForce A101 standard range 0-44 N (10 lbf)",
    "hysteresis_pct": "datasheet bound < 4.5 % of full scale; 0 by default (a worst case)",
    "resolution_N": "assumption: a 10-bit ADC over the full range",
    "noise_N": "assumption: half an ADC quantum RMS",
    "threshold_N": "assumption: 0.1 N, below which a thin-film resistor hardly conducts",
    "period_s": "assumption: 100 Hz, a prosthetic hand's control rate",
    "latency_s": "assumption: one sample (read, filter, send)",
}


class _Share:
    """A share spline g(u) tabulated at 0.001 N steps and interpolated linearly (one np.interp
    per law and env step: the B-spline costs about 50 us for the env's 18 loads); the table's
    error, h^2/8 max|g''|, is below 1e-5 N for every shipped law (4e-6 N measured; a test), far under a 10-bit
    quantum (0.043 N). 0 for u <= 0, linear past the fitted range (as `ElasticLaw.force`)."""

    STEP_N = 0.001

    def __init__(self, law: TransferLaw) -> None:
        top = law.share.max_mm
        self.u = np.linspace(0.0, top, int(np.ceil(top / self.STEP_N)) + 1)
        self.g = law.share.force(self.u)
        self.top, self.k_top = top, law.share.end_stiffness
        #: u at which the share reaches g (the table's monotone inverse, made once)
        self.inverse = MonotoneInverse(self.u, self.g)

    def __call__(self, u: np.ndarray) -> np.ndarray:
        out = np.interp(u, self.u, self.g, left=0.0)
        beyond = u > self.top
        if beyond.any():
            out[beyond] = self.g[-1] + (u[beyond] - self.top) * self.k_top
        return out


class TransferBank:
    """The transfer laws of all sensing regions, stepped together (one QLV state per region).

    Args:
        laws: per region its law, or None for an ideal surface sensor (the reading is the load:
            a skin without FE, such as rigid or a reference tissue).
        step_s: the env step (constant).
    """

    def __init__(self, laws: list[TransferLaw | None], step_s: float) -> None:
        self.laws = list(laws)
        n = len(laws)
        terms = max([len(law.kernel.c) for law in laws if law is not None] or [0])
        self.dead = np.array([0.0 if law is None else law.dead_band_N for law in laws])
        self.k_inf = np.ones(n)
        self.c = np.zeros((n, terms))
        self.decay = np.ones((n, terms))
        self.ramp = np.zeros((n, terms))
        self._groups: dict[int, tuple[TransferLaw, np.ndarray]] = {}
        self._share: dict[int, _Share] = {}
        for i, law in enumerate(laws):
            if law is None:
                continue
            k = len(law.kernel.c)
            self.k_inf[i] = law.kernel.k_inf
            self.c[i, :k] = law.kernel.c
            d, r = law.kernel.step_factors(step_s)
            self.decay[i, :k], self.ramp[i, :k] = d, r
            key = id(law)
            idx = self._groups.get(key, (law, np.zeros(0, int)))[1]
            self._groups[key] = (law, np.append(idx, i))
            self._share.setdefault(key, _Share(law))
        self.reset()

    def reset(self) -> None:
        self.h = np.zeros_like(self.c)
        self.g = np.zeros(len(self.laws))

    def step(self, load_N: np.ndarray) -> np.ndarray:
        """Readings (N on each patch) after one env step that ends at loads ``load_N``."""
        g = np.array(load_N, dtype=float)  # ideal regions: g = load
        for key, (law, idx) in self._groups.items():
            g[idx] = self._share[key](g[idx] - law.dead_band_N)
        self.h = self.decay * self.h + self.c * self.ramp * (g - self.g)[:, None]
        self.g = g
        return self.k_inf * g + self.h.sum(axis=1)

    def load_estimate(self, reading_N: np.ndarray) -> np.ndarray:
        """The load a calibrated read-out infers from each reading: the static share inverted on
        its table (a reading of 0 gives 0: a dead band cannot be seen into; past the fitted range,
        the table's end)."""
        out = np.array(reading_N, dtype=float)
        for key, (law, idx) in self._groups.items():
            share, r = self._share[key], out[idx]
            out[idx] = np.where(r > 0, share.inverse(r) + law.dead_band_N, 0.0)
        return out


class SensorChain:
    """Transfer laws followed by the electronics (module docstring) for the sensing regions."""

    def __init__(self, laws: list[TransferLaw | None], spec: SensorSpec, step_s: float) -> None:
        self.spec = spec.on_grid(step_s)
        self.bank = TransferBank(laws, step_s)
        self._period = max(1, round(self.spec.period_s / step_s))
        self._lag = round(self.spec.latency_s / step_s)
        self.reset(np.random.default_rng(0))

    def reset(self, rng: np.random.Generator) -> None:
        n = len(self.bank.laws)
        self.rng = rng
        self.bank.reset()
        self._k = 0
        self._play = np.zeros(n)
        self._queue: list[tuple[int, np.ndarray]] = []  # (step available, sample)
        self.reading = np.zeros(n)

    def step(self, load_N: np.ndarray) -> np.ndarray:
        """The readings after one env step ending at ``load_N`` (N on each patch)."""
        s = self.spec
        self._k += 1
        r = self.bank.step(load_N)
        if s.hysteresis_pct > 0:
            # a play operator whose band narrows to 0 at no load (an unloaded sensor reads 0)
            half = np.minimum(0.5e-2 * s.hysteresis_pct * s.full_scale_N, np.maximum(r, 0.0))
            self._play = np.clip(self._play, r - half, r + half)
            r = self._play
        if self._k % self._period == 0:
            x = r + (self.rng.normal(0.0, s.noise_N, r.shape) if s.noise_N > 0 else 0.0)
            x = np.where(x < s.threshold_N, 0.0, np.minimum(x, s.full_scale_N))  # no tension
            if s.resolution_N > 0:
                x = np.round(x / s.resolution_N) * s.resolution_N
            self._queue.append((self._k + self._lag, x))
        while self._queue and self._queue[0][0] <= self._k:
            self.reading = self._queue.pop(0)[1]
        return self.reading
