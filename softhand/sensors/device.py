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
from numba import njit

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
    """A share spline g(u) tabulated at 0.001 N steps, interpolated linearly by the bank's
    compiled kernels (the B-spline costs about 50 us for the env's 18 loads); the table's
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
        # each law's share table (made once per law), laid end to end for the compiled kernels;
        # per region where its table starts and ends (an empty range: an ideal sensor)
        shares: dict[int, tuple[int, _Share]] = {}
        self._table = np.zeros((n, 2), np.int64)
        for i, law in enumerate(laws):
            if law is None:
                continue
            k = len(law.kernel.c)
            self.k_inf[i] = law.kernel.k_inf
            self.c[i, :k] = law.kernel.c
            d, r = law.kernel.step_factors(step_s)
            self.decay[i, :k], self.ramp[i, :k] = d, r
            start = sum(len(sh.u) for _, sh in shares.values())
            start, share = shares.setdefault(id(law), (start, _Share(law)))
            self._table[i] = start, start + len(share.u)
        tables = [sh for _, sh in shares.values()]
        self._u = np.concatenate([sh.u for sh in tables] or [np.zeros(0)])
        self._g = np.concatenate([sh.g for sh in tables] or [np.zeros(0)])
        self._g_inverse = np.concatenate([sh.inverse.f for sh in tables] or [np.zeros(0)])
        self._top = np.array([0.0 if law is None else law.share.max_mm for law in laws])
        self._k_top = np.array([0.0 if law is None else law.share.end_stiffness for law in laws])
        self.reset()

    def reset(self) -> None:
        self.h = np.zeros_like(self.c)
        self.g = np.zeros(len(self.laws))

    def share(self, load_N: np.ndarray) -> np.ndarray:
        """Each region's static share of its load (N on the patch): its law's static curve past
        the dead band on the law's table, 0 below it, linear past the fitted range (as
        `ElasticLaw.force`); an ideal sensor's share is the load."""
        return _shares(np.asarray(load_N, float), self.dead, self._table, self._u, self._g,
                       self._top, self._k_top)

    def step(self, load_N: np.ndarray) -> np.ndarray:
        """Readings (N on each patch) after one env step that ends at loads ``load_N``."""
        return _step(np.asarray(load_N, float), self.dead, self._table, self._u, self._g,
                     self._top, self._k_top, self.g, self.h, self.decay, self.c, self.ramp,
                     self.k_inf)

    def load_estimate(self, reading_N: np.ndarray) -> np.ndarray:
        """The load a calibrated read-out infers from each reading: the static share inverted on
        its table (a reading of 0 gives 0: a dead band cannot be seen into; past the fitted range,
        the table's end)."""
        return _estimate(np.asarray(reading_N, float), self.dead, self._table, self._u,
                         self._g_inverse)


@njit(cache=True)
def _shares(load, dead, table, u, g, top, k_top):
    """Each region's static share of its load: `_Share` of (load - dead band) on its law's
    table (np.interp, 0 below the table, linear past it); an ideal sensor's is the load."""
    out = load.copy()
    for i in range(load.size):
        a, b = table[i]
        if a == b:
            continue
        x = load[i] - dead[i]
        if x < u[a]:
            out[i] = 0.0
        elif x > top[i]:
            out[i] = g[b - 1] + (x - top[i]) * k_top[i]
        else:
            out[i] = np.interp(x, u[a:b], g[a:b])
    return out


@njit(cache=True)
def _step(load, dead, table, u, g, top, k_top, g_last, h, decay, c, ramp, k_inf):
    """TransferBank.step in one compiled call: `_shares`, then `_relax`."""
    return _relax(_shares(load, dead, table, u, g, top, k_top), g_last, h, decay, c, ramp,
                  k_inf)


@njit(cache=True)
def _relax(g, g_last, h, decay, c, ramp, k_inf):
    """One env step of the QLV kernels: updates the branch states ``h`` and the last shares
    ``g_last`` in place, returns the readings (the branches summed in numpy's order)."""
    out = np.empty(g.size)
    for i in range(g.size):
        dg = g[i] - g_last[i]
        total = 0.0
        for j in range(h.shape[1]):
            h[i, j] = decay[i, j] * h[i, j] + c[i, j] * ramp[i, j] * dg
            total += h[i, j]
        g_last[i] = g[i]
        out[i] = k_inf[i] * g[i] + total
    return out


@njit(cache=True)
def _estimate(reading, dead, table, u, g_inverse):
    """TransferBank.load_estimate, compiled: np.interp on each law's monotone inverse."""
    out = reading.copy()
    for i in range(reading.size):
        a, b = table[i]
        if a == b:
            continue
        r = reading[i]
        out[i] = np.interp(r, g_inverse[a:b], u[a:b]) + dead[i] if r > 0 else 0.0
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
            noise = self.rng.normal(0.0, s.noise_N, r.shape) if s.noise_N > 0 else _NO_NOISE
            self._queue.append((self._k + self._lag, _sample(r, noise, s.threshold_N,
                                                              s.full_scale_N, s.resolution_N)))
        while self._queue and self._queue[0][0] <= self._k:
            self.reading = self._queue.pop(0)[1]
        return self.reading


_NO_NOISE = np.zeros(0)


@njit(cache=True)
def _sample(reading, noise, threshold_N, full_scale_N, resolution_N):
    """One sample of the readings: plus the noise (if drawn), 0 below the threshold (a thin film
    reads no tension), clipped to full scale, rounded to the quantum (half to even, as
    np.round)."""
    out = reading.copy()
    for i in range(out.size):
        x = out[i] + noise[i] if noise.size else out[i]
        x = 0.0 if x < threshold_N else (x if x != x else min(x, full_scale_N))
        if resolution_N > 0:
            x = np.rint(x / resolution_N) * resolution_N
        out[i] = x
    return out
