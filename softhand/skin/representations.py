"""The MuJoCo representations of a skin, one class each, in one registry.

A representation is how a calibrated skin law becomes MuJoCo elements. Each class here is the
whole contract of its level of detail, and every stage goes through it (the rig, ``softhand
calibrate``, the benchmarks, the hands): adding a representation means adding a class here.

Each representation, the MuJoCo elements it adds, and its memory (relaxation):

- ``rigid``: the geom's stock contact (MuJoCo's defaults); no memory, and no law
- ``soft-contact``: the pair's solref/solimp, fitted to the loading curve
  (`softhand.skin.soft_contact`); no memory: the 0.5 mm/s loading curve
- ``soft-contact+relaxation``: a pad body on a slide joint with the QLV law's spline spring and
  Maxwell branches (`softhand.skin.pad`); QLV, exact for the law's Prony terms
- ``flex``: a tetrahedral flex pad (`softhand.skin.flex`); no memory (SVK solid)

Every class provides: `Representation.fit` (from a skin law and its FE curve),
`parse` / `to_dict` (the calibration file),
`add_to_rig` and `rig_contact` (the indentation rig of
`softhand.skin.rig`), `add_to_hand` and
`hand_pair_law` (a skin geom of an articulated hand against the other hand's
tissue). Its fitted error and cost are measured in the rig by ``softhand calibrate`` and
``softhand bench calibration`` (the representation's ``RepresentationResult``).

On a hand, the relaxation pad is a *hand pad* (`HandPad`): the skin geom rides a pad body
that slides along the skin's outward normal under the segment, with the QLV law as its spring and
branches; the pair against the partner's tissue carries the tissue's law alone, so that skin and
tissue are in series mechanically. It runs under the hand's ``implicitfast`` integrator at 2 ms
thanks to the pad joint's armature (HandPad.armature_kg; the rig's pad, pressed by a rigid
plate through a stiff contact, needs the ``discrete`` integrator instead). Under the
``discrete`` integrator the calibrated soft contacts do not hold (MuJoCo folds each row's
spring into its impedance: the rig's loading error went from 6 % to thousands of % of 2 N), so the
hand stays on ``implicitfast``. The pad compresses along its normal only: a contact from the side
of a phalanx meets the tissue's law alone.

For the same reason a ``flex`` region lives in its own scene, the hand alone with one phalanx
wearing the pad (`softhand.hands.flex_region`, ``softhand skin flex-press``): there the pad
on the articulated finger follows the rig's curve, extended and flexed (the error is measured by
``softhand bench flex``, ``reports/bench-flex.md``), with its
contact area and pressure (`softhand.skin.flex.contact_patch`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, ClassVar

import mujoco
import numpy as np

from softhand.laws.elastic import monotone_inverse
from softhand.laws.fit import REFERENCE_FORCE_N, Curve, SkinLaw, split_errors
from softhand.skin.pad import PadParams, add_pad
from softhand.skin.soft_contact import SoftContactParams, fit_soft_contact
from softhand.validate import check_mapping, check_number, check_numbers, join

__all__ = ["REPRESENTATIONS", "Fitted", "Flex", "HandPad", "Relaxation", "Representation",
           "Rigid", "SoftContact", "StockContact", "add_hand_pad", "get_representation",
           "hand_pad_params", "loading_ramp", "pad_contact"]

#: MuJoCo's default contact (solref, solimp), the ``rigid`` baseline
STOCK_SOLREF = (0.02, 1.0)
STOCK_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)


@dataclass(frozen=True)
class StockContact:
    """The ``rigid`` representation's parameters: MuJoCo's stock contact."""

    solref: tuple[float, float] = STOCK_SOLREF
    solimp: tuple[float, float, float, float, float] = STOCK_SOLIMP

    def to_dict(self) -> dict:
        return {"solref": list(self.solref), "solimp": list(self.solimp)}


@dataclass(frozen=True)
class Fitted:
    """What `Representation.fit` found.

    Attributes:
        params: the representation's parameter object (`Representation.parse` makes the
            same object from the file).
        record: the curve it is checked on in the rig (None: it was checked in its own rig and
            ``errors`` holds the result).
        extra: fit details kept in the calibration file (status, closed-form errors, ...).
        errors: for a representation with its own rig: rms and max error (% of 2 N), step_us,
            rig simulations.
    """

    params: Any
    record: Curve | None
    extra: dict[str, Any] = field(default_factory=dict)
    errors: dict[str, float] | None = None


@dataclass(frozen=True)
class HandPad:
    """Settings of the relaxation pad on an articulated hand (see the module docstring).

    Attributes:
        armature_kg: armature of the pad's slide joint (kg): inertia that makes the pad's spline
            spring stable under ``implicitfast`` at 2 ms (the pad alone, 5 g, is not: omega h > 2
            for the stiffest skins). 10 g: a region's pad then follows the QLV law at its own
            compression to 0.8-3.6 % of the held force over a 2 s hold (measured with shipped
            designs pressed to about 3 N through human tissue; the largest, pocket2-pu).
        n_knots: pieces of the branches' piecewise-linear law (each Prony term adds this many
            branch dofs per skin geom). 6, as in the rig: with 3 the pocket's stiffening is
            poorly split among the branches (pocket2-pu: 20 % of the held force off the law
            instead of 3.6 %, and a third of its relaxation).
        max_compression_m: the pad's joint limit, the skin's thickness over the bone. Both
            ends of the pad's range (its rest and the bone) are MuJoCo's stiffest limit the
            timestep resolves (solref time constant 2 timesteps, critically damped): with
            MuJoCo's default (20 ms) a 3.7 N push from behind drove a 15 g pad 3 mm past its
            rest.

    The pad's spring is integrated explicitly (``implicitfast`` is implicit in velocity only,
    and the pad dof has no damping; its branches lock on a step's time scale, so it feels the
    law's instantaneous stiffness): the pad is stable while omega h < 2, omega = sqrt(K / m),
    K the law's stiffness and m the pad's 5 g plus the armature. `max_timestep_s` gives
    the largest timestep for a law up to a force.
    """

    armature_kg: float = 0.01
    n_knots: int = 6
    max_compression_m: float = 0.006

    def __post_init__(self) -> None:
        check_number("armature_kg", self.armature_kg, lo=0.0, lo_open=True, hi=1.0)
        check_number("n_knots", self.n_knots, lo=1, hi=50, integer=True)
        check_number("max_compression_m", self.max_compression_m, lo=0.0, lo_open=True, hi=0.05)

    def max_timestep_s(self, law: SkinLaw, force_N: float) -> tuple[float, float, float, float]:
        """The largest timestep (s) at which a hand pad of ``law`` is stable up to ``force_N``,
        with the numbers behind it: the law's stiffest point up to that force (N/m), its
        compression there (mm) and the pad's moving mass (kg): ``h = 2 sqrt(m / K)``.

        Measured on one pocket2-sil pad pressed through human tissue to 7 N (a 1 kg mount,
        tests/test_divergence.py): its force holds to 1 % up to 2.9 ms, oscillates off the law
        from 3.05 ms and ends stuck at 33 N at 3.3 ms, without a MuJoCo warning (this bound:
        2.65 ms; the tissue in series softens the pad a little).
        """
        e = law.elastic
        top = min(float(force_N), float(e.force(e.max_mm)))
        x = np.linspace(0.0, float(e.displacement_at(top)), 400)
        k = float(np.max(e.stiffness(x))) * 1e3  # N/mm -> N/m
        mass = hand_pad_params(law, self).pad_mass_kg + self.armature_kg
        return 2.0 * float(np.sqrt(mass / k)), k, float(x[-1]), mass

    def max_stable_force(self, law: SkinLaw, timestep_s: float) -> tuple[float, float]:
        """The largest force (N) up to which a hand pad of ``law`` is stable at ``timestep_s``
        (inf: everywhere), and the stiffness it may reach there, ``K = 4 m / h^2`` (N/m); the
        inverse of `max_timestep_s`."""
        e = law.elastic
        mass = hand_pad_params(law, self).pad_mass_kg + self.armature_kg
        k_max = 4.0 * mass / float(timestep_s) ** 2
        x = np.linspace(0.0, e.max_mm, 2000)
        over = np.flatnonzero(e.stiffness(x) * 1e3 > k_max)
        return (float(e.force(x[over[0]])) if over.size else float("inf")), k_max


class Representation(ABC):
    """One way to put a skin law into MuJoCo (see the module docstring)."""

    #: the name used in calibration files, the CLI and the env
    name: ClassVar[str]
    #: the rig's integrator (RigSettings.integrator None picks it)
    rig_integrator: ClassVar[str] = "implicitfast"
    #: None when the handshake's hands take it as a skin geom, else why not (one line, for the
    #: error message)
    not_on_hand: ClassVar[str | None] = None

    @abstractmethod
    def parse(self, params: Any, law: SkinLaw, key: str = "params") -> Any:
        """The parameter object of a calibration file's ``params``, every value checked
        (ValueError naming ``key`` and the value)."""

    def to_dict(self, params: Any) -> dict:
        """``params`` as the calibration file holds them (`parse` reads it back)."""
        return params.to_dict()

    @abstractmethod
    def fit(self, law: SkinLaw, curve: Curve, settings) -> Fitted:
        """Fit to ``law`` and its FE loading ``curve`` (0.5 mm/s), in the rig at ``settings``."""

    def add_to_rig(self, spec: mujoco.MjSpec, bone: mujoco.MjsBody, params: Any
                   ) -> mujoco.MjsBody:
        """The body of the rig that carries the skin geom (default: the bone itself)."""
        return bone

    def rig_contact(self, params: Any) -> SoftContactParams | None:
        """The law of the skin-plate pair in the rig (None: ``params``' stock values)."""
        return None

    def add_to_hand(self, spec: mujoco.MjSpec, geom: str, params: Any, *,
                    outward: tuple[float, float, float], hand_pad: HandPad) -> None:
        """Make the skin geom ``geom`` of a hand this representation (default: the geom as it
        is). ``outward``: the skin's outward normal in the geom's body frame."""
        if self.not_on_hand:
            raise ValueError(f"representation {self.name!r} is not available on a hand's skin "
                             f"geom: {self.not_on_hand}")

    def hand_pair_law(self, pair_law: SoftContactParams, tissue: SoftContactParams
                      ) -> SoftContactParams:
        """The law of a pair (skin geom, the other hand's tissue geom): ``pair_law`` is the
        skin's law in series with the tissue's (one contact for both), ``tissue`` the tissue's
        alone (for representations that carry the skin's compliance in their own elements)."""
        return pair_law


def loading_ramp(curve: Curve, top_N: float | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The loading ramp of ``curve`` (time, indentation, force), up to ``top_N`` if given."""
    i = curve.peak_index
    t, d, f = curve.time_s[:i + 1], curve.displacement_mm[:i + 1], curve.force_N[:i + 1]
    if top_N is not None:
        keep = f <= top_N
        keep[:2] = True
        t, d, f = t[keep], d[keep], f[keep]
    return t, d, f


class Rigid(Representation):
    """MuJoCo's stock contact: the skin as hard as the bone (the baseline of every comparison)."""

    name = "rigid"

    def parse(self, params, law, key="params"):
        check_mapping(key, params, required=("solref", "solimp"))
        solref = check_numbers(join(key, "solref"), params["solref"], length=2)
        solimp = check_numbers(join(key, "solimp"), params["solimp"], length=5)
        return StockContact(tuple(solref), tuple(solimp))

    def fit(self, law, curve, settings):
        return Fitted(StockContact(), curve)

    def hand_pair_law(self, pair_law, tissue):
        return tissue  # only the tissue indents


class SoftContact(Representation):
    """The pair's solref/solimp, fitted in closed form to the loading curve (no memory)."""

    name = "soft-contact"

    def parse(self, params, law, key="params"):
        return SoftContactParams.from_dict(params, key=key)

    def fit(self, law, curve, settings):
        from softhand.skin.calibrate import MASS_FACTORS, posture_sensitivity

        _, d, f = loading_ramp(curve)
        soft, rms_n, status = fit_soft_contact(
            d, f, reference_mass_kg=settings.mass_kg * MASS_FACTORS[0])
        at_2n = float(monotone_inverse(REFERENCE_FORCE_N, d, f))
        extra = {"fit_status": status.value, "closed_form_rms_pct_of_2N": 100 * rms_n / 2.0,
                 "closed_form": split_errors(soft.force(d[1:]), f[1:]),
                 "posture_sensitivity_pct": posture_sensitivity(soft, at_2n)}
        return Fitted(soft, curve, extra)

    def rig_contact(self, params):
        return params


class Relaxation(Representation):
    """The relaxation pad: QLV with the law's own Prony terms (`softhand.skin.pad`)."""

    name = "soft-contact+relaxation"
    rig_integrator = "discrete"  # light bodies limit-cycle under implicitfast in the rig

    def parse(self, params, law, key="params"):
        return PadParams.from_dict(params, law, key=key)

    def fit(self, law, curve, settings):
        from softhand.skin.calibrate import fit_pad, social_touch_record

        record = social_touch_record(law, curve)
        pad, evals, status = fit_pad(law, record, settings)
        extra = {"fit_status": status.value, "rig_simulations": evals,
                 "record": ("FE ramp to 2 N, then the law's 10 s hold at that depth (the pad went "
                            "unstable in holds above 7 N for 6 of 14 skins)")}
        return Fitted(pad, record, extra)

    def add_to_rig(self, spec, bone, params):
        return add_pad(spec, bone, "skin", params)

    def rig_contact(self, params):
        return pad_contact(params)

    def add_to_hand(self, spec, geom, params, *, outward, hand_pad):
        add_hand_pad(spec, geom, params.law, outward=outward, settings=hand_pad)

    def hand_pair_law(self, pair_law, tissue):
        return tissue  # the pad is the skin; the contact is the tissue in series with it


class Flex(Representation):
    """A tetrahedral flex pad (contact area and pressure; its own rig)."""

    name = "flex"
    not_on_hand = ("MuJoCo 4 integrates flex elasticity only under the discrete integrator, "
                   "where the handshake's calibrated soft contacts give 2.7-23x their force, and "
                   "the tissue's law would act at each of the flex surface's tens of contact "
                   "points; a flex pad on one phalanx of the hand has its own scene: `softhand "
                   "skin flex-press` (softhand.hands.flex_region)")

    def parse(self, params, law, key="params"):
        from dataclasses import fields

        from softhand.skin.flex import FlexPadParams

        check_mapping(key, params, optional=[f.name for f in fields(FlexPadParams)])
        for k, v in params.items():
            if k != "material":
                check_number(join(key, k), v)
        try:
            return FlexPadParams(**params)
        except ValueError as exc:
            raise ValueError(f"{key}: {exc}") from None

    def to_dict(self, params):
        from dataclasses import asdict

        return asdict(params)

    def fit(self, law, curve, settings):
        from softhand.skin.flex import fit_flex

        # a flex pad is for contact area at social-touch forces: fitted to 2 N (an SVK solid
        # cannot stiffen when a pocket closes, so the 2-20 N tail is left out)
        _, d, f = loading_ramp(curve, REFERENCE_FORCE_N)
        fit = fit_flex(d, f, speed_mm_s=curve.speed_mm_s)
        errors = {"rms_error_pct_of_2N": float(fit.rms_error_pct_of_2N),
                  "max_error_pct_of_2N": float(fit.max_error_pct_of_2N),
                  "step_us": float(fit.step_us)}
        return Fitted(fit.params, None, {"rig_simulations": int(fit.n_simulations)}, errors)

    def add_to_rig(self, spec, bone, params):
        raise ValueError("the flex representation is built by softhand.skin.flex.build_flex_rig")


#: every representation, from the cheapest; the order of reports and files
REPRESENTATIONS: dict[str, Representation] = {r.name: r for r in (Rigid(), SoftContact(),
                                                                  Relaxation(), Flex())}


def get_representation(name: str) -> Representation:
    """The representation called ``name``; ValueError naming it and the allowed names."""
    if name not in REPRESENTATIONS:
        raise ValueError(f"representation {name!r} is unknown; allowed: "
                         f"{', '.join(REPRESENTATIONS)}")
    return REPRESENTATIONS[name]


def pad_contact(pad: PadParams) -> SoftContactParams:
    """The stiff, linear contact that presses a rig pad (constant impedance, critically damped)."""
    d = 0.3
    k = pad.contact_stiffness * (1 - d)  # F = k r / (1 - d) at constant impedance
    damping = 2.0 * np.sqrt(pad.contact_stiffness * pad.pad_mass_kg) * (1 - d)
    return SoftContactParams(k, damping, (d, d, 1e-3, 0.5, 1.0))


def hand_pad_params(law: SkinLaw, settings: HandPad) -> PadParams:
    """The pad of ``law`` on a hand: no contact compliance taken out of its spring (its contact
    is the tissue, in series), the analytic branch damping (exact for the branches' law)."""
    e = law.elastic
    ref = e.displacement_at(REFERENCE_FORCE_N) if float(e.force(e.max_mm)) >= 2.0 else e.max_mm
    return PadParams(law, ref, contact_stiffness=np.inf,
                     max_compression_mm=settings.max_compression_m * 1e3,
                     n_knots=settings.n_knots)


def add_hand_pad(spec: mujoco.MjSpec, geom: str, law: SkinLaw, *,
                 outward: tuple[float, float, float], settings: HandPad) -> mujoco.MjsBody:
    """Move the skin geom ``geom`` of a hand onto a relaxation pad under its body.

    The geom is re-added, with all its attributes, to a pad body at the same place that slides
    along ``-outward`` (compression); the pad's spring and branches are the QLV law's
    (`softhand.skin.pad.add_pad`); the pad joint gets ``settings.armature_kg``. Sites and
    sensors that name the geom keep naming it. Returns the pad body.

    Raises:
        ValueError: no geom ``geom`` in ``spec``, or a zero ``outward``.
    """
    g = spec.geom(geom)
    if g is None:
        raise ValueError(f"skin geom {geom!r} not found")
    n = np.asarray(outward, dtype=float)
    if not np.isfinite(n).all() or np.linalg.norm(n) == 0:
        raise ValueError(f"outward = {outward!r}: expected a non-zero direction")
    body = g.parent
    pad = add_pad(spec, body, geom, hand_pad_params(law, settings), normal=tuple(n))
    joint = spec.joint(f"{geom}_pad")
    joint.armature = settings.armature_kg
    joint.solref_limit = [2.0 * spec.option.timestep, 1.0]  # rest and bone: stiff stops
    copy = {a: getattr(g, a) for a in ("type", "size", "pos", "quat", "fromto", "meshname",
                                       "rgba", "contype", "conaffinity", "group", "condim",
                                       "friction", "margin", "gap", "priority", "solmix")}
    if copy["type"] != mujoco.mjtGeom.mjGEOM_MESH:
        copy.pop("meshname")
    spec.delete(g)
    new = pad.add_geom(name=geom, mass=0.0)
    for a, v in copy.items():
        setattr(new, a, v)
    return pad
