"""Geometric checks of a compiled hand with trimesh: how deep each bone lies under the soft layer.

``skin_cover_m`` samples points on the whole surface of every bone capsule, caps included (or on
its shaft only, ``end_m`` clear of its ends) and measures, for each point,
how far it lies inside the union of the hand's soft geoms (skin or tissue), as the largest depth
inside any one of them, the palm's pieces merged into the convex body they were cut from. Every
such body is convex, so the depth of a point inside it is its smallest distance to the planes of
its faces (trimesh's convex hull of the geom's surface; capsules are tessellated to 0.1 mm);
outside, that value is negative. A point that no soft geom covers has a negative cover. The
handshake needs every bone that can meet the other hand under skin: tests/test_hands.py bounds
the thinnest cover.
"""

from __future__ import annotations

import mujoco
import numpy as np
import trimesh

__all__ = ["geom_mesh", "skin_cover_m"]


def geom_mesh(model: mujoco.MjModel, data: mujoco.MjData, geom: int) -> trimesh.Trimesh:
    """The geom's surface as a closed triangle mesh in the world frame (capsule, sphere,
    ellipsoid, box or convex mesh)."""
    size, kind = model.geom_size[geom], model.geom_type[geom]
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        mesh = trimesh.creation.capsule(height=2 * size[1], radius=size[0], count=[24, 24])
    elif kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        mesh = trimesh.creation.icosphere(subdivisions=3, radius=size[0])
    elif kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        mesh = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
        mesh.apply_scale(size)
    elif kind == mujoco.mjtGeom.mjGEOM_BOX:
        mesh = trimesh.creation.box(extents=2 * size)
    elif kind == mujoco.mjtGeom.mjGEOM_MESH:
        m = model.geom_dataid[geom]
        start, n = model.mesh_vertadr[m], model.mesh_vertnum[m]
        mesh = trimesh.Trimesh(vertices=model.mesh_vert[start:start + n]).convex_hull
    else:
        raise ValueError(f"geom {model.geom(geom).name!r}: type {kind} is not supported")
    transform = np.eye(4)
    transform[:3, :3] = data.geom_xmat[geom].reshape(3, 3)
    transform[:3, 3] = data.geom_xpos[geom]
    mesh.apply_transform(transform)
    return mesh


def _convex_depth(mesh: trimesh.Trimesh, points: np.ndarray) -> np.ndarray:
    """Smallest distance (m) of each point to the face planes of a convex mesh, positive inside."""
    normals = mesh.face_normals  # outward
    offsets = np.einsum("ij,ij->i", normals, mesh.triangles[:, 0])
    return np.min(offsets[None, :] - points @ normals.T, axis=1)


def _convex_groups(model: mujoco.MjModel, data: mujoco.MjData, soft: list[int]
                   ) -> list[trimesh.Trimesh]:
    """The soft geoms as convex meshes, with the mesh pieces of one body merged into one hull: a
    convex body cut by planes (the palm's quarters) is the hull of its pieces' vertices."""
    by_body: dict[int, list[np.ndarray]] = {}
    out = []
    for g in soft:
        mesh = geom_mesh(model, data, g)
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
            by_body.setdefault(int(model.geom_bodyid[g]), []).append(mesh.vertices)
        else:
            out.append(mesh)
    out += [trimesh.Trimesh(vertices=np.concatenate(v)).convex_hull for v in by_body.values()]
    return out


def _shaft_points(model: mujoco.MjModel, data: mujoco.MjData, geom: int, n_along: int,
                  n_around: int, end_m: float | None) -> np.ndarray:
    """Points on the cylinder of a capsule geom (world frame), ``end_m`` clear of its ends;
    ``end_m=None``: the whole surface, its two hemispherical caps included."""
    radius, half = model.geom_size[geom][:2]
    rot = data.geom_xmat[geom].reshape(3, 3)
    reach = half if end_m is None else max(half - end_m, 0.0)
    z = np.linspace(-reach, reach, n_along)
    a = np.linspace(0.0, 2 * np.pi, n_around, endpoint=False)
    zz, aa = np.meshgrid(z, a)
    local = np.column_stack([radius * np.cos(aa.ravel()), radius * np.sin(aa.ravel()), zz.ravel()])
    if end_m is None:
        polar = np.linspace(0.0, 0.5 * np.pi, n_along // 2 + 1)[1:]  # off the equator, to the pole
        pp, aa = np.meshgrid(polar, a)
        ring = np.column_stack([radius * np.cos(pp.ravel()) * np.cos(aa.ravel()),
                                radius * np.cos(pp.ravel()) * np.sin(aa.ravel()),
                                radius * np.sin(pp.ravel())])
        caps = [ring + [0.0, 0.0, half], ring * [1.0, 1.0, -1.0] - [0.0, 0.0, half]]
        local = np.concatenate([local, *caps])
    return data.geom_xpos[geom] + local @ rot.T


def skin_cover_m(model: mujoco.MjModel, data: mujoco.MjData, bones: list[int],
                 soft: list[int], *, end_m: float | None = None, n_along: int = 9,
                 n_around: int = 16) -> dict[str, float]:
    """Thinnest soft cover (m) over each bone capsule, keyed by bone geom name (see the module
    docstring): over its whole surface, caps included (``end_m=None``), or over its shaft leaving
    out ``end_m`` at each end; negative where part of it lies outside every soft geom."""
    meshes = _convex_groups(model, data, soft)
    out = {}
    for bone in bones:
        if model.geom_type[bone] != mujoco.mjtGeom.mjGEOM_CAPSULE:
            raise ValueError(f"bone {model.geom(bone).name!r} is not a capsule")
        points = _shaft_points(model, data, bone, n_along, n_around, end_m)
        depth = np.max([_convex_depth(m, points) for m in meshes], axis=0)
        out[model.geom(bone).name] = float(depth.min())
    return out
