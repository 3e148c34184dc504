"""The rigid indenter of an FE run: the paper's flat plate, a cylinder or a sphere.

Written ``plate``, ``cylinder:R_MM[@ANGLE_DEG]`` or ``sphere:R_MM`` (radius R in [1, 1000] mm;
the cylinder's axis at ANGLE_DEG from the phalanx axis, default 90: across the finger). Every
indenter moves down (-y) at the run's speed, centred over the top of the phalanx (x = z = 0):
the plate's face, the cylinder's lowest line and the sphere's lowest point start at the top of
the skin.

Which models can carry which indenter (the meshes are a quarter in 3D, with symmetry planes
x = 0 and z = 0, and a half cross-section in 2D, perpendicular to the phalanx axis):

* 3D: the plate, a sphere, and a cylinder at 0 deg (along the phalanx) or 90 deg (across it)
  keep both symmetry planes and run on the quarter. A cylinder at another angle breaks them and
  runs on the full model (`softhand.fem.mesh.full_model`, 4x the elements; no embedded
  sensor patches are read there, and it is not exported to Abaqus or CalculiX decks).
* 2D (plane strain in the cross-section): the plate and a cylinder at 0 deg (its axis is normal
  to the section). A sphere, or a cylinder across the section, is not a plane-strain problem.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

__all__ = ["INDENTER_FORMS", "MAX_RADIUS_MM", "MIN_RADIUS_MM", "SYMMETRIC_ANGLES", "Indenter", "parse_indenter"]

MAX_RADIUS_MM = 1000.0  # a 1000 mm cylinder gives the plate's force within 1 % (tested, 2D)
#: the smallest radius: a fingertip's is 7-11 mm; under 1 mm the contact is narrower than the
#: phalanx's surface elements and the penalty contact cannot resolve it (a needle, not a touch)
MIN_RADIUS_MM = 1.0
SYMMETRIC_ANGLES = (0.0, 90.0)  # cylinder angles the quarter model can carry
INDENTER_FORMS = ("plate, cylinder:R_MM[@ANGLE_DEG] or sphere:R_MM with R in [1, 1000] mm and "
                  "ANGLE_DEG in [0, 90] from the phalanx axis (default 90: across it)")
_FORM = re.compile(r"^(plate|cylinder|sphere)(?::([^@]+)(?:@(.+))?)?$")


def _fmt(v: float) -> str:
    return f"{v:.12g}"


@dataclass(frozen=True)
class Indenter:
    """A rigid indenter.

    Attributes:
        kind: ``"plate"``, ``"cylinder"`` or ``"sphere"``.
        radius_mm: radius of the cylinder or sphere, in [1, 1000] mm (None for the plate).
        angle_deg: the cylinder's axis from the phalanx axis, in [0, 90] (None otherwise).
    """

    kind: str
    radius_mm: float | None = None
    angle_deg: float | None = None

    @property
    def text(self) -> str:
        """The canonical written form (``plate``, ``cylinder:7.4@90``, ``sphere:5``)."""
        if self.kind == "plate":
            return "plate"
        if self.kind == "sphere":
            return f"sphere:{_fmt(self.radius_mm)}"
        return f"cylinder:{_fmt(self.radius_mm)}@{_fmt(self.angle_deg)}"

    @property
    def axis(self) -> np.ndarray | None:
        """The cylinder's unit axis in model coordinates (x across, y up, z along the phalanx);
        None for the plate and the sphere."""
        if self.kind != "cylinder":
            return None
        a = math.radians(self.angle_deg)
        return np.array([math.sin(a), 0.0, math.cos(a)])

    @property
    def full_model(self) -> bool:
        """True if the indenter breaks the quarter model's symmetry (needs the whole phalanx)."""
        return self.kind == "cylinder" and self.angle_deg not in SYMMETRIC_ANGLES

    def check_mode(self, mode: str) -> None:
        """Raise ValueError if the ``mode`` model (``"3d"`` or ``"2d"``) cannot carry it."""
        if mode == "2d" and self.kind == "sphere":
            raise ValueError(f"indenter = {self.text!r}: a sphere is not a plane-strain problem; "
                             "use mode 3d (allowed in 2d: plate, cylinder:R@0)")
        if mode == "2d" and self.kind == "cylinder" and self.angle_deg != 0.0:
            raise ValueError(f"indenter = {self.text!r}: in 2d (plane strain in the cross-section) "
                             "only a cylinder along the phalanx (angle 0) is a plane-strain "
                             "problem; use mode 3d (allowed in 2d: plate, cylinder:R@0)")


def parse_indenter(text: str) -> Indenter:
    """Parse ``plate``, ``cylinder:R_MM[@ANGLE_DEG]`` or ``sphere:R_MM``.

    Raises:
        ValueError: naming the value and the allowed forms and ranges.
    """
    m = _FORM.match(text.strip()) if isinstance(text, str) else None
    bad = f"indenter = {text!r}: expected {INDENTER_FORMS}"
    if m is None:
        raise ValueError(bad)
    kind, r_text, a_text = m.groups()
    if kind == "plate":
        if r_text is not None:
            raise ValueError(f"indenter = {text!r}: the plate takes no radius; expected "
                             f"{INDENTER_FORMS}")
        return Indenter("plate")
    if r_text is None:
        raise ValueError(bad)
    if kind == "sphere" and a_text is not None:
        raise ValueError(f"indenter = {text!r}: a sphere takes no angle; expected {INDENTER_FORMS}")
    try:
        r = float(r_text)
    except ValueError:
        raise ValueError(bad) from None
    if not (math.isfinite(r) and MIN_RADIUS_MM <= r <= MAX_RADIUS_MM):
        raise ValueError(f"indenter = {text!r}: radius {r_text} mm outside the allowed range "
                         f"[{MIN_RADIUS_MM:g}, {MAX_RADIUS_MM:g}] mm")
    if kind == "sphere":
        return Indenter("sphere", r)
    angle = 90.0
    if a_text is not None:
        try:
            angle = float(a_text) + 0.0  # -0 -> 0
        except ValueError:
            raise ValueError(bad) from None
        if not (math.isfinite(angle) and 0.0 <= angle <= 90.0):
            raise ValueError(f"indenter = {text!r}: angle {a_text} deg outside the allowed range "
                             "[0, 90] deg from the phalanx axis")
    return Indenter("cylinder", r, angle)
