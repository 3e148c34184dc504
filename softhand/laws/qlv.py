r"""Quasi-linear viscoelasticity (Fung): an elastic law convolved with a Prony relaxation function.

.. math::

    F(t) = \int_0^t G(t - s)\,\frac{d F_e(\delta(s))}{ds}\,ds, \qquad
    G(t) = g_\infty + \sum_i g_i e^{-t/\tau_i}, \quad g_\infty + \sum_i g_i = 1,

with :math:`F_e` the *instantaneous* elastic law (:class:`~softhand.laws.elastic.ElasticLaw`); the
long-term law is :math:`g_\infty F_e`. The integral is evaluated with one hereditary variable per term,
exactly for an :math:`F_e(t)` that is linear between samples (the same recursion as the FE stage's
Prony update):

.. math::

    h_i^{n} = e^{-\Delta t/\tau_i} h_i^{n-1}
              + g_i\,\frac{\tau_i}{\Delta t}\left(1 - e^{-\Delta t/\tau_i}\right)\Delta F_e,
    \qquad F^n = g_\infty F_e^n + \sum_i h_i^n.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from softhand.validate import check_mapping, check_number, check_numbers, join, show

__all__ = ["Prony", "qlv_force", "qlv_response_matrix"]


@dataclass(frozen=True)
class Prony:
    """Normalised relaxation function G(t) = g_inf + sum g_i exp(-t / tau_i), G(0) = 1.

    Attributes:
        g: relaxation fractions, each >= 0, sum < 1.
        tau_s: time constants (s), each > 0, same length as ``g``.
    """

    g: tuple[float, ...] = ()
    tau_s: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        g = tuple(float(x) for x in self.g)
        tau = tuple(float(x) for x in self.tau_s)
        if len(g) != len(tau):
            raise ValueError(f"g has {len(g)} terms but tau_s has {len(tau)}")
        for x in g:
            if not np.isfinite(x) or x < 0:
                raise ValueError(f"g = {g}: each g_i must be finite and >= 0")
        if sum(g) >= 1:
            raise ValueError(f"sum(g) = {sum(g):.6g} must be < 1 (g_inf > 0)")
        for x in tau:
            if not np.isfinite(x) or x <= 0:
                raise ValueError(f"tau_s = {tau}: each tau_i must be finite and > 0")
        object.__setattr__(self, "g", g)
        object.__setattr__(self, "tau_s", tau)

    @property
    def g_inf(self) -> float:
        return 1.0 - sum(self.g)

    def relaxation(self, t_s) -> np.ndarray:
        """G(t) for t >= 0."""
        t = np.asarray(t_s, dtype=float)
        out = np.full(t.shape, self.g_inf)
        for g, tau in zip(self.g, self.tau_s, strict=True):
            out = out + g * np.exp(-t / tau)
        return out

    def to_dict(self) -> dict:
        return {"g": list(self.g), "tau_s": list(self.tau_s), "g_inf": self.g_inf}

    @classmethod
    def from_dict(cls, d: Any, *, key: str = "prony") -> Prony:
        """Parse :meth:`to_dict` output, checking every value.

        Args:
            d: mapping with ``g`` (numbers in [0, 1), sum < 1), ``tau_s`` (as many numbers > 0)
                and optionally ``g_inf`` (must equal 1 - sum(g) within 1e-6).
            key: key path of ``d`` in messages.

        Raises:
            ValueError: ``"{key}.tau_s[0] = -1.0: expected a finite number > 0"`` and the like.
        """
        check_mapping(key, d, required=("g", "tau_s"), optional=("g_inf",))
        g = check_numbers(join(key, "g"), d["g"], lo=0.0, hi=1.0, hi_open=True)
        tau = check_numbers(join(key, "tau_s"), d["tau_s"], length=len(g), lo=0.0, lo_open=True,
                            why=f"(as many as {join(key, 'g')})")
        if sum(g) >= 1:
            raise ValueError(f"{join(key, 'g')} = {show(list(g))}: the sum {sum(g):.6g} must be "
                             "< 1 (g_inf > 0)")
        if "g_inf" in d:
            g_inf = check_number(join(key, "g_inf"), d["g_inf"], lo=0.0, hi=1.0, lo_open=True)
            if abs(g_inf - (1.0 - sum(g))) > 1e-6:
                raise ValueError(f"{join(key, 'g_inf')} = {show(d['g_inf'])}: expected "
                                 f"1 - sum(g) = {1.0 - sum(g):.9g}")
        return cls(g, tau)


def _weights(prony: Prony, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-step decay factors and ramp weights, shape (n_terms, n_steps)."""
    dt = np.diff(np.asarray(t_s, dtype=float))
    if np.any(dt < 0) or not np.all(np.isfinite(dt)):
        raise ValueError("time must be finite and non-decreasing")
    tau = np.asarray(prony.tau_s)[:, None]
    x = dt[None, :] / tau
    decay = np.exp(-x)
    with np.errstate(invalid="ignore", divide="ignore"):
        ramp = np.where(x > 1e-12, -np.expm1(-x) / x, 1.0)
    return decay, ramp


def qlv_force(fe: np.ndarray, t_s: np.ndarray, prony: Prony) -> np.ndarray:
    """F(t) from the instantaneous elastic force history ``fe`` sampled at ``t_s``."""
    fe = np.asarray(fe, dtype=float)
    return qlv_response_matrix(fe[:, None], t_s, prony)[:, 0]


def qlv_response_matrix(fe: np.ndarray, t_s: np.ndarray, prony: Prony) -> np.ndarray:
    """QLV force for several elastic histories at once: ``fe`` has shape (n_times, n_columns).

    The response is linear in ``fe``; a fit uses this to solve for the elastic law's coefficients.
    """
    fe = np.asarray(fe, dtype=float)
    out = prony.g_inf * fe
    if not prony.g:
        return out
    decay, ramp = _weights(prony, t_s)
    dfe = np.diff(fe, axis=0)
    h = np.zeros((len(prony.g), fe.shape[1]))
    g = np.asarray(prony.g)[:, None]
    hist = np.zeros_like(fe)
    for n in range(dfe.shape[0]):
        h = decay[:, n, None] * h + g * ramp[:, n, None] * dfe[n][None, :]
        hist[n + 1] = h.sum(axis=0)
    return out + hist
