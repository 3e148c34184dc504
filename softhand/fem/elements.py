"""Quadratic Lagrange elements (Q9 quadrilateral, Q27 hexahedron) and Gauss rules.

Local nodes are the tensor grid {0, 1, 2}^dim of the 1D nodes xi = -1, 0, 1; local node index
``sum_k p_k 3^k`` with ``p_0`` the fastest. Quadratic displacement fields with full Gauss
integration (3 points per direction) carry bending without shear locking and stay accurate at
nu = 0.49 (the mesh-convergence study in the benchmark report measures it).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

__all__ = ["ReferenceElement", "gauss_1d", "lagrange_1d", "reference_element"]


def gauss_1d(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points and weights on [-1, 1]."""
    if n < 1:
        raise ValueError(f"n = {n!r} Gauss points: allowed range n >= 1")
    return np.polynomial.legendre.leggauss(n)


def lagrange_1d(xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quadratic Lagrange shape functions on nodes (-1, 0, 1) and their derivatives."""
    xi = np.asarray(xi, dtype=float)
    N = np.stack([0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)], axis=-1)
    dN = np.stack([xi - 0.5, -2.0 * xi, xi + 0.5], axis=-1)
    return N, dN


@dataclass(frozen=True)
class ReferenceElement:
    """Shape functions of a tensor-product quadratic element at a tensor Gauss rule.

    Attributes:
        dim: 1, 2 or 3.
        N: shape functions, (n_qp, n_nodes).
        dN: derivatives with respect to the local coordinates, (n_qp, n_nodes, dim).
        weights: quadrature weights, (n_qp,).
        points: quadrature points, (n_qp, dim).
    """

    dim: int
    N: np.ndarray
    dN: np.ndarray
    weights: np.ndarray
    points: np.ndarray

    @property
    def n_nodes(self) -> int:
        return self.N.shape[1]


def reference_element(dim: int, n_gauss: int = 3) -> ReferenceElement:
    """Quadratic Lagrange element of dimension ``dim`` with ``n_gauss`` points per direction."""
    if dim not in (1, 2, 3):
        raise ValueError(f"dim = {dim!r}: allowed 1, 2 or 3")
    g, w = gauss_1d(n_gauss)
    N1, dN1 = lagrange_1d(g)
    qps = list(itertools.product(range(n_gauss), repeat=dim))  # last index fastest
    nodes = list(itertools.product(range(3), repeat=dim))
    # local node index sum p_k 3^k: reverse so that p_0 varies fastest
    nodes = [tuple(reversed(n)) for n in nodes]
    qps = [tuple(reversed(q)) for q in qps]
    N = np.ones((len(qps), len(nodes)))
    dN = np.ones((len(qps), len(nodes), dim))
    for iq, q in enumerate(qps):
        for a, p in enumerate(nodes):
            for k in range(dim):
                N[iq, a] *= N1[q[k], p[k]]
                for j in range(dim):
                    dN[iq, a, j] *= dN1[q[k], p[k]] if j == k else N1[q[k], p[k]]
    weights = np.array([np.prod([w[i] for i in q]) for q in qps])
    points = np.array([[g[i] for i in q] for q in qps])
    return ReferenceElement(dim, N, dN, weights, points)
