"""The local geometry of a contact, read from its two geoms at the contact point, not from names.

A pair's law is chosen once, from its two geoms' types (`softhand.skin.contact_classes.classify`:
a round skin geom is a phalanx, a mesh a palm; a round counterpart up to
`FINGER_MAX_RADIUS_MM` presses like a finger, anything else like a flat). Where a contact lies
decides what it really is: a finger on a convex palm mesh presses its flat palmar face or the
rounded border between that face and the back, and two capsules cross at any angle, while the
FE's finger classes are a cylinder across the phalanx (90 deg). So each contact is classified by
the shapes at its point (issue 36):

* a capsule or cylinder: ``round``, its radius and its axis; a sphere: ``round`` without an axis;
  an ellipsoid: ``round`` with its smallest semi-axis and the axis of its largest;
* a mesh (MuJoCo collides a mesh as its convex hull, so the hull is what presses): ``face`` where
  the normals of the hull's faces near the point agree within `FACE_DEG` (a flat patch: the faces
  within `WINDOW_MM` of the point, and the face the point lies under), else
  ``border``: a rounded edge, its radius estimated as the arc of 2 x `WINDOW_MM` over the
  normals' spread and its axis the edge's direction (the cross product of the two normals that
  differ most), read at the centre of the point's `CELL_MM` cube of the geom's frame (once per
  cube: a contact moves little between frames). The audit that filed issue 36 used the same test
  (normals within 6 mm agreeing within 15 deg);
* a box or a plane: ``face``.

`contact_class` names the class of a law's body pressed by its counterpart, with the crossing
angle of two axes (0 deg: parallel, 90: across). `law_fits` says whether a law was made for that
class: the law's body and counterpart must be the contact's, and a finger law (the FE's cylinder
at its class's crossing angle: 90 deg across a phalanx, 90, 60 or 30 deg across a border,
`softhand.skin.contact_classes.BORDER_CROSSINGS_DEG`) counts within `CROSSING_TOLERANCE_DEG` of
its angle (the accounting's crossing bins by their centres). A rounded palm border has the
``border/finger`` laws (`softhand.skin.contact_classes`: the FE's stand-in of a 12.5 mm
border). A rounded border that presses the partner's tissue is a finger-like counterpart where
its radius is a finger class's (up to `FINGER_MAX_RADIUS_MM`, as for a round geom: the
tissue's finger law, a 9 mm cylinder across the phalanx, was made for it), a border of its own
beyond (no law: the accounting says so).

Units: MuJoCo's (m) in, mm and deg out.
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np

from softhand.skin.contact_classes import (
    FINGER_MAX_RADIUS_MM,
    border_class,
    class_parts,
    classify,
    partner_tissue_class,
)

__all__ = ["BORDER_REACH_M", "CELL_MM", "CROSSING_BIN_DEG", "CROSSING_TOLERANCE_DEG", "FACE_DEG",
           "FINGER_BORDER", "WINDOW_MM", "LocalGeometry", "LocalShape", "border_contact",
           "contact_class", "crossing_bin", "crossing_deg", "geometry_accounting", "law_classes",
           "law_fits", "pair_class", "palm_border_share_pct", "state_class", "surface_point"]

#: the neighbourhood of a contact point whose hull faces decide face or border (mm)
WINDOW_MM = 6.0
#: largest angle between those faces' normals of a flat face (deg)
FACE_DEG = 15.0
#: a finger law (the FE's cylinder at its class's crossing angle) counts for crossings within
#: this of its angle (deg): half the spacing of the border's laws
CROSSING_TOLERANCE_DEG = 15.0
#: the crossing angle's bins in the accounting (deg)
CROSSING_BIN_DEG = 15.0
#: the counterpart a rounded border of a finger's radius (up to `FINGER_MAX_RADIUS_MM`) is: a
#: finger law fits it (the prosthetic palm's border pressing the partner's phalanx is a cylinder
#: of 8-23 mm, p10-p90, across it, as the FE's 9 mm finger)
FINGER_BORDER = "finger-sized border"
#: a mesh's shape is read at the centre of the point's cube of this edge in the geom's frame and
#: kept for that cube (mm): a sixth of `WINDOW_MM`
CELL_MM = 1.0
#: a counterpart this close to a palm's skin at the state a pair's class is read at (m; the
#: handshake's grasp, or a keyframe of `softhand skin apply`) is placed where it is nearest:
#: the grasp presses the hands 0.5-1.5 mm into each other, and a finger a few millimetres off the
#: palm there meets it where it is nearest once the grip closes. The fingertips lie 5-14 mm off
#: the palm at the grasp (default hands) and keep the palm/finger law, though they close onto the
#: border (12 % of the default run's force). A 30 mm reach gives them the border's law (89 % of
#: the force through it, seeds 0-2), but the softer fingertips let the palms part 1.4 mm at
#: mid-shake (the load-path criterion is 1 mm) and the grip of a 216 x 73 mm partner miss its
#: target by 25 % (95th percentile; criterion 15 %): kept at 5 mm until the fingertips' contact is
#: understood
BORDER_REACH_M = 0.005

_CAPSULE = int(mujoco.mjtGeom.mjGEOM_CAPSULE)
_CYLINDER = int(mujoco.mjtGeom.mjGEOM_CYLINDER)
_SPHERE = int(mujoco.mjtGeom.mjGEOM_SPHERE)
_ELLIPSOID = int(mujoco.mjtGeom.mjGEOM_ELLIPSOID)
_MESH = int(mujoco.mjtGeom.mjGEOM_MESH)


class LocalShape(NamedTuple):
    """A geom's shape at a contact point.

    Attributes:
        kind: ``round``, ``face`` or ``border`` (module docstring).
        radius_mm: a round geom's or a border's radius (None for a face).
        axis: unit axis in the world (a capsule's, a border's edge), or None.
    """

    kind: str
    radius_mm: float | None
    axis: np.ndarray | None


class _Hull:
    """A mesh geom's faces in its own frame: vertices, triangles, outward unit normals and plane
    offsets (n . x = offset on the face)."""

    def __init__(self, model: mujoco.MjModel, geom: int) -> None:
        mesh = int(model.geom_dataid[geom])
        v0, nv = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
        f0, nf = int(model.mesh_faceadr[mesh]), int(model.mesh_facenum[mesh])
        self.vert = np.array(model.mesh_vert[v0:v0 + nv], dtype=float)
        self.face = np.array(model.mesh_face[f0:f0 + nf], dtype=int)
        a, b, c = (self.vert[self.face[:, i]] for i in range(3))
        n = np.cross(b - a, c - a)
        keep = np.linalg.norm(n, axis=1) > 1e-18
        self.face, n, a = self.face[keep], n[keep], a[keep]
        n /= np.linalg.norm(n, axis=1)[:, None]
        centre = self.vert.mean(axis=0)
        n *= np.where(np.einsum("ij,ij->i", n, a - centre) < 0.0, -1.0, 1.0)[:, None]
        self.normal = n
        self.offset = np.einsum("ij,ij->i", n, a)
        tri = np.stack([self.vert[self.face[:, i]] for i in range(3)], axis=1)  # (F, 3, 3)
        self._tri = tri
        self._edges = np.roll(tri, -1, axis=1) - tri
        self._inward = np.cross(self.normal[:, None, :], self._edges)
        self._edge2 = np.maximum((self._edges ** 2).sum(axis=2), 1e-30)
        self._centroid = tri.mean(axis=1)
        self._reach = np.linalg.norm(tri - self._centroid[:, None, :], axis=2).max(axis=1)
        self._cells: dict[tuple[int, int, int], tuple] = {}

    def cell(self, index: tuple[int, int, int]) -> tuple[str, float | None, np.ndarray | None]:
        """`shape_at` the centre of the `CELL_MM` cell ``index`` of the geom's frame, kept."""
        found = self._cells.get(index)
        if found is None:
            found = self._cells[index] = self.shape_at(np.array(index, dtype=float)
                                                       * (1e-3 * CELL_MM))
        return found

    def shape_at(self, p: np.ndarray) -> tuple[str, float | None, np.ndarray | None]:
        """(kind, radius mm, axis in the geom's frame) at ``p`` (the geom's frame, m)."""
        under = int(np.argmax(self.normal @ p - self.offset))  # the face it lies under
        normals = self.normal[np.append(self.within(p, 1e-3 * WINDOW_MM), under)]
        dots = np.clip(normals @ normals.T, -1.0, 1.0)
        i, j = np.unravel_index(int(np.argmin(dots)), dots.shape)
        spread = float(np.arccos(dots[i, j]))
        if np.degrees(spread) <= FACE_DEG:
            return "face", None, None
        edge = np.cross(normals[i], normals[j])
        return "border", 2.0 * WINDOW_MM / spread, edge / np.linalg.norm(edge)

    def within(self, p: np.ndarray, radius: float) -> np.ndarray:
        """The faces (indices) within ``radius`` (m) of ``p`` (the geom's frame)."""
        cand = np.flatnonzero(np.linalg.norm(self._centroid - p, axis=1)
                              <= radius + self._reach)
        tri, edges = self._tri[cand], self._edges[cand]
        rel = p - tri
        # inside the triangle's prism: the distance to its plane; outside: to its nearest edge
        inside = ((self._inward[cand] * rel).sum(axis=2) >= 0.0).all(axis=1)
        plane = np.abs(self.normal[cand] @ p - self.offset[cand])
        t = np.clip((rel * edges).sum(axis=2) / self._edge2[cand], 0.0, 1.0)
        seg = np.linalg.norm(rel - t[..., None] * edges, axis=2).min(axis=1)
        return cand[np.where(inside, plane, seg) <= radius]


#: the hulls read so far, by their vertices and faces, with the cells classified on them: a
#: population's worlds and an env's episodes share the same palm (a few hundred cells an
#: episode, each a hull query); at most `_HULLS_KEPT` hulls are kept
_HULLS: dict[bytes, _Hull] = {}
_HULLS_KEPT = 256


def _hull(model: mujoco.MjModel, geom: int) -> _Hull:
    mesh = int(model.geom_dataid[geom])
    v0, nv = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
    f0, nf = int(model.mesh_faceadr[mesh]), int(model.mesh_facenum[mesh])
    key = (model.mesh_vert[v0:v0 + nv].tobytes() + model.mesh_face[f0:f0 + nf].tobytes()
           + repr((CELL_MM, WINDOW_MM, FACE_DEG)).encode())
    hull = _HULLS.get(key)
    if hull is None:
        if len(_HULLS) >= _HULLS_KEPT:
            _HULLS.pop(next(iter(_HULLS)))
        hull = _HULLS[key] = _Hull(model, geom)
    return hull


class LocalGeometry:
    """`LocalShape` of any geom of ``model`` at a point (the meshes' hulls read once).

    Each geom's kind and radius are read from the model once; a call costs a few microseconds
    (a handshake classifies about 10 000 contact sides), a mesh's new cell a hull query."""

    def __init__(self, model: mujoco.MjModel) -> None:
        self.model = model
        self._hulls: dict[int, _Hull] = {}
        # per geom: (kind, radius mm, the column of geom_xmat of its axis, or -1 for none)
        self._kinds: list[tuple[str, float | None, int]] = []
        for g in range(model.ngeom):
            kind, size = int(model.geom_type[g]), model.geom_size[g]
            if kind in (_CAPSULE, _CYLINDER):
                self._kinds.append(("round", 1e3 * float(size[0]), 2))
            elif kind == _SPHERE:
                self._kinds.append(("round", 1e3 * float(size[0]), -1))
            elif kind == _ELLIPSOID:
                self._kinds.append(("round", 1e3 * float(size[:3].min()),
                                    int(np.argmax(size[:3]))))
            else:
                self._kinds.append(("mesh" if kind == _MESH else "face", None, -1))

    def shape(self, data: mujoco.MjData, geom: int, point) -> LocalShape:
        """The shape of ``geom`` at ``point`` (world, m), e.g. a contact's ``pos``."""
        kind, radius, column = self._kinds[geom]
        if kind == "round":
            if column < 0:
                return LocalShape("round", radius, None)
            x = data.geom_xmat[geom]
            return LocalShape("round", radius, np.array((x[column], x[column + 3],
                                                         x[column + 6])))
        if kind == "face":
            return LocalShape("face", None, None)
        # the shape at the centre of the point's CELL_MM cell of the geom's frame, kept per
        # cell: a contact moves little between frames, and the answer depends on the cell alone
        x = data.geom_xmat[geom].tolist()
        c = data.geom_xpos[geom].tolist()
        p = point.tolist() if isinstance(point, np.ndarray) else list(point)
        dx, dy, dz = p[0] - c[0], p[1] - c[1], p[2] - c[2]
        scale = 1.0 / (1e-3 * CELL_MM)
        hull = self._hulls.get(geom)
        if hull is None:
            hull = self._hulls[geom] = _hull(self.model, geom)
        kind, radius, axis = hull.cell((round((x[0] * dx + x[3] * dy + x[6] * dz) * scale),
                                        round((x[1] * dx + x[4] * dy + x[7] * dz) * scale),
                                        round((x[2] * dx + x[5] * dy + x[8] * dz) * scale)))
        if axis is None:
            return LocalShape(kind, radius, None)
        return LocalShape(kind, radius, data.geom_xmat[geom].reshape(3, 3) @ axis)


def border_contact(model: mujoco.MjModel, data: mujoco.MjData, skin_geom: int, other_geom: int,
                   *, local: LocalGeometry | None = None
                   ) -> tuple[LocalShape, LocalShape] | None:
    """Where a skin geom of class ``palm/finger`` (`softhand.skin.contact_classes.classify`)
    and its finger lie, at the state in ``data`` (its kinematics computed), within
    `BORDER_REACH_M` and nearest where the palm's surface is a rounded border (`LocalGeometry`:
    the hull's normals within `WINDOW_MM` spread over `FACE_DEG`): (the palm's shape there, the
    finger's at its nearest point; their `crossing_deg` is the crossing); None for any other
    pair or state. ``local``: a `LocalGeometry` of ``model`` to reuse (its hulls read once)."""
    if classify(model, skin_geom, other_geom) != "palm/finger":
        return None
    fromto = np.zeros(6)
    dist = mujoco.mj_geomDistance(model, data, skin_geom, other_geom, BORDER_REACH_M, fromto)
    if dist >= BORDER_REACH_M:
        return None
    local = local or LocalGeometry(model)
    palm = local.shape(data, skin_geom, fromto[:3])
    if palm.kind != "border":
        return None
    return palm, local.shape(data, other_geom, fromto[3:])


def state_class(model: mujoco.MjModel, data: mujoco.MjData, skin_geom: int, other_geom: int,
                *, local: LocalGeometry | None = None) -> str:
    """The contact class (`softhand.skin.contact_classes.CLASSES`) of a skin geom and the geom
    that presses it, at the state in ``data``: their types' class
    (`softhand.skin.contact_classes.classify`), but where the finger lies on the palm's rounded
    border at this state (`border_contact`), the border class of its crossing there
    (`border_class`: ``border/finger`` across or where an axis is missing, ``border/finger@A``
    oblique).

    The one path from a pair's geometry to its class: the handshake's scene reads it at the
    grasp (`softhand.envs.skins.border_pairs`), ``softhand skin apply`` at the model's qpos0 or
    a keyframe. ``local``: a `LocalGeometry` of ``model`` to reuse."""
    on = border_contact(model, data, skin_geom, other_geom, local=local)
    if on is None:
        return classify(model, skin_geom, other_geom)
    return border_class(crossing_deg(*on))


def crossing_deg(a: LocalShape, b: LocalShape) -> float | None:
    """The angle between two shapes' axes, 0 (parallel) to 90 deg (across); None without both."""
    if a.axis is None or b.axis is None:
        return None
    return float(np.degrees(np.arccos(min(1.0, abs(float(a.axis @ b.axis))))))


def _body(s: LocalShape) -> str:
    return "phalanx" if s.kind == "round" else "palm face" if s.kind == "face" else "palm border"


def _counterpart(s: LocalShape) -> str:
    if s.kind == "round":
        return "finger" if s.radius_mm <= FINGER_MAX_RADIUS_MM else "flat"
    if s.kind == "face":
        return "flat"
    # a rounded border presses like a finger where it is no rounder than a finger's class
    # allows a round geom to be (its radius up to FINGER_MAX_RADIUS_MM), like a flat-ish edge
    # otherwise
    return FINGER_BORDER if s.radius_mm <= FINGER_MAX_RADIUS_MM else "border"


def contact_class(body: LocalShape, counterpart: LocalShape) -> tuple[str, str, float | None]:
    """(body, counterpart, crossing) of a law's body pressed by ``counterpart``: body
    ``phalanx``, ``palm face`` or ``palm border``; counterpart ``finger``, ``flat``,
    `FINGER_BORDER` (a rounded border up to `FINGER_MAX_RADIUS_MM`) or ``border`` (a rounder
    one); the crossing angle (deg) where both have an axis."""
    return _body(body), _counterpart(counterpart), crossing_deg(body, counterpart)


def pair_class(skin: LocalShape, other: LocalShape) -> tuple[str, str, str, str, int]:
    """Both sides of a contact, the key of `geometry_accounting`: (the skin's body, its
    counterpart, the tissue's body, its counterpart, their crossing bin)."""
    body, counterpart, crossing = contact_class(skin, other)
    return body, counterpart, _body(other), _counterpart(skin), crossing_bin(crossing)


def surface_point(contact, geom: int) -> np.ndarray:
    """Where ``geom``'s own surface is at a MuJoCo contact (world, m): the contact point is the
    midpoint of the two surfaces, and the normal points from geom1 into geom2, so geom1's
    surface lies half the depth along it and geom2's half the depth against it."""
    half = 0.5 * max(-float(contact.dist), 0.0) * contact.frame[:3]
    return contact.pos + half if geom == contact.geom1 else contact.pos - half


def law_classes(label: str) -> tuple[str, str]:
    """The classes (`softhand.skin.contact_classes.CLASSES`) of the skin's law and of the
    tissue's law in a pair that carries ``label`` (`softhand.envs.skins.PairChoice.law`): a
    class law and the tissue's law for what the skin's body presses it with; the plate law
    (``plate``, ``plate (no ... law)``, ``plate pad``) and the tissue's plate law; ``tissue``
    (a rigid region): the tissue's plate law on both sides of the account."""
    if label.split("/")[0] in ("phalanx", "palm", "border"):
        return label, partner_tissue_class(label)
    return "phalanx/flat", "phalanx/flat"


def law_fits(law: str, body: str, counterpart: str, crossing: float | None) -> bool:
    """Whether a law of class ``law`` (``phalanx/finger``...) was made for a contact of
    `contact_class` (body, counterpart, crossing): the same body (``palm`` is a palm face) and
    counterpart, and a finger on a phalanx or a border within `CROSSING_TOLERANCE_DEG` of the
    law's crossing angle (`softhand.skin.contact_classes.class_parts`)."""
    law_body, law_counterpart, law_crossing = class_parts(law)
    if body != {"phalanx": "phalanx", "palm": "palm face", "border": "palm border"}[law_body]:
        return False
    if counterpart != law_counterpart and not (law_counterpart == "finger"
                                               and counterpart == FINGER_BORDER):
        return False
    if law_crossing is not None and law_body != "palm" and crossing is not None:
        return abs(crossing - law_crossing) <= CROSSING_TOLERANCE_DEG
    return True


def crossing_bin(crossing: float | None) -> int:
    """The `CROSSING_BIN_DEG` bin of a crossing angle (0: 0-15 deg, ...), -1 for none."""
    if crossing is None:
        return -1
    return min(int(crossing // CROSSING_BIN_DEG), round(90.0 / CROSSING_BIN_DEG) - 1)


def _bin_text(b: int) -> str:
    return "" if b < 0 else f" {b * CROSSING_BIN_DEG:g}-{(b + 1) * CROSSING_BIN_DEG:g} deg"


def _fits(law: str, body: str, counterpart: str, b: int) -> bool:
    # a bin fits where its centre does (the laws' angles are bin edges: a bin is within the
    # tolerance of a law's angle whole, or not at all)
    return law_fits(law, body, counterpart, None if b < 0 else (b + 0.5) * CROSSING_BIN_DEG)


def geometry_accounting(sums: dict[tuple, float], labels: tuple[str, ...] | list[str],
                        dt: float) -> dict:
    """The force between the hands by the geometry it met and the law that carried it.

    ``sums``: (law index in ``labels``, *`pair_class`) -> normal force (N) summed over frames
    ``dt`` apart (`softhand.envs.run.ContactAreas.geometry`: each side's class as
    `contact_class` names it, the skin's pressed by the tissue's geom and the tissue's by the
    skin's, and the crossing bin both share). Returns the shares
    (%) of the force whose skin law, tissue law and both were made for the contact's class
    (`law_fits`; a relaxation pad's contact is counted whole), and per class and law its force
    (N s), share and fits, largest first.
    """
    total = sum(sums.values())
    rows: dict[tuple, dict] = {}
    own = {"skin": 0.0, "tissue": 0.0, "both": 0.0}
    for (li, body, cp, t_body, t_cp, b), f in sums.items():
        label = labels[li]
        skin_law, tissue_law = law_classes(label)
        skin_ok = _fits(skin_law, body, cp, b)
        tissue_ok = _fits(tissue_law, t_body, t_cp, b)
        own["skin"] += f * skin_ok
        own["tissue"] += f * tissue_ok
        own["both"] += f * (skin_ok and tissue_ok)
        key = (f"{cp} on {body}{_bin_text(b)}", label)
        row = rows.setdefault(key, {"contact": key[0], "law": label, "skin_law_class": skin_law,
                                    "skin_fits": skin_ok, "force_Ns": 0.0, "tissue": {}})
        row["force_Ns"] += f * dt
        tkey = f"{t_cp} on {t_body}{_bin_text(b)}"
        t = row["tissue"].setdefault(tkey, {"tissue_law_class": tissue_law,
                                            "fits": tissue_ok, "force_Ns": 0.0})
        t["force_Ns"] += f * dt
    pct = (lambda v: 100.0 * v / total) if total > 0 else (lambda v: 0.0)
    classes = sorted(rows.values(), key=lambda r: -r["force_Ns"])
    for r in classes:
        r["share_pct"] = pct(r["force_Ns"] / dt) if dt > 0 else 0.0
    return {"total_Ns": total * dt,
            "skin_own_class_share_pct": pct(own["skin"]),
            "tissue_own_class_share_pct": pct(own["tissue"]),
            "own_class_share_pct": pct(own["both"]),
            "classes": classes}


def palm_border_share_pct(accounting: dict) -> float:
    """The share (%) of a `geometry_accounting`'s force pressed into a rounded palm border."""
    return float(sum(c["share_pct"] for c in accounting["classes"]
                     if c["contact"].split(" on ")[1].startswith("palm border")))
