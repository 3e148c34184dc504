r"""Frictionless penalty contact, integrated at surface Gauss points.

Each contact set is a linear gap `g = g_0 + G u` evaluated at Gauss points of a surface,
with weights `w` (reference area). The penalty energy
`\Pi_c=\tfrac12\,\varepsilon\sum_q w_q\langle -g_q\rangle^2` gives

    r_c = -G^T (\varepsilon\, w \langle -g\rangle), \qquad K_c = G^T\,\mathrm{diag}(\varepsilon w\,[g<0])\,G,

and the contact force `\sum_q \varepsilon w_q\langle -g_q\rangle`. Integrating at Gauss points
(not nodes) lets the contact zone grow inside an element, which keeps the force curve smooth.

* Plate: a rigid plane ``y = top - d`` (d the plate displacement). Frictionless: only the vertical
  component enters the gap. Exact for a flat plate, any sliding. A plate smaller than the body
  (``Mesh.plate_half_mm``, the palm) acts on the surface points under its face only.
* Cylinder or sphere (`RoundGaps`): the gap to a rigid cylinder or sphere of radius R is
  nonlinear in u, `g = |P(x - c)| - R` with `x` the current point, `c` the
  centre (on the axis) and `P` the projection off the cylinder's axis (the identity for a
  sphere); it is linearised at every Newton iterate, `G = n^T N` with the unit normal
  `n = P(x-c)/|P(x-c)|`, into a `GapSet`. The tangent drops the curvature term
  `\varepsilon w\, g\,(P - nn^T)/|P(x-c)|` (relative size penetration / R, about 1e-4):
  Newton converges slightly less than quadratically, and the residual is exact.
* Pocket: roof underside against floor, paired at the same surface coordinates (small sliding),
  gap measured along the floor's reference normal. Adequate while the roof closes onto the floor
  without sliding far along it, which is how the pocket closes under a flat plate.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from softhand.fem.mesh import Mesh, face_element

__all__ = ["POCKET_CONTACTS", "GapSet", "PairedPocket", "PocketContact", "RoundGaps",
           "floor_through_roof_mm", "plate_gaps", "pocket_contact", "pocket_gaps"]


@dataclass(frozen=True)
class GapSet:
    """A linear gap function at surface Gauss points: g = g0 + G u (mm).

    ``weight`` is each point's share of the undeformed surface (mm^2; mm in plane strain),
    ``points`` its undeformed position (mm), where known.
    """

    g0: np.ndarray
    G: sp.csr_matrix
    weight: np.ndarray
    points: np.ndarray | None = None

    @property
    def size(self) -> int:
        return self.g0.size

    def gaps(self, u: np.ndarray, shift: float = 0.0) -> np.ndarray:
        return self.g0 + shift + self.G @ u

    def force(self, u: np.ndarray, penalty: float, shift: float = 0.0) -> float:
        """Contact force on the modelled part (N; N/mm in plane strain) of this set."""
        return float(penalty * (self.weight * np.maximum(-self.gaps(u, shift), 0.0)).sum())

    def pressure(self, u: np.ndarray, penalty: float, shift: float = 0.0) -> np.ndarray:
        """Contact pressure at each point (MPa = N/mm^2): the penalty times the overlap."""
        return penalty * np.maximum(-self.gaps(u, shift), 0.0)

    def contact_area(self, u: np.ndarray, shift: float = 0.0) -> float:
        """Undeformed surface in contact (mm^2 of the modelled part; mm in plane strain): the
        weights of the points whose gap is closed. Resolution: one Gauss point's weight."""
        return float(self.weight[self.gaps(u, shift) < 0.0].sum())

    def penalty_forces(self, u: np.ndarray, penalty: float, shift: float = 0.0):
        """Residual contribution, each point's penalty stiffness ``eps w [g < 0]`` (the
        diagonal of the tangent `stiffness`) and the number of closed points."""
        g = self.gaps(u, shift)
        closed = g < 0.0
        lam = penalty * self.weight * np.where(closed, -g, 0.0)
        r = -(self.transposed @ lam)
        return r, penalty * self.weight * closed, int(closed.sum())

    @cached_property
    def transposed(self) -> sp.csr_matrix:
        """The gap matrix ``G`` transposed, in CSR (dofs x points), formed once: `penalty_forces` runs at every
        Newton iteration, and transposing there took 0.06 s of a 0.87 s 2D run."""
        return self.G.T.tocsr()

    def stiffness(self, kw: np.ndarray) -> sp.csr_matrix:
        """The tangent ``G^T diag(kw) G`` for the point stiffnesses of `penalty_forces`."""
        return self.G.T @ sp.diags(kw) @ self.G


def _face_geometry(mesh: Mesh, faces: np.ndarray, n_gauss: int):
    """Shape values, positions, unit normals and area weights at face Gauss points."""
    fref = face_element(mesh.dim, n_gauss)
    Xf = mesh.X[faces]  # (nf, npf, dim)
    pos = np.einsum("qn,fnd->fqd", fref.N, Xf)
    tang = np.einsum("qnj,fnd->fqdj", fref.dN, Xf)  # (nf, nq, dim, dim-1)
    if mesh.dim == 2:
        t = tang[..., 0]
        normal = np.stack([t[..., 1], -t[..., 0]], axis=-1)
    else:
        normal = np.cross(tang[..., 0], tang[..., 1])
    area = np.linalg.norm(normal, axis=-1)
    normal = normal / area[..., None]
    weight = area * fref.weights[None, :]
    return fref.N, pos, normal, weight


def _gap_matrix(mesh: Mesh, faces: np.ndarray, N: np.ndarray, direction: np.ndarray, sign: float):
    """Sparse rows (one per face Gauss point) of sign * sum_a N_a (u_a . direction)."""
    nf, npf = faces.shape
    nq = N.shape[0]
    dim = mesh.dim
    rows = np.broadcast_to(np.arange(nf * nq).reshape(nf, nq, 1, 1), (nf, nq, npf, dim))
    cols = faces[:, None, :, None] * dim + np.arange(dim)
    cols = np.broadcast_to(cols, (nf, nq, npf, dim))
    vals = sign * N[None, :, :, None] * direction[:, :, None, :]
    return sp.csr_matrix((vals.ravel(), (rows.ravel(), cols.ravel())),
                         shape=(nf * nq, mesh.n_dofs))


def plate_gaps(mesh: Mesh, top_mm: float, n_gauss: int = 4) -> GapSet:
    """Gap between the outer surface and the plate ``y = top_mm - shift`` (shift = -d).

    A finite plate (``mesh.plate_half_mm`` = (hx, hz), a body wider than the plate) presses only
    the points under its face, ``|x| <= hx`` and ``|z| <= hz`` in the undeformed state (2D:
    ``|x| <= hx``): frictionless points hardly slide, so the set is fixed for the run. The face's
    edge falls between Gauss points unless a mesh line lies on it (the palm mesh puts one at
    ``z = hz``). Without ``plate_half_mm`` (the phalanx) every point of the outer surface is in
    the set, as before.
    """
    N, pos, _, weight = _face_geometry(mesh, mesh.outer_faces, n_gauss)
    down = np.zeros(pos.shape)
    down[..., 1] = 1.0
    G = _gap_matrix(mesh, mesh.outer_faces, N, down, -1.0)
    gaps = GapSet((top_mm - pos[..., 1]).ravel(), G, weight.ravel(), pos.reshape(-1, mesh.dim))
    if mesh.plate_half_mm is None:
        return gaps
    hx, hz = mesh.plate_half_mm
    tol = 1e-9
    under = np.abs(gaps.points[:, 0]) <= hx + tol
    if mesh.dim == 3:
        under &= np.abs(gaps.points[:, 2]) <= hz + tol
    return GapSet(gaps.g0[under], gaps.G[under], gaps.weight[under], gaps.points[under])


class RoundGaps:
    """Gap between the outer surface and a rigid cylinder or sphere moving down (-y).

    The centre is at ``(0, top_mm + radius_mm - d, 0)`` for indenter travel ``d``: at ``d = 0``
    the indenter touches the top of the skin. ``axis`` is the cylinder's unit axis in model
    coordinates (3D), or None for a sphere (3D) and for a cylinder normal to a 2D section.
    """

    def __init__(self, mesh: Mesh, top_mm: float, radius_mm: float,
                 axis: np.ndarray | None, n_gauss: int = 4) -> None:
        N, pos, _, weight = _face_geometry(mesh, mesh.outer_faces, n_gauss)
        self.mesh, self.N, self.top_mm, self.radius_mm = mesh, N, top_mm, radius_mm
        self.axis = None if axis is None else np.asarray(axis, dtype=float)[:mesh.dim]
        self.points = pos.reshape(-1, mesh.dim)
        self.weight = weight.ravel()
        self._shape = pos.shape  # (faces, points per face, dim)

    def centre(self, d: float) -> np.ndarray:
        c = np.zeros(self.mesh.dim)
        c[1] = self.top_mm + self.radius_mm - d
        return c

    def _normal(self, u: np.ndarray, d: float) -> tuple[np.ndarray, np.ndarray]:
        """Gap and unit normal (away from the axis or centre) at each point for state u."""
        un = u.reshape(-1, self.mesh.dim)[self.mesh.outer_faces]
        x = self.points + np.einsum("qn,fnd->fqd", self.N, un).reshape(self.points.shape)
        r = x - self.centre(d)
        if self.axis is not None:
            r = r - np.outer(r @ self.axis, self.axis)
        rho = np.linalg.norm(r, axis=1)
        return rho - self.radius_mm, r / rho[:, None]

    def linearised(self, u: np.ndarray, d: float) -> GapSet:
        """The gap linearised at state u (exact gap at u), for indenter travel d."""
        g, n = self._normal(u, d)
        G = _gap_matrix(self.mesh, self.mesh.outer_faces, self.N, n.reshape(self._shape), 1.0)
        return GapSet(g - G @ u, G, self.weight, self.points)

    def force(self, u: np.ndarray, d: float, penalty: float) -> float:
        """Reaction on the indenter along its travel (+ = the skin pushes it up), modelled part."""
        g, n = self._normal(u, d)
        return float(penalty * (self.weight * np.maximum(-g, 0.0) * -n[:, 1]).sum())


class PocketContact:
    """The closing pocket: the floor and the pocket's side wall against the roof.

    Large sliding, node-to-surface at Gauss points, one pass: each Gauss point ``x_s`` of the
    floor and of the side wall (the slave faces) is projected on the current roof underside
    (the master): ``x_m``, the closest point of its quadratic faces that hold one of the two
    roof nodes nearest ``x_s`` (Gauss-Newton in each, held inside it; a search by node follows
    a point however far it slides, where a window of faces around the one it faced at rest
    missed a 1.5 mm slide). Its gap is ``g = (x_s - x_m) . n``, ``n`` the roof's unit
    normal there pointing into the pocket (beyond a face's edge, the unit vector from ``x_m``
    to ``x_s``: the gap is then the distance, continuous across the edge). Linearised as
    `RoundGaps` is, ``G = n^T (N_s - N_m)`` with the projection held (the curvature terms
    dropped); `softhand.fem.solver` holds one linearisation through a Newton pass and projects
    again at its solution. Each row of ``G`` couples the slave face's dofs with those of the
    roof face it projects on; the compiled engine's pattern follows it
    (`softhand.fem.linear.TangentSystem.set_contact`).

    Why not the pairing by surface coordinates this replaced (roof and floor points at the same
    place on their faces, the gap along the floor's normal at rest): under a plate the roof
    flattens and spreads sideways while the floor keeps its dome, so the point the roof meets
    is no longer the one it faced at rest. Paired that way, the floor of pocket2-sil passes
    through the flattened roof by 0.12 mm at 2 N and 0.67 mm at 20 N (2D, default mesh) while
    every paired gap stays above -0.004 mm, and the side wall, which has no contact there,
    folds through the roof at the pocket's corner; soft designs pinch elements there until
    Newton fails at 2.8-5.0 N. Sliding, the floor stays out of the roof within 0.005 mm to
    20 N (reports/pocket-contact.md).

    The rows: the floor's Gauss points first, in `_face_geometry` order (what the pocket-floor
    sensor reads, `floor_gaps`), then the side wall's.
    """

    def __init__(self, mesh: Mesh, n_gauss: int = 4) -> None:
        dim = mesh.dim
        self.mesh, self.dim = mesh, dim
        walls = mesh.wall_faces if mesh.wall_faces is not None else np.zeros(
            (0, mesh.floor_faces.shape[1]), dtype=np.int64)
        self.slave = np.concatenate([mesh.floor_faces, walls]).astype(np.int64)
        N, pos, _, weight = _face_geometry(mesh, self.slave, n_gauss)
        self.N_s = N
        self.weight = weight.ravel()
        self.points = pos.reshape(-1, dim)
        nf, nq = pos.shape[:2]
        self.n_faces, self.nq = nf, nq
        self.n_floor_points = len(mesh.floor_faces) * nq
        roof = mesh.roof_faces
        c_roof = mesh.X[roof].mean(axis=1)
        # each roof face's normal points into the pocket: towards the floor face facing it
        facing = np.argmin(np.linalg.norm(c_roof[:, None] - mesh.X[mesh.floor_faces].mean(
            axis=1)[None], axis=-1), axis=1)
        _, t = self._surface(mesh.X[roof], np.zeros((len(roof), dim - 1)))
        n0 = self._normal(t)
        towards = mesh.X[mesh.floor_faces].mean(axis=1)[facing] - c_roof
        self.sign = np.where(np.einsum("fd,fd->f", towards, n0) < 0, -1.0, 1.0)
        self.n_dofs = mesh.n_dofs
        npf = self.slave.shape[1]
        self._row_len = 2 * npf * dim
        self._indptr = np.arange(nf * nq + 1) * self._row_len
        self._slave_cols = np.repeat(
            (self.slave[:, :, None] * dim + np.arange(dim)).reshape(nf, -1), nq, axis=0)
        self.assigned: np.ndarray | None = None  # roof face per row of the last linearisation
        # candidates: the roof faces of the two roof nodes nearest a point (a closest point
        # lies on a face of a nearby node; the faces of each node, -1 padded)
        self._roof_nodes = np.unique(roof)
        where = {a: i for i, a in enumerate(self._roof_nodes.tolist())}
        faces_of: list[list[int]] = [[] for _ in self._roof_nodes]
        for f, row in enumerate(roof):
            for a in set(row.tolist()):
                faces_of[where[a]].append(f)
        width = max(len(v) for v in faces_of)
        self._node_faces = np.array([v + [-1] * (width - len(v)) for v in faces_of])

    @staticmethod
    def _shape(xi: np.ndarray):
        """Shape functions and their derivatives of a quadratic face at local ``xi``
        (..., dim - 1), nodes in `softhand.fem.elements.reference_element` order."""
        from softhand.fem.elements import lagrange_1d

        N1, dN1 = lagrange_1d(xi[..., 0])
        if xi.shape[-1] == 1:
            return N1, dN1[..., None]
        N2, dN2 = lagrange_1d(xi[..., 1])
        N = (N2[..., :, None] * N1[..., None, :]).reshape(*xi.shape[:-1], 9)
        d1 = (N2[..., :, None] * dN1[..., None, :]).reshape(*xi.shape[:-1], 9)
        d2 = (dN2[..., :, None] * N1[..., None, :]).reshape(*xi.shape[:-1], 9)
        return N, np.stack([d1, d2], axis=-1)

    def _surface(self, xf: np.ndarray, xi: np.ndarray):
        """Point and tangents of faces with nodes ``xf`` (..., npf, dim) at ``xi``."""
        N, dN = self._shape(xi)
        return np.einsum("...a,...ad->...d", N, xf), np.einsum("...aj,...ad->...dj", dN, xf)

    def _normal(self, t: np.ndarray) -> np.ndarray:
        n = (np.stack([t[..., 1, 0], -t[..., 0, 0]], axis=-1) if self.dim == 2
             else np.cross(t[..., 0], t[..., 1]))
        return n / np.linalg.norm(n, axis=-1, keepdims=True)

    def project(self, u: np.ndarray):
        """Per row: the slave point, the roof face it projects on, the local coordinates there,
        the closest point and the unit gap direction (module docstring)."""
        dim, nf, nq = self.dim, self.n_faces, self.nq
        x = self.mesh.X + u.reshape(-1, dim)
        xs = np.einsum("qa,fad->fqd", self.N_s, x[self.slave])  # (nf, nq, dim)
        roof = self.mesh.roof_faces
        xn = x[self._roof_nodes]
        d2 = ((xs[:, :, None, :] - xn[None, None]) ** 2).sum(axis=-1)
        near = np.argpartition(d2, 1, axis=-1)[..., :2]  # the two nearest roof nodes
        cand = self._node_faces[near].reshape(nf, nq, -1)  # (nf, nq, C), -1 padded
        valid = cand >= 0
        cand = np.where(valid, cand, cand[..., :1])
        C = cand.shape[-1]
        xr = x[roof[cand]]  # (nf, nq, C, npf, dim)
        target = np.broadcast_to(xs[:, :, None, :], (nf, nq, C, dim))
        xi = np.zeros((nf, nq, C, dim - 1))
        for _ in range(8):  # Gauss-Newton on |x(xi) - x_s|^2, held inside the face
            p, t = self._surface(xr, xi)
            g = np.einsum("...d,...dj->...j", p - target, t)
            H = np.einsum("...dj,...dk->...jk", t, t)
            xi = np.clip(xi - np.linalg.solve(H, g[..., None])[..., 0], -1.0, 1.0)
        p, t = self._surface(xr, xi)
        dist = np.where(valid, np.linalg.norm(p - target, axis=-1), np.inf)
        best = np.argmin(dist, axis=-1)  # (nf, nq) candidate

        def take(a: np.ndarray) -> np.ndarray:
            return np.take_along_axis(a, best.reshape(nf, nq, 1, *([1] * (a.ndim - 3))),
                                      axis=2)[:, :, 0]

        xi_b, p_b, t_b = take(xi), take(p), take(t)
        face = np.take_along_axis(cand, best[..., None], axis=2)[..., 0]  # (nf, nq) roof face
        n = self._normal(t_b) * self.sign[face][..., None]
        v = xs - p_b
        length = np.linalg.norm(v, axis=-1, keepdims=True)
        side = np.where(np.einsum("fqd,fqd->fq", v, n) < 0, -1.0, 1.0)[..., None]
        n = np.where(length > 1e-9, side * v / np.maximum(length, 1e-300), n)
        return xs, face, xi_b, p_b, n

    def linearised(self, u: np.ndarray) -> GapSet:
        """The gaps at state ``u`` (exact) and their linearisation, as a `GapSet`; sets
        `assigned`."""
        dim = self.dim
        xs, face, xi, p, n = self.project(u)
        g = np.einsum("fqd,fqd->fq", xs - p, n).ravel()
        Nm, _ = self._shape(xi)  # (nf, nq, npf)
        nflat = n.reshape(-1, dim)
        slave = (np.broadcast_to(self.N_s[None], Nm.shape)[..., None]
                 * n[:, :, None, :]).reshape(len(nflat), -1)
        master = -(Nm[..., None] * n[:, :, None, :]).reshape(len(nflat), -1)
        roof = self.mesh.roof_faces[face.ravel()]  # (rows, npf)
        roof_cols = (roof[:, :, None] * dim + np.arange(dim)).reshape(len(nflat), -1)
        indices = np.concatenate([self._slave_cols, roof_cols], axis=1).ravel()
        data = np.concatenate([slave, master], axis=1).ravel()
        G = sp.csr_matrix((data, indices, self._indptr), shape=(len(nflat), self.n_dofs))
        self.assigned = face.ravel().copy()
        return GapSet(g - G @ u, G, self.weight, self.points)

    def gaps(self, u: np.ndarray) -> np.ndarray:
        """The gap at each row's point at state ``u`` (mm)."""
        xs, _, _, p, n = self.project(u)
        return np.einsum("fqd,fqd->fq", xs - p, n).ravel()

    def floor_gaps(self, u: np.ndarray) -> np.ndarray:
        """The gaps at the floor's Gauss points (the pocket-floor sensor's rows)."""
        return self.gaps(u)[:self.n_floor_points]


def pocket_gaps(mesh: Mesh, n_gauss: int = 4) -> GapSet | None:
    """Gap between the pocket roof and floor along the floor's reference normal, or None:
    each floor Gauss point paired with the roof point at the same place on its face (small
    sliding; `PairedPocket`)."""
    if mesh.floor_faces.size == 0:
        return None
    N, pos_f, normal, weight = _face_geometry(mesh, mesh.floor_faces, n_gauss)
    pos_r = np.einsum("qn,fnd->fqd", N, mesh.X[mesh.roof_faces])
    gap0 = np.einsum("fqd,fqd->fq", pos_r - pos_f, normal)
    flip = np.where(gap0 < 0, -1.0, 1.0)
    normal = normal * flip[..., None]
    gap0 = gap0 * flip
    G = (_gap_matrix(mesh, mesh.roof_faces, N, normal, 1.0)
         + _gap_matrix(mesh, mesh.floor_faces, N, normal, -1.0))
    return GapSet(gap0.ravel(), G.tocsr(), weight.ravel())


class PairedPocket:
    """The pocket's contact of the shipped FE curves: each floor Gauss point against the roof
    point at the same place on its face, the gap along the floor's normal at rest
    (`pocket_gaps`; linear in u, one `GapSet` for the run). Right while the roof closes onto
    the floor without sliding along it; under a plate it does slide, and the floor's dome
    passes through the flattened roof (`PocketContact`'s docstring has the numbers)."""

    assigned = None  # one structure for the run

    def __init__(self, gaps: GapSet) -> None:
        self._gaps = gaps
        self.n_floor_points = gaps.size

    def linearised(self, u: np.ndarray) -> GapSet:
        return self._gaps

    def gaps(self, u: np.ndarray) -> np.ndarray:
        return self._gaps.gaps(u)

    floor_gaps = gaps


def floor_through_roof_mm(mesh: Mesh, u: np.ndarray, samples: int = 41) -> float:
    """How far the pocket's floor lies inside the roof at state ``u`` (mm; 0: it does not),
    from the geometry alone (2D): the floor's curve against the roof's, both sampled at
    ``samples`` points a face, the floor's height above the roof's along y where they overlap
    across. Independent of either contact's gap function, so that it can judge both."""
    if mesh.dim != 2:
        raise ValueError(f"mesh.dim = {mesh.dim}: the check is 2D (allowed: 2)")
    from softhand.fem.elements import lagrange_1d

    N, _ = lagrange_1d(np.linspace(-1.0, 1.0, samples))
    x = mesh.X + u.reshape(-1, 2)
    roof = np.einsum("qa,fad->fqd", N, x[mesh.roof_faces]).reshape(-1, 2)
    floor = np.einsum("qa,fad->fqd", N, x[mesh.floor_faces]).reshape(-1, 2)
    order = np.argsort(roof[:, 0])
    across = (floor[:, 0] >= roof[order, 0].min()) & (floor[:, 0] <= roof[order, 0].max())
    if not across.any():
        return 0.0
    y_roof = np.interp(floor[across, 0], roof[order, 0], roof[order, 1])
    return float(max(0.0, (floor[across, 1] - y_roof).max()))


#: The pocket contacts `pocket_contact` builds (`IndentationSettings.pocket_contact`).
POCKET_CONTACTS = ("paired", "sliding")


def pocket_contact(mesh: Mesh, n_gauss: int = 4, kind: str = "paired"
                   ) -> PairedPocket | PocketContact | None:
    """The pocket's contact, ``kind`` one of `POCKET_CONTACTS` (``paired``: `PairedPocket`;
    ``sliding``: `PocketContact`), or None for a mesh without a pocket."""
    if kind not in POCKET_CONTACTS:
        raise ValueError(f"pocket_contact = {kind!r}: allowed {', '.join(POCKET_CONTACTS)}")
    if mesh.floor_faces.size == 0:
        return None
    if kind == "paired":
        return PairedPocket(pocket_gaps(mesh, n_gauss))
    return PocketContact(mesh, n_gauss)
