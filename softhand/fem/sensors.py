"""Embedded sensors in the FE phalanx: the force on a sensor patch inside the skin.

A prosthetic skin's sensors sit inside it. Three placements (`PLACEMENTS`):

- ``bone``: on the fixed base (the bone under the core): the support's reaction
- ``interface``: at the core / outer-layer interface (under the 0.8 mm outer layer): the force the
  outer layer passes to the core
- ``pocket-floor``: on the pocket's floor (pocketed designs): the roof's contact force, zero while
  the pocket is open

A patch (`SensorPatch`) is a rectangle in plan view (``width_mm`` across the finger,
``length_mm`` along it, centred at ``center_x_mm``, ``center_z_mm`` from the apex line and the
middle of the phalanx), projected onto its surface. The default, 4 x 4 mm under the indenter's
centre, is an assumption standing for one taxel of a tactile array or a small piezoresistive
force sensor (a FlexiForce A101's sensing area is about 4 mm across, a FSR 400's about 5 mm).

Reading: the vertical force (along the indentation) on the patch, positive in compression, for
the whole phalanx (the modelled quarter or half section and its mirror images). For the bone and
the interface it comes from nodal forces, which are the element's own consistent (work-conjugate)
integration of the traction: the patch's surface is cut along element faces (a face belongs to
the patch when its centroid does, with multiplicity for the mirror images), and a node's force is
shared among its faces in proportion to the integral of its shape function over each face, which
is exact for a uniform traction (the patch test) and adds up to the whole reaction for a patch
that covers the surface. For the pocket floor it is the penalty contact force at the floor's
Gauss points inside the patch. Areas are reference areas (mm^2).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from softhand.fem.contact import _face_geometry
from softhand.fem.geometry import PhalanxGeometry
from softhand.fem.mesh import Mesh
from softhand.validate import check_number

__all__ = ["PLACEMENTS", "SensorPatch", "SensorReader", "default_patches"]

PLACEMENTS = ("bone", "interface", "pocket-floor")
DEFAULT_SIZE_MM = 4.0
_TOL = 1e-9


@dataclass(frozen=True)
class SensorPatch:
    """One sensor patch (see the module docstring); ``name`` defaults to the placement."""

    placement: str
    width_mm: float = DEFAULT_SIZE_MM
    length_mm: float = DEFAULT_SIZE_MM
    center_x_mm: float = 0.0
    center_z_mm: float = 0.0
    name: str = ""

    def __post_init__(self) -> None:
        if self.placement not in PLACEMENTS:
            raise ValueError(f"sensor placement {self.placement!r} is unknown; allowed: "
                             f"{', '.join(PLACEMENTS)}")
        for key in ("width_mm", "length_mm"):
            check_number(f"sensor {self.label} {key}", getattr(self, key), lo=0.0, lo_open=True)
        for key in ("center_x_mm", "center_z_mm"):
            check_number(f"sensor {self.label} {key}", getattr(self, key))

    @property
    def label(self) -> str:
        return self.name or self.placement

    def check_fits(self, geom: PhalanxGeometry) -> None:
        """ValueError naming the patch and the allowed extent when it leaves its surface."""
        half_w = 0.5 * geom.width_mm
        if self.placement == "interface":
            half_w -= geom.outer_layer_mm
        if self.placement == "pocket-floor":
            if not geom.has_pocket:
                raise ValueError(f"sensor {self.label}: the design has no pocket (a pocket-floor "
                                 "patch needs a pocketed design)")
            half_w = geom.pocket_half_width_mm
        reach = abs(self.center_x_mm) + 0.5 * self.width_mm
        if reach > half_w + _TOL:
            where = "the pocket's floor" if self.placement == "pocket-floor" else "the part"
            raise ValueError(f"sensor {self.label}: |center_x_mm| + width_mm / 2 = {reach:g} mm "
                             f"is outside {where} (allowed up to {half_w:g} mm across)")
        reach_z = abs(self.center_z_mm) + 0.5 * self.length_mm
        if reach_z > 0.5 * geom.length_mm + _TOL:
            raise ValueError(f"sensor {self.label}: |center_z_mm| + length_mm / 2 = {reach_z:g} mm "
                             f"is outside the part (allowed up to {0.5 * geom.length_mm:g} mm "
                             "along it)")


def default_patches(geom: PhalanxGeometry) -> tuple[SensorPatch, ...]:
    """A 4 x 4 mm patch under the indenter at each placement the design has."""
    return tuple(SensorPatch(p) for p in PLACEMENTS if p != "pocket-floor" or geom.has_pocket)


def _element_faces(mesh: Mesh):
    """(element, face nodes (3^(dim-1),)) of every face of every element, face nodes ordered as
    `softhand.fem.mesh.face_element` expects (the lower local axis fastest)."""
    dim = mesh.dim
    local = [tuple(reversed(n)) for n in itertools.product(range(3), repeat=dim)]
    faces = []
    for axis in range(dim):
        for end in (0, 2):
            faces.append([a for a, p in enumerate(local) if p[axis] == end])
    for e, conn in enumerate(mesh.elements):
        for f in faces:
            yield e, conn[f]


def _mirror_multiplicity(x: np.ndarray, center: float, half: float) -> np.ndarray:
    """How many of a patch and its mirror image (about 0) cover each coordinate x >= 0."""
    return ((np.abs(x - center) <= half + _TOL).astype(float)
            + (np.abs(-x - center) <= half + _TOL).astype(float))


class SensorReader:
    """Reads each patch's force from a solved state (see the module docstring).

    Args:
        mesh: the FE mesh (2D half section or 3D quarter).
        geom: the phalanx geometry (patch extents are checked against it).
        patches: the patches; names must be unique.
        n_gauss: Gauss points per face direction (the contact's).
        penalty: the contact penalty (pocket-floor readings).
        length_mm: in 2D, the phalanx length the section's force per unit length is multiplied
            by (a patch gets min(its length, the phalanx's)).
    """

    def __init__(self, mesh: Mesh, geom: PhalanxGeometry, patches: tuple[SensorPatch, ...],
                 n_gauss: int, penalty: float) -> None:
        names = [p.label for p in patches]
        if len(set(names)) != len(names):
            raise ValueError(f"sensor names {names} are not unique: give each patch a name")
        for p in patches:
            p.check_fits(geom)
        self.mesh, self.patches, self.penalty = mesh, tuple(patches), penalty
        self.dim = mesh.dim
        self._nodal: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self._floor: dict[str, np.ndarray] = {}
        self.area_mm2: dict[str, float] = {}
        base, interface = self._surfaces()
        for p in patches:
            if p.placement == "pocket-floor":
                self._floor[p.label] = self._floor_weights(p, n_gauss)
            else:
                faces = base if p.placement == "bone" else interface
                self._nodal[p.label] = self._nodal_weights(p, faces, n_gauss)
        self._outer = np.flatnonzero(mesh.layer == 1)

    # --- set-up ----------------------------------------------------------------------------
    def _surfaces(self) -> tuple[np.ndarray, np.ndarray]:
        """Faces of the base (y = 0) and of the core / outer-layer interface (the outer-layer
        element's side)."""
        mesh = self.mesh
        y = mesh.X[:, 1]
        base, by_nodes = [], {}
        for e, nodes in _element_faces(mesh):
            if np.unique(nodes).size < nodes.size:
                continue  # a face collapsed to a line (the core's base centre): no area
            if np.all(np.abs(y[nodes]) < _TOL):
                base.append(nodes)
            by_nodes.setdefault(tuple(sorted(nodes.tolist())), []).append((e, nodes))
        interface = []
        for shared in by_nodes.values():
            layers = {int(mesh.layer[e]) for e, _ in shared}
            if len(shared) == 2 and layers == {0, 1}:
                interface.append(next(n for e, n in shared if mesh.layer[e] == 1))
        return np.array(base), np.array(interface)

    def _multiplicity(self, p: SensorPatch, pos: np.ndarray) -> np.ndarray:
        """Patch multiplicity at positions (..., dim): mirror images in x, and in z (3D)."""
        m = _mirror_multiplicity(pos[..., 0], p.center_x_mm, 0.5 * p.width_mm)
        if self.dim == 3:
            m = m * _mirror_multiplicity(pos[..., 2], p.center_z_mm, 0.5 * p.length_mm)
        else:
            m = m * min(p.length_mm, self._length())
        return m

    def _length(self) -> float:
        return float(self.mesh.length_mm)

    def _nodal_weights(self, p: SensorPatch, faces: np.ndarray, n_gauss: int):
        """Per node: the patch's share of its force (0..multiplicity)."""
        N, pos, _, w = _face_geometry(self.mesh, faces, n_gauss)
        integral = np.einsum("qa,fq->fa", N, w)  # int N_a dA per face and node
        total = np.zeros(self.mesh.X.shape[0])
        np.add.at(total, faces.ravel(), integral.ravel())
        centroid = (pos * w[..., None]).sum(axis=1) / w.sum(axis=1)[:, None]
        m = self._multiplicity(p, centroid)  # per face
        share = np.zeros(self.mesh.X.shape[0])
        np.add.at(share, faces.ravel(), (integral * m[:, None]).ravel())
        nodes = np.flatnonzero(share > 0)
        if nodes.size == 0:
            raise ValueError(f"sensor {p.label}: the patch covers no element face; make it "
                             "larger than the mesh's faces")
        self.area_mm2[p.label] = float((w.sum(axis=1) * m).sum())
        return nodes, share[nodes] / total[nodes]

    def _floor_weights(self, p: SensorPatch, n_gauss: int) -> np.ndarray:
        """Per pocket-floor Gauss point (the pocket GapSet's rows, same rule): multiplicity x
        vertical component of the floor normal x Gauss weight (mm^2)."""
        mesh = self.mesh
        _, pos, normal, w = _face_geometry(mesh, mesh.floor_faces, n_gauss)
        m = self._multiplicity(p, pos)
        if not np.any(m > 0):
            raise ValueError(f"sensor {p.label}: the patch covers no point of the pocket floor")
        self.area_mm2[p.label] = float((w * m).sum())
        return (m * np.abs(normal[..., 1]) * w).ravel()

    # --- reading ---------------------------------------------------------------------------
    def read(self, outer_force: np.ndarray, internal_force: np.ndarray,
             pocket_gaps: np.ndarray | None) -> dict[str, float]:
        """Each patch's force (N, positive in compression).

        Args:
            outer_force: internal force vector of the outer-layer elements alone (interface).
            internal_force: internal force vector of the whole mesh (the base's reactions).
            pocket_gaps: the pocket contact's gaps at its Gauss points (mm), None without one.
        """
        dim, out = self.dim, {}
        for p in self.patches:
            name = p.label
            if p.placement == "pocket-floor":
                if pocket_gaps is None:
                    out[name] = 0.0
                    continue
                pressure = self.penalty * np.maximum(-pocket_gaps, 0.0)  # N/mm^2
                out[name] = float((self._floor[name] * pressure).sum())
                continue
            nodes, share = self._nodal[name]
            f = internal_force if p.placement == "bone" else outer_force
            out[name] = float((share * f[nodes * dim + 1]).sum())
        return out

    def outer_elements(self) -> np.ndarray:
        """The outer-layer elements (their internal force makes the interface reading)."""
        return self._outer
