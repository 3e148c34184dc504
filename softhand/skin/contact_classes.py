"""Contact geometry classes: the law a contact takes follows the shapes of its two geoms.

Every skin law of the paper's protocol comes from a flat 20 x 10 mm plate pressed on a phalanx. A
handshake presses skins with fingers (round, radius 7.4-10.7 mm across the partner population)
and with palms (flat), on phalanges (round) and on palm and back pieces (flat slabs over
metacarpals). At equal depth a finger-sized cylinder gives 0.5-0.8x the plate's force on a
phalanx (the FE; Hertz and elastic-foundation estimates 0.33-0.8x, Johnson, Contact Mechanics,
1985, sections 4.2 and 5.8), so the law of a contact is chosen by its geometry:

* **body**, the skin's side: ``phalanx`` for a round geom (capsule, cylinder, sphere, ellipsoid),
  ``palm`` for a flat one (mesh, box, plane);
* **counterpart**, what presses the skin: ``finger`` for a round geom of radius at most
  `FINGER_MAX_RADIUS_MM`, ``flat`` otherwise.

The classes ``body/counterpart`` have their FE curves in folders of the FE root
(`FE_FOLDERS`): the paper's plate on the phalanx (the root itself), a cylinder of radius
`FINGER_RADIUS_MM` across the phalanx (``finger/``), the palm model of
`softhand.fem.palm` under the plate and the cylinder (``palm-plate/``, ``palm-finger/``), and
the same cylinder across a rounded palm border (``border-finger/``, class ``border/finger``).

* **border**: where a partner's finger wraps the convex palm's rounded border (between its
  palmar face and the back: 94 % of the default handshake's force, radius 8-23 mm, median 13.6,
  `reports/contact-geometry.md`), neither the phalanx's section (16 x 9 mm) nor the palm's flat
  slab is pressed. The FE has no body of the palm's own section; its nearest is the phalanx
  section widened to `BORDER_GEOMETRY` (20 x 8 mm, a half ellipse: 12.5 mm radius at its top,
  the median border's within 1.1 mm; the design's layers and pocket as on the phalanx, over a
  flat bone), pressed by the same finger across it: a stated stand-in, whose radius moved to
  13.0 and 11.1 mm changes pocket2-sil's depth at 2 N by -2 % and +7 %
  (`reports/border-law-error.md`). A pair's body is a border when the handshake's grasp puts
  the finger on the border (`softhand.envs.skins.border_pairs`), not from the geoms' types.
A class's skin law keeps the plate law's relaxation (quasi-linear viscoelasticity: the
relaxation function is the material's, the elastic law the shape's) and fits its own elastic law
to the class's FE ramp (`fit_class_law`).

The tissue side of a pair (the partner's human tissue) is pressed by the skin's geom: a
prosthetic phalanx presses it like a finger, a prosthetic palm like a flat. Published human
data with curved indenters on the finger's middle phalanx were not found; so the tissue's
``finger`` law is a stated assumption: the tissue's plate law
(`softhand.laws.references.human_law`) times the FE's cylinder/plate force ratio of the
solid silicone phalanx at the same depth (`tissue_class_law`), a homogeneous soft layer of
the finger's size over bone, as finger pulp is.

A class without FE curves for a skin falls back to the plate law (``phalanx/flat``), and the run
says so (`pair_law_label`).
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from softhand.laws.elastic import ElasticLaw
from softhand.laws.fit import Curve, SkinLaw, fit_skin_law

__all__ = ["BODIES", "BORDER_GEOMETRY", "CLASSES", "COUNTERPARTS", "FE_BODY", "FE_FOLDERS",
           "FINGER_MAX_RADIUS_MM", "FINGER_RADIUS_MM", "INDENTERS", "PLATE_CLASS", "TISSUE_REFERENCE_DESIGN",
           "class_curve", "classify", "fit_class_law", "geom_shape", "shape_ratio",
           "tissue_class_law", "tissue_counterpart"]

BODIES = ("phalanx", "palm", "border")
COUNTERPARTS = ("flat", "finger")
#: every class with FE curves: each body under each counterpart, but the border (a palm's rounded
#: edge, pressed by fingers that wrap it: no flat presses a border alone)
CLASSES = ("phalanx/flat", "phalanx/finger", "palm/flat", "palm/finger", "border/finger")
#: the paper's protocol: the class every skin has (the plate on the phalanx)
PLATE_CLASS = "phalanx/flat"
#: the finger counterpart's radius in the FE: the middle of the partner population's finger
#: radii (7.4-10.7 mm: the capsules of softhand.hands.partner over Table 1's hand sizes)
FINGER_RADIUS_MM = 9.0
#: a round geom up to this radius presses like a finger; a larger one (or a flat one) like a flat
FINGER_MAX_RADIUS_MM = 15.0
#: the FE indenter of each class's counterpart
INDENTERS = {"flat": "plate", "finger": f"cylinder:{FINGER_RADIUS_MM:g}@90"}
#: each class's FE folder under the FE root ("" = the root: the paper's plate on the phalanx)
FE_FOLDERS = {"phalanx/flat": "", "phalanx/finger": "finger", "palm/flat": "palm-plate",
              "palm/finger": "palm-finger", "border/finger": "border-finger"}
#: the FE body (`softhand.fem.solver.IndentationSettings.body`) of each class's body
FE_BODY = {"phalanx": "phalanx", "palm": "palm", "border": "phalanx"}
#: the phalanx geometry (`softhand.fem.geometry.PhalanxGeometry` fields) that stands in for the
#: palm's rounded border (module docstring)
BORDER_GEOMETRY = {"width_mm": 20.0, "height_mm": 8.0}
#: the design whose FE shape factor stands in for the human tissue's (module docstring)
TISSUE_REFERENCE_DESIGN = "solid-sil"
_ROUND = {int(mujoco.mjtGeom.mjGEOM_CAPSULE), int(mujoco.mjtGeom.mjGEOM_CYLINDER),
          int(mujoco.mjtGeom.mjGEOM_SPHERE), int(mujoco.mjtGeom.mjGEOM_ELLIPSOID)}


def geom_shape(model: mujoco.MjModel, geom: int) -> tuple[str, float | None]:
    """(``"round"``, radius in mm) for a capsule, cylinder, sphere or ellipsoid (an ellipsoid:
    its smallest semi-axis), else (``"flat"``, None)."""
    kind = int(model.geom_type[geom])
    if kind in _ROUND:
        size = model.geom_size[geom]
        r = float(size[:3].min()) if kind == int(mujoco.mjtGeom.mjGEOM_ELLIPSOID) else float(size[0])
        return "round", 1e3 * r
    return "flat", None


def _counterpart(model: mujoco.MjModel, geom: int) -> str:
    shape, r = geom_shape(model, geom)
    return "finger" if shape == "round" and r <= FINGER_MAX_RADIUS_MM else "flat"


def classify(model: mujoco.MjModel, skin_geom: int, other_geom: int) -> str:
    """The class (``body/counterpart``, `CLASSES`) of a contact between a skin geom and the
    geom that presses it."""
    body = "phalanx" if geom_shape(model, skin_geom)[0] == "round" else "palm"
    return f"{body}/{_counterpart(model, other_geom)}"


def tissue_counterpart(key: str) -> str:
    """What presses the tissue in a pair of class ``key``: the skin's body (a phalanx presses
    like a finger, and a rounded palm border, of a finger's radius, too; a palm face like a
    flat)."""
    return "flat" if key.split("/")[0] == "palm" else "finger"


def class_curve(design: str, key: str, fe_root: str | Path) -> Path:
    """The FE curve file of ``design`` for class ``key`` (it may not exist)."""
    folder = Path(fe_root) / FE_FOLDERS[key] if FE_FOLDERS[key] else Path(fe_root)
    return folder / f"{design}.csv"


def fit_class_law(design: str, key: str, plate_law: SkinLaw, curve: Curve) -> SkinLaw:
    """The skin law of ``design`` for class ``key``: ``plate_law``'s relaxation, an elastic law
    fitted to ``curve`` (the class's FE ramp at the paper's 0.5 mm/s)."""
    return fit_skin_law(f"{design} {key}", [curve], prony=plate_law.prony)


def tissue_class_law(tissue: SkinLaw, counterpart: str, plate: Curve | None = None,
                     finger: Curve | None = None) -> SkinLaw:
    """The human tissue's law for a counterpart: ``flat``: ``tissue`` itself; ``finger``: its
    elastic force times the cylinder/plate force ratio of `TISSUE_REFERENCE_DESIGN`'s FE
    ramps (``plate``, ``finger``) at the same depth (module docstring: a stated assumption),
    the ratio held at its last value beyond the FE's common depth range.

    Raises:
        ValueError: an unknown counterpart, or ``finger`` without both curves.
    """
    if counterpart == "flat":
        return tissue
    if counterpart != "finger":
        raise ValueError(f"counterpart = {counterpart!r}: allowed {', '.join(COUNTERPARTS)}")
    if plate is None or finger is None:
        raise ValueError("the tissue's finger law needs the plate and finger FE curves of "
                         f"{TISSUE_REFERENCE_DESIGN}")
    ratio = shape_ratio(plate, finger)
    top = tissue.elastic.max_mm
    d = np.linspace(0.0, top, 200)[1:]
    force = tissue.elastic.force(d) * ratio(d)
    elastic = ElasticLaw.fit(np.concatenate([[0.0], d]), np.concatenate([[0.0], force]),
                             max_mm=top)
    source = {**tissue.source, "shape_factor": f"{TISSUE_REFERENCE_DESIGN} FE cylinder/plate "
              f"({finger.label} / {plate.label})"}
    return SkinLaw(f"{tissue.name} (finger)", elastic, tissue.prony, source=source)


def shape_ratio(plate: Curve, other: Curve):
    """A function of depth (mm): ``other``'s ramp force over ``plate``'s at that depth, from
    0.25 mm (below it the first FE steps are too coarse for a ratio: held at its 0.25 mm value)
    to the depth both ramps reach (held beyond)."""
    def ramp(c: Curve) -> tuple[np.ndarray, np.ndarray]:
        i = c.peak_index
        return c.displacement_mm[:i + 1], c.force_N[:i + 1]

    dp, fp = ramp(plate)
    do, fo = ramp(other)
    top = min(dp[-1], do[-1])
    grid = np.linspace(0.25, top, 120)
    values = np.interp(grid, do, fo) / np.interp(grid, dp, fp)
    return lambda d: np.interp(np.asarray(d, dtype=float), grid, values)
