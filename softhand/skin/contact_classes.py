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
  palmar face and the back: 88 % of the default handshake's force, radius 8-23 mm, median 13.9,
  `reports/contact-geometry.md`), neither the phalanx's section (16 x 9 mm) nor the palm's flat
  slab is pressed. The FE has no body of the palm's own section; its nearest is the phalanx
  section widened to `BORDER_GEOMETRY` (20 x 8 mm, a half ellipse: 12.5 mm radius at its top,
  the median border's within 1.4 mm; the design's layers and pocket as on the phalanx, over a
  flat bone), pressed by the same finger across it: a stated stand-in, whose radius moved to
  13.0 and 11.1 mm changes pocket2-sil's depth at 2 N by -2 % and +7 %
  (`reports/border-law-error.md`). The stand-in is 40 mm long, as a palm's border is long
  beside a finger: the finger's contact reaches the ends of the paper's 10 mm phalanx (its free
  ends then bulge: pocket2-sil's force at 2 mm 13 % low), while 40 and 60 mm give the same
  curve within 0.1 % (`softhand.fem.geometry.PhalanxGeometry.length_mm`). A pair's body is a
  border when the handshake's grasp puts the finger on the border
  (`softhand.envs.skins.border_pairs`), not from the geoms' types.
* **crossing**: the fingers cross the border at 30-90 deg, and a finger crossing it obliquely
  presses stiffer (crossed cylinders: the contact lengthens, Johnson 1985, section 4.2;
  pocket2-sil's FE depth at 2 N 2.26 mm at 90 deg, 2.00 at 30). The border's finger class comes
  per crossing angle (`BORDER_CROSSINGS_DEG`: ``border/finger`` at 90, ``border/finger@60``
  and ``border/finger@30``, the FE's cylinder at that angle to the stand-in's axis, the whole
  part modelled: ``border-finger-60/``, ``border-finger-30/``), and a pair takes the class of
  the nearest angle to its crossing at the grasp (`border_class`). A skin without a crossing's
  curve takes the border's law across (`class_fallback`). The phalanx's finger class stays the
  FE's 90 deg (1.7 % of the default run's force).
A class's skin law keeps the plate law's relaxation (quasi-linear viscoelasticity: the
relaxation function is the material's, the elastic law the shape's) and fits its own elastic law
to the class's FE ramp (`fit_class_law`).

The human tissue has a law per class too, from an FE of the tissue (`TISSUE_FE_FOLDER`,
written by ``python tools/tissue_fe.py --classes``): the paper's phalanx envelope as one
homogeneous layer of tissue over the flat bone (one Storakers term, alpha 2, Poisson's ratio
0.45: assumptions; mu fitted so that the plate gives the paper's human mean 3.68 mm at 2 N;
it then follows the tissue's exponential law within 5 % in depth at 5 and 7 N,
reports/tissue-fe.md), pressed as each class presses it: the plate and the finger on the
phalanx, the palm slab under both, the border stand-in under the finger. A class's tissue law
is the tissue's plate law (`softhand.laws.references.human_law`, the paper's numbers) times
that FE's force ratio, class over plate, at the same depth (`tissue_class_law`): the paper
fixes the plate's curve, the tissue's own FE its shape. No published indentation data with
curved indenters on the middle phalanx, or of the palm's border, were found; the ratio is the
FE's prediction, and the layer's constants are assumptions (`TISSUE_FE_FOLDER`'s summary
records them). The tissue's data (a flat plate to 7 N) end at a depth, 6.24 mm; a class's law
rests on them to that depth, not to that force, and beyond it on the tissue FE of its class as
far as that FE runs and the law follows it (`tissue_class_depths`, `TISSUE_FE_CONFIRM`): the
finger class (0.69 x the plate's force) on data to 4.8 N and on its FE to 8.1 N, its crossings
to 5.6 and 7.6 N (60 deg) and 8.7 and 11.6 N (30 deg), the palm slab under a finger to 11.4 and
18.9 N, the border class to 13.4 and 16.4 N, its crossings to 11.8 N (60 deg: its FE stops at
5.75 mm) and 6.7 N (30 deg: at 3.72 mm), and the palm slab under the plate (its FE stops at
2.07 mm) to 3.9 N (reports/tissue-classes.md).

* the partner's tissue side of a pair is pressed by the skin's body: a prosthetic phalanx (or
  a rounded border, of a finger's radius) like a finger, a palm face like a flat
  (`tissue_counterpart`): its law is the tissue's ``phalanx/finger`` or plate law;
* where the skin's rounded border crosses the partner's finger obliquely (``border/finger@A``),
  the partner's phalanx is crossed at the same angle, and its side takes the tissue's
  ``phalanx/finger@A`` (`TISSUE_CROSSINGS`, tissue-only classes: `partner_tissue_class`). The
  paper's 10 mm specimen cannot hold an oblique cylinder (it runs off the ends), so the
  crossing comes from a long phalanx (`TISSUE_LONG_PHALANX`, 40 mm as the border stand-in):
  the law is the 90 deg finger law (the specimen's) times the long phalanx's force at the angle
  over its force across (`TISSUE_CROSSING_BASES`), at the same depth (`tissue_class_law`). A
  tissue FE folder without those curves leaves the skins' oblique classes out (their pairs take
  the border's law across, `class_fallback`);
* the sensored human hand (the paper's protocol, `softhand handshake --hand human`) takes the
  tissue's law of each contact's own class, its pair law against the partner's tissue side as
  above; its border's oblique classes the same way as the partner's phalanx: its border law
  across times the border stand-in's force at the angle over across, both on the coarse mesh
  (`TISSUE_CROSSING_BASES`).

A class without FE curves for a skin falls back to the plate law (``phalanx/flat``), and the run
says so (`pair_law_label`).
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from softhand.laws.elastic import ElasticLaw
from softhand.laws.fit import Curve, SkinLaw, fit_skin_law

__all__ = ["BODIES", "BORDER_CROSSINGS_DEG", "BORDER_GEOMETRY", "CLASSES", "COUNTERPARTS",
           "FE_BODY", "FE_FOLDERS", "FINGER_MAX_RADIUS_MM", "FINGER_RADIUS_MM", "INDENTERS",
           "PLATE_CLASS", "TISSUE_CLASSES", "TISSUE_CROSSINGS", "TISSUE_CROSSING_BASES",
           "TISSUE_CROSSING_MESH", "TISSUE_CROSSING_REFERENCES", "TISSUE_FE_CONFIRM",
           "TISSUE_FE_FOLDER", "TISSUE_LONG_PHALANX", "TISSUE_OPTIONAL", "border_class",
           "class_crossing",
           "class_curve", "class_fallback", "class_indenter", "class_parts", "classify",
           "fit_class_law", "geom_shape", "law_class", "partner_tissue_class", "shape_ratio",
           "tissue_class_curves", "tissue_class_data_range", "tissue_class_depths",
           "tissue_class_law", "tissue_class_needs", "tissue_counterpart", "tissue_curve_file"]

BODIES = ("phalanx", "palm", "border")
COUNTERPARTS = ("flat", "finger")
#: the crossing angles (deg, the finger's axis against the border's edge) of the border's finger
#: classes: ``border/finger`` itself (90, across), and ``border/finger@A`` for each other angle A.
#: A handshake's fingers cross the palm's border at 30-90 deg (reports/contact-geometry.md), and
#: the FE's border is stiffer the more oblique the finger (pocket2-sil's depth at 2 N 2.26 mm at
#: 90 deg, 2.21 at 60, 2.00 at 30: reports/border-law-error.md); laws 30 deg apart leave every
#: crossing from 15 to 90 deg within 15 deg of one (`border_class`)
BORDER_CROSSINGS_DEG = (90.0, 60.0, 30.0)
#: every class with FE curves: each body under each counterpart, but the border (a palm's rounded
#: edge, pressed by fingers that wrap it: no flat presses a border alone), whose finger classes
#: come per crossing angle (`BORDER_CROSSINGS_DEG`)
CLASSES = ("phalanx/flat", "phalanx/finger", "palm/flat", "palm/finger", "border/finger",
           *(f"border/finger@{a:g}" for a in BORDER_CROSSINGS_DEG[1:]))
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
              "palm/finger": "palm-finger", "border/finger": "border-finger",
              **{f"border/finger@{a:g}": f"border-finger-{a:g}" for a in BORDER_CROSSINGS_DEG[1:]},
              # the tissue's crossing runs (its folder's file names; no skin folder)
              **{f"phalanx/finger@{a:g}": f"finger-{a:g}" for a in BORDER_CROSSINGS_DEG},
              "border/finger@90": "border-finger-90"}
#: the FE body (`softhand.fem.solver.IndentationSettings.body`) of each class's body
FE_BODY = {"phalanx": "phalanx", "palm": "palm", "border": "phalanx"}
#: the phalanx geometry (`softhand.fem.geometry.PhalanxGeometry` fields) that stands in for the
#: palm's rounded border (module docstring)
BORDER_GEOMETRY = {"width_mm": 20.0, "height_mm": 8.0, "length_mm": 40.0}
#: the classes whose tissue FE curves the human tissue's laws may lack: the border's oblique
#: crossings and their reference across (`TISSUE_CROSSING_BASES`; an oblique finger needs the
#: whole part, 4x a quarter's elements). Without them the sensored human hand's pairs there take
#: its border law across (`class_fallback`), and its geometry accounting counts them as not
#: fitting
TISSUE_OPTIONAL = (*(f"border/finger@{a:g}" for a in BORDER_CROSSINGS_DEG[1:]), "border/finger@90")
#: the tissue's crossing laws: each oblique class -> (its 90 deg class, whose law it scales; the
#: reference run across on the crossing's own body and mesh, ``@90``: not a law of its own). The
#: partner's phalanx crossed on the long phalanx; the sensored human hand's border on the border
#: stand-in (`tissue_class_law`)
TISSUE_CROSSING_BASES = {
    **{f"phalanx/finger@{a:g}": ("phalanx/finger", "phalanx/finger@90")
       for a in BORDER_CROSSINGS_DEG[1:]},
    **{f"border/finger@{a:g}": ("border/finger", "border/finger@90")
       for a in BORDER_CROSSINGS_DEG[1:]}}
#: the tissue-only classes of `TISSUE_CROSSING_BASES`: the partner's phalanx crossed by a skin's
#: rounded border at an oblique angle (the partner's side of ``border/finger@A``,
#: `partner_tissue_class`); no skin has them (a skin's phalanx under an oblique finger keeps
#: ``phalanx/finger``)
TISSUE_CROSSINGS = tuple(k for k in TISSUE_CROSSING_BASES if k not in CLASSES)
#: the reference runs across of `TISSUE_CROSSING_BASES`
TISSUE_CROSSING_REFERENCES = tuple(dict.fromkeys(r for _, r in TISSUE_CROSSING_BASES.values()))
#: every class the tissue FE folder may hold a curve of
TISSUE_CLASSES = (*CLASSES, *TISSUE_CROSSING_REFERENCES, *TISSUE_CROSSINGS)
#: the phalanx geometry (`softhand.fem.geometry.PhalanxGeometry` fields) of the tissue's
#: crossing runs: the paper's section, as long as the border stand-in, so that an oblique finger
#: stays on it (the paper's 10 mm specimen has free ends within the finger's contact)
TISSUE_LONG_PHALANX = {"length_mm": BORDER_GEOMETRY["length_mm"]}
#: the mesh level of the tissue's crossing runs (`softhand.fem.solver.IndentationSettings.mesh`):
#: an oblique finger needs the whole long part (no symmetry), which on the default mesh takes
#: hours of the soft tissue's small steps; the coarse mesh, the same for the reference across
#: and each angle, so that their ratio is one mesh's (the plate's depth at 7 N moves 2.5 % from
#: the default to the coarse mesh, reports/tissue-fe.md)
TISSUE_CROSSING_MESH = "coarse"
#: the folder under the FE root with the human tissue's FE curves, one file per class
#: (`tissue_curve_file`) and a summary.json that records them (module docstring)
TISSUE_FE_FOLDER = "tissue"
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


def class_parts(key: str) -> tuple[str, str, float | None]:
    """(body, counterpart, crossing deg) of class ``key`` (`CLASSES`): a finger class's crossing
    is the angle after ``@`` (90 without one: the FE's cylinder across), a flat's None.

    Raises:
        ValueError: not a class.
    """
    if key not in TISSUE_CLASSES:
        raise ValueError(f"class = {key!r}: allowed {', '.join(CLASSES)}")
    kind, _, angle = key.partition("@")
    body, counterpart = kind.split("/")
    if counterpart != "finger":
        return body, counterpart, None
    return body, counterpart, float(angle) if angle else 90.0


def class_crossing(key: str) -> float | None:
    """The crossing angle (deg) of class ``key``'s FE finger (`class_parts`)."""
    return class_parts(key)[2]


def class_indenter(key: str) -> str:
    """The FE indenter (`softhand.fem.solver.IndentationSettings.indenter`) of class ``key``:
    the plate, or the finger's cylinder at the class's crossing angle."""
    _, counterpart, crossing = class_parts(key)
    if crossing is None or crossing == 90.0:
        return INDENTERS[counterpart]
    return f"cylinder:{FINGER_RADIUS_MM:g}@{crossing:g}"


def border_class(crossing: float | None) -> str:
    """The ``border/finger`` class of a finger crossing a rounded palm border at ``crossing``
    deg: the one of the nearest angle of `BORDER_CROSSINGS_DEG` (90 where the angle is unknown;
    the larger angle at a tie)."""
    if crossing is None:
        return "border/finger"
    a = min(BORDER_CROSSINGS_DEG, key=lambda x: (abs(x - float(crossing)), -x))
    return "border/finger" if a == 90.0 else f"border/finger@{a:g}"


def class_fallback(key: str) -> str | None:
    """The class whose law a pair of class ``key`` carries where its skin has no law of ``key``:
    an oblique border crossing takes the border's law across (90 deg), the border's the palm
    face's (``palm/finger``: what the border's pairs carried before they had a law); None for
    the others (the plate law then, `softhand.envs.skins.pair_choices`)."""
    body, _, crossing = class_parts(key)
    if body != "border":
        return None
    return "palm/finger" if crossing == 90.0 else "border/finger"


def law_class(key: str, has) -> str | None:
    """The class whose law a pair of class ``key`` carries, given which classes a skin has laws
    of (``has``: a container of class keys, e.g. a calibration's ``pair_laws``): ``key`` itself,
    else its `class_fallback` chain's first that ``has`` holds; None: none (the skin's plate law
    then). The one rule for the scene (`softhand.envs.skins.pair_choices`) and ``softhand skin
    apply`` (`softhand.skin.apply.apply_skin`)."""
    while key is not None and key not in has:
        key = class_fallback(key)
    return key


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
    return "flat" if class_parts(key)[0] == "palm" else "finger"


def class_curve(design: str, key: str, fe_root: str | Path) -> Path:
    """The FE curve file of ``design`` for class ``key`` (it may not exist)."""
    folder = Path(fe_root) / FE_FOLDERS[key] if FE_FOLDERS[key] else Path(fe_root)
    return folder / f"{design}.csv"


def fit_class_law(design: str, key: str, plate_law: SkinLaw, curve: Curve) -> SkinLaw:
    """The skin law of ``design`` for class ``key``: ``plate_law``'s relaxation, an elastic law
    fitted to ``curve`` (the class's FE ramp at the paper's 0.5 mm/s)."""
    return fit_skin_law(f"{design} {key}", [curve], prony=plate_law.prony)


def partner_tissue_class(key: str) -> str:
    """The tissue class law the partner's side of a pair of class ``key`` takes: the tissue
    pressed like a finger (``phalanx/finger``) or like a flat (`PLATE_CLASS`) by the skin's
    body (`tissue_counterpart`); by a border crossing it obliquely, the tissue's crossing at
    that angle (``border/finger@30`` -> ``phalanx/finger@30``, `TISSUE_CROSSINGS`)."""
    if tissue_counterpart(key) != "finger":
        return PLATE_CLASS
    body, _, crossing = class_parts(key)
    if body == "border" and crossing is not None and crossing != 90.0:
        return f"phalanx/finger@{crossing:g}"
    return "phalanx/finger"


def tissue_class_needs(key: str) -> tuple[str, ...]:
    """The tissue FE curves (class keys) that make the tissue's law of class ``key``: the
    plate's and the class's own; a crossing's (`TISSUE_CROSSING_BASES`) its 90 deg class's, its
    reference run across and its run at the angle."""
    if key not in TISSUE_CROSSING_BASES:
        return tuple(dict.fromkeys((PLATE_CLASS, key)))
    return (PLATE_CLASS, *TISSUE_CROSSING_BASES[key], key)


def tissue_class_curves(key: str, curves: dict[str, Curve]
                        ) -> tuple[Curve, Curve, tuple[Curve, Curve] | None] | None:
    """The tissue FE curves (plate, class, crossing) that make the tissue's law of class ``key``
    (`tissue_class_law`) from ``curves`` (a tissue FE folder's, key -> curve): the plate's and
    the class's own; for a crossing (`TISSUE_CROSSING_BASES`) its 90 deg class's and the pair
    of its reference run across and its run at the angle (`tissue_class_needs`). None where one
    is missing."""
    if any(k not in curves for k in tissue_class_needs(key)):
        return None
    plate = curves[PLATE_CLASS]
    if key not in TISSUE_CROSSING_BASES:
        return plate, curves[key], None
    base, reference = TISSUE_CROSSING_BASES[key]
    return plate, curves[base], (curves[reference], curves[key])


def tissue_curve_file(key: str) -> str:
    """The file name of class ``key``'s curve in `TISSUE_FE_FOLDER`."""
    class_parts(key)
    return f"{FE_FOLDERS[key] or 'plate'}.csv"


def tissue_class_law(tissue: SkinLaw, key: str, plate: Curve | None = None,
                     other: Curve | None = None, cross: tuple[Curve, Curve] | None = None
                     ) -> SkinLaw:
    """The human tissue's law in class ``key`` (module docstring): `PLATE_CLASS`: ``tissue``
    itself; another class: its elastic force times the tissue FE's force ratio ``other`` (the
    class's curve) over ``plate`` (the plate's) at the same depth, the ratio held at its last
    value beyond the depth both FE ramps reach (`shape_ratio`); a crossing
    (`TISSUE_CROSSING_BASES`: ``other`` its 90 deg class's curve) times the ratio of ``cross``,
    its body at the angle over across, too. The relaxation is ``tissue``'s. `tissue_class_curves` picks the
    curves from a tissue FE folder's.

    Raises:
        ValueError: an unknown class, or another class than the plate's without its curves.
    """
    if key not in TISSUE_CLASSES or key in TISSUE_CROSSING_REFERENCES:
        raise ValueError(f"class = {key!r}: allowed {', '.join((*CLASSES, *TISSUE_CROSSINGS))}")
    if key == PLATE_CLASS:
        return tissue
    crossing = key in TISSUE_CROSSING_BASES
    if plate is None or other is None or (crossing and cross is None):
        raise ValueError(f"the tissue's {key} law needs the tissue FE's plate and {key} curves "
                         f"({TISSUE_FE_FOLDER}/ of the FE root)")
    ratio = shape_ratio(plate, other)
    cross_ratio = shape_ratio(*cross) if crossing else (lambda d: 1.0)
    top = tissue.elastic.max_mm
    d = np.linspace(0.0, top, 200)[1:]
    force = tissue.elastic.force(d) * ratio(d) * cross_ratio(d)
    elastic = ElasticLaw.fit(np.concatenate([[0.0], d]), np.concatenate([[0.0], force]),
                             max_mm=top)
    factor = f"tissue FE {key} / plate ({other.label} / {plate.label})"
    if crossing:
        base = TISSUE_CROSSING_BASES[key][0]
        body = "long phalanx" if base.startswith("phalanx") else "border stand-in"
        factor = (f"tissue FE {base} / plate ({other.label} / {plate.label}) x {body} at the "
                  f"crossing / across ({cross[1].label} / {cross[0].label})")
    source = {**tissue.source, "shape_factor": factor}
    return SkinLaw(f"{tissue.name} ({key})", elastic, tissue.prony, source=source)


#: How closely the tissue FE of a class must follow the class's tissue law beyond the plate's
#: data for the law to rest on it there (`tissue_class_depths`): the law's depth at the FE's
#: force within this share of the FE's depth, the criterion the FE body was chosen by (alpha 2
#: follows the tissue's law within 5 % in depth at 5 and 7 N, reports/tissue-fe.md)
TISSUE_FE_CONFIRM = 0.05


def tissue_class_data_range(tissue: SkinLaw, key: str, law: SkinLaw, plate: Curve | None = None,
                            other: Curve | None = None, data_N: float | None = None,
                            cross: tuple[Curve, Curve] | None = None) -> float:
    """The force up to which ``law``, the tissue's law in class ``key`` (`tissue_class_law`),
    rests on data or on the tissue FE of its class: its force at `tissue_class_depths`'s
    second depth."""
    return float(law.elastic.force(
        tissue_class_depths(tissue, key, law, plate, other, data_N, cross)[1]))


def tissue_class_depths(tissue: SkinLaw, key: str, law: SkinLaw, plate: Curve | None = None,
                        other: Curve | None = None, data_N: float | None = None,
                        cross: tuple[Curve, Curve] | None = None) -> tuple[float, float, float]:
    """Where ``law``, the tissue's law in class ``key`` (`tissue_class_law`), rests on the
    tissue's data and on its class's FE: (the depth where the data end, the depth to which the
    FE confirms the law, both mm; the largest difference between the law's depth and the FE's
    between them, as a share of the FE's depth).

    The tissue's data are the plate's (``data_N``, default `DATA_MAX_N` of the tissue: the
    force range over which its exponential was confirmed), so they end at a depth, the plate
    law's at ``data_N``; a class's law is the plate's times the FE's ratio at the same depth, so
    its data end at that depth too, and no deeper than both FE ramps reach (beyond it the ratio
    is a held value, `shape_ratio`). Its force there: a finger class, softer than the plate
    (ratio 0.7), rests on data to about 0.7 x ``data_N``, not to ``data_N``. A crossing's
    (``cross``, `tissue_class_law`) ends no deeper than its long phalanx's ramps.

    Beyond that depth the law of a class other than the plate's (whose range is its data's)
    rests on its class's FE (``other``, times the crossing's ratio), pinned to the data where
    they end (times the plate law's force over the plate FE's there): as deep as that FE runs
    and the law's depth at the FE's force stays within `TISSUE_FE_CONFIRM` of the FE's depth.
    The tissue FE (one body whose constants the paper's plate fixes) is not data: above the
    plate's 7 N it is the only evidence, as issue 35 allows ("cited data beyond 7 N, or an FE
    of the tissue")."""
    from softhand.laws.references import DATA_MAX_N, HUMAN

    top_N = DATA_MAX_N[HUMAN] if data_N is None else float(data_N)
    depth = float(tissue.elastic.displacement_at(top_N))
    if key == PLATE_CLASS or plate is None or other is None:  # the plate: its data's own
        return depth, depth, 0.0
    runs = (other, *(cross or ()))
    depth = min(depth, _reach(plate), *(_reach(c) for c in runs))  # where the data end
    pin = float(tissue.elastic.force(depth)) / _ramp_force(plate, depth)

    def fe(d: float) -> float:
        f = _ramp_force(other, d) * pin
        return f * _ramp_force(cross[1], d) / _ramp_force(cross[0], d) if cross else f

    confirmed, worst, reach = depth, 0.0, min(_reach(c) for c in runs)
    for d in np.linspace(depth, reach, 60)[1:] if reach > depth else ():
        off = abs(float(law.elastic.displacement_at(fe(d))) - d) / d
        if off > TISSUE_FE_CONFIRM:
            break
        confirmed, worst = float(d), max(worst, off)
    return depth, confirmed, worst


def _ramp(c: Curve) -> tuple[np.ndarray, np.ndarray]:
    """A curve's ramp to its largest force: depth (mm), force (N)."""
    i = c.peak_index
    return c.displacement_mm[:i + 1], c.force_N[:i + 1]


def _reach(c: Curve) -> float:
    """The deepest depth (mm) of a curve's ramp."""
    return float(_ramp(c)[0][-1])


def _ramp_force(c: Curve, d: float) -> float:
    """A curve's ramp force (N) at depth ``d`` (mm), linear between its points."""
    return float(np.interp(d, *_ramp(c)))


def shape_ratio(plate: Curve, other: Curve):
    """A function of depth (mm): ``other``'s ramp force over ``plate``'s at that depth, from
    0.25 mm (below it the first FE steps are too coarse for a ratio: held at its 0.25 mm value)
    to the depth both ramps reach (held beyond)."""
    dp, fp = _ramp(plate)
    do, fo = _ramp(other)
    top = min(dp[-1], do[-1])
    grid = np.linspace(0.25, top, 120)
    values = np.interp(grid, do, fo) / np.interp(grid, dp, fp)
    return lambda d: np.interp(np.asarray(d, dtype=float), grid, values)
