r"""Quasi-linear viscoelasticity (Fung): an elastic law convolved with a Prony relaxation function.

    F(t) = \int_0^t G(t - s)\,\frac{d F_e(\delta(s))}{ds}\,ds, \qquad
    G(t) = g_\infty + \sum_i g_i e^{-t/\tau_i}, \quad g_\infty + \sum_i g_i = 1,

with `F_e` the *instantaneous* elastic law (`ElasticLaw`); the
long-term law is `g_\infty F_e`. The integral is evaluated with one hereditary variable per term,
exactly for an `F_e(t)` that is linear between samples (the same recursion as the FE stage's
Prony update):

    h_i^{n} = e^{-\Delta t/\tau_i} h_i^{n-1}
              + g_i\,\frac{\tau_i}{\Delta t}\left(1 - e^{-\Delta t/\tau_i}\right)\Delta F_e,
    \qquad F^n = g_\infty F_e^n + \sum_i h_i^n.
"""

from __future__ import annotations

import numpy as np

from softhand.fem.materials import Prony  # the one relaxation function (re-exported)

__all__ = ["Prony", "qlv_force", "qlv_response_matrix"]


def _weights(prony: Prony, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-step decay factors and ramp weights, shape (n_terms, n_steps)."""
    dt = np.diff(np.asarray(t_s, dtype=float))
    if np.any(dt < 0) or not np.all(np.isfinite(dt)):
        raise ValueError("time must be finite and non-decreasing")
    return prony.step_factors(dt)


def qlv_force(fe: np.ndarray, t_s: np.ndarray, prony: Prony) -> np.ndarray:
    """F(t) from the instantaneous elastic force history ``fe`` sampled at ``t_s``."""
    fe = np.asarray(fe, dtype=float)
    return qlv_response_matrix(fe[:, None], t_s, prony)[:, 0]


def qlv_response_matrix(fe: np.ndarray, t_s: np.ndarray, prony: Prony) -> np.ndarray:
    """QLV force for several elastic histories at once: ``fe`` has shape (n_times, n_columns).

    The response is linear in ``fe``; a fit uses this to solve for the elastic law's coefficients.
    ``prony`` is a `Prony` or any kernel with ``g``, ``g_inf`` and ``step_factors`` (the
    sensors' share kernel, whose ratios may be negative: `softhand.sensors.transfer`).
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
