"""Skins on the handshake scene: which design each region wears, and the contact pairs that carry it.

Every prosthetic skin geom meets every partner tissue geom through an explicit ``<pair>``; its law
is the series combination of the region's skin and the partner's human tissue (both indent: the
indentation of the pair is the sum of the two at the same force), shipped as each skin's
``pair_law`` (`softhand.skin.pair`, fitted over 0-20 N by ``softhand calibrate``) and scaled
by the pair's inverse inertia (`softhand.skin.soft_contact`). A ``rigid`` region leaves only
the tissue's compliance. Laws come from the shipped calibration files; no FE run, no refit.

The prosthetic hand's skin covers its whole envelope (`softhand.hands.envelope`): one geom per
phalanx, one for the palm's continuous surface (Palm1, Palm2, Back1 and Back2 are its zones, so
they wear one design) and the non-sensing thenar skin; each wears the design of the region of
`softhand.hands.prosthetic.SKIN_KEYS` and has its pairs. No bare shell meets the partner: every
pair is a skin (or a ``rigid`` region) against tissue.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from softhand.hands import partner_tissue_geoms, regions
from softhand.hands.prosthetic import SKIN_KEYS, SURFACES, paper_regions
from softhand.laws.references import DATA_MAX_N, HUMAN
from softhand.skin.calibrate import skin_names
from softhand.skin.contact_classes import (
    CLASSES,
    PLATE_CLASS,
    class_parts,
    classify,
    law_class,
)
from softhand.skin.files import SKINS_DIR, load_calibration
from softhand.skin.local_geometry import LocalGeometry, state_class
from softhand.skin.representations import (
    REPRESENTATIONS,
    HandPad,
    Representation,
    get_representation,
)
from softhand.skin.rig import RangeIssue, pair_law_values, warn_range_issues
from softhand.skin.soft_contact import SoftContactParams
from softhand.validate import show

__all__ = [
    "BORDER_PAIRS_TEXT",
    "CONTACT_LAWS",
    "DEFAULT_DESIGN",
    "DEFAULT_REPRESENTATION",
    "GRASP_KEY",
    "HAND_REPRESENTATIONS",
    "OUTWARD",
    "PAD_TESTED_MAX_TIMESTEP_S",
    "SKIN_CHOICES",
    "CalibratedRangeWarning",
    "PairChoice",
    "add_skin_pairs",
    "border_pairs",
    "calibrated_max_force",
    "check_contact_laws",
    "check_pad_timestep",
    "pair_choices",
    "palm_skin",
    "parse_skins",
    "series_law",
    "skin_keys",
    "skin_of_pair",
    "skin_representation",
    "write_skin_laws",
]

class CalibratedRangeWarning(UserWarning):
    """Contacts between the hands carried more force than their pair laws were calibrated to (the
    force above the range is an extrapolation of the law), or a bone bottomed out under a region.
    Raised once per episode, at its end, as a summary: contact-steps beyond range, pairs, the
    worst pair and its force against its law's limit (``info["beyond_range_summary"]``)."""


DEFAULT_DESIGN = "pocket2-sil"  # the most lifelike design (calibration/skins/index.json ranking)
DEFAULT_REPRESENTATION = "soft-contact"
#: the representations the handshake takes (flex needs its own scene: softhand.hands.flex_region)
HAND_REPRESENTATIONS = tuple(n for n, r in REPRESENTATIONS.items() if r.not_on_hand is None)
#: outward normal of each prosthetic skin geom's contact side in its body's frame: palmar (-z)
#: for the phalanges, the thenar and the palmar quarters, dorsal (+z) for the back's quarters
#: (the palm's one surface has two faces: it takes no pad, see `skin_representation`)
OUTWARD = {"Back1": (0.0, 0.0, 1.0), "Back2": (0.0, 0.0, 1.0)}
PALMAR = (0.0, 0.0, -1.0)
SKIN_CHOICES = (*[n for n in skin_names() if n != HUMAN], "rigid")


def parse_skins(design: str | None = None, overrides: Mapping[str, str] | None = None,
                representation: str | None = None, *, calibrated: tuple[str, ...] = ()
                ) -> tuple[dict[str, str], dict[str, str]]:
    """Region -> skin design and region -> representation: ``design`` (default the most
    lifelike) in ``representation`` (default ``soft-contact``) everywhere, then ``overrides``,
    each ``DESIGN`` or ``DESIGN@REPRESENTATION``, keyed by region or by a surface's key
    (``Palm``: its four zones at once; the zones of one surface must end with one skin).

    A ``rigid`` region (the design, or any design ``@rigid``) is MuJoCo's stock contact against
    the tissue: its design is ``rigid`` and its representation ``rigid``.

    ``calibrated``: skins besides `SKIN_CHOICES` that the scene's calibration folder holds (a
    searched design's file, `softhand.skin.files.skin_file_folder`).

    None is the default; an empty string is not (it is refused like any unknown name).

    Raises:
        ValueError: an unknown region, skin or representation, or one the hand does not take,
            naming it and the allowed values; ``overrides`` not a mapping of region names to
            strings.
    """
    names = paper_regions()
    rep = _hand_representation(DEFAULT_REPRESENTATION if representation is None
                               else representation, "representation")
    design = DEFAULT_DESIGN if design is None else design
    choices = (*SKIN_CHOICES, *(c for c in calibrated if c not in SKIN_CHOICES and c != HUMAN))
    if design not in choices:
        raise ValueError(f"skin design {design!r} is unknown; allowed: {', '.join(choices)}")
    designs, reps = dict.fromkeys(names, design), dict.fromkeys(names, rep)
    if overrides is not None and not isinstance(overrides, Mapping):
        raise ValueError(f"skins = {overrides!r}: expected a mapping region -> DESIGN or "
                         f"DESIGN@REPRESENTATION, e.g. {{'Index1': 'rigid'}}")
    expanded: dict[str, object] = {}
    for region, choice in (overrides or {}).items():  # a surface's key: each of its zones
        if region not in designs and region not in SURFACES:
            raise ValueError(f"region {region!r} is unknown; allowed: {', '.join(names)} "
                             f"(or {', '.join(SURFACES)}: all of its zones)")
        expanded.update(dict.fromkeys(SURFACES.get(region, (region,)), choice))
    for region, choice in expanded.items():
        if not isinstance(choice, str):
            raise ValueError(f"skin {choice!r} for region {region}: expected DESIGN or "
                             f"DESIGN@REPRESENTATION (a string)")
        skin, at, own = choice.partition("@")
        if skin not in choices:
            raise ValueError(f"skin {skin!r} for region {region} is unknown; allowed: "
                             f"{', '.join(choices)}")
        designs[region] = skin
        if at:  # "DESIGN@" names an empty representation: refused, not the default
            reps[region] = _hand_representation(own, f"representation for region {region}")
            if skin == "rigid" and own != "rigid":
                raise ValueError(f"skin 'rigid' for region {region} has only the rigid "
                                 f"representation, not {own!r}")
    for region in names:
        if designs[region] == "rigid" or reps[region] == "rigid":
            designs[region] = reps[region] = "rigid"
    for key, zones in SURFACES.items():
        worn = {(designs[z], reps[z]) for z in zones}
        if len(worn) > 1:
            said = ", ".join(f"{z}={designs[z]}@{reps[z]}" for z in zones)
            raise ValueError(f"skins {said}: {', '.join(zones)} are zones of one {key.lower()} "
                             "skin and wear one design and representation; give them the same")
    return designs, reps


def skin_representation(key: str, representation: str) -> str:
    """The representation the skin geom ``skin_{key}`` takes for its region's ``representation``:
    the same, except on a surface of several zones (the palm's), whose faces are pressed from
    opposite sides (the palm between the partner's palm and fingers): one relaxation pad, a rigid
    body on one slide, would feel the difference of the two pushes, not the squeeze, so such a
    surface keeps soft contact. The scene never meets this case: with relaxation on the palm it
    builds the palm in quarters, one pad each (`palm_skin`); a hand skinned by hand may."""
    if key in SURFACES and representation == "soft-contact+relaxation":
        return DEFAULT_REPRESENTATION
    return representation


def _hand_representation(name: str, what: str) -> str:
    if not isinstance(name, str) or name not in REPRESENTATIONS:
        raise ValueError(f"{what} {name!r} is unknown; allowed: {', '.join(HAND_REPRESENTATIONS)}")
    why = get_representation(name).not_on_hand
    if why:
        raise ValueError(f"{what} {name!r} is not available in the handshake ({why}); allowed: "
                         f"{', '.join(HAND_REPRESENTATIONS)}")
    return name


def palm_skin(representations: Mapping[str, str]) -> str:
    """How the scene builds the palm's skin (`softhand.hands.config.PALM_SKINS`) for these
    representations: one surface, or its quarters when the palm's zones ride relaxation pads
    (one pad per quarter; the seams come back, and `ContactAreas.double_N` measures them)."""
    relax = "soft-contact+relaxation"
    return ("quarters" if any(representations.get(z) == relax for z in SURFACES["Palm"])
            else "surface")


def skin_keys(spec: mujoco.MjSpec | mujoco.MjModel, pro: str = "pro_") -> list[str]:
    """The keys of the skin geoms ``{pro}skin_{key}`` the hand has (SKIN_KEYS: its regions'
    own skins, the palm's surface or quarters, the thenar), in SKIN_KEYS's order.

    Raises:
        ValueError: a hand with neither the palm's surface nor all four of its quarters.
    """
    def has(name: str) -> bool:
        if isinstance(spec, mujoco.MjSpec):
            return spec.geom(name) is not None
        return mujoco.mj_name2id(spec, mujoco.mjtObj.mjOBJ_GEOM, name) >= 0

    keys = [k for k in SKIN_KEYS if has(f"{pro}skin_{k}")]
    missing = [k for k in SKIN_KEYS if k not in keys and k not in SURFACES["Palm"]
               and k not in SURFACES]
    palm = "Palm" in keys or all(z in keys for z in SURFACES["Palm"])
    if missing or not palm:
        raise ValueError(f"prosthetic skin geoms {', '.join(f'{pro}skin_{k}' for k in missing)}"
                         f"{' and the palm' if not palm else ''} not found")
    return keys


def add_skin_pairs(spec: mujoco.MjSpec, *, pro: str = "pro_", hum: str = "hum_") -> list[str]:
    """Add one pair per (prosthetic skin geom, partner tissue geom); return their names,
    ``{Skin}__{tissue}`` with Skin a key of SKIN_KEYS: a phalanx's region (``Index1``), the palm's
    surface (``Palm``) or a non-sensing skin (``Thenar``)."""
    tissues = partner_tissue_geoms(spec, hum)
    regions(spec, pro)  # checks every region's elements are there
    geoms = {key: f"{pro}skin_{key}" for key in skin_keys(spec, pro)}
    names = []
    for key, geom in geoms.items():
        for tissue in tissues:
            name = f"{key}__{tissue}"
            spec.add_pair(name=name, geomname1=geom, geomname2=tissue, condim=3,
                          friction=[1.0, 1.0, 0.005, 0.0001, 0.0001])
            names.append(name)
    return names


def skin_of_pair(pair: str, skins: Mapping[str, str]) -> tuple[str, str]:
    """(skin geom key, design) of a pair name made by `add_skin_pairs`: the design of the
    region the skin wears (SKIN_KEYS: a phalanx's own, Palm1's for the palm and the thenar)."""
    key = pair.partition("__")[0]
    return key, skins.get(SKIN_KEYS.get(key, key), "rigid")


@functools.lru_cache(maxsize=32)
def _calibration(skin: str, directory: str):
    return load_calibration(skin, directory, require=("soft-contact",))


@functools.lru_cache(maxsize=32)
def series_law(skin: str, directory: str = str(SKINS_DIR)) -> SoftContactParams:
    """The pair law of ``skin`` against human tissue: the shipped ``pair_law`` of its calibration
    (`softhand.skin.pair`: the two laws in series, fitted over the whole 0-20 N range);
    ``rigid``: the tissue's own soft contact (only the tissue indents).

    Raises:
        ValueError: a calibration file without a pair law (written before they existed).
    """
    if skin == "rigid":
        return _calibration(HUMAN, directory).soft_contact
    cal = _calibration(skin, directory)
    if cal.pair_law is None:
        raise ValueError(f"calibration of skin {skin!r} in {directory} has no pair_law (the law "
                         f"against human tissue): run `softhand calibrate {skin}`")
    return cal.pair_law.params


@functools.lru_cache(maxsize=32)
def calibrated_max_force(skin: str, directory: str = str(SKINS_DIR)) -> float:
    """Largest normal force (N) up to which ``skin``'s pair law against human tissue is calibrated:
    the smaller of the two laws' data ranges (a design's FE curves, 20 N; the tissue's published
    data, `DATA_MAX_N`, 7 N). ``rigid``: the tissue's range."""
    if skin == "rigid":
        return float(DATA_MAX_N[HUMAN])
    series_law(skin, directory)  # checks the file has a pair law
    return float(_calibration(skin, directory).pair_law.calibrated_max_N)


#: the longest timestep at which relaxation pads are tested in whole handshakes (issue 20): a hard
#: grip (squeeze 5) loads regions beyond the calibrated 7 N, to 12-45 N for partners across Table
#: 1's range at 2 ms (within 10 % at 1 ms); at 2.5 ms, where a pocket2-sil pad is stable only to
#: 7.5 N, the pads oscillate (peaks of 95-127 N for partners of 215 x 75 and 160 x 100 mm)
PAD_TESTED_MAX_TIMESTEP_S = 0.002


def check_pad_timestep(skins: Mapping[str, str], representations: Mapping[str, str],
                       timestep_s: float, directory: str | Path = SKINS_DIR,
                       hand_pad: HandPad | None = None) -> None:
    """Refuse a timestep at which a region's relaxation pad is unstable: inside its skin's
    calibrated range (`HandPad.max_timestep_s`: the pad's spring is integrated explicitly;
    the shipped designs hold their calibrated range up to 2.48 ms (solid-pu, 7 N) to 3.46 ms
    (prosthetic-102l, 1 N)), or under a hard grip beyond it: above
    `PAD_TESTED_MAX_TIMESTEP_S` unless the pad is stable at every force (a linear law:
    prosthetic-102l, to 3.46 ms).

    Raises:
        ValueError: naming the timestep, the skin and its regions, the numbers behind the
            refusal (the pad's stiffness, mass and omega, or the force it holds at this
            timestep) and the largest timestep allowed.
    """
    hand_pad = hand_pad or HandPad()
    relax = "soft-contact+relaxation"
    by_skin: dict[str, list[str]] = {}
    for region, skin in skins.items():
        if representations.get(region) == relax and skin != "rigid":
            by_skin.setdefault(skin, []).append(region)
    for skin, regions_of in by_skin.items():
        where = ("every region" if len(regions_of) == len(skins)
                 else f"regions {', '.join(regions_of)}")
        force = calibrated_max_force(skin, str(directory))
        law = _calibration(skin, str(directory)).law
        h, k, x, mass = hand_pad.max_timestep_s(law, force)
        h_any = hand_pad.max_timestep_s(law, float("inf"))[0]  # stable at every force below it
        top = min(h, max(h_any, PAD_TESTED_MAX_TIMESTEP_S))
        if timestep_s <= top:
            continue
        if timestep_s > h:
            why = (f"the pad's spring, integrated explicitly, reaches {k:.0f} N/m at {force:g} N "
                   f"({x:.2f} mm, the top of its calibrated range) on {mass * 1e3:.3g} g (pad "
                   f"and armature), omega = {np.sqrt(k / mass):.0f} rad/s, and is stable only "
                   f"while omega * timestep < 2 (up to {h * 1e3:.2f} ms)")
        else:
            held, k_h = hand_pad.max_stable_force(law, timestep_s)
            why = (f"at {timestep_s * 1e3:g} ms a pad ({mass * 1e3:.3g} g with its armature) is "
                   f"stable only up to {held:.1f} N (its spring below {k_h:.0f} N/m: omega * "
                   "timestep < 2), and a hard grip loads regions to 12-45 N, where the pads "
                   "oscillate (peaks of 95-127 N measured at 2.5 ms, against 12-45 N at 1 and "
                   "2 ms)")
        raise ValueError(f"timestep_s = {timestep_s:g} s is too long for the {relax} pads of "
                         f"{skin} ({where}): {why}; allowed timestep <= {top * 1e3:.3g} ms, or "
                         "its soft-contact representation")


#: which laws the skin pairs take: ``geometry`` (default): the law of the pair's contact class
#: (`softhand.skin.contact_classes`); ``plate``: every pair the paper's plate protocol
CONTACT_LAWS = ("geometry", "plate")


def check_contact_laws(value: str) -> str:
    """``value`` if it is one of `CONTACT_LAWS` (ValueError naming it otherwise)."""
    if value not in CONTACT_LAWS:
        raise ValueError(f"contact_laws = {show(value)}: allowed {', '.join(CONTACT_LAWS)}")
    return value


#: the name of the scene's keyframe of its grasp (`write_skin_laws`)
GRASP_KEY = "grasp"
#: the name of the scene's custom text that lists the pairs whose finger the grasp puts on a
#: rounded palm border (space-separated pair names; absent: none): the MJCF carries the choice
BORDER_PAIRS_TEXT = "softhand_border_pairs"


def _skin_first(model: mujoco.MjModel, pid: int) -> tuple[int, int]:
    """Pair ``pid``'s geoms, the prosthetic skin first (the compiler may swap a pair's order)."""
    g1, g2 = int(model.pair_geom1[pid]), int(model.pair_geom2[pid])
    if not (model.geom(g1).name or "").startswith("pro_skin_"):
        g1, g2 = g2, g1
    return g1, g2


def border_pairs(model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, str]:
    """The skin pairs of ``model`` whose finger, at the state in ``data`` (the handshake's grasp:
    `softhand.hands.grasp.set_grasp_state`), lies on a rounded palm border, each with the border
    class of its crossing there (`softhand.skin.local_geometry.state_class`, the path ``softhand
    skin apply`` takes too): pair name -> ``border/finger`` or ``border/finger@A``.

    A pair's law is one for its whole episode, so where its finger lies at the grasp decides;
    a finger that slides from the border onto the face, or turns to another crossing, keeps the
    law of where it began (the run's geometry accounting measures the force that did).
    """
    local = LocalGeometry(model)
    out = {}
    for pid in range(model.npair):
        key = state_class(model, data, *_skin_first(model, pid), local=local)
        if class_parts(key)[0] == "border":
            out[mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_PAIR, pid) or str(pid)] = key
    return out


def _border_text(borders: Mapping[str, str]) -> str:
    """`BORDER_PAIRS_TEXT`'s data: a pair's name, with ``@A`` where its class is
    ``border/finger@A``."""
    return " ".join(name + key.removeprefix("border/finger") for name, key in borders.items())


def _recorded_border_pairs(model: mujoco.MjModel) -> dict[str, str]:
    """The model's `BORDER_PAIRS_TEXT` read back (`_border_text`): pair name -> border class
    (``border/finger`` for a name without an angle: models written before the crossing laws);
    empty when it has none."""
    tid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXT, BORDER_PAIRS_TEXT)
    if tid < 0:
        return {}
    adr, size = int(model.text_adr[tid]), int(model.text_size[tid])
    out = {}
    for token in bytes(model.text_data[adr:adr + size]).rstrip(b"\0").decode().split():
        name, at, angle = token.partition("@")
        out[name] = key = f"border/finger@{angle}" if at else "border/finger"
        if key not in CLASSES:
            angles = [k.partition("@")[2] for k in CLASSES if k.startswith("border/finger@")]
            raise ValueError(f"custom text {BORDER_PAIRS_TEXT}: {token!r} has no border law; "
                             f"allowed a pair's name alone (90 deg) or with @{', @'.join(angles)}")
    return out


@dataclass(frozen=True)
class PairChoice:
    """The law one skin pair carries, and why.

    Attributes:
        contact: the pair's contact class (``body/counterpart``): from its two geoms, and
            ``border/finger`` (``border/finger@A`` at an oblique crossing) where the grasp puts
            the finger on a rounded palm border (`border_pairs`).
        law: the law it carries: the class (``phalanx/finger``...; where the skin has no law of
            its class, its `softhand.skin.contact_classes.class_fallback`'s: an oblique border
            crossing the border's law across, the border's ``palm/finger``), ``plate`` (the paper's
            protocol, by choice), ``plate (no CLASS law)`` (the skin has no law of its class),
            ``tissue`` (a ``rigid`` region: the tissue's law alone) or ``plate pad`` (a
            relaxation pad: the skin's plate law on the pad, the tissue's law in the pair).
        params: the pair's soft contact (before the inverse-inertia scaling).
        calibrated_max_N: the force up to which that law is calibrated.
    """

    contact: str
    law: str
    params: SoftContactParams
    calibrated_max_N: float


def pair_choices(model: mujoco.MjModel, skins: Mapping[str, str],
                 representations: Mapping[str, str] | None = None, *,
                 directory: str | Path = SKINS_DIR,
                 contact_laws: str = "geometry") -> dict[str, PairChoice]:
    """The law of every skin pair of ``model`` (pairs named by `add_skin_pairs`): the one
    place that decides which law a pair takes (the scene's spec, its force ranges and its
    accounting all read it). A pair is of a border class when the model's `BORDER_PAIRS_TEXT`
    lists it (`write_skin_laws` records `border_pairs` at the grasp)."""
    check_contact_laws(contact_laws)
    reps = dict(representations or {})
    tissue = series_law("rigid", str(directory))
    borders = _recorded_border_pairs(model)
    out = {}
    for pid in range(model.npair):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_PAIR, pid) or str(pid)
        key, skin = skin_of_pair(name, skins)
        region = SKIN_KEYS.get(key, key)
        rep = get_representation(skin_representation(
            key, reps.get(region, DEFAULT_REPRESENTATION)))
        g1, g2 = _skin_first(model, pid)
        contact = borders.get(name) or classify(model, g1, g2)
        if skin == "rigid":
            out[name] = PairChoice(contact, "tissue", tissue, float(DATA_MAX_N[HUMAN]))
            continue
        cal = _calibration(skin, str(directory))
        by_class = cal.pair_laws.get(contact) if contact_laws == "geometry" else None
        contact_law = contact
        if by_class is None and contact_laws == "geometry":
            # no FE curve of this class for the skin (a search's winner has no border's): the
            # nearest class's law
            contact_law = law_class(contact, cal.pair_laws) or contact
            by_class = cal.pair_laws.get(contact_law)
        if by_class is not None:
            law, params, top = contact_law, by_class.pair.params, by_class.pair.calibrated_max_N
        else:
            law = "plate" if contact_laws == "plate" or contact == PLATE_CLASS else \
                f"plate (no {contact} law)"
            params, top = series_law(skin, str(directory)), calibrated_max_force(skin,
                                                                                 str(directory))
        if type(rep).add_to_hand is not Representation.add_to_hand:
            law = "plate pad"  # the pad carries the skin's plate law; the pair the tissue's
        out[name] = PairChoice(contact, law, rep.hand_pair_law(params, tissue), float(top))
    return out


def write_skin_laws(spec: mujoco.MjSpec, skins: Mapping[str, str],
                    representations: Mapping[str, str] | None = None, *,
                    directory: str | Path = SKINS_DIR, pro: str = "pro_",
                    hand_pad: HandPad | None = None,
                    contact_laws: str = "geometry", grasp=None) -> list[str]:
    """Put each region's skin on the hand and add the skin pairs (`add_skin_pairs`) with
    their laws in ``solref``/``solimp`` (a non-sensing skin: its region's design and
    representation; default representation ``soft-contact``).

    Each pair's law is chosen by `pair_choices` (``contact_laws``: by the pair's contact
    geometry, or the plate law everywhere). With ``grasp`` (`softhand.hands.grasp.Grasp` of
    the scene), the pairs whose finger it puts on a rounded palm border (`border_pairs`) are
    recorded in the spec (`BORDER_PAIRS_TEXT`) and take the border's law. Each representation
    goes through its class
    (`softhand.skin.representations`):
    ``soft-contact`` leaves the geom as it is and gives its pairs the skin-and-tissue pair law;
    ``soft-contact+relaxation`` moves the geom onto a relaxation pad along its outward normal
    (`OUTWARD`) and gives its pairs the tissue's law alone; ``rigid``: the tissue's law.
    Everything is written into the spec before the caller compiles it, so the MJCF of the spec
    (``spec.to_xml()``, ``models/mjcf/handshake_scene.xml``) is the simulated model; with
    ``grasp``, it holds the grasp as its keyframe `GRASP_KEY`. The pair's
    inverse inertia that scales each law is read from one compile of the spec with the pairs.

    Returns:
        The pair names.
    """
    reps = dict(representations or {})
    hand_pad = hand_pad or HandPad()
    for key in skin_keys(spec, pro):
        region = SKIN_KEYS[key]
        rep = get_representation(skin_representation(
            key, reps.get(region, DEFAULT_REPRESENTATION)))
        design = skins.get(region, "rigid")
        if type(rep).add_to_hand is Representation.add_to_hand or design == "rigid":
            continue
        geom = f"{pro}skin_{key}"
        rep.add_to_hand(spec, geom, _calibration(design, str(directory)).params(rep.name),
                        outward=OUTWARD.get(key, PALMAR), hand_pad=hand_pad)
    names = add_skin_pairs(spec, pro=pro)
    model = spec.compile()
    if grasp is not None:
        from softhand.hands.grasp import set_grasp_state

        at = mujoco.MjData(model)
        set_grasp_state(model, at, grasp)
        # the grasp as a keyframe: the state the pairs' classes are read at, for a viewer and
        # for ``softhand skin apply --keyframe grasp`` (the same classes, tests/test_skin_apply.py)
        spec.add_key(name=GRASP_KEY, qpos=at.qpos.tolist())
        borders = border_pairs(model, at) if contact_laws == "geometry" else {}
        if borders:
            spec.add_text(name=BORDER_PAIRS_TEXT, data=_border_text(borders))
        model = spec.compile()
    choices = pair_choices(model, skins, reps, directory=directory, contact_laws=contact_laws)
    issues: list[RangeIssue] = []  # one SkinRangeWarning for all the pairs
    data = mujoco.MjData(model)  # qpos0, for every pair's mobility
    mujoco.mj_forward(model, data)
    for name in names:
        pair = spec.pair(name)
        pair.solref, pair.solimp = pair_law_values(model, name, choices[name].params,
                                                   issues=issues, data=data)
    warn_range_issues(issues)
    return names
