r"""Compiled element kernels (numba): the same element arithmetic as the NumPy reference of
`softhand.fem.assembly` and `softhand.fem.materials`, one Gauss point at a time.

Why compiled: the NumPy path spends its time on temporaries of small batched arrays (3 x 3
eigenproblems, the 6 x 81 strain matrix per Gauss point and its products), not on arithmetic.
These kernels evaluate the Storakers hyperfoam with Prony relaxation (paper eq. 1-5; the same
formulas, divided differences and small-argument switches as `Hyperfoam` and
`Material`) and the element force at each Gauss point in one pass, in parallel over
elements (``numba.prange``; numba's threading layer releases the GIL).

The tangent never forms the strain matrix. With `G` the shape-function gradients and
`\mathbb{C}_{abcd}` the material tangent (from the Voigt `D`),

    K_{n i, m j} = \sum_q w_q \sum_d E^q_{n i j d}\, G^q_{m d}, \qquad
    E^q_{nijd} = \sum_{a b c} F_{ia} G^q_{nb} \mathbb{C}_{abcd} F_{jc} + \delta_{ij} (G^q S)_{nd},

the material and geometric stiffness of `softhand.fem.assembly` in index form (minor
symmetry of `\mathbb{C}` removes the symmetrisation of the strain). The kernel builds
`E` (a few thousand multiply-adds per Gauss point) and the contraction over
``(q, d)`` is one batched matrix product per element (BLAS).

Plane strain (``dim = 2``): only in-plane indices enter, exactly as in the reference
(`F_{33} = 1`, no out-of-plane gradient).

Results equal the NumPy reference to rounding (the tests compare forces and tangents at 1e-12
relative, and whole curves within the solver tolerance).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

__all__ = ["element_tangents", "evaluate_group", "inverted_points", "scatter_add", "sym_eig3"]

_VOIGT_A = np.array([0, 1, 2, 0, 1, 0])
_VOIGT_B = np.array([0, 1, 2, 1, 2, 2])
# Voigt index of the tensor pair (a, b)
_VOIGT_OF = np.array([[0, 3, 5], [3, 1, 4], [5, 4, 2]])
_PAIR_A = np.array([0, 1, 0])  # the pairs (0, 1), (1, 2), (0, 2) of Hyperfoam.stress
_PAIR_B = np.array([1, 2, 2])
_DD_SWITCH = 1e-6  # the same switch as softhand.fem.materials


@njit(cache=True, inline="always")
def _phi1(x):
    if abs(x) < 1e-8:
        return 1.0 + 0.5 * x
    return math.expm1(x) / x


@njit(cache=True)
def sym_eig3(A, w, V):
    """Eigenvalues ``w`` (3,) and orthonormal eigenvectors (columns of ``V``, 3 x 3) of the
    symmetric 3 x 3 matrix ``A`` by cyclic Jacobi rotations (high relative accuracy; converges
    in a few sweeps). ``A`` is not modified. Returns the number of sweeps made."""
    return _sym_eig3(A, w, V, np.empty((3, 3)))


@njit(cache=True)
def _sym_eig3(A, w, V, a):
    """`sym_eig3` with the 3 x 3 work array ``a`` given (no allocation)."""
    for i in range(3):
        for j in range(3):
            a[i, j] = A[i, j]
            V[i, j] = 1.0 if i == j else 0.0
    sweeps = 0
    while sweeps < 60:
        off = a[0, 1] * a[0, 1] + a[0, 2] * a[0, 2] + a[1, 2] * a[1, 2]
        diag = a[0, 0] * a[0, 0] + a[1, 1] * a[1, 1] + a[2, 2] * a[2, 2]
        if off <= 1e-36 * diag or off == 0.0:
            break
        sweeps += 1
        for p in range(2):
            for q in range(p + 1, 3):
                apq = a[p, q]
                if apq == 0.0:
                    continue
                theta = (a[q, q] - a[p, p]) / (2.0 * apq)
                t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
                if theta < 0.0:
                    t = -t
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(3):  # A <- J^T A J
                    akp, akq = a[k, p], a[k, q]
                    a[k, p] = c * akp - s * akq
                    a[k, q] = s * akp + c * akq
                for k in range(3):
                    apk, aqk = a[p, k], a[q, k]
                    a[p, k] = c * apk - s * aqk
                    a[q, k] = s * apk + c * aqk
                for k in range(3):
                    vkp, vkq = V[k, p], V[k, q]
                    V[k, p] = c * vkp - s * vkq
                    V[k, q] = s * vkp + c * vkq
    for i in range(3):
        w[i] = a[i, i]
    return sweeps


@njit(cache=True, inline="always")
def _f(x, mu, alpha):
    s = 0.0
    for i in range(mu.size):
        s += 2.0 * mu[i] * x * _phi1(alpha[i] * x)
    return s


@njit(cache=True, inline="always")
def _fprime(x, mu, alpha):
    s = 0.0
    for i in range(mu.size):
        s += 2.0 * mu[i] * math.exp(alpha[i] * x)
    return s


@njit(cache=True)
def _gamma(la, lb, fa, fb, ema, emb, epb, V, mu, alpha):
    """(S_a - S_b)/(c_a - c_b) without cancellation (Hyperfoam._gamma), from the values at the
    two log-stretches computed once per Gauss point: ``fa = f(la)``, ``fb = f(lb)``,
    ``ema = exp(-2 la)``, ``emb = exp(-2 lb)``, ``epb = exp(2 lb)`` (the same numbers as
    evaluating them here)."""
    h = la - lb
    if abs(h) < _DD_SWITCH:
        mid = 0.5 * (la + lb)
        dq = (_fprime(mid, mu, alpha) - 2.0 * _f(mid, mu, alpha)) * math.exp(-2.0 * mid)
    else:
        dq = (fa * ema - fb * emb) / h
    dd_c = 2.0 * epb * _phi1(2.0 * h)
    dd_e = -2.0 * emb * _phi1(-2.0 * h)
    return (dq + V * dd_e) / dd_c


@njit(cache=True)
def _hyperfoam(C, mu, alpha, beta, S, D, work):
    """Instantaneous S (Voigt) and D = 2 dS/dC (Voigt 6 x 6) at C (Hyperfoam.stress).
    ``work``: a (10, 6) scratch array (no allocation per Gauss point).
    Returns False when C is not positive definite."""
    c = work[0, :3]
    l = work[0, 3:]
    tau = work[1, :3]
    fa = work[1, 3:]  # f(l_a) of _gamma
    em = work[2, :3]  # exp(-2 l_a)
    ep = work[2, 3:]  # exp(2 l_a)
    N = work[3:, :3]
    dtau = work[3:, 3:]
    _sym_eig3(C, c, N, D[:3, :3])  # D is written below: its corner serves as the work array
    for a in range(3):
        if not (c[a] > 0.0) or not math.isfinite(c[a]):
            return False
    for a in range(3):
        l[a] = 0.5 * math.log(c[a])
        tau[a] = 0.0
        fa[a] = 0.0
        em[a] = math.exp(-2.0 * l[a])
        ep[a] = math.exp(2.0 * l[a])
        for b in range(3):
            dtau[a, b] = 0.0
    L = l[0] + l[1] + l[2]
    Vv = 0.0
    for i in range(mu.size):
        m, al = mu[i], alpha[i]
        vol = beta * L * _phi1(-al * beta * L)
        ev = beta * math.exp(-al * beta * L)
        Vv += 2.0 * m * vol
        for a in range(3):
            phi = _phi1(al * l[a])
            tau[a] += 2.0 * m * (l[a] * phi + vol)
            fa[a] += 2.0 * m * l[a] * phi  # the sum of _f, term by term
            for b in range(3):
                dtau[a, b] += 2.0 * m * ((math.exp(al * l[a]) if a == b else 0.0) + ev)
    mv = work[6:9]  # Voigt of n_a n_a^T
    for a in range(3):
        for v in range(6):
            mv[a, v] = N[_VOIGT_A[v], a] * N[_VOIGT_B[v], a]
    for v in range(6):
        s = 0.0
        for a in range(3):
            s += tau[a] / c[a] * mv[a, v]
        S[v] = s
    for v in range(6):
        for u in range(6):
            D[v, u] = 0.0
    for a in range(3):
        for b in range(3):
            dS = dtau[a, b] / (c[a] * c[b])
            if a == b:
                dS -= 2.0 * tau[a] / (c[a] * c[a])
            for v in range(6):
                for u in range(6):
                    D[v, u] += dS * mv[a, v] * mv[b, u]
    p = work[9]
    for k in range(3):
        a, b = _PAIR_A[k], _PAIR_B[k]
        g4 = 4.0 * _gamma(l[a], l[b], fa[a], fa[b], em[a], em[b], ep[b], Vv, mu, alpha)
        for v in range(6):
            i, j = _VOIGT_A[v], _VOIGT_B[v]
            p[v] = 0.5 * (N[i, a] * N[j, b] + N[j, a] * N[i, b])
        for v in range(6):
            for u in range(6):
                D[v, u] += g4 * p[v] * p[u]
    return True


@njit(cache=True, inline="always")
def _deformation_gradient(u, elements, dim, dNdX, e, q, F):
    """F (3 x 3, written into ``F``) at Gauss point ``q`` of element ``e``; returns det F."""
    nn = elements.shape[1]
    for i in range(3):
        for j in range(3):
            F[i, j] = 1.0 if i == j else 0.0
    for n in range(nn):
        node = elements[e, n]
        g0, g1 = dNdX[e, q, n, 0], dNdX[e, q, n, 1]
        if dim == 3:
            g2 = dNdX[e, q, n, 2]
            for i in range(3):
                ui = u[node * 3 + i]
                F[i, 0] += ui * g0
                F[i, 1] += ui * g1
                F[i, 2] += ui * g2
        else:
            for i in range(2):
                ui = u[node * 2 + i]
                F[i, 0] += ui * g0
                F[i, 1] += ui * g1
    return (F[0, 0] * (F[1, 1] * F[2, 2] - F[1, 2] * F[2, 1])
            - F[0, 1] * (F[1, 0] * F[2, 2] - F[1, 2] * F[2, 0])
            + F[0, 2] * (F[1, 0] * F[2, 1] - F[1, 1] * F[2, 0]))


@njit(parallel=True, cache=True)
def evaluate_group(u, elements, dim, idx, dNdX, wdet, mu, alpha, beta, g, decay, ramp,
                   S0_old, H_old, visco, fe, F_out, S_out, D_out, S0_new, H_new):
    """Material update and element forces of the elements ``idx`` of one material.

    Writes, for each element ``e = idx[k]``: its force ``fe[e]`` (``sum_q w G P``, P = F S),
    ``F_out[e]``, the total stress ``S_out[e]`` and tangent ``D_out[e]`` (Voigt), and the new
    history ``S0_new``, ``H_new`` (rows ``k * nq + q``, the layout of `ViscoState`).
    ``visco``: the material has a Prony series (``g``, ``decay``, ``ramp``: its factors over
    this step, `Prony.step_factors`).

    Returns the number of Gauss points with det F <= 0 or an indefinite C (0: all fine).
    """
    nq = dNdX.shape[1]
    nn = elements.shape[1]
    n_terms = g.size
    bad = np.zeros(idx.size, dtype=np.int64)
    for k in prange(idx.size):
        e = idx[k]
        F = np.empty((3, 3))
        C = np.empty((3, 3))
        S0 = np.empty(6)
        D0 = np.empty((6, 6))
        St = np.zeros((3, 3))
        P = np.empty((3, 3))
        work = np.empty((10, 6))
        for r in range(nn * dim):
            fe[e, r] = 0.0
        for q in range(nq):
            det = _deformation_gradient(u, elements, dim, dNdX, e, q, F)
            for i in range(3):
                for j in range(3):
                    F_out[e, q, i, j] = F[i, j]
            if not det > 0.0:
                bad[k] += 1
                continue
            for i in range(3):
                for j in range(3):
                    s = 0.0
                    for m in range(3):
                        s += F[m, i] * F[m, j]
                    C[i, j] = s
            if not _hyperfoam(C, mu, alpha, beta, S0, D0, work):
                bad[k] += 1
                continue
            row = k * nq + q
            factor = 1.0
            for v in range(6):
                S_out[e, q, v] = S0[v]
            if visco:
                for v in range(6):
                    dS0 = S0[v] - S0_old[row, v]
                    S0_new[row, v] = S0[v]
                    for t in range(n_terms):
                        h = decay[t] * H_old[t, row, v] + ramp[t] * dS0
                        H_new[t, row, v] = h
                        S_out[e, q, v] -= g[t] * (S0[v] - h)
                for t in range(n_terms):
                    factor -= g[t] * (1.0 - ramp[t])
            for v in range(6):
                for w_ in range(6):
                    D_out[e, q, v, w_] = factor * D0[v, w_]
            w = wdet[e, q]
            for v in range(6):
                a, b = _VOIGT_A[v], _VOIGT_B[v]
                St[a, b] = S_out[e, q, v] * w
                St[b, a] = St[a, b]
            for i in range(dim):
                for b in range(dim):
                    s = 0.0
                    for m in range(dim):
                        s += F[i, m] * St[m, b]
                    P[i, b] = s
            for n in range(nn):  # the sum over b written out (same order), as in the tangent
                g0, g1 = dNdX[e, q, n, 0], dNdX[e, q, n, 1]
                if dim == 3:
                    g2 = dNdX[e, q, n, 2]
                    for i in range(3):
                        fe[e, n * 3 + i] += g0 * P[i, 0] + g1 * P[i, 1] + g2 * P[i, 2]
                else:
                    for i in range(2):
                        fe[e, n * 2 + i] += g0 * P[i, 0] + g1 * P[i, 1]
    return int(bad.sum())


@njit(cache=True)
def _tangent_factor(e, F, S, D, dNdX, wdet, E):
    r"""The factor `E_{nijd}` of element ``e`` (module docstring), weights included, into
    ``E`` of shape ``(nn * dim * dim, nq * dim)``: rows ``(n, i, j)``, columns ``(q, d)``.

    Per Gauss point the 9 x 9 matrix `M_{ib,jd} = w(\sum_{ac} F_{ia}\mathbb{C}_{abcd}
    F_{jc} + \delta_{ij} S_{bd})` is formed once; then `E_{nijd} = \sum_b G_{nb}
    M_{ib,jd}`.
    """
    nq, nn, dim = dNdX.shape[1], dNdX.shape[2], dNdX.shape[3]
    T = np.empty((3, 3, 3, 3))  # T[i, b, c, d] = sum_a F_ia C_abcd
    M = np.empty((3, 3, 3, 3))  # M[i, b, j, d]
    for q in range(nq):
        w = wdet[e, q]
        # sums written out below as in the E loop (same additions, same order)
        for i in range(dim):
            f0, f1, f2 = F[e, q, i, 0], F[e, q, i, 1], F[e, q, i, 2]
            for b in range(dim):
                for c in range(dim):
                    for d in range(dim):
                        cd = _VOIGT_OF[c, d]
                        s = (f0 * D[e, q, _VOIGT_OF[0, b], cd]
                             + f1 * D[e, q, _VOIGT_OF[1, b], cd])
                        if dim == 3:
                            s += f2 * D[e, q, _VOIGT_OF[2, b], cd]
                        T[i, b, c, d] = s
        for j in range(dim):
            f0, f1, f2 = F[e, q, j, 0], F[e, q, j, 1], F[e, q, j, 2]
            for i in range(dim):
                for b in range(dim):
                    for d in range(dim):
                        s = S[e, q, _VOIGT_OF[b, d]] if i == j else 0.0
                        s = s + T[i, b, 0, d] * f0 + T[i, b, 1, d] * f1
                        if dim == 3:
                            s += T[i, b, 2, d] * f2
                        M[i, b, j, d] = w * s
        # the sum over b written out (the same additions in the same order as a loop from
        # s = 0) keep the factors in registers: with the other two, the factor of a 3D tangent of
        # pocket2-sil took 2.1 ms instead of 10.8 (the product after it, BLAS, 4.3 ms)
        for n in range(nn):
            g0, g1 = dNdX[e, q, n, 0], dNdX[e, q, n, 1]
            if dim == 3:
                g2 = dNdX[e, q, n, 2]
                for i in range(3):
                    for j in range(3):
                        row = (n * 3 + i) * 3 + j
                        for d in range(3):
                            E[row, q * 3 + d] = (g0 * M[i, 0, j, d] + g1 * M[i, 1, j, d]
                                                 + g2 * M[i, 2, j, d])
            else:
                for i in range(2):
                    for j in range(2):
                        row = (n * 2 + i) * 2 + j
                        for d in range(2):
                            E[row, q * 2 + d] = g0 * M[i, 0, j, d] + g1 * M[i, 1, j, d]


@njit(parallel=True, cache=True)
def element_tangents(F, S, D, dNdX, wdet, G_qdm, K):
    """Element tangents ``K[e]`` of shape ``(nn * dim * dim, nn)``, entries ordered
    ``(n, i, j), m``: `K_{ni,mj}` (material plus geometric stiffness), from the factor of
    `_tangent_factor` and one matrix product per element (BLAS) with ``G_qdm[e]``, the
    shape-function gradients ordered ``(q, d), m``."""
    ne, nq, nn, dim = dNdX.shape
    for e in prange(ne):
        E = np.empty((nn * dim * dim, nq * dim))
        _tangent_factor(e, F, S, D, dNdX, wdet, E)
        K[e] = np.dot(E, G_qdm[e])


@njit(cache=True)
def scatter_add(out, index, values):
    """``out[index[k]] += values[k]`` for every ``k`` with ``index[k] >= 0``, in the order of
    ``k`` (one thread): the sums of ``np.bincount(index, weights=values)`` bit for bit, with
    no array of the pattern's size in between."""
    for k in range(index.size):
        i = index[k]
        if i >= 0:
            out[i] += values[k]


@njit(parallel=True, cache=True)
def inverted_points(u, elements, dim, dNdX):
    """The number of Gauss points with det F <= 0 (or not a number) at displacement ``u``:
    the deformation gradient of `evaluate_group`, without the material."""
    ne, nq = dNdX.shape[0], dNdX.shape[1]
    bad = np.zeros(ne, dtype=np.int64)
    for e in prange(ne):
        F = np.empty((3, 3))
        for q in range(nq):
            if not _deformation_gradient(u, elements, dim, dNdX, e, q, F) > 0.0:
                bad[e] += 1
    return int(bad.sum())
