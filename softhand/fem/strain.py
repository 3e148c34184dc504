"""Strains at the peak of an indentation: how close each layer comes to tearing.

From the displacements at the end of the ramp (`IndentationResult.ramp_end_u`, the largest force
reached), the deformation gradient at every Gauss point (`Assembler.deformation_gradient`) gives
the principal stretches, the square roots of the eigenvalues of C = F^T F. Per layer (the inner
part and the outer layer) the peak **maximum principal nominal strain** ``lambda_max - 1`` is
compared with its material's elongation at break (a uniaxial-tension datasheet value, in the
same measure): the *usage* ``strain / elongation at break`` is 1 where a uniaxial specimen would
break. A multiaxial state breaks at another strain, and the closed pocket's ends are crack-like
slit tips whose peak strain grows with mesh refinement: the usage ranks designs on one mesh, it
does not predict the cycles to failure.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from softhand.fem.assembly import Assembler
from softhand.fem.geometry import Design
from softhand.fem.materials import material
from softhand.fem.mesh import build_mesh
from softhand.fem.solver import IndentationResult

__all__ = ["LAYERS", "LayerStrain", "peak_strains"]

LAYERS = ("inner", "outer")


@dataclass(frozen=True)
class LayerStrain:
    """The peak strain of one layer at the end of the ramp.

    Attributes:
        layer: ``inner`` or ``outer``.
        max_principal_strain: largest ``lambda_max - 1`` over the layer's Gauss points.
        min_principal_strain: smallest ``lambda_min - 1`` (compression, negative).
        at_mm: reference (x, y) position of the element centre holding the peak (mm; x across
            the width, y up from the bone).
    """

    layer: str
    max_principal_strain: float
    min_principal_strain: float
    at_mm: tuple[float, float]

    def to_dict(self) -> dict:
        return {"layer": self.layer, "max_principal_strain": self.max_principal_strain,
                "min_principal_strain": self.min_principal_strain, "at_mm": list(self.at_mm)}


def peak_strains(result: IndentationResult, design: Design | None = None) -> dict[str, LayerStrain]:
    """Per layer, the peak principal strains of ``result`` at its largest force.

    Args:
        result: a phalanx run (its design's mesh is rebuilt from its settings).
        design: the design the run indented (default: parsed from ``result.design``).

    Raises:
        ValueError: the run kept no displacements (no ramp step) or ran on another body.
    """
    from softhand.fem.geometry import parse_design

    if result.ramp_end_u is None:
        raise ValueError(f"{result.design}: the run has no ramp step, so no peak strain")
    s = result.settings
    if s.body != "phalanx":
        raise ValueError(f"body = {s.body!r}: peak strains are read on the phalanx only")
    design = design or parse_design(result.design)
    geom = design.geometry(**s.geometry)
    mesh = build_mesh(geom, s.mesh_spec, dim=3 if s.mode == "3d" else 2)
    if mesh.n_dofs != result.ramp_end_u.size:
        raise ValueError(f"{result.design}: {result.ramp_end_u.size} displacements for a mesh of "
                         f"{mesh.n_dofs} DOFs (a full-model run?)")
    dummy = material("sil", elastic_only=True)  # F needs only the mesh
    asm = Assembler(mesh, [dummy, dummy], threads=1, engine="numpy")
    try:
        F = asm.deformation_gradient(result.ramp_end_u)  # (ne, nq, 3, 3)
    finally:
        asm.close()
    C = np.einsum("enki,enkj->enij", F, F)
    stretch = np.sqrt(np.linalg.eigvalsh(C))  # ascending
    emax, emin = stretch[..., -1].max(axis=1) - 1.0, stretch[..., 0].min(axis=1) - 1.0
    centres = mesh.X[mesh.elements].mean(axis=1)
    out = {}
    for k, name in enumerate(LAYERS):
        sel = np.flatnonzero(mesh.layer == k)
        if sel.size == 0:
            continue
        top = sel[int(np.argmax(emax[sel]))]
        out[name] = LayerStrain(name, float(emax[top]), float(emin[sel].min()),
                                (float(centres[top, 0]), float(centres[top, 1])))
    return out
