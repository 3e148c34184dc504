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

from softhand.compiled import interp
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
        # the compiled kernels take few arrays (each argument costs a call): per region its
        # numbers (dead band, the share table's end and end stiffness, k_inf), its QLV
        # factors (decay, c x ramp), its state (last share, branches); the attributes are views
        self._f = np.zeros((n, 4))
        self._f[:, 3] = 1.0
        self.dead, self.k_inf = self._f[:, 0], self._f[:, 3]
        self._qlv = np.zeros((2, n, terms))
        self._qlv[0] = 1.0
        self.decay = self._qlv[0]
        self._state = np.zeros((n, 1 + terms))
        self.g, self.h = self._state[:, 0], self._state[:, 1:]
        # each law's share table (made once per law), laid end to end; per region where its
        # table starts and ends (an empty range: an ideal sensor)
        shares: dict[int, tuple[int, _Share]] = {}
        self._table = np.zeros((n, 2), np.int64)
        for i, law in enumerate(laws):
            if law is None:
                continue
            k = len(law.kernel.c)
            d, r = law.kernel.step_factors(step_s)
            self._f[i] = (law.dead_band_N, law.share.max_mm, law.share.end_stiffness,
                          law.kernel.k_inf)
            self._qlv[0, i, :k] = d
            self._qlv[1, i, :k] = np.asarray(law.kernel.c, float) * r  # c x ramp, as the step
            start = sum(len(sh.u) for _, sh in shares.values())
            start, share = shares.setdefault(id(law), (start, _Share(law)))
            self._table[i] = start, start + len(share.u)
        tables = [sh for _, sh in shares.values()]
        # the tables' u, g(u) and the monotone inverse's g, end to end
        self._tables = np.array([np.concatenate(parts or [np.zeros(0)]) for parts in (
            [sh.u for sh in tables], [sh.g for sh in tables], [sh.inverse.f for sh in tables])])

    def reset(self, regions: slice | np.ndarray | None = None) -> None:
        """The QLV states of ``regions`` (default all) to rest."""
        self._state[slice(None) if regions is None else regions] = 0.0

    def share(self, load_N: np.ndarray) -> np.ndarray:
        """Each region's static share of its load (N on the patch): its law's static curve past
        the dead band on the law's table, 0 below it, linear past the fitted range (as
        `ElasticLaw.force`); an ideal sensor's share is the load."""
        return _shares(np.asarray(load_N, float), self._table, self._tables, self._f)

    def step(self, load_N: np.ndarray) -> np.ndarray:
        """Readings (N on each patch) after one env step that ends at loads ``load_N``."""
        return _bank_step(np.asarray(load_N, float), self._table, self._tables, self._f,
                          self._qlv, self._state)

    def load_estimate(self, reading_N: np.ndarray) -> np.ndarray:
        """The load a calibrated read-out infers from each reading: the static share inverted on
        its table (a reading of 0 gives 0: a dead band cannot be seen into; past the fitted range,
        the table's end)."""
        return _estimate(np.asarray(reading_N, float), self._table, self._tables, self._f)


@njit(cache=True, inline="always")
def _share(i, load, table, tables, f):
    """Region ``i``'s static share of its load: `_Share` of (load - dead band) on its law's
    table (np.interp, 0 below the table, linear past it); an ideal sensor's is the load."""
    a, b = table[i, 0], table[i, 1]
    if a == b:
        return load
    u, g = tables[0], tables[1]
    x = load - f[i, 0]
    if x < u[a]:
        return 0.0
    if x > f[i, 1]:
        return g[b - 1] + (x - f[i, 1]) * f[i, 2]
    return interp(x, u[a:b], g[a:b])


@njit(cache=True, inline="always")
def _relax(i, g, state, qlv, f):
    """One env step of region ``i``'s QLV kernel at share ``g``: updates its last share
    (``state[i, 0]``) and branch states (``state[i, 1:]``) in place, returns its reading (the
    branches summed in numpy's order)."""
    dg = g - state[i, 0]
    total = 0.0
    for j in range(qlv.shape[2]):
        state[i, 1 + j] = qlv[0, i, j] * state[i, 1 + j] + qlv[1, i, j] * dg
        total += state[i, 1 + j]
    state[i, 0] = g
    return f[i, 3] * g + total


@njit(cache=True)
def _shares(load, table, tables, f):
    """TransferBank.share: `_share` of every region."""
    out = np.empty(load.size)
    for i in range(load.size):
        out[i] = _share(i, load[i], table, tables, f)
    return out


@njit(cache=True)
def _bank_step(load, table, tables, f, qlv, state):
    """TransferBank.step: `_share`, then `_relax`, of every region."""
    out = np.empty(load.size)
    for i in range(load.size):
        out[i] = _relax(i, _share(i, load[i], table, tables, f), state, qlv, f)
    return out


@njit(cache=True, inline="always")
def _estimate_one(i, r, table, tables, f):
    """Region ``i``'s load estimate from its reading ``r``: np.interp on its law's monotone
    inverse past the dead band, 0 for a reading of 0 or less; an ideal sensor's is the reading."""
    a, b = table[i, 0], table[i, 1]
    if a == b:
        return r
    return interp(r, tables[2, a:b], tables[0, a:b]) + f[i, 0] if r > 0 else 0.0


@njit(cache=True)
def _estimate(reading, table, tables, f):
    """TransferBank.load_estimate, compiled: `_estimate_one` of every region."""
    out = np.empty(reading.size)
    for i in range(reading.size):
        out[i] = _estimate_one(i, reading[i], table, tables, f)
    return out


class SensorChain:
    """Transfer laws followed by the electronics (module docstring) for the sensing regions of
    one world, or of W worlds at once (`stack`, the vector env's): each world has its own laws'
    states, noise stream and sampling clock, and every operation is per region, so that a
    world's readings are those its own chain gives. The single env is one world (W = 1).

    Args:
        laws: per region its law, or None for an ideal surface sensor (TransferBank).
        spec: the electronics.
        step_s: the env step (constant).
    """

    #: samples of noise drawn at a time per world
    NOISE_BLOCK = 64

    def __init__(self, laws: list[TransferLaw | None], spec: SensorSpec, step_s: float) -> None:
        self._setup(spec.on_grid(step_s), step_s, TransferBank(laws, step_s), 1, len(laws))
        self.reset(np.random.default_rng(0))

    @classmethod
    def stack(cls, chains: list[SensorChain]) -> SensorChain:
        """One chain of the one-world ``chains``' worlds (in order), at rest, each world's noise
        drawn from its chain's generator; their electronics and env step must be the same."""
        first = chains[0]
        for c in chains:
            if c.worlds != 1 or (c.spec, c.step_s, c.regions) != (first.spec, first.step_s,
                                                                    first.regions):
                raise ValueError("SensorChain.stack: every chain must be one world with the "
                                 "same sensor spec, env step and regions")
        out = cls.__new__(cls)
        out._setup(first.spec, first.step_s, TransferBank(
            [law for c in chains for law in c.bank.laws], first.step_s), len(chains),
            first.regions)
        for w, c in enumerate(chains):
            out.reset(c.rngs[0], w)
        return out

    def _setup(self, spec: SensorSpec, step_s: float, bank: TransferBank, worlds: int,
               regions: int) -> None:
        self.spec, self.step_s, self.bank = spec, step_s, bank
        self.worlds, self.regions = worlds, regions
        self._period = max(1, round(spec.period_s / step_s))
        self._lag = round(spec.latency_s / step_s)
        # samples waiting for their latency: a sample taken every _period steps is due _lag
        # steps later, so at most _lag // _period + 1 wait at once (a ring of that many slots)
        slots = self._lag // self._period + 1
        self.rngs: list[np.random.Generator] = [np.random.default_rng(0)] * worlds
        self._k = np.zeros(worlds, np.int64)
        # per world and region: the hysteresis' play, the reading and the load a calibrated
        # read-out infers from it (TransferBank.load_estimate); half the band at full load
        self._wr = np.zeros((3, worlds, regions))
        self._play, self.readings, self.estimates = self._wr[0], self._wr[1], self._wr[2]
        # each world's noise, drawn from its stream NOISE_BLOCK samples at a time (the same
        # numbers as one draw per sample: a generator's draws run on, whatever their sizes);
        # without noise one row of zeros that every sample adds
        self._noise = np.zeros((worlds, self.NOISE_BLOCK if spec.noise_N > 0 else 1, regions))
        self._noise_at = np.full(worlds, self._noise.shape[1] if spec.noise_N > 0 else 0)
        self._band = 0.5e-2 * spec.hysteresis_pct * spec.full_scale_N
        self._flags = np.ones((2, worlds), bool)  # the worlds stepping, those sampling
        self._pending = np.zeros((worlds, slots, regions))
        self._due = np.full((worlds, slots), -1, np.int64)  # -1: an empty slot

    @property
    def reading(self) -> np.ndarray:
        """The current readings: (regions,) for one world, else (W, regions)."""
        return self.readings[0].copy() if self.worlds == 1 else self.readings.copy()

    @property
    def estimate(self) -> np.ndarray:
        """The load a calibrated read-out infers from each current reading
        (TransferBank.load_estimate, made with the reading): shaped as `reading`."""
        return self.estimates[0].copy() if self.worlds == 1 else self.estimates.copy()

    def reset(self, rng: np.random.Generator, world: int = 0) -> None:
        """World ``world`` at rest (no load, nothing sampled), its noise drawn from ``rng``."""
        self.rngs[world] = rng
        r = self.regions
        self.bank.reset(slice(world * r, (world + 1) * r))
        self._k[world] = 0
        self._play[world] = 0.0
        self.estimates[world] = 0.0  # a reading of 0 infers no load
        if self.spec.noise_N > 0:
            self._noise_at[world] = self.NOISE_BLOCK  # a new stream: drawn at its first sample
        self._due[world] = -1
        self.readings[world] = 0.0

    def step(self, load_N: np.ndarray, worlds: np.ndarray | None = None) -> np.ndarray:
        """The readings after one env step ending at ``load_N`` (N on each patch: (regions,) for
        one world, (W, regions) for W); ``worlds``, a mask (W,): only those step, the others
        keep their state. Returns the readings, shaped as ``load_N``."""
        s, bank, flags = self.spec, self.bank, self._flags
        if worlds is None and self.worlds == 1:  # the single env: no array arithmetic here
            flags[0, 0], flags[1, 0] = True, (int(self._k[0]) + 1) % self._period == 0
        else:
            flags[0] = True if worlds is None else np.asarray(worlds, bool)
            flags[1] = flags[0] & ((self._k + 1) % self._period == 0)  # who samples now
        if s.noise_N > 0:  # a world that samples with its block used up draws the next block
            used_up = self._noise_at >= self.NOISE_BLOCK
            for w in ((0,) if flags[1, 0] and used_up[0] else ()) if self.worlds == 1 else \
                    np.flatnonzero(flags[1] & used_up):
                self._noise[w] = self.rngs[w].normal(0.0, s.noise_N, self._noise.shape[1:])
                self._noise_at[w] = 0
        _chain_step(np.asarray(load_N, float).reshape(self.worlds, self.regions), flags,
                    bank._table, bank._tables, bank._f, bank._qlv, bank._state, self._wr,
                    self._noise, self._noise_at, self._k, self._pending, self._due, self._band,
                    self._period, self._lag, s.threshold_N, s.full_scale_N, s.resolution_N)
        return self.readings[0].copy() if np.ndim(load_N) == 1 else self.readings.copy()


@njit(cache=True)
def _chain_step(loads, flags, table, tables, f, qlv, state, wr, noise, noise_at, k, pending,
                due, band, period, lag, threshold_N, full_scale_N, resolution_N):
    """SensorChain.step of the worlds ``flags[0]`` (those sampling: ``flags[1]``) in one
    compiled call: their regions' transfer laws (TransferBank's `_share`, `_relax`), the
    hysteresis' play operator (``band`` > 0: half its width at full load, narrowing to 0 at no
    load, as np.clip(play, r - half, r + half)), then `_electronics`, then the load estimates.
    ``wr``: play, readings and estimates (3, W, regions); ``noise`` (W, block, regions) from row
    ``noise_at`` on."""
    worlds, regions = loads.shape
    r = np.zeros((worlds, regions))
    for w in range(worlds):
        if not flags[0, w]:
            continue
        k[w] += 1
        for i in range(regions):
            at = w * regions + i  # the region's row in the bank
            r[w, i] = _relax(at, _share(at, loads[w, i], table, tables, f), state, qlv, f)
            if band > 0:
                half = min(band, max(r[w, i], 0.0))
                wr[0, w, i] = min(max(wr[0, w, i], r[w, i] - half), r[w, i] + half)
                r[w, i] = wr[0, w, i]
    _electronics(r, noise, noise_at, flags, k, period, lag, pending, due, wr, threshold_N,
                 full_scale_N, resolution_N)
    for w in range(worlds):  # what a calibrated read-out infers from the new readings
        if flags[0, w]:
            for i in range(regions):
                wr[2, w, i] = _estimate_one(w * regions + i, wr[1, w, i], table, tables, f)


@njit(cache=True)
def _electronics(r, noise, noise_at, flags, k, period, lag, pending, due, wr, threshold_N,
                 full_scale_N, resolution_N):
    """Sampling, latency and hold of every active world (SensorChain.step): a world that samples
    at its step k stores `_sample` of its readings plus its next row of ``noise`` (a block of
    one row of zeros without noise: ``noise_at`` stays 0) in its ring, due at k + lag; its
    reading (``wr[1]``) is then the latest sample due by k, and every sample due by k leaves
    the ring. ``flags``: the worlds stepping, those sampling."""
    slots = due.shape[1]
    noisy = noise.shape[1] > 1
    for w in range(r.shape[0]):
        if not flags[0, w]:
            continue
        if flags[1, w]:
            slot = (k[w] // period) % slots
            row = noise_at[w]
            for i in range(r.shape[1]):
                pending[w, slot, i] = _sample(r[w, i] + noise[w, row, i], threshold_N,
                                              full_scale_N, resolution_N)
            if noisy:
                noise_at[w] += 1
            due[w, slot] = k[w] + lag
        latest = -1
        for j in range(slots):
            if 0 <= due[w, j] <= k[w] and (latest < 0 or due[w, j] > due[w, latest]):
                latest = j
        if latest >= 0:
            for i in range(r.shape[1]):
                wr[1, w, i] = pending[w, latest, i]
            for j in range(slots):
                if 0 <= due[w, j] <= k[w]:
                    due[w, j] = -1


@njit(cache=True, inline="always")
def _sample(x, threshold_N, full_scale_N, resolution_N):
    """One sample of a reading (its noise added): 0 below the threshold (a thin film reads no
    tension), clipped to full scale, rounded to the quantum (half to even, as np.round)."""
    x = 0.0 if x < threshold_N else (x if x != x else min(x, full_scale_N))
    if resolution_N > 0:
        x = np.rint(x / resolution_N) * resolution_N
    return x
