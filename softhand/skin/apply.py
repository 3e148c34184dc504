"""Give the geoms of any MJCF hand a calibrated skin (``softhand skin apply``).

For a hand softhand did not build (a MuJoCo Menagerie-style MJCF: default classes, tendons or
equality couplings, any number of fingers), `apply_skin` turns named geoms into calibrated
skin pads on an `mujoco.MjSpec`:

* each named geom gets ``contype = conaffinity = 0`` and one explicit ``<pair>`` with every
  counterpart geom (``against``; default: every geom outside the hand's subtree that can collide,
  i.e. with a non-zero ``contype`` or ``conaffinity``), so that no stock contact duplicates the
  calibrated one;
* each pair carries the design's law in its ``solref``/``solimp`` in MuJoCo's direct form, scaled
  by the pair's inverse inertia from one compile of the spec (the compiler's ``body_invweight0``,
  which MuJoCo's constraint solver uses at every posture): the force at a given penetration is
  the law's, whatever the hand's masses and posture ("mass-compensated", as the handshake);
* the counterparts are rigid (a plate, an object): the pair's law is the skin's own
  (`softhand.skin.soft_contact.SoftContactParams`), from the shipped calibration. The
  shipped soft contact is fitted to the whole 0-20 N FE loading curve; ``max_force_N`` instead
  fits it, in closed form, to the shipped FE loading curve up to that force, which is more
  accurate below it (`skin_law_error` measures it; pocket2-sil fitted to 5 N follows its FE
  curve up to 2 N within 3 % RMS of 2 N on a fingertip, tests/test_skin_apply.py);
* each pair's law follows its contact class, read by the path the handshake's scene takes
  (`softhand.skin.local_geometry.state_class`): a round skinned geom (capsule, cylinder, sphere,
  ellipsoid) is a phalanx, a flat one (mesh, box) a palm; a counterpart round up to 15 mm in
  radius presses like a finger, anything else like a flat; and a finger that lies, at the
  model's qpos0 or at the ``keyframe`` given, within 5 mm of a mesh palm where its hull is a
  rounded border presses that border, at its crossing angle (``border/finger``,
  ``border/finger@60``, ``border/finger@30``). A pair's class is read once, at that state, as
  the scene reads its pairs' at the grasp: a finger that slides from the face onto the border
  keeps its first class (the scene's run measures the force that did: its geometry accounting).
  The phalanx pressed by a flat takes the shipped law (the paper's plate); the other classes the
  skin's law of that class (or of its nearest class the skin has,
  `softhand.skin.contact_classes.law_class`, as in the scene), fitted in closed form to its
  loading ramp (a finger-sized cylinder on a phalanx carries 0.5-0.8x the plate's force at equal
  depth); a class the skin has no law of takes the plate law, and the header says so for each
  pair;
* the law is MuJoCo's per contact point: a skinned geom that meets a counterpart in two points
  at once is twice as stiff as the law. MuJoCo's capsule-box and capsule-plane colliders make two
  contacts of a capsule lying flat on a face, and its convex-convex collider (meshes) makes
  several when the ``multiccd`` flag is on (the default): the handshake turns multiccd off (it had
  15 % of its force in two-contact capsule-on-mesh pairs); for a model of your own, turn it off
  too when a skinned geom or its counterpart is a mesh. Skin geoms that touch in one point (a
  fingertip's cap, a sphere, an ellipsoid) follow the law exactly;
* a skinned geom touches only its counterparts: name the hand's own geoms with ``against`` for
  self-contact;
* representations: ``soft-contact`` (default) and ``rigid`` (the stock contact, kept as a pair
  for comparison). A relaxation pad needs the skin's outward normal and a body of its own
  (`softhand.skin.representations.add_hand_pad` does that for a known normal);
  ``flex`` needs the ``discrete`` integrator (softhand.hands.flex_region).

The result is plain MJCF that plain MuJoCo loads: `write_skinned` writes the *source
file's own text* with only these changes spliced in (collision flags of the skinned geoms, the
``<pair>`` elements, absolute asset paths when the output is in another folder), lists them
(`ModelChange`) and records them, the designs, laws and softhand version in a header
comment; comments, attribute order, indentation and includes stay as the user wrote them
(`softhand.skin.mjcf_edit`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from softhand import __version__
from softhand.laws.fit import REFERENCE_FORCE_N
from softhand.paths import FE_DIR, SKINS_DIR
from softhand.skin.contact_classes import PLATE_CLASS, law_class
from softhand.skin.local_geometry import LocalGeometry, state_class
from softhand.skin.representations import StockContact, get_representation, loading_ramp
from softhand.skin.rig import RangeIssue, pair_law_values, warn_range_issues
from softhand.skin.soft_contact import SoftContactParams, fit_soft_contact

__all__ = ["APPLY_REPRESENTATIONS", "ModelChange", "SkinnedFile", "SkinnedGeom", "apply_skin",
           "check_keyframe", "check_skinnable", "parse_geom_skins", "skin_law_error",
           "skinned_text", "write_skinned"]

#: the representations skin apply writes (the others need a body per pad, or are rig-only)
APPLY_REPRESENTATIONS = ("soft-contact", "rigid")
MAX_FORCE_RANGE_N = (0.5, 20.0)


@dataclass(frozen=True)
class SkinnedGeom:
    """One skinned geom: its design, representation, law, and the pairs made for it."""

    geom: str
    design: str
    representation: str
    law: SoftContactParams | None
    pairs: tuple[str, ...]
    fit_range_N: float | None  # None: the shipped 0-20 N law
    #: per pair: the contact class of its two geoms and the law it got (the class, or
    #: ``plate`` where the skin has no law of the class; `softhand.skin.contact_classes`)
    pair_laws: dict[str, str] = field(default_factory=dict)
    #: the geom's (contype, conaffinity) before it was skinned (after its default classes)
    flags_before: tuple[int, int] = (0, 0)


def parse_geom_skins(items: Mapping[str, str] | Sequence[str]) -> dict[str, tuple[str, str]]:
    """``GEOM=DESIGN[@REPRESENTATION]`` items (or a mapping geom -> ``DESIGN[@REP]``) to
    geom -> (design, representation); ValueError naming a malformed item."""
    if isinstance(items, Mapping):
        pairs = list(items.items())
    else:
        pairs = []
        for item in items:
            geom, sep, choice = str(item).partition("=")
            if not sep or not geom.strip() or not choice.strip():
                raise ValueError(f"--geom {item!r}: expected GEOM=DESIGN[@REPRESENTATION] "
                                 "(e.g. index_tip=pocket2-sil)")
            pairs.append((geom.strip(), choice.strip()))
    out = {}
    for geom, choice in pairs:
        design, _, rep = str(choice).partition("@")
        out[geom] = (design, rep or "soft-contact")
    return out


def _subtree_root(spec: mujoco.MjSpec, bodies: list[mujoco.MjsBody]) -> mujoco.MjsBody:
    """The child of the world whose subtree holds every body of ``bodies`` (the hand)."""
    world = spec.worldbody

    def top(body: mujoco.MjsBody) -> mujoco.MjsBody:
        while body.parent is not None and body.parent != world:
            body = body.parent
        return body

    roots = {top(b).name for b in bodies}
    if len(roots) != 1:
        raise ValueError(f"the skinned geoms lie on {len(roots)} separate bodies of the world "
                         f"({', '.join(sorted(roots))}): skin one hand at a time, or name the "
                         "counterparts with against=")
    return top(bodies[0])


def _subtree_geoms(body: mujoco.MjsBody) -> set[str]:
    names = {g.name for g in body.geoms}
    for child in body.bodies:
        names |= _subtree_geoms(child)
    return names


def _law(design: str, max_force_N: float | None, skins_dir, fe_dir) -> SoftContactParams:
    from softhand.skin.calibrate import fe_curves, law_curve
    from softhand.skin.files import load_calibration

    cal = load_calibration(design, skins_dir, require=("soft-contact",))
    if max_force_N is None:
        return cal.soft_contact
    try:
        curve = fe_curves(design, fe_dir)[0][0]
    except FileNotFoundError:
        curve = law_curve(cal.law)  # reference skins: their paper-based law
    _, d, f = loading_ramp(curve, max_force_N)
    return fit_soft_contact(d, f).params


def _class_law(design: str, key: str, max_force_N: float | None, skins_dir
               ) -> tuple[str, SoftContactParams] | None:
    """The skin's own soft contact for contact class ``key`` (a rigid counterpart): (the class
    whose law it is: ``key``, or the nearest the skin has, `law_class`; the soft contact fitted
    to the loading ramp of that law, to ``max_force_N``, default 20 N); None when the skin has
    no law of the class nor of a fallback."""
    from softhand.skin.calibrate import law_curve
    from softhand.skin.files import load_calibration

    cal = load_calibration(design, skins_dir)
    key = law_class(key, cal.pair_laws)
    if key is None:
        return None
    c = cal.pair_laws[key]
    _, d, f = loading_ramp(law_curve(c.law), max_force_N or MAX_FORCE_RANGE_N[1])
    # one start from the skin's plate soft contact (the multi-start search takes ~20 s)
    return key, fit_soft_contact(d, f, initial=cal.soft_contact).params


def skin_law_error(design: str, law: SoftContactParams, *, top_N: float = REFERENCE_FORCE_N,
                   fe_dir: str | os.PathLike = FE_DIR,
                   skins_dir: str | os.PathLike = SKINS_DIR) -> float:
    """RMS error (% of 2 N) of ``law`` against the design's FE loading curve up to ``top_N``."""
    from softhand.skin.calibrate import fe_curves, law_curve
    from softhand.skin.files import load_calibration

    try:
        curve = fe_curves(design, fe_dir)[0][0]
    except FileNotFoundError:
        curve = law_curve(load_calibration(design, skins_dir).law)
    _, d, f = loading_ramp(curve, top_N)
    return float(100 * np.sqrt(np.mean((law.force(d) - f) ** 2)) / REFERENCE_FORCE_N)


def check_keyframe(spec: mujoco.MjSpec, keyframe: str | None) -> int | None:
    """The index of keyframe ``keyframe`` of ``spec`` (None for None); ValueError naming it and
    the model's keyframes when it has no such keyframe."""
    if keyframe is None:
        return None
    keys = [k.name for k in spec.keys]
    if keyframe not in keys:
        raise ValueError(f"keyframe {keyframe!r}: the model has "
                         + (f"the keyframes {', '.join(repr(k) for k in keys)}" if keys else
                            "no keyframe (its pairs' classes are read at qpos0 without one)"))
    return keys.index(keyframe)


def apply_skin(spec: mujoco.MjSpec, geoms: Mapping[str, str] | Sequence[str], *,
               against: Sequence[str] | None = None, max_force_N: float | None = None,
               keyframe: str | None = None, skins_dir: str | os.PathLike = SKINS_DIR,
               fe_dir: str | os.PathLike = FE_DIR) -> list[SkinnedGeom]:
    """Make the named geoms of ``spec`` calibrated skin pads (see the module docstring).

    Args:
        spec: the hand (and its world), e.g. ``mujoco.MjSpec.from_file("hand.xml")``.
        geoms: geom -> ``DESIGN[@REPRESENTATION]``, or ``GEOM=DESIGN[@REPRESENTATION]`` items.
        against: the counterpart geoms (default: every collidable geom outside the hand).
        max_force_N: fit each law to its FE loading curve up to this force, in [0.5, 20] N
            (default: the shipped 0-20 N law).
        keyframe: the name of a keyframe of ``spec`` whose state the pairs' contact classes
            are read at (default: the model's qpos0): the posture where the hand holds what it
            touches (the handshake scene's is ``grasp``).
        skins_dir, fe_dir: the calibration (default: the shipped one).

    Returns:
        One `SkinnedGeom` per named geom. Everything is checked before ``spec`` is
        changed.

    Raises:
        ValueError: an unknown geom, design or representation, an unknown counterpart, no
            counterpart, ``max_force_N`` out of range, or an unknown keyframe: naming the
            value.
    """
    from softhand.skin.calibrate import skin_names
    from softhand.skin.files import shipped_skins

    chosen = parse_geom_skins(geoms)
    if not chosen:
        raise ValueError("no geom to skin: give at least one GEOM=DESIGN")
    if max_force_N is not None:
        lo, hi = MAX_FORCE_RANGE_N
        if not (isinstance(max_force_N, (int, float)) and np.isfinite(max_force_N)
                and lo <= max_force_N <= hi):
            raise ValueError(f"max_force_N = {max_force_N!r}: expected a number of newtons in "
                             f"[{lo:g}, {hi:g}] (the FE curves reach 20 N)")
    check_keyframe(spec, keyframe)
    known = {g.name for g in spec.geoms}
    calibrated = set(shipped_skins(skins_dir))
    for geom, (design, rep) in chosen.items():
        if geom not in known:
            raise ValueError(f"geom {geom!r} is not in the model; it has {len(known)} named geoms "
                             f"(e.g. {', '.join(sorted(n for n in known if n)[:5])})")
        if design not in calibrated:
            allowed = [s for s in skin_names() if s in calibrated]
            raise ValueError(f"skin {design!r} for geom {geom} is unknown; allowed: "
                             f"{', '.join(allowed)}")
        if rep not in APPLY_REPRESENTATIONS:
            get_representation(rep)  # an unknown name: its own message
            raise ValueError(f"representation {rep!r} for geom {geom} is not written by skin "
                             f"apply (allowed: {', '.join(APPLY_REPRESENTATIONS)}): a relaxation "
                             "pad needs its own body along the skin's normal "
                             "(softhand.skin.representations.add_hand_pad), a flex pad its own "
                             "scene (softhand.hands.flex_region)")
    root = _subtree_root(spec, [spec.geom(g).parent for g in chosen])
    hand = _subtree_geoms(root)
    if against is None:
        others = [g.name for g in spec.geoms if g.name not in hand
                  and (g.contype or g.conaffinity)]
        if not others and root.name == spec.worldbody.name:
            raise ValueError(f"the skinned geoms {', '.join(chosen)} meet only in the world body "
                             "(a geom of the world, or of two separate bodies), so every geom of "
                             "the model counts as the skinned hand and none is left to press it: "
                             "name the counterparts with --against")
        if not others:
            raise ValueError(f"no collidable geom outside the hand (body {root.name!r}) to press "
                             "the skin against: name the counterparts with --against")
        for g in spec.geoms:
            if g.name not in hand and (g.contype or g.conaffinity) and not g.name:
                raise ValueError("a collidable geom outside the hand has no name: name it, or "
                                 "give the counterparts with --against")
    else:
        others = list(dict.fromkeys(against))
        for name in others:
            if name not in known:
                raise ValueError(f"--against geom {name!r} is not in the model")
            if name in chosen:
                raise ValueError(f"--against geom {name!r} is one of the skinned geoms")
    laws = {design: _law(design, max_force_N, skins_dir, fe_dir)
            for design, rep in chosen.values() if rep == "soft-contact"}
    made: dict[str, list[str]] = {}
    before: dict[str, tuple[int, int]] = {}
    for geom in chosen:
        g = spec.geom(geom)
        before[geom] = (int(g.contype), int(g.conaffinity))
        g.contype, g.conaffinity = 0, 0
        made[geom] = []
        for other in others:
            name = f"skin_{geom}__{other}"
            friction = np.maximum(np.asarray(g.friction), np.asarray(spec.geom(other).friction))
            spec.add_pair(name=name, geomname1=geom, geomname2=other, condim=3,
                          friction=[float(friction[0]), float(friction[0]),
                                    float(friction[1]), float(friction[2]),
                                    float(friction[2])])
            made[geom].append(name)
    model = spec.compile()
    data = mujoco.MjData(model)  # qpos0, for every pair's mobility
    mujoco.mj_forward(model, data)
    at = data  # the state the pairs' classes are read at
    if keyframe is not None:
        at = mujoco.MjData(model)
        mujoco.mj_resetDataKeyframe(model, at, check_keyframe(spec, keyframe))
        mujoco.mj_kinematics(model, at)
    local = LocalGeometry(model)
    out = []
    issues: list[RangeIssue] = []  # one SkinRangeWarning for all the pairs
    by_class: dict[tuple[str, str], tuple[str, SoftContactParams] | None] = {}
    for geom, (design, rep) in chosen.items():
        law = laws.get(design) if rep == "soft-contact" else None
        used = {}
        for name in made[geom]:
            pair = spec.pair(name)
            pid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_PAIR, name)
            # the skin's side by its name: MuJoCo's compiler may put the other geom first (a
            # world geom, a table or a fixed plate, is always pair_geom1)
            skin = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, geom)
            g1, g2 = int(model.pair_geom1[pid]), int(model.pair_geom2[pid])
            key = state_class(model, at, skin, g2 if g1 == skin else g1, local=local)
            if law is None:  # rigid: MuJoCo's stock contact
                stock = StockContact()
                pair.solref, pair.solimp = list(stock.solref), list(stock.solimp)
                used[name] = f"{key}: stock contact"
                continue
            this = law  # the plate law: the paper's protocol and every class without a law
            used[name] = key
            if key != PLATE_CLASS:
                if (design, key) not in by_class:
                    by_class[(design, key)] = _class_law(design, key, max_force_N, skins_dir)
                found = by_class[(design, key)]
                if found is None:
                    used[name] = f"{key}: plate law"
                else:
                    this = found[1]
                    if found[0] != key:
                        used[name] = f"{key}: {found[0]} law"
            pair.solref, pair.solimp = pair_law_values(model, name, this, issues=issues,
                                                       data=data)
        out.append(SkinnedGeom(geom, design, rep, law, tuple(made[geom]),
                               None if law is None else max_force_N, used, before[geom]))
    warn_range_issues(issues)
    return out


@dataclass(frozen=True)
class ModelChange:
    """One change ``skin apply`` makes to the user's MJCF: the element (as a tag that finds it in
    the file) and what changed (``contype 1 -> 0``, ``added: ...``)."""

    element: str
    change: str

    def to_dict(self) -> dict[str, str]:
        return {"element": self.element, "change": self.change}

    def __str__(self) -> str:
        return f"{self.element}: {self.change}"


@dataclass(frozen=True)
class SkinnedFile:
    """What `write_skinned` wrote: the file (``str()`` and ``os.fspath`` give its path)
    and every change made to the source, in file order of kind (flags, pairs, paths)."""

    path: Path
    changes: tuple[ModelChange, ...]

    def __fspath__(self) -> str:
        return str(self.path)

    def __str__(self) -> str:
        return str(self.path)


ASSET_FILES = {"mesh": ("file",), "hfield": ("file",), "skin": ("file",),
               "texture": ("file", "fileright", "fileleft", "fileup", "filedown", "filefront",
                           "fileback")}


def check_skinnable(source: str | os.PathLike, geoms: Sequence[str]) -> None:
    """Check, before any work, that `write_skinned` can edit ``source`` for ``geoms``:
    the file is well-formed MJCF and each geom is written by name in it (not only in a file it
    includes, which skin apply does not rewrite, nor made by ``<replicate>``).

    Raises:
        ValueError: naming the file, the geom and where it is.
    """
    from softhand.skin.mjcf_edit import MjcfEditor, MjcfError

    try:
        editor = MjcfEditor.from_file(source)
    except (OSError, MjcfError) as exc:
        raise ValueError(str(exc)) from None
    src = Path(source).resolve().parent
    for geom in geoms:
        found = editor.find("geom", name=geom)
        if len(found) == 1:
            continue
        if len(found) > 1:
            raise ValueError(f"geom {geom!r} is written {len(found)} times in {editor.name}")
        where = ""
        for inc in editor.find("include"):
            path = src / inc.attrs.get("file", "")
            try:
                if MjcfEditor.from_file(path).find("geom", name=geom):
                    where = f" (it is in the included file {inc.attrs['file']!r})"
            except (OSError, MjcfError):
                continue
        raise ValueError(f"geom {geom!r} is not written by name in {editor.name}{where}: skin "
                         "apply edits only the file given (it writes one file and keeps the "
                         "files it includes as they are); give it the file that defines the "
                         "geom, with its counterparts, or paste the include into it")


def _numbers(values) -> str:
    return " ".join(repr(float(v)) for v in values)


def _absolute_paths(editor, src: Path, changes: list[ModelChange]) -> None:
    """Make the file's relative asset folders and includes absolute (the output lives in
    another folder than the source)."""
    from softhand.skin.mjcf_edit import MjcfEditor, MjcfError

    def absolute(value: str) -> str:
        return str((src / value).resolve())

    for inc in editor.find("include"):
        value = inc.attrs.get("file", "")
        if value and not Path(value).is_absolute():
            editor.set_attr(inc, "file", absolute(value))
            changes.append(ModelChange(f'<include file="{value}">',
                                       f"file made absolute: {absolute(value)}"))
    compilers = editor.find("compiler")
    dirs = {}
    for comp in compilers:
        for attr in ("assetdir", "meshdir", "texturedir"):
            value = comp.attrs.get(attr)
            if value is None:
                continue
            dirs[attr] = value
            if not Path(value).is_absolute():
                editor.set_attr(comp, attr, absolute(value))
                changes.append(ModelChange("<compiler>", f"{attr} {value!r} made absolute: "
                                                         f"{absolute(value)}"))
    files = [editor] + [e for e in (_try_editor(src / i.attrs.get("file", ""), MjcfEditor,
                                                MjcfError) for i in editor.find("include")) if e]
    need = set()
    for ed in files:
        for tag, attrs in ASSET_FILES.items():
            for el in ed.find(tag):
                if any(el.attrs.get(a) and not Path(el.attrs[a]).is_absolute() for a in attrs):
                    need.add("texturedir" if tag == "texture" else "meshdir")
    add = sorted(a for a in need if a not in dirs and "assetdir" not in dirs)
    if not add:
        return
    if compilers:
        for attr in add:
            editor.set_attr(compilers[0], attr, str(src))
            changes.append(ModelChange("<compiler>", f"{attr} added: {src} (the source's "
                                                     "folder, where its relative asset files are)"))
    else:
        attrs = " ".join(f'{a}="{src}"' for a in add)
        editor.prepend_child(editor.root, f"<compiler {attrs}/>".encode())
        changes.append(ModelChange("<compiler>", f"added as the first element, {', '.join(add)} "
                                                 f"= {src} (the source's folder, where its "
                                                 "relative asset files are)"))


def _try_editor(path, cls, error):
    try:
        return cls.from_file(path)
    except (OSError, error):
        return None


def skinned_text(spec: mujoco.MjSpec, skinned: list[SkinnedGeom], source: str | os.PathLike,
                 out: str | os.PathLike) -> tuple[bytes, tuple[ModelChange, ...]]:
    """The text of ``source`` with the changes `apply_skin` made to ``spec``, and the list
    of them (see `write_skinned`)."""
    from softhand.skin.mjcf_edit import MjcfEditor

    check_skinnable(source, [s.geom for s in skinned])
    editor = MjcfEditor.from_file(source)
    changes: list[ModelChange] = []
    for s in skinned:
        (el,) = editor.find("geom", name=s.geom)
        parts = []
        for key, old in zip(("contype", "conaffinity"), s.flags_before, strict=True):
            if old != 0:
                editor.set_attr(el, key, "0")
                parts.append(f"{key} {old} -> 0")
        what = (", ".join(parts) + " (it touches its counterparts only through its pairs)"
                if parts else "contype and conaffinity already 0: unchanged")
        changes.append(ModelChange(f'<geom name="{s.geom}">', what))
    lines = []
    for s in skinned:
        for name in s.pairs:
            p = spec.pair(name)
            lines.append(f'<pair name="{name}" geom1="{p.geomname1}" geom2="{p.geomname2}" '
                         f'condim="{p.condim}" friction="{_numbers(p.friction)}" '
                         f'solref="{_numbers(p.solref)}" solimp="{_numbers(p.solimp)}"/>')
            used = s.pair_laws.get(name, "")  # "class", or "class: the law it took instead"
            law = ("MuJoCo's stock contact" if s.law is None else
                   f"{s.design} soft contact, {used}" + ("" if ":" in used else " law"))
            changes.append(ModelChange(f'<pair name="{name}">',
                                       f"added: {p.geomname1} against {p.geomname2}, {law}"))
    contacts = [c for c in editor.root.children if c.tag == "contact"]
    if contacts:
        for line in lines:
            editor.append_child(contacts[-1], line.encode())
    elif lines:
        nl, inner = editor.newline, editor.child_indent(editor.root) + editor.indent_unit()
        outer = editor.child_indent(editor.root)
        block = (b"<contact>" + b"".join(nl + inner + line.encode() for line in lines)
                 + nl + outer + b"</contact>")
        editor.append_child(editor.root, block)
        changes.insert(len(skinned), ModelChange("<contact>", "added at the end of <mujoco> "
                                                              "(the model had none): the pairs"))
    src = Path(source).resolve().parent
    if Path(out).resolve().parent != src:
        _absolute_paths(editor, src, changes)
    header = [f"Skinned by softhand {__version__} (softhand skin apply) from {Path(source).name}; "
              f"MuJoCo {mujoco.__version__}.",
              "Laws: shipped calibration, mass-compensated per pair."]
    for s in skinned:
        fit = ("MuJoCo's stock contact" if s.law is None
               else "shipped 0-20 N law" if s.fit_range_N is None
               else f"soft contact fitted to the FE loading curve up to {s.fit_range_N:g} N")
        n = len(s.pairs)
        header.append(f"{s.geom}: {s.design}@{s.representation} ({fit}), {n} pair{'s' * (n != 1)}; "
                      + ", ".join(f"{p}: {k}" for p, k in s.pair_laws.items()))
    header.append(f"Changed from {Path(source).name} (the rest is as written there):")
    header += [f"  {c}" for c in changes]
    nl = editor.newline.decode()
    body = nl.join(f"  {line}".replace("--", "- -") for line in header)
    editor.insert_at_top(f"<!--{nl}{body}{nl}-->{nl}".encode())
    return editor.text(), tuple(changes)


def write_skinned(spec: mujoco.MjSpec, skinned: list[SkinnedGeom], source: str | os.PathLike,
                  out: str | os.PathLike) -> SkinnedFile:
    """Write the skinned model to ``out`` (atomically) as the text of ``source`` with only the
    changes `apply_skin` made, and return them with the path.

    The changes, each listed in `SkinnedFile.changes` and in a header comment at the top
    of the file:

    * each skinned geom's ``contype`` and ``conaffinity`` set to 0 where they were not (the old
      values are the geom's after its default classes; an attribute written in the tag gets its
      new value in place, a missing one is added after the tag's last attribute);
    * one ``<pair>`` per skinned geom and counterpart, after the last child of the file's last
      top-level ``<contact>`` (a new ``<contact>`` at the end of ``<mujoco>`` if it has none),
      with the pair's geoms, ``condim``, ``friction``, ``solref`` and ``solimp`` (the law, in
      full precision);
    * when ``out`` is in another folder than ``source``: relative ``<include file>``,
      ``<compiler>`` ``assetdir``/``meshdir``/``texturedir`` made absolute, and ``meshdir`` or
      ``texturedir`` (set to the source's folder) added to ``<compiler>`` (or a new first
      ``<compiler>``) when relative asset files need it, so that the file loads from anywhere.

    Everything else is kept byte for byte (`softhand.skin.mjcf_edit`): comments, attribute
    and element order, indentation, blank lines, quotes, character references, ``<include>``
    and defaults. A new element takes the indentation of its parent's first child and the
    file's line ending; its attributes are in double quotes (single where the edited tag uses
    them). The written file is loaded with MuJoCo and checked against the skinned ``spec``
    (geoms' collision flags and every pair's values) before it replaces ``out``.

    Raises:
        ValueError: a geom is not written by name in ``source`` (`check_skinnable`), or
            the written file does not compile to the skinned spec.
    """
    import tempfile

    from softhand.io import atomic_open

    text, changes = skinned_text(spec, skinned, source, out)
    expected = spec.compile()
    path = Path(out)
    path.parent.mkdir(parents=True, exist_ok=True)
    # checked from a file in the output's folder, where its relative paths resolve
    fd, probe = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".check.xml", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(text)
        try:
            got = mujoco.MjModel.from_xml_path(probe)
        except ValueError as exc:
            raise ValueError(f"the skinned {path.name} does not load in MuJoCo: "
                             f"{str(exc).splitlines()[0]}") from None
    finally:
        os.unlink(probe)
    for attr in ("geom_contype", "geom_conaffinity", "pair_geom1", "pair_geom2", "pair_dim",
                 "pair_friction", "pair_solref", "pair_solimp", "pair_margin", "pair_gap"):
        if not np.array_equal(getattr(got, attr), getattr(expected, attr)):
            raise ValueError(f"the skinned {path.name} compiles to other {attr} than the skinned "
                             "model (a softhand bug: please report it with the source file)")
    with atomic_open(path, "wb") as fh:
        fh.write(text)
    return SkinnedFile(path, changes)
