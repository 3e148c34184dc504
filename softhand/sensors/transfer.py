r"""Transfer laws of the embedded sensors: what a sensor inside the skin reads for a load on it.

For one design and one placement (`softhand.fem.sensors.PLACEMENTS`) the law maps the
history of the force F(t) pressing the skin to the sensor patch's reading R(t) (N on the patch):

    R(t) = \int_0^t K(t - s)\, \frac{d}{ds}\, g\big(u(s)\big)\, ds, \qquad
    u = \max(F - F_0, 0), \qquad
    K(t) = 1 - \sum_k c_k \left(1 - e^{-t/\tau_k}\right),

* ``F_0`` the **dead band**: the load below which the patch reads nothing: the load that closes
  the pocket for a pocket-floor patch, and for a bone patch under a pocket (which the FE finds in
  *tension* while the pocket is open: the roof's load goes down the side walls and lifts the
  base between them); about 0 elsewhere. The sensors are compression sensors (a thin-film force
  sensor reads no tension), so the law is fitted to, and judged against, the FE's reading
  clipped at 0 (`compression`);
* ``g`` the **instantaneous share**: a monotone spline (`ElasticLaw`,
  the skin laws' own, with the load in N on its axis instead of a depth in mm), so that
  ``dg/du`` at small loads is the sensor's sensitivity (reading per newton);
* ``K`` the **share's relaxation**: how the reading changes against the load while it is held.
  The coefficients ``c_k`` may have either sign: the reading can relax more than the load (the
  load spreads away from a bone patch) or less (it concentrates under the outer layer); the
  recursion is the one Prony update of the whole package (`Prony.step_factors`).

The law is fitted to the FE's readings under the paper's protocol (a rigid plate at 0.5 mm/s to
20 N, a 10 s hold; ``calibration/sensors/fe``), ``F`` being the plate force, and validated on the
same protocol at 2 mm/s. Assumption (stated wherever a reading is used on the hand): a region's
load is spread over the phalanx as the plate's is, and the share's relaxation measured at a held
indentation also holds for the load histories of a handshake.

Errors (`TransferError`) are in percent of the reading at the peak of the ramp (20 N), so
that a designer reads them against the sensor's span: RMS over the whole record, the largest on the
ramp, the largest in the hold; and, for the light touches of a handshake, the RMS on the ramp up
to 2 N of load in percent of the reading at 2 N.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import least_squares, nnls

from softhand.fem.geometry import DESIGNS
from softhand.fem.materials import Prony
from softhand.fem.sensors import PLACEMENTS
from softhand.fem.solver import IndentationResult, IndentationSettings
from softhand.laws.elastic import ElasticLaw, basis_matrix, knots_at
from softhand.laws.qlv import qlv_response_matrix
from softhand.validate import check_mapping, check_number, join, show

__all__ = [
    "FE_SETTINGS",
    "SPEEDS_MM_S",
    "SensorRecord",
    "ShareKernel",
    "TransferError",
    "TransferLaw",
    "fit_transfer",
    "load_records",
    "record_from_result",
    "records_csv",
]

#: Plate speeds of the FE records: 0.5 mm/s is fitted, 2 mm/s validates (the skin laws' protocol).
SPEEDS_MM_S = (0.5, 2.0)
#: The FE protocol of the records: the shipped skin curves' (calibration/fe) with the sensors on.
FE_SETTINGS = IndentationSettings(max_force_N=20.0, max_depth_mm=7.0, hold_s=10.0)
#: Interior knots of the share spline, in N of load above the dead band: dense at low load, where
#: the pocket closes and the share changes fastest.
KNOTS_N = (0.25, 0.5, 1.0, 2.0, 4.0, 7.0, 12.0)
N_TERMS = 2
LOW_N = 2.0  # the light-touch error is measured up to this load (the paper's 2 N reference)
TAU_BOUNDS_S = (0.05, 60.0)


# --- records -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SensorRecord:
    """One FE run's embedded-sensor readings: the plate force and each patch's reading in time."""

    design: str
    speed_mm_s: float
    time_s: np.ndarray
    force_N: np.ndarray
    hold: np.ndarray
    readings_N: dict[str, np.ndarray]
    placements: dict[str, str]
    area_mm2: dict[str, float]

    @property
    def peak_index(self) -> int:
        return int(np.flatnonzero(~self.hold)[-1])


def record_from_result(r: IndentationResult) -> SensorRecord:
    """The sensor record of a finished FE run."""
    s = r.embedded_sensors
    return SensorRecord(r.design, float(r.settings.speed_mm_s), np.asarray(r.time_s, float),
                        np.asarray(r.force_N, float), np.asarray(r.hold, bool),
                        {k: np.asarray(v["force_N"], float) for k, v in s.items()},
                        {k: v["placement"] for k, v in s.items()},
                        {k: float(v["area_mm2"]) for k, v in s.items()})


def records_csv(rec: SensorRecord) -> str:
    """``time_s, force_N, hold`` and one ``{sensor}_N`` column per patch, as CSV text."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    names = list(rec.readings_N)
    w.writerow(["time_s", "force_N", "hold", *[f"{n}_N" for n in names]])
    for i in range(rec.time_s.size):
        w.writerow([f"{rec.time_s[i]:.6g}", f"{rec.force_N[i]:.8g}", int(rec.hold[i]),
                    *[f"{rec.readings_N[n][i]:.8g}" for n in names]])
    return buf.getvalue()


def load_records(fe_dir: str | Path, design: str, speed_mm_s: float,
                 meta: dict[str, Any]) -> SensorRecord:
    """Read ``{design}.csv`` of one speed folder (see `softhand.sensors.calibrate`).

    Args:
        meta: the folder's ``summary.json`` entry of the design: ``placements`` and ``area_mm2``.

    Raises:
        ValueError: naming the file, the line and the column of the first bad cell.
    """
    path = Path(fe_dir) / f"{design}.csv"
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: cannot read the sensor record ({exc})") from None
    rows = list(csv.reader(text.splitlines()))
    if len(rows) < 4:
        raise ValueError(f"{path}: {max(len(rows) - 1, 0)} data rows; at least 3 are needed")
    header = rows[0]
    names = [h[:-2] for h in header[3:]]
    if header[:3] != ["time_s", "force_N", "hold"] or not names or \
            any(not h.endswith("_N") for h in header[3:]):
        raise ValueError(f"{path}: line 1: header {','.join(header)!r} is not "
                         "time_s,force_N,hold,{sensor}_N,...")
    data = np.empty((len(rows) - 1, len(header)))
    for n, cells in enumerate(rows[1:], start=2):
        if len(cells) != len(header):
            raise ValueError(f"{path}: line {n}: {len(cells)} cells, expected {len(header)}")
        for j, cell in enumerate(cells):
            try:
                v = float(cell)
            except ValueError:
                raise ValueError(f"{path}: line {n}, column {header[j]}: {cell!r} is not a "
                                 "number") from None
            if not np.isfinite(v):
                raise ValueError(f"{path}: line {n}, column {header[j]}: {cell!r}: expected a "
                                 "finite number")
            data[n - 2, j] = v
    if np.any(np.diff(data[:, 0]) <= 0):
        raise ValueError(f"{path}: column time_s must increase")
    placements = meta.get("placements", {})
    for name in names:
        if placements.get(name) not in PLACEMENTS:
            raise ValueError(f"{path}: sensor {name!r} has no placement in summary.json "
                             f"(allowed: {', '.join(PLACEMENTS)})")
    return SensorRecord(design, float(speed_mm_s), data[:, 0], data[:, 1], data[:, 2] > 0.5,
                        {n: data[:, 3 + j] for j, n in enumerate(names)},
                        {n: placements[n] for n in names},
                        {n: float(meta.get("area_mm2", {}).get(n, np.nan)) for n in names})


# --- the law -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ShareKernel:
    """K(t) = 1 - sum_k c_k (1 - exp(-t / tau_k)), c_k of either sign, K(inf) > 0."""

    c: tuple[float, ...] = ()
    tau_s: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        c = tuple(float(v) for v in self.c)
        tau = tuple(float(v) for v in self.tau_s)
        object.__setattr__(self, "c", c)
        object.__setattr__(self, "tau_s", tau)
        if len(c) != len(tau):
            raise ValueError(f"c has {len(c)} terms and tau_s has {len(tau)}: need the same number")
        for k, v in enumerate(c):
            check_number(f"c[{k}]", v)
        for k, v in enumerate(tau):
            check_number(f"tau_s[{k}]", v, lo=0.0, lo_open=True)
        if not 1.0 - sum(c) > 0:
            raise ValueError(f"1 - sum(c) = {1 - sum(c)!r}: the long-term share K(inf) must be > 0")

    @property
    def k_inf(self) -> float:
        return 1.0 - sum(self.c)

    # K(t) = k_inf + sum c_k exp(-t / tau_k): a Prony series whose ratios may be negative, so the
    # QLV recursion of softhand.laws.qlv runs on it unchanged (it reads g, g_inf, step_factors)
    @property
    def g(self) -> tuple[float, ...]:
        return self.c

    @property
    def g_inf(self) -> float:
        return self.k_inf

    def step_factors(self, dt_s) -> tuple[np.ndarray, np.ndarray]:
        """The package's one hereditary recursion (`Prony.step_factors`) for these times."""
        return Prony((0.0,) * len(self.tau_s), self.tau_s).step_factors(dt_s)

    def response(self, g: np.ndarray, t_s: np.ndarray) -> np.ndarray:
        """R for instantaneous-share histories ``g`` (n_times, n_columns) sampled at ``t_s``."""
        return qlv_response_matrix(g, t_s, self)

    def to_dict(self) -> dict:
        return {"c": list(self.c), "tau_s": list(self.tau_s), "k_inf": self.k_inf}


@dataclass(frozen=True)
class TransferError:
    """Errors of a transfer law against one FE record, in % of the reading at the ramp's peak."""

    label: str
    rms_pct: float
    ramp_max_pct: float
    hold_max_pct: float | None
    to_2N_rms_pct: float | None = None

    def to_dict(self) -> dict:
        return {"label": self.label, "rms_pct": self.rms_pct, "ramp_max_pct": self.ramp_max_pct,
                "hold_max_pct": self.hold_max_pct, "to_2N_rms_pct": self.to_2N_rms_pct}


@dataclass(frozen=True)
class TransferLaw:
    """The reading of one sensor for a load history (see the module docstring).

    Attributes:
        design: the skin design; placement: bone, interface or pocket-floor.
        area_mm2: the patch's area; patch: its size and centre (the FE's SensorPatch fields).
        dead_band_N: F_0; share: g (N of reading against N of load above F_0); kernel: K.
        fitted, validated: errors against the fitted and the validation records.
        source: the FE records it was fitted to (sha256) and how.
    """

    design: str
    placement: str
    area_mm2: float
    dead_band_N: float
    share: ElasticLaw
    kernel: ShareKernel
    max_load_N: float
    fitted: tuple[TransferError, ...] = ()
    validated: tuple[TransferError, ...] = ()
    source: dict = field(default_factory=dict)

    def reading(self, time_s, load_N) -> np.ndarray:
        """R(t) for a load history sampled at ``time_s`` (exact for a piecewise-linear g)."""
        g = self.share.force(np.maximum(np.asarray(load_N, float) - self.dead_band_N, 0.0))
        return self.kernel.response(g[:, None], time_s)[:, 0]

    def sensitivity(self, load_N: float) -> float:
        """Instantaneous reading per newton of load at ``load_N`` (0 inside the dead band)."""
        u = load_N - self.dead_band_N
        return float(self.share.stiffness(u)) if u > 0 else 0.0

    def to_dict(self) -> dict:
        return {"design": self.design, "placement": self.placement, "area_mm2": self.area_mm2,
                "dead_band_N": self.dead_band_N, "max_load_N": self.max_load_N,
                "share": self.share.to_dict(), "kernel": self.kernel.to_dict(),
                "fitted": [e.to_dict() for e in self.fitted],
                "validated": [e.to_dict() for e in self.validated], "source": self.source}

    @classmethod
    def from_dict(cls, d: Any, *, key: str = "law") -> TransferLaw:
        """Parse `to_dict` output, checking every value; ValueError names the key path."""
        check_mapping(key, d, required=("design", "placement", "area_mm2", "dead_band_N",
                                        "max_load_N", "share", "kernel"),
                      optional=("fitted", "validated", "source"))
        if d["design"] not in DESIGNS:
            raise ValueError(f"{join(key, 'design')} = {show(d['design'])}: expected one of "
                             f"{', '.join(DESIGNS)}")
        if d["placement"] not in PLACEMENTS:
            raise ValueError(f"{join(key, 'placement')} = {show(d['placement'])}: expected one "
                             f"of {', '.join(PLACEMENTS)}")
        kern = d["kernel"]
        check_mapping(join(key, "kernel"), kern, required=("c", "tau_s"), optional=("k_inf",))
        for part in ("c", "tau_s"):
            if not isinstance(kern[part], list):
                raise ValueError(f"{join(join(key, 'kernel'), part)} = {show(kern[part])}: "
                                 "expected a list of numbers")
        try:
            kernel = ShareKernel(tuple(kern["c"]), tuple(kern["tau_s"]))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{join(key, 'kernel')}: {exc}") from None
        if "k_inf" in kern:  # written for the reader; derived from c, so it must agree
            k = check_number(join(join(key, "kernel"), "k_inf"), kern["k_inf"])
            if abs(k - kernel.k_inf) > 1e-9:
                raise ValueError(f"{join(join(key, 'kernel'), 'k_inf')} = {show(k)}: it is "
                                 f"1 - sum(c) = {kernel.k_inf!r}; correct or remove it")
        errors = {}
        for part in ("fitted", "validated"):
            items = d.get(part, [])
            if not isinstance(items, list):
                raise ValueError(f"{join(key, part)} = {show(items)}: expected a list")
            rows = []
            for i, e in enumerate(items):
                at = f"{join(key, part)}[{i}]"
                check_mapping(at, e, required=("rms_pct", "ramp_max_pct"),
                              optional=("label", "hold_max_pct", "to_2N_rms_pct"))
                num = {f: None if e.get(f) is None else check_number(join(at, f), e[f], lo=0.0)
                       for f in ("rms_pct", "ramp_max_pct", "hold_max_pct", "to_2N_rms_pct")}
                rows.append(TransferError(str(e.get("label", "")), num["rms_pct"],
                                          num["ramp_max_pct"], num["hold_max_pct"],
                                          num["to_2N_rms_pct"]))
            errors[part] = tuple(rows)
        return cls(d["design"], d["placement"],
                   check_number(join(key, "area_mm2"), d["area_mm2"], lo=0.0, lo_open=True),
                   check_number(join(key, "dead_band_N"), d["dead_band_N"], lo=0.0),
                   ElasticLaw.from_dict(d["share"], key=join(key, "share")), kernel,
                   check_number(join(key, "max_load_N"), d["max_load_N"], lo=0.0, lo_open=True),
                   errors["fitted"], errors["validated"], dict(d.get("source", {})))


def compression(rec: SensorRecord, name: str) -> np.ndarray:
    """What a compression sensor reads of the FE's patch force: the force clipped at 0 N."""
    return np.maximum(rec.readings_N[name], 0.0)


def transfer_errors(law: TransferLaw, rec: SensorRecord, name: str) -> TransferError:
    """Errors of ``law`` against the reading ``name`` of ``rec`` (% of the reading at the peak)."""
    model = law.reading(rec.time_s, rec.force_N)
    target = compression(rec, name)
    span = max(float(target[rec.peak_index]), 1e-9)
    err = model - target
    ramp = ~rec.hold
    hold = float(100 * np.abs(err[rec.hold]).max() / span) if rec.hold.any() else None
    low = ramp & (rec.force_N <= LOW_N)
    at = float(np.interp(LOW_N, rec.force_N[ramp], target[ramp]))
    to_2 = float(100 * np.sqrt(np.mean(err[low] ** 2)) / at) if low.any() and at > 0 else None
    return TransferError(f"{rec.design}@{rec.speed_mm_s:g}mm/s",
                         float(100 * np.sqrt(np.mean(err**2)) / span),
                         float(100 * np.abs(err[ramp]).max() / span), hold, to_2)


def _dead_band_bracket(rec: SensorRecord, name: str) -> tuple[float, float]:
    """The plate force between the last FE step at which the patch read nothing in compression
    and the next (the ramp's end of the patch's dead band)."""
    f = compression(rec, name)
    ramp = np.flatnonzero(~rec.hold)
    off = ramp[f[ramp] <= 1e-9]
    i = int(off[-1]) + 1 if off.size else 0
    if i > ramp[-1]:
        raise ValueError(f"{rec.design}: sensor {name} reads nothing on the ramp")
    return (float(rec.force_N[i - 1]) if i > 0 else 0.0), float(rec.force_N[i])


def _fit_at(dead_N: float, fit: list[SensorRecord], name: str, knots: np.ndarray
            ) -> tuple[ElasticLaw, ShareKernel, float]:
    """Share and kernel for one dead band: kernel times by least squares, share by NNLS."""
    cols = [basis_matrix(knots, np.maximum(r.force_N - dead_N, 0.0)) for r in fit]
    weights = [1.0 / (max(float(compression(r, name)[r.peak_index]), 1e-9) * np.sqrt(r.time_s.size))
               for r in fit]
    target = np.concatenate([w * compression(r, name) for w, r in zip(weights, fit, strict=True)])

    def unpack(theta: np.ndarray) -> ShareKernel:
        tau = np.exp(theta[:N_TERMS])
        c = np.tanh(theta[N_TERMS:]) * 0.9 / N_TERMS  # |c_k| < 0.45: K(inf) in (0.1, 1.9)
        return ShareKernel(tuple(c), tuple(tau))

    def solve(theta: np.ndarray):
        kernel = unpack(theta)
        A = np.concatenate([w * kernel.response(B, r.time_s)
                            for w, B, r in zip(weights, cols, fit, strict=True)])
        coef, _ = nnls(A, target)
        return coef, A @ coef - target

    lo, hi = TAU_BOUNDS_S
    theta0 = np.concatenate([np.log(np.geomspace(0.5, 5.0, N_TERMS)), np.zeros(N_TERMS)])
    bounds = (np.concatenate([np.full(N_TERMS, np.log(lo)), np.full(N_TERMS, -3.0)]),
              np.concatenate([np.full(N_TERMS, np.log(hi)), np.full(N_TERMS, 3.0)]))
    res = least_squares(lambda th: solve(th)[1], theta0, bounds=bounds, diff_step=1e-4,
                        xtol=1e-10, ftol=1e-12, max_nfev=200)
    coef, resid = solve(res.x)
    return ElasticLaw(knots, coef), unpack(res.x), float(resid @ resid)


def fit_transfer(name: str, fit: list[SensorRecord], validation: list[SensorRecord] = (),
                 *, dead_band_steps: int = 9) -> TransferLaw:
    """Fit the transfer law of sensor ``name`` to FE records of one design.

    The dead band is searched on ``dead_band_steps`` values across the FE's bracket (the plate
    force of the last ramp step the patch read nothing in compression and of the next);
    for each, the kernel's times and coefficients are fitted by least squares with the share's
    spline coefficients by non-negative least squares (a monotone share), all records weighted
    equally, each in units of its peak reading.
    """
    if not fit:
        raise ValueError("fit is empty: at least one record is needed")
    first = fit[0]
    placement = first.placements[name]
    top = max(float(r.force_N.max()) for r in fit)
    lo, hi = _dead_band_bracket(first, name)
    candidates = np.linspace(lo, hi, dead_band_steps)
    best = None
    for dead in candidates:
        knots = knots_at(top - dead, np.asarray(KNOTS_N))
        share, kernel, cost = _fit_at(float(dead), fit, name, knots)
        if best is None or cost < best[0]:
            best = (cost, float(dead), share, kernel)
    _, dead, share, kernel = best
    law = TransferLaw(first.design, placement, first.area_mm2[name], dead, share, kernel, top,
                      source={"fe_records": {f"{r.design}@{r.speed_mm_s:g}mm/s": r.speed_mm_s
                                             for r in fit},
                              "validation": {f"{r.design}@{r.speed_mm_s:g}mm/s": r.speed_mm_s
                                             for r in validation}})
    return replace(law, fitted=tuple(transfer_errors(law, r, name) for r in fit),
                   validated=tuple(transfer_errors(law, r, name) for r in validation))
