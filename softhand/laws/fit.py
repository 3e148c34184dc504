"""Fit a skin law (elastic law + Prony QLV relaxation) to indentation curves, and score it.

The fit is a variable projection: for given relaxation times and fractions the QLV force is linear
in the elastic law's non-negative coefficients (a non-negative least-squares problem); an outer
least-squares search moves the relaxation parameters. Every curve counts equally, whatever its
number of samples. The curves reach 20 N (the handshake's range): residuals are weighted by
`force_weights`, absolute up to the paper's 2 N and relative above it, so that the stiff tail
does not swamp the lifelike low-force part. Errors are reported as a percentage of 2 N over the
whole curve and up to 2 N, and as a percentage of the force itself above 2 N
(`CurveError`).
"""

from __future__ import annotations

import csv
import hashlib
import warnings
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import least_squares, nnls

from softhand.laws.elastic import ElasticLaw, basis_matrix, knot_vector, knots_at, monotone_inverse
from softhand.laws.qlv import Prony, qlv_force, qlv_response_matrix
from softhand.paper import paper
from softhand.validate import check_mapping, check_number, join, show

__all__ = [
    "CURVE_COLUMNS",
    "KNOT_FORCES_N",
    "Curve",
    "CurveError",
    "FitStatus",
    "FitWarning",
    "SkinLaw",
    "curve_errors",
    "fit_skin_law",
    "fit_status",
    "force_weights",
    "load_curve",
    "paired_arrays",
    "split_errors",
]


class FitStatus(str, Enum):
    """How a least-squares fit ended."""

    CONVERGED = "converged"  # a tolerance (xtol, ftol or gtol) was met
    BUDGET = "evaluation budget"  # stopped at max_nfev: the result is the best found, not a minimum


class FitWarning(UserWarning):
    """A fit stopped at its evaluation budget instead of converging."""


def fit_status(result, what: str) -> FitStatus:
    """The `FitStatus` of a ``scipy.optimize.least_squares`` result; warns
    (`FitWarning`, naming ``what``) when it stopped at its evaluation budget."""
    if result.status > 0:
        return FitStatus.CONVERGED
    warnings.warn(f"{what}: the fit stopped after {result.nfev} evaluations without meeting its "
                  f"tolerances (cost {result.cost:.3g}); the result is the best found",
                  FitWarning, stacklevel=3)
    return FitStatus.BUDGET


#: the social-touch force of the paper (its loading went to 2 N; its comparisons are at 2 N)
REFERENCE_FORCE_N = float(paper()["loading"]["max_force_N"])


#: Forces (N) at whose depths the elastic law's interior knots sit (fit_skin_law).
KNOT_FORCES_N = (0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0, 8.0, 12.0)


def force_weights(force_N) -> np.ndarray:
    """Residual weights 1 / max(1, F / 2 N): a force error counts in N up to the paper's 2 N and
    relative to the force above it (1 % of 20 N weighs like 1 % of 2 N)."""
    return 1.0 / np.maximum(1.0, np.abs(np.asarray(force_N, float)) / REFERENCE_FORCE_N)


def split_errors(model_N, target_N) -> dict[str, float | None]:
    """RMS force error of ``model_N`` against ``target_N`` below and above 2 N:
    ``rms_pct_of_2N_to_2N`` (over samples with target <= 2 N, % of 2 N) and
    ``rms_pct_above_2N`` (over samples above 2 N, % of each sample's force; None if none)."""
    m, t = np.asarray(model_N, float), np.asarray(target_N, float)
    low = t <= REFERENCE_FORCE_N
    err = m - t
    below = float(100 * np.sqrt(np.mean(err[low] ** 2)) / REFERENCE_FORCE_N) if low.any() else 0.0
    above = (float(100 * np.sqrt(np.mean((err[~low] / t[~low]) ** 2))) if (~low).any() else None)
    return {"rms_pct_of_2N_to_2N": below, "rms_pct_above_2N": above}


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

    The one force-displacement record of softhand: the FE's curves (read back from their CSV),
    and the simulated records of MuJoCo (the rig, the flex pad, the finger press) alike.

    Attributes:
        monotone: True for a measured or FE record, whose ramp must be monotone (checked);
            False for a simulated record (a contact's force may dip as it settles).
        stats: a simulated record's run statistics (``wall_s``, ``steps``, ``step_us``, and what
            a simulator adds: ``step_wall_s``, ``max_penetration_mm``, ``n_warnings``).

    Raises:
        ValueError: NaN, unequal lengths, decreasing time, or (``monotone``) a ramp whose
            displacement or force is not monotone.
    """

    time_s: np.ndarray
    displacement_mm: np.ndarray
    force_N: np.ndarray
    hold: np.ndarray
    label: str = ""
    sha256: str = ""
    monotone: bool = True
    stats: dict = field(default_factory=dict)

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
        checked = (("displacement", arrays[1][ramp]), ("force", arrays[2][ramp]))
        for name, a in checked if self.monotone else ():
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

    def force_at(self, displacement_mm) -> np.ndarray:
        """Force (N) on the ramp at plate displacements ``displacement_mm`` (linear between
        samples, on the monotone envelope of the displacement)."""
        ramp = ~self.hold
        d = np.maximum.accumulate(self.displacement_mm[ramp])
        return np.interp(np.asarray(displacement_mm, dtype=float), d, self.force_N[ramp])

    @classmethod
    def simulated(cls, time_s, displacement_mm, force_N, *, label: str = "",
                  **stats) -> Curve:
        """A simulated ramp (no hold flag, not checked monotone) with its run statistics;
        ``step_us`` is added from ``wall_s`` and ``steps`` when both are given."""
        if "wall_s" in stats and "steps" in stats:
            stats["step_us"] = 1e6 * stats["wall_s"] / max(int(stats["steps"]), 1)
        t = np.asarray(time_s, dtype=float)
        return cls(t, displacement_mm, force_N, np.zeros(t.shape, bool), label,
                   monotone=False, stats=stats)


def _text_hash(text: str) -> str:
    """SHA-256 of the text with universal newlines (as ``Path.read_text`` reads it)."""
    return hashlib.sha256(text.replace("\r\n", "\n").replace("\r", "\n").encode()).hexdigest()


CURVE_COLUMNS = ("time_s", "displacement_mm", "force_N", "hold")


def load_curve(path: str | Path, label: str | None = None) -> Curve:
    """Read a curve CSV written by the FE stage (time_s, displacement_mm, force_N, hold).

    The file is checked line by line before a curve is made: UTF-8 text, a header naming the four
    columns (in any order), then rows of four finite numbers with ``hold`` 0 or 1 and time
    strictly increasing from 0; at least 3 rows.

    Raises:
        ValueError: ``"{path}: line {n}, column {name}: ..."`` for the first bad cell (or the
            file-level problem: unreadable, empty, not UTF-8, a bad header or too few rows).
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise ValueError(f"{p}: cannot read the curve file ({exc.strerror or exc})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise ValueError(f"{p}: line {line}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at "
                         f"offset {exc.start})") from None
    lines = text.splitlines()
    if not lines or not text.strip():
        raise ValueError(f"{p}: the file is empty; expected the header {','.join(CURVE_COLUMNS)} "
                         "and rows of numbers")
    header = [h.strip() for h in next(csv.reader([lines[0]]))]
    if sorted(header) != sorted(CURVE_COLUMNS):
        missing = [c for c in CURVE_COLUMNS if c not in header]
        extra = [h for h in header if h not in CURVE_COLUMNS]
        what = (f"missing {', '.join(missing)}" if missing else "") + (
            ("; " if missing and extra else "") + (f"unknown {', '.join(map(repr, extra))}"
                                                   if extra else ""))
        if not what:
            what = "a column appears twice"
        raise ValueError(f"{p}: line 1: header {lines[0]!r} is not the FE curve header "
                         f"{','.join(CURVE_COLUMNS)} ({what})")
    cols: dict[str, list[float]] = {c: [] for c in CURVE_COLUMNS}
    last_t = None
    for n, cells in enumerate(csv.reader(lines[1:]), start=2):
        if not cells or all(not c.strip() for c in cells):
            if n == len(lines):  # a blank last line
                break
            raise ValueError(f"{p}: line {n}: empty row inside the file")
        if len(cells) != len(header):
            raise ValueError(f"{p}: line {n}: {len(cells)} cells {','.join(cells)!r}, expected "
                             f"{len(header)} ({','.join(header)}): truncated or malformed row")
        for name, cell in zip(header, cells, strict=True):
            where = f"{p}: line {n}, column {name}"
            try:
                v = float(cell)
            except ValueError:
                raise ValueError(f"{where}: {cell!r} is not a number") from None
            if not np.isfinite(v):
                raise ValueError(f"{where}: {cell.strip()!r}: expected a finite number")
            if name == "hold" and v not in (0.0, 1.0):
                raise ValueError(f"{where}: {cell.strip()!r}: expected 0 (ramp) or 1 (hold)")
            if name == "time_s":
                if last_t is None and v != 0.0:
                    raise ValueError(f"{where}: {cell.strip()!r}: the first time must be 0")
                if last_t is not None and not v > last_t:
                    raise ValueError(f"{where}: {cell.strip()!r}: time must increase (previous "
                                     f"row {last_t!r})")
                last_t = v
            cols[name].append(v)
    rows = len(cols["time_s"])
    if rows < 3:
        raise ValueError(f"{p}: {rows} data rows; at least 3 are needed")
    try:
        return Curve(np.array(cols["time_s"]), np.array(cols["displacement_mm"]),
                     np.array(cols["force_N"]), np.array(cols["hold"]) > 0.5,
                     label=label or p.stem, sha256=_text_hash(text))
    except ValueError as exc:
        raise ValueError(f"{p}: {exc}") from None


@dataclass(frozen=True)
class CurveError:
    """Law against one curve: RMS and max of the force error, % of 2 N, and in the hold; the
    loading ramp's RMS error up to 2 N (% of 2 N) and above it (% of the force), split_errors."""

    label: str
    rms_pct_of_2N: float
    max_pct_of_2N: float
    hold_max_pct: float | None  # max |error| in the hold, % of the force at the start of the hold
    rms_pct_of_2N_to_2N: float | None = None
    rms_pct_above_2N: float | None = None

    def to_dict(self) -> dict:
        return {"label": self.label, "rms_pct_of_2N": self.rms_pct_of_2N,
                "max_pct_of_2N": self.max_pct_of_2N, "hold_max_pct": self.hold_max_pct,
                "rms_pct_of_2N_to_2N": self.rms_pct_of_2N_to_2N,
                "rms_pct_above_2N": self.rms_pct_above_2N}

    @classmethod
    def from_dict(cls, d: Any, *, key: str = "error") -> CurveError:
        """Parse `to_dict` output: a string label and errors >= 0 (the hold and the split
        errors: or null)."""
        names = ("label", "rms_pct_of_2N", "max_pct_of_2N", "hold_max_pct")
        split = ("rms_pct_of_2N_to_2N", "rms_pct_above_2N")
        check_mapping(key, d, required=names, optional=split)
        if not isinstance(d["label"], str):
            raise ValueError(f"{join(key, 'label')} = {show(d['label'])}: expected a string")

        def maybe(name: str) -> float | None:
            v = d.get(name)
            return None if v is None else check_number(join(key, name), v, lo=0.0)

        return cls(d["label"], check_number(join(key, "rms_pct_of_2N"), d["rms_pct_of_2N"], lo=0.0),
                   check_number(join(key, "max_pct_of_2N"), d["max_pct_of_2N"], lo=0.0),
                   maybe("hold_max_pct"), maybe("rms_pct_of_2N_to_2N"), maybe("rms_pct_above_2N"))


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
        g_inf = max(self.prony.g_inf, 1e-6)
        # the elastic depth of the force, past it by the relaxation's share; where the ramp has
        # not reached the force there (a law that ends flat, fitted to a soft design's curve that
        # stops where its FE did, reaches its largest force near its end), to the law's end
        for top in (self.elastic.displacement_at(force_N) / g_inf + 1.0,
                    max(self.elastic.displacement_at(force_N), self.elastic.max_mm) / g_inf + 1.0):
            d = np.linspace(0.0, top, 4000)
            f = self.force(d / speed_mm_s, d)
            # up to the ramp's largest force: a law that ends flat relaxes past its end, and
            # its ramp falls there
            k = int(np.argmax(f))
            if f[k] >= force_N:
                return float(monotone_inverse(force_N, d[:k + 1], f[:k + 1]))
        raise ValueError(f"{self.name}: {force_N} N is not reached by {top:.3g} mm")

    def to_dict(self) -> dict:
        return {"name": self.name, "elastic": self.elastic.to_dict(),
                "prony": self.prony.to_dict(),
                "fitted": [e.to_dict() for e in self.fitted],
                "validated": [e.to_dict() for e in self.validated], "source": self.source}

    @classmethod
    def from_dict(cls, d: Any, *, key: str = "law") -> SkinLaw:
        """Parse `to_dict` output, checking every value (eagerly, here).

        Args:
            d: mapping with ``name`` (a string), ``elastic`` (`ElasticLaw.from_dict`),
                ``prony`` (`Prony.from_dict`) and optionally ``fitted`` / ``validated``
                (lists of `CurveError` records) and ``source`` (an object).
            key: key path of ``d`` in messages.

        Raises:
            ValueError: naming the key path, e.g. ``"law.prony.g[0] = 'x': expected ..."``.
        """
        check_mapping(key, d, required=("name", "elastic", "prony"),
                      optional=("fitted", "validated", "source"))
        if not isinstance(d["name"], str):
            raise ValueError(f"{join(key, 'name')} = {show(d['name'])}: expected a string")
        errors = {}
        for part in ("fitted", "validated"):
            items = d.get(part, [])
            if not isinstance(items, list):
                raise ValueError(f"{join(key, part)} = {show(items)}: expected a list of error "
                                 "records")
            errors[part] = tuple(CurveError.from_dict(e, key=join(join(key, part), i))
                                 for i, e in enumerate(items))
        source = d.get("source", {})
        check_mapping(join(key, "source"), source, optional=None)
        return cls(d["name"], ElasticLaw.from_dict(d["elastic"], key=join(key, "elastic")),
                   Prony.from_dict(d["prony"], key=join(key, "prony")),
                   errors["fitted"], errors["validated"], dict(source))


def curve_errors(law: SkinLaw, curve: Curve) -> CurveError:
    """Errors of ``law`` against ``curve`` (see `CurveError`)."""
    model = law.force(curve.time_s, curve.displacement_mm)
    err = model - curve.force_N
    hold_max = None
    if curve.hold.any():
        f0 = curve.force_N[curve.peak_index]
        hold_max = float(100 * np.abs(err[curve.hold]).max() / f0)
    ramp = ~curve.hold
    split = split_errors(model[ramp], curve.force_N[ramp])
    return CurveError(curve.label, float(100 * np.sqrt(np.mean(err**2)) / REFERENCE_FORCE_N),
                      float(100 * np.abs(err).max() / REFERENCE_FORCE_N), hold_max,
                      split["rms_pct_of_2N_to_2N"], split["rms_pct_above_2N"])


def fit_skin_law(name: str, curves: list[Curve], *, validation: list[Curve] = (),
                 n_terms: int = 2, n_basis: int = 10,
                 knot_forces_N: tuple[float, ...] | None = KNOT_FORCES_N,
                 tau_bounds_s: tuple[float, float] = (0.01, 60.0),
                 initial_tau_s: tuple[float, ...] | None = None,
                 prony: Prony | None = None) -> SkinLaw:
    """Fit an elastic law and an ``n_terms`` Prony series to ``curves`` (ramp + hold records).

    Args:
        name: the law's name (design).
        curves: records to fit, at one or more plate speeds.
        validation: records only to report errors against.
        n_terms: Prony terms (0 fits an elastic law to the ramps and ignores the holds).
        n_basis: stiffness spline functions of the elastic law (uniform knots), when
            ``knot_forces_N`` is None.
        knot_forces_N: place the interior knots at the depths where the first curve's loading
            ramp reaches these forces (those it reaches): dense where the force is low, so an
            11-function law fits 0-2 N and 2-20 N alike (a uniform 32-function law fits as well,
            but its 33 pieces break the relaxation pad built on it, measured: hold error 100 %).
        tau_bounds_s: range of the relaxation times.
        initial_tau_s: starting relaxation times (default: log-spaced inside the bounds' middle).
        prony: keep this relaxation and fit only the elastic law (one non-negative least-squares
            solve; ``n_terms`` is then ignored). For a law of another contact geometry of the same
            skin: the relaxation function of QLV is the material's, the elastic law the shape's.
    """
    if not curves:
        raise ValueError("curves is empty: at least one curve is needed")
    if n_terms < 0:
        raise ValueError(f"n_terms = {n_terms!r} must be >= 0")
    lo, hi = tau_bounds_s
    if not 0 < lo < hi:
        raise ValueError(f"tau_bounds_s = {tau_bounds_s!r} must satisfy 0 < low < high")
    if prony is not None:
        n_terms = len(prony.g)
    if n_terms == 0:
        curves = [Curve(c.time_s[~c.hold], c.displacement_mm[~c.hold], c.force_N[~c.hold],
                        c.hold[~c.hold], c.label, c.sha256) for c in curves]
    top = max(float(c.displacement_mm.max()) for c in curves)
    if knot_forces_N is None:
        knots = knot_vector(top, n_basis)
    else:
        first = curves[0]
        i = first.peak_index
        ramp_f = first.force_N[:i + 1]
        reach = [f for f in knot_forces_N if f < ramp_f.max()]
        knots = knots_at(top, monotone_inverse(reach, first.displacement_mm[:i + 1], ramp_f))
    bases = [basis_matrix(knots, c.displacement_mm) for c in curves]
    # every curve counts equally (1 / sqrt(samples)); within a curve, force_weights
    weights = [force_weights(c.force_N) / np.sqrt(c.time_s.size) for c in curves]
    target = np.concatenate([w * c.force_N for w, c in zip(weights, curves, strict=True)])

    def unpack(theta: np.ndarray) -> Prony:
        if prony is not None:
            return prony
        if n_terms == 0:
            return Prony()
        tau = np.exp(theta[:n_terms])
        z = np.exp(theta[n_terms:])
        g = z / (1.0 + z.sum())  # softmax-like: g_i > 0 and sum(g) < 1
        return Prony(tuple(g), tuple(tau))

    def solve(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        prony = unpack(theta)
        A = np.concatenate([w[:, None] * qlv_response_matrix(B, c.time_s, prony)
                            for w, B, c in zip(weights, bases, curves, strict=True)])
        coef, _ = nnls(A, target)
        return coef, A @ coef - target

    if n_terms and prony is None:
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
        status = fit_status(res, f"{name}: Prony terms")
    else:
        theta = np.zeros(0)
        status = FitStatus.CONVERGED  # the elastic part is a linear (NNLS) solve
    coef, _ = solve(theta)
    relax = unpack(theta)
    order = np.argsort(relax.tau_s)
    relax = Prony(tuple(np.asarray(relax.g)[order]), tuple(np.asarray(relax.tau_s)[order]))
    law = SkinLaw(name, ElasticLaw(knots, coef), relax,
                  source={"curves": {c.label: c.sha256 for c in curves},
                          "validation": {c.label: c.sha256 for c in validation},
                          "fit_status": status.value})
    return SkinLaw(law.name, law.elastic, law.prony,
                   tuple(curve_errors(law, c) for c in curves),
                   tuple(curve_errors(law, c) for c in validation), law.source)
