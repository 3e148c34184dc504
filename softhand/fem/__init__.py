"""Stage 1: finite-element indentation of synthetic finger phalanges (paper, Methods: FE).

Public entry points: `indent` for one design, `run_sweep` for many, and the
materials, geometry and mesh building blocks they use.
"""

from softhand.fem.geometry import DESIGNS, Design, PhalanxGeometry, parse_design
from softhand.fem.materials import Hyperfoam, Material, Prony, material
from softhand.fem.solver import (
    ConvergenceError,
    IndentationResult,
    IndentationSettings,
    indent,
)

__all__ = [
    "DESIGNS",
    "ConvergenceError",
    "Design",
    "Hyperfoam",
    "IndentationResult",
    "IndentationSettings",
    "Material",
    "PhalanxGeometry",
    "Prony",
    "indent",
    "material",
    "parse_design",
]
