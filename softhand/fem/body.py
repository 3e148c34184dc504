"""Which body an FE run indents: the paper's phalanx or the palm (and back of the hand).

``body_mesh(body, design, mesh_level, dim)`` builds the body's mesh for
`softhand.fem.solver.indent` (``mesh=``). The phalanx is the mesh ``indent`` builds itself
when given none (pass none to read its embedded sensor patches or to run a crossing cylinder on
its full model); the palm is `softhand.fem.palm.palm_mesh` with its default geometry.
"""

from __future__ import annotations

from softhand.fem.geometry import Design, parse_design
from softhand.fem.indenter import parse_indenter
from softhand.fem.mesh import MESH_LEVELS, Mesh, MeshSpec, build_mesh
from softhand.fem.palm import PALM_MESH_LEVELS, PalmGeometry, PalmMeshSpec, palm_mesh

__all__ = ["BODIES", "body_mesh", "check_body"]

#: The bodies an FE run can indent.
BODIES = ("phalanx", "palm")
_LEVELS = {"phalanx": MESH_LEVELS, "palm": PALM_MESH_LEVELS}


def check_body(body: str, indenter: str = "plate") -> None:
    """Raise ValueError naming ``body`` unless it is a body that can carry ``indenter``.

    The palm is a quarter cell (symmetry planes x = 0 and z = 0) with no full model: a cylinder
    at an angle other than 0 or 90 deg is refused there.
    """
    if body not in BODIES:
        raise ValueError(f"body = {body!r}: allowed {', '.join(BODIES)}")
    ind = parse_indenter(indenter)
    if body == "palm" and ind.full_model:
        raise ValueError(f"indenter = {ind.text!r} on body 'palm': the palm is a quarter cell "
                         "(symmetry planes x = 0 and z = 0); allowed there: plate, sphere:R, "
                         "cylinder:R@0 or cylinder:R@90")


def body_mesh(body: str, design: str | Design, mesh_level: str | MeshSpec | PalmMeshSpec =
              "default", dim: int = 3, *, indenter: str = "plate") -> Mesh:
    """The mesh of ``body`` for ``design`` at ``mesh_level`` (``dim`` 3 or 2).

    ``mesh_level`` is a level name of the body (``coarse``, ``default``, ``fine``; the phalanx
    also ``uniform``) or the body's own element counts (`MeshSpec` for the phalanx,
    `PalmMeshSpec` for the palm).

    Raises:
        ValueError: an unknown body, mesh level or design, element counts of the other body, a
            bad ``dim``, or an indenter the body's model cannot carry.
    """
    check_body(body, indenter)
    levels = _LEVELS[body]
    spec_type = MeshSpec if body == "phalanx" else PalmMeshSpec
    if isinstance(mesh_level, spec_type):
        spec = mesh_level
    elif isinstance(mesh_level, str) and mesh_level in levels:
        spec = levels[mesh_level]
    else:
        raise ValueError(f"mesh_level = {mesh_level!r} for body {body!r}: allowed "
                         f"{', '.join(levels)} or a {spec_type.__name__}")
    design = parse_design(design) if isinstance(design, str) else design
    if body == "phalanx":
        if dim not in (2, 3):
            raise ValueError(f"dim = {dim!r}: allowed 2 (plane strain) or 3")
        return build_mesh(design.geometry(), spec, dim=dim)
    return palm_mesh(design, PalmGeometry(), spec, dim=dim)
