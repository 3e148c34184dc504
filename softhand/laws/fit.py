"""Fit a skin law (elastic law + Prony QLV relaxation) to indentation curves, and score it.

The fit is a variable projection: for given relaxation times and fractions the QLV force is linear
in the elastic law's non-negative coefficients (a non-negative least-squares problem); an outer
least-squares search moves the relaxation parameters. Every curve counts equally, whatever its
number of samples. Errors are reported as a percentage of 2 N, the paper's indentation force.
"""

from __future__ import annotations

import csv
import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares, nnls

from softhand.laws.elastic import ElasticLaw, basis_matrix, knot_vector
from softhand.laws.qlv import Prony, qlv_force, qlv_response_matrix

__all__ = ["Curve", "CurveError", "SkinLaw", "curve_errors", "fit_skin_law", "load_curve",
           "paired_arrays"]

REFERENCE_FORCE_N = 2.0


def paired_arrays(x, y, names: tuple[str, str], min_size: int = 2
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Two finite 1-D float arrays of the same length >= ``min_size``, or a ValueError naming them."""
    a = np.asarray(x, dtype=float)
    b = np.asarray(y, dtype=float)
    if a.shape != b.shape or a.ndim != 1 or a.size < min_size:
        raise ValueError(f"{names[0]} and {names[1]} must be 1-D arrays of the same length "
                         f">= {min_size} (got shapes {a.shape} and {b.shape})")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ValueError(f"{names[0]} and {names[1]} must be finite")
    return a, b


@dataclass(frozen=True)
class Curve:
    """One indentation record: plate displacement and force against time, ramp then hold.

    Raises:
        ValueError: NaN, unequal lengths, decreasing time, or a ramp whose displacement or force
            is not monotone.
    """

    time_s: np.ndarray
    displacement_mm: np.ndarray
    force_N: np.ndarray
    hold: np.ndarray
    label: str = ""
    sha256: str = ""

    def __post_init__(self) -> None:
        arrays = [np.asarray(a, dtype=float) for a in
                  (self.time_s, self.displacement_mm, self.force_N)]
        hold = np.asarray(self.hold, dtype=bool)
        n = arrays[0].size
        if any(a.shape != (n,) for a in arrays) or hold.shape != (n,):
            raise ValueError(f"curve {self.label!r}: time, displacement, force and hold must be "
                             "1-D arrays of the same length")
        if n < 3:
            raise ValueError(f"curve {self.label!r} has {n} points; at least 3 are needed")
        for name, a in zip(("time_s", "displacement_mm", "force_N"), arrays, strict=True):
            bad = np.flatnonzero(~np.isfinite(a))
            if bad.size:
                raise ValueError(f"curve {self.label!r}: {name} is not finite at row {bad[0]} "
                                 f"({a[bad[0]]!r})")
        if np.any(np.diff(arrays[0]) < 0):
            raise ValueError(f"curve {self.label!r}: time decreases at row "
                             f"{int(np.argmax(np.diff(arrays[0]) < 0)) + 1}")
        ramp = ~hold
        for name, a in (("displacement", arrays[1][ramp]), ("force", arrays[2][ramp])):
            steps = np.diff(a)
            tol = 1e-9 * max(1.0, float(np.abs(a).max()))
            if np.any(steps < -tol):
                i = int(np.argmax(steps < -tol))
                raise ValueError(f"curve {self.label!r}: ramp {name} is not monotone "
                                 f"({a[i]:.6g} then {a[i + 1]:.6g} at ramp row {i + 1})")
        for name, a in zip(("time_s", "displacement_mm", "force_N"), arrays, strict=True):
            object.__setattr__(self, name, a)
        object.__setattr__(self, "hold", hold)

    @property
    def peak_index(self) -> int:
        """Index of the last ramp point."""
        ramp = np.flatnonzero(~self.hold)
        return int(ramp[-1])

    @property
    def speed_mm_s(self) -> float:
        i = self.peak_index
        return float(self.displacement_mm[i] / self.time_s[i])


def load_curve(path: str | Path, label: str | None = None) -> Curve:
    """Read a curve CSV written by the FE stage (time_s, displacement_mm, force_N, hold)."""
    p = Path(path)
    text = p.read_text(encoding="utf-8")
    rows = list(csv.DictReader(text.splitlines()))
    need = {"time_s", "displacement_mm", "force_N", "hold"}
    if not rows or not need <= set(rows[0]):
        raise ValueError(f"{p}: expected columns {sorted(need)}")
    try:
        cols = {k: np.array([float(r[k]) for r in rows]) for k in need}
    except ValueError as exc:
        raise ValueError(f"{p}: {exc}") from None
    return Curve(cols["time_s"], cols["displacement_mm"], cols["force_N"], cols["hold"] > 0.5,
                 label=label or p.stem, sha256=hashlib.sha256(text.encode()).hexdigest())


@dataclass(frozen=True)
class CurveError:
    """Law against one curve: RMS and max of the force error, % of 2 N, and in the hold."""

    label: str
    rms_pct_of_2N: float
    max_pct_of_2N: float
    hold_max_pct: float | None  # max |error| in the hold, % of the force at the start of the hold

    def to_dict(self) -> dict:
        return {"label": self.label, "rms_pct_of_2N": self.rms_pct_of_2N,
                "max_pct_of_2N": self.max_pct_of_2N, "hold_max_pct": self.hold_max_pct}


@dataclass(frozen=True)
class SkinLaw:
    """An elastic law (instantaneous) with its relaxation, and how well it fits.

    Attributes:
        name: design or reference name.
        elastic: instantaneous elastic law F_e(delta).
        prony: normalised relaxation G(t); the long-term law is ``prony.g_inf * F_e``.
        fitted: errors against the curves it was fitted to.
        validated: errors against curves it was not fitted to.
        source: where it came from (curve hashes, or the paper numbers it encodes).
    """

    name: str
    elastic: ElasticLaw
    prony: Prony
    fitted: tuple[CurveError, ...] = ()
    validated: tuple[CurveError, ...] = ()
    source: dict = field(default_factory=dict)

    def long_term_force(self, delta_mm) -> np.ndarray:
        return self.prony.g_inf * self.elastic.force(delta_mm)

    def force(self, time_s, displacement_mm) -> np.ndarray:
        """QLV force for a displacement history."""
        return qlv_force(self.elastic.force(displacement_mm), time_s, self.prony)

    def quasi_static_displacement_at(self, force_N: float, speed_mm_s: float = 0.5) -> float:
        """Indentation reached at ``force_N`` in a ramp at ``speed_mm_s`` (as in the paper)."""
        if not np.isfinite(speed_mm_s) or speed_mm_s <= 0:
            raise ValueError(f"speed_mm_s = {speed_mm_s!r} must be finite and > 0")
        top = self.elastic.displacement_at(force_N) / max(self.prony.g_inf, 1e-6) + 1.0
        d = np.linspace(0.0, top, 4000)
        f = self.force(d / speed_mm_s, d)
        if f[-1] < force_N:
            raise ValueError(f"{self.name}: {force_N} N is not reached by {top:.3g} mm")
        return float(np.interp(force_N, f, d))

    def to_dict(self) -> dict:
        return {"name": self.name, "elastic": self.elastic.to_dict(),
                "prony": self.prony.to_dict(),
                "fitted": [e.to_dict() for e in self.fitted],
                "validated": [e.to_dict() for e in self.validated], "source": self.source}

    @classmethod
    def from_dict(cls, d: dict) -> SkinLaw:
        errs = lambda key: tuple(CurveError(**e) for e in d.get(key, []))  # noqa: E731
        return cls(d["name"], ElasticLaw.from_dict(d["elastic"]), Prony.from_dict(d["prony"]),
                   errs("fitted"), errs("validated"), d.get("source", {}))


def curve_errors(law: SkinLaw, curve: Curve) -> CurveError:
    """Errors of ``law`` against ``curve`` (see :class:`CurveError`)."""
    model = law.force(curve.time_s, curve.displacement_mm)
    err = model - curve.force_N
    hold_max = None
    if curve.hold.any():
        f0 = curve.force_N[curve.peak_index]
        hold_max = float(100 * np.abs(err[curve.hold]).max() / f0)
    return CurveError(curve.label, float(100 * np.sqrt(np.mean(err**2)) / REFERENCE_FORCE_N),
                      float(100 * np.abs(err).max() / REFERENCE_FORCE_N), hold_max)


def fit_skin_law(name: str, curves: list[Curve], *, validation: list[Curve] = (),
                 n_terms: int = 2, n_basis: int = 10, tau_bounds_s: tuple[float, float] = (0.01, 60.0),
                 initial_tau_s: tuple[float, ...] | None = None) -> SkinLaw:
    """Fit an elastic law and an ``n_terms`` Prony series to ``curves`` (ramp + hold records).

    Args:
        name: the law's name (design).
        curves: records to fit, at one or more plate speeds.
        validation: records only to report errors against.
        n_terms: Prony terms (0 fits an elastic law to the ramps and ignores the holds).
        n_basis: stiffness spline functions of the elastic law.
        tau_bounds_s: range of the relaxation times.
        initial_tau_s: starting relaxation times (default: log-spaced inside the bounds' middle).
    """
    if not curves:
        raise ValueError("curves is empty: at least one curve is needed")
    if n_terms < 0:
        raise ValueError(f"n_terms = {n_terms!r} must be >= 0")
    lo, hi = tau_bounds_s
    if not 0 < lo < hi:
        raise ValueError(f"tau_bounds_s = {tau_bounds_s!r} must satisfy 0 < low < high")
    if n_terms == 0:
        curves = [Curve(c.time_s[~c.hold], c.displacement_mm[~c.hold], c.force_N[~c.hold],
                        c.hold[~c.hold], c.label, c.sha256) for c in curves]
    top = max(float(c.displacement_mm.max()) for c in curves)
    knots = knot_vector(top, n_basis)
    bases = [basis_matrix(knots, c.displacement_mm) for c in curves]
    weights = [1.0 / np.sqrt(c.time_s.size) for c in curves]
    target = np.concatenate([w * c.force_N for w, c in zip(weights, curves, strict=True)])

    def unpack(theta: np.ndarray) -> Prony:
        if n_terms == 0:
            return Prony()
        tau = np.exp(theta[:n_terms])
        z = np.exp(theta[n_terms:])
        g = z / (1.0 + z.sum())  # softmax-like: g_i > 0 and sum(g) < 1
        return Prony(tuple(g), tuple(tau))

    def solve(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        prony = unpack(theta)
        A = np.concatenate([w * qlv_response_matrix(B, c.time_s, prony)
                            for w, B, c in zip(weights, bases, curves, strict=True)])
        coef, _ = nnls(A, target)
        return coef, A @ coef - target

    if n_terms:
        tau0 = np.asarray(initial_tau_s if initial_tau_s is not None
                          else np.geomspace(max(lo, 0.1), min(hi, 10.0), n_terms), dtype=float)
        if tau0.size != n_terms:
            raise ValueError(f"initial_tau_s has {tau0.size} values; n_terms = {n_terms}")
        theta0 = np.concatenate([np.log(np.clip(tau0, lo, hi)), np.log(np.full(n_terms, 0.1))])
        bounds = (np.concatenate([np.full(n_terms, np.log(lo)), np.full(n_terms, -12.0)]),
                  np.concatenate([np.full(n_terms, np.log(hi)), np.full(n_terms, 5.0)]))
        res = least_squares(lambda th: solve(th)[1], theta0, bounds=bounds, x_scale=1.0,
                            diff_step=1e-4, xtol=1e-10, ftol=1e-12, max_nfev=300)
        theta = res.x
    else:
        theta = np.zeros(0)
    coef, _ = solve(theta)
    prony = unpack(theta)
    order = np.argsort(prony.tau_s)
    prony = Prony(tuple(np.asarray(prony.g)[order]), tuple(np.asarray(prony.tau_s)[order]))
    law = SkinLaw(name, ElasticLaw(knots, coef), prony,
                  source={"curves": {c.label: c.sha256 for c in curves},
                          "validation": {c.label: c.sha256 for c in validation}})
    return SkinLaw(law.name, law.elastic, law.prony,
                   tuple(curve_errors(law, c) for c in curves),
                   tuple(curve_errors(law, c) for c in validation), law.source)
