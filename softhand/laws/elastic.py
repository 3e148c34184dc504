r"""Elastic skin laws: a smooth, monotone force-indentation curve that is zero at zero.

The law is written through its stiffness, a quadratic B-spline with non-negative coefficients,

    F(\delta) = \int_0^\delta \sum_j c_j M_j(s)\,ds = \sum_j c_j I_j(\delta), \qquad c_j \ge 0,

so that `F(0) = 0`, `F' \ge 0` (monotone) and `F \in C^2` for every coefficient
vector; the force is linear in `c`, so a fit is a non-negative least-squares problem. Past the
last knot the law continues with its end stiffness (a straight line); below zero it gives no force
(a skin does not pull).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.interpolate import BSpline

from softhand.validate import check_mapping, check_numbers, join

__all__ = ["ElasticLaw", "MonotoneInverse", "basis_matrix", "knot_vector", "knots_at",
           "monotone_inverse"]

_DEGREE = 2  # stiffness degree; force is one degree higher


def knot_vector(max_mm: float, n_basis: int) -> np.ndarray:
    """Clamped knots on [0, max_mm] for ``n_basis`` quadratic stiffness splines (uniform)."""
    if not np.isfinite(max_mm) or max_mm <= 0:
        raise ValueError(f"max_mm = {max_mm!r} must be finite and > 0")
    if n_basis < _DEGREE + 1:
        raise ValueError(f"n_basis = {n_basis!r} must be >= {_DEGREE + 1}")
    inner = np.linspace(0.0, max_mm, n_basis - _DEGREE + 1)
    return np.concatenate([[0.0] * _DEGREE, inner, [max_mm] * _DEGREE])


def knots_at(max_mm: float, inner_mm) -> np.ndarray:
    """Clamped knots on [0, max_mm] with the given interior knots (mm; those outside (0, max_mm)
    are dropped)."""
    if not np.isfinite(max_mm) or max_mm <= 0:
        raise ValueError(f"max_mm = {max_mm!r} must be finite and > 0")
    inner = np.unique(np.asarray(inner_mm, dtype=float))
    inner = inner[(inner > 0) & (inner < max_mm)]
    return np.concatenate([[0.0] * (_DEGREE + 1), inner, [max_mm] * (_DEGREE + 1)])


def basis_matrix(knots: np.ndarray, delta_mm: np.ndarray) -> np.ndarray:
    """``I_j(delta)`` for every basis function (columns), with the linear continuation."""
    knots = np.asarray(knots, dtype=float)
    n = knots.size - _DEGREE - 1
    eye = np.eye(n)
    return np.stack([ElasticLaw(knots, eye[j]).force(delta_mm) for j in range(n)], axis=-1)


def monotone_inverse(y, x, f) -> np.ndarray:
    """The one inversion of a tabulated monotone curve: x at which f(x) (non-decreasing, sampled
    at increasing ``x``) reaches each ``y``, linear between samples, clamped to the table's ends.
    A flat or slightly falling step of the samples (round-off of a tabulated ramp) is taken as
    flat, so that the inverse stays single-valued. (A law inverts itself exactly:
    `ElasticLaw.displacement_at`; a table inverted many times: `MonotoneInverse`.)"""
    return MonotoneInverse(x, f)(y)


class MonotoneInverse:
    """`monotone_inverse` of one table, called many times: the samples made single-valued (their
    running maximum) once, when made, instead of at every call."""

    def __init__(self, x, f) -> None:
        self.x = np.asarray(x, dtype=float)
        self.f = np.maximum.accumulate(np.asarray(f, dtype=float))

    def __call__(self, y) -> np.ndarray:
        return np.interp(y, self.f, self.x)


@dataclass(frozen=True)
class ElasticLaw:
    """F(delta) in N for indentation delta in mm (see the module docstring).

    Attributes:
        knots: clamped knot vector of the quadratic stiffness spline (mm).
        coefficients: non-negative stiffness coefficients (N/mm), one per basis function.
    """

    knots: np.ndarray
    coefficients: np.ndarray

    def __post_init__(self) -> None:
        k = np.asarray(self.knots, dtype=float)
        c = np.asarray(self.coefficients, dtype=float)
        if k.ndim != 1 or c.ndim != 1 or k.size != c.size + _DEGREE + 1:
            raise ValueError(f"{k.size} knots and {c.size} coefficients do not make a "
                             f"degree-{_DEGREE} spline (need knots = coefficients + {_DEGREE + 1})")
        if not (np.all(np.isfinite(k)) and np.all(np.isfinite(c))):
            raise ValueError("knots and coefficients must be finite")
        if np.any(np.diff(k) < 0) or k[0] != 0.0:
            raise ValueError(f"knots must start at 0 and not decrease, got {k.tolist()}")
        if np.any(c < 0):
            raise ValueError(f"coefficients must be >= 0 (a monotone law), got min {c.min():.3g}")
        object.__setattr__(self, "knots", k)
        object.__setattr__(self, "coefficients", c)
        stiff = BSpline(k, c, _DEGREE, extrapolate=False)
        object.__setattr__(self, "_stiffness", stiff)
        object.__setattr__(self, "_force", stiff.antiderivative())

    @property
    def max_mm(self) -> float:
        """End of the fitted range; beyond it the law is a straight line."""
        return float(self.knots[-1])

    def stiffness(self, delta_mm) -> np.ndarray:
        """dF/d delta (N/mm)."""
        d = np.clip(np.asarray(delta_mm, dtype=float), 0.0, self.max_mm)
        k = np.nan_to_num(self._stiffness(d))
        return np.where(np.asarray(delta_mm) < 0, 0.0, k)

    def force(self, delta_mm) -> np.ndarray:
        """F(delta) in N; 0 for delta <= 0, linear past `max_mm`."""
        d = np.asarray(delta_mm, dtype=float)
        inside = np.clip(d, 0.0, self.max_mm)
        f = np.nan_to_num(self._force(inside))
        beyond = np.maximum(d - self.max_mm, 0.0)
        return np.where(d <= 0, 0.0, f + beyond * self.end_stiffness)

    @property
    def end_stiffness(self) -> float:
        """Stiffness at the end of the fitted range (N/mm), used past it."""
        return float(self.coefficients[-1])

    def displacement_at(self, force_N):
        """Indentation (mm) at which the law reaches ``force_N`` (each > 0): the one inversion of a
        law, by bisection (the law is monotone; 60 halvings: to round-off), linear past
        `max_mm`. A float for a number, an array for an array."""
        f = np.asarray(force_N, dtype=float)
        if not np.all(np.isfinite(f)) or np.any(f <= 0):
            bad = f.ravel()[~(np.isfinite(f.ravel()) & (f.ravel() > 0))][0]
            raise ValueError(f"force_N = {float(bad)!r} must be finite and > 0")
        f_end = float(self.force(self.max_mm))
        beyond = f >= f_end
        if np.any(f > f_end) and self.end_stiffness <= 0:  # f_end itself is reached at max_mm
            raise ValueError(f"the law never reaches {float(f.max())} N (at most {f_end:.4g} N)")
        lo, hi = np.zeros_like(f), np.full_like(f, self.max_mm)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            below = self.force(mid) < f
            lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
        out = np.where(beyond, self.max_mm + (f - f_end) / max(self.end_stiffness, 1e-300),
                       0.5 * (lo + hi))
        return float(out) if out.ndim == 0 else out

    def to_dict(self) -> dict:
        return {"knots_mm": self.knots.tolist(), "coefficients_N_per_mm": self.coefficients.tolist()}

    @classmethod
    def from_dict(cls, d: Any, *, key: str = "elastic") -> ElasticLaw:
        """Parse `to_dict` output, checking every value.

        Args:
            d: mapping with ``knots_mm`` (>= 4 numbers, from 0, not decreasing) and
                ``coefficients_N_per_mm`` (``len(knots) - 3`` numbers >= 0).
            key: key path of ``d`` in messages.

        Raises:
            ValueError: ``"{key}.knots_mm[2] = 'x': expected a finite number"`` and the like.
        """
        check_mapping(key, d, required=("knots_mm", "coefficients_N_per_mm"))
        knots = check_numbers(join(key, "knots_mm"), d["knots_mm"], min_length=_DEGREE + 2, lo=0.0)
        coef = check_numbers(join(key, "coefficients_N_per_mm"), d["coefficients_N_per_mm"],
                             length=len(knots) - _DEGREE - 1, lo=0.0,
                             why=f"(len(knots_mm) - {_DEGREE + 1})")
        try:
            return cls(np.asarray(knots), np.asarray(coef))
        except ValueError as exc:
            raise ValueError(f"{key}: {exc}") from None

    @classmethod
    def fit(cls, delta_mm, force_N, *, n_basis: int = 10, max_mm: float | None = None
            ) -> ElasticLaw:
        """Least-squares monotone law through static points (no time dependence)."""
        from scipy.optimize import nnls

        d = np.asarray(delta_mm, dtype=float)
        f = np.asarray(force_N, dtype=float)
        knots = knot_vector(max_mm or float(d.max()), n_basis)
        c, _ = nnls(basis_matrix(knots, d), f)
        return cls(knots, c)
