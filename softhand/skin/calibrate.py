"""Calibrate every MuJoCo representation of a skin against its FE curves, and ship the result.

For one design (or a reference skin):

1. the law: elastic spline + Prony QLV fitted to the FE ramp-and-hold at 0.5 mm/s and at a faster
   ramp (5 mm/s, when ``calibration/fe/speed-5`` holds it), validated on 2 mm/s (``speed-2``);
2. ``soft-contact``: solref/solimp fitted to the 0.5 mm/s loading curve (closed-form rest law),
   then checked in the rig at the calibration mass and at 0.01x and 100x that mass;
3. ``soft-contact+relaxation``: the pad's branch damping fitted by least squares against simulated
   indentations in the rig (ramp and hold), then the same checks;
4. ``rigid``: stock contact in the same rig, as the baseline.

Error measures (all in the rig at timestep 1 ms unless told otherwise):

* ``rms_error_pct_of_2N`` / ``max_error_pct_of_2N``: force error over the 0.5 mm/s loading ramp,
  % of 2 N, at the same indentation;
* ``relaxation_error_pct``: largest force error in the hold, % of the force at the start of the hold;
* ``mass_sensitivity_pct``: largest RMS difference (% of 2 N) between the loading curves at 0.01x
  and 100x the calibration mass and the curve at the calibration mass.
* ``posture_sensitivity_pct`` (soft-contact): largest RMS difference (% of 2 N) between the force
  on the fingertip of an articulated three-link finger, pressed in four postures, and the law at the
  same indentation (`softhand.skin.finger`).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from scipy.optimize import least_squares

from softhand import __version__
from softhand.laws.fit import (
    REFERENCE_FORCE_N,
    Curve,
    FitStatus,
    SkinLaw,
    fit_skin_law,
    fit_status,
    load_curve,
    split_errors,
)
from softhand.laws.references import DATA_MAX_N, HUMAN, TABLE_MAX_N, reference_law
from softhand.skin.contact_classes import (
    BORDER_GEOMETRY,
    CLASSES,
    FE_BODY,
    PLATE_CLASS,
    TISSUE_CLASSES,
    TISSUE_CROSSING_BASES,
    TISSUE_CROSSING_MESH,
    TISSUE_CROSSING_REFERENCES,
    TISSUE_FE_FOLDER,
    TISSUE_LONG_PHALANX,
    class_curve,
    class_indenter,
    class_parts,
    fit_class_law,
    partner_tissue_class,
    tissue_class_curves,
    tissue_class_data_range,
    tissue_class_law,
    tissue_counterpart,
    tissue_curve_file,
)
from softhand.skin.pad import PadParams
from softhand.skin.pair import PairLaw, fit_pair_law
from softhand.skin.representations import REPRESENTATIONS, get_representation, loading_ramp
from softhand.skin.rig import RigSettings, SkinRangeWarning, build_rig, run_rig
from softhand.skin.soft_contact import SoftContactParams
from softhand.validate import check_mapping, check_number, join, show

__all__ = [
    "CALIBRATION_MASS_KG",
    "FORMAT_VERSION",
    "ClassLaw",
    "RepresentationResult",
    "SkinCalibration",
    "calibrate_design",
    "calibrate_skin",
    "check_fe_folders",
    "class_folders",
    "class_pair_laws",
    "fe_curves",
    "fit_pad",
    "hold_error",
    "law_curve",
    "loading_error",
    "posture_sensitivity",
    "refit_class_laws",
    "skin_names",
    "social_touch_record",
]

FORMAT_VERSION = 2  # 2: FE curves and laws to 20 N, split errors, the pair law against tissue
CALIBRATION_MASS_KG = 0.2  # a hand segment; the mass tests use 0.01x (2 g) and 100x (20 kg)
MASS_FACTORS = (0.01, 100.0)
PAD_CONTACT_FACTOR = 300.0  # pad contact stiffness / the skin's largest tangent stiffness


#: The speed (mm/s) of each curve folder of an FE folder: fitted, fitted fast, validation
FE_SPEED_FOLDERS = {".": 0.5, "speed-5": 5.0, "speed-2": 2.0}


def fe_curves(design: str, fe_dir: str | Path) -> tuple[list[Curve], list[Curve]]:
    """FE curves to fit (0.5 mm/s, and 5 mm/s if present) and to validate on (2 mm/s).

    Each curve is checked against the sha256 that its folder's ``summary.json`` recorded when
    ``softhand fe sweep`` wrote it (when the folder has a summary): a curve cut at a row boundary
    parses as a shorter curve, but not with the recorded hash. The folders' settings are checked
    first (`check_fe_folders`): curves of other settings are never mixed.

    Raises:
        FileNotFoundError: no 0.5 mm/s curve for ``design``.
        ValueError: a malformed curve, one whose hash differs from the recorded one or that its
            folder's summary does not record, a corrupt summary, or folders of other settings.
    """
    root = Path(fe_dir)
    summaries = check_fe_folders(root)
    main = root / f"{design}.csv"
    if not main.exists():
        raise FileNotFoundError(f"no FE curve for {design!r} at {main}: run `softhand fe sweep`")
    fit = [_recorded_curve(main, f"{design}@0.5mm/s", summaries["."])]
    fast = root / "speed-5" / f"{design}.csv"
    if fast.exists():
        fit.append(_recorded_curve(fast, f"{design}@5mm/s", summaries["speed-5"]))
    val = root / "speed-2" / f"{design}.csv"
    return fit, ([_recorded_curve(val, f"{design}@2mm/s", summaries["speed-2"])]
                 if val.exists() else [])


def check_fe_folders(root: str | Path) -> dict[str, dict | None]:
    """The summaries of an FE folder and its ``speed-5``/``speed-2`` folders, checked to be of
    one setting: each folder at its speed, and mode, mesh, force, hold, materials... the same.

    Raises:
        ValueError: naming the file, for a corrupt summary; naming both settings, for a mix.
    """
    from softhand.fem.sweep import read_summary

    root = Path(root)
    summaries = {sub: read_summary(root / sub) for sub in FE_SPEED_FOLDERS}
    ref = None
    for sub, data in summaries.items():
        if data is None:
            continue
        settings = {k: v for k, v in data["provenance"]["settings"].items() if k != "threads"}
        settings.setdefault("indenter", "plate")  # written before indenters: plate curves
        path = root / sub / "summary.json"
        if settings.get("speed_mm_s") != FE_SPEED_FOLDERS[sub]:
            raise ValueError(f"{path}: its curves were run at speed_mm_s = "
                             f"{settings.get('speed_mm_s')!r}; this folder holds the "
                             f"{FE_SPEED_FOLDERS[sub]:g} mm/s curves")
        settings.pop("speed_mm_s")
        if ref is None:
            ref = (path, settings)
            continue
        diff = [f"{k} {ref[1][k]!r} ({ref[0]}) vs {settings[k]!r} ({path})"
                for k in sorted(settings) if k in ref[1] and ref[1][k] != settings[k]]
        if diff:
            raise ValueError("FE curves of other settings in one folder: " + "; ".join(diff))
    return summaries


def _recorded_curve(path: Path, label: str, summary: dict | None) -> Curve:
    curve = load_curve(path, label)
    if summary is None:
        return curve  # hand-made curves: no record to compare with
    recorded = summary["provenance"]["curve_sha256"].get(path.stem)
    where = path.parent / "summary.json"
    if recorded is None:
        raise ValueError(f"{path}: {where} has no record of this curve (it lists "
                         f"{', '.join(summary['provenance']['curve_sha256']) or 'none'}): the "
                         "curve was not written by `softhand fe sweep` with that folder's settings")
    if recorded != curve.sha256:
        raise ValueError(f"{path}: its sha256 {curve.sha256[:12]}... differs from the "
                         f"{recorded[:12]}... that {where} recorded: the "
                         "file was changed or truncated after `softhand fe sweep` wrote it")
    return curve


@dataclass(frozen=True)
class RepresentationResult:
    """One representation of one skin: parameters, errors and cost."""

    representation: str
    params: dict[str, Any]
    rms_error_pct_of_2N: float
    max_error_pct_of_2N: float
    mass_sensitivity_pct: float | None
    relaxation_error_pct: float | None
    step_us: float
    fit_s: float
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"representation": self.representation, "params": self.params,
                "rms_error_pct_of_2N": self.rms_error_pct_of_2N,
                "max_error_pct_of_2N": self.max_error_pct_of_2N,
                "mass_sensitivity_pct": self.mass_sensitivity_pct,
                "relaxation_error_pct": self.relaxation_error_pct, "step_us": self.step_us,
                "fit_s": self.fit_s, **self.extra}


@dataclass(frozen=True)
class ClassLaw:
    """A skin's law for one contact class (`softhand.skin.contact_classes`) and its pair law
    against the human tissue's law for that class.

    Attributes:
        key: the class, ``body/counterpart``.
        law: the skin's law under the class's indenter (``phalanx/flat``: the plate law itself).
        pair: the pair law against the tissue (pressed by the skin's body: ``tissue``).
        indenter: the FE indenter of the class's curve.
        tissue: the tissue's counterpart class (``finger`` or ``flat``).
        curve: the FE curve's label and sha256.
    """

    key: str
    law: SkinLaw
    pair: PairLaw
    indenter: str
    tissue: str
    curve: dict[str, str]

    def to_dict(self) -> dict:
        return {"law": self.law.to_dict(), "pair_law": self.pair.to_dict(),
                "indenter": self.indenter, "tissue": self.tissue, "curve": self.curve}

    @classmethod
    def from_dict(cls, key: str, d: Any, *, path: str) -> ClassLaw:
        """Parse `to_dict` output under ``path`` (ValueError naming the key path)."""
        if key not in CLASSES:
            raise ValueError(f"{path} = {show(key)}: unknown class; allowed: {', '.join(CLASSES)}")
        check_mapping(path, d, required=("law", "pair_law", "indenter", "tissue", "curve"))
        for text in ("indenter", "tissue"):
            if not isinstance(d[text], str):
                raise ValueError(f"{join(path, text)} = {show(d[text])}: expected a string")
        check_mapping(join(path, "curve"), d["curve"], optional=None)
        return cls(key, SkinLaw.from_dict(d["law"], key=join(path, "law")),
                   PairLaw.from_dict(d["pair_law"], key=join(path, "pair_law")), d["indenter"],
                   d["tissue"], dict(d["curve"]))


@dataclass(frozen=True)
class SkinCalibration:
    """Everything the hand needs for one skin, with provenance.

    ``pair_law`` is the paper's protocol (skin and tissue both under a plate); ``pair_laws`` the
    laws per contact class (`ClassLaw`), which the handshake uses by default.
    """

    design: str
    law: SkinLaw
    representations: dict[str, RepresentationResult]
    provenance: dict[str, Any]
    pair_law: PairLaw | None = None
    pair_laws: dict[str, ClassLaw] = field(default_factory=dict)
    _parsed: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)

    def _representation(self, name: str) -> RepresentationResult:
        if name not in self.representations:
            have = ", ".join(self.representations) or "none"
            raise ValueError(f"skin {self.design}: representation {name!r} is not calibrated "
                             f"(calibrated: {have}); run `softhand calibrate {self.design}`")
        return self.representations[name]

    def params(self, representation: str) -> Any:
        """The parsed parameters of a calibrated representation (ValueError naming the skin if
        it is not calibrated)."""
        if representation not in self._parsed:
            r = self._representation(representation)
            self._parsed[representation] = get_representation(representation).parse(
                r.params, self.law)
        return self._parsed[representation]

    @property
    def soft_contact(self) -> SoftContactParams:
        """The ``soft-contact`` parameters."""
        return self.params("soft-contact")

    @property
    def pad(self) -> PadParams:
        """The ``soft-contact+relaxation`` pad of the rig."""
        return self.params("soft-contact+relaxation")

    def to_dict(self) -> dict:
        out = {"format_version": FORMAT_VERSION, "design": self.design,
               "law": self.law.to_dict(),
               "representations": {k: v.to_dict() for k, v in self.representations.items()},
               "provenance": self.provenance}
        if self.pair_law is not None:
            out["pair_law"] = self.pair_law.to_dict()
        if self.pair_laws:
            out["pair_laws"] = {k: v.to_dict() for k, v in self.pair_laws.items()}
        return out

    @classmethod
    def from_dict(cls, d: Any, *, source: str = "calibration", skin: str | None = None,
                  require: tuple[str, ...] = ()) -> SkinCalibration:
        """Parse `to_dict` output, checking every value now (not on first use).

        Args:
            d: the parsed JSON.
            source: where it came from (a file path), first in every message.
            skin: the skin the caller asked for; ``design`` must match it.
            require: representations that must be present (the handshake needs
                ``soft-contact``).

        Raises:
            ValueError: ``"{source}: skin {skin}: {key path} = {value}: expected ..."``.
        """
        name = skin or (d.get("design") if isinstance(d, dict) and isinstance(d.get("design"), str)
                        else "?")
        try:
            check_mapping("", d, required=("format_version", "design", "law", "representations"),
                          optional=("provenance", "pair_law", "pair_laws"))
            version = d["format_version"]
            if version != FORMAT_VERSION or isinstance(version, bool):
                raise ValueError(f"format_version {version!r} is not {FORMAT_VERSION} (written by "
                                 "another softhand version): run `softhand calibrate`")
            if not isinstance(d["design"], str) or (skin is not None and d["design"] != skin):
                want = f"{skin!r} (the file's skin)" if skin is not None else "a string"
                raise ValueError(f"design = {show(d['design'])}: expected {want}")
            law = SkinLaw.from_dict(d["law"], key="law")
            reps_in = check_mapping("representations", d["representations"],
                                    optional=tuple(REPRESENTATIONS))
            for rep in require:
                if rep not in reps_in:
                    raise ValueError(f"representations.{rep}: missing (needed here; calibrated: "
                                     f"{', '.join(reps_in) or 'none'}): run `softhand calibrate "
                                     f"{name}`")
            reps, parsed = {}, {}
            for rep, r in reps_in.items():
                reps[rep], value = _parse_representation(rep, r, law, join("representations", rep))
                if value is not None:
                    parsed[rep] = value
            provenance = d.get("provenance", {})
            check_mapping("provenance", provenance, optional=None)
            pair = PairLaw.from_dict(d["pair_law"]) if "pair_law" in d else None
            classes = check_mapping("pair_laws", d.get("pair_laws", {}), optional=None)
            by_class = {k: ClassLaw.from_dict(k, v, path=join("pair_laws", k))
                        for k, v in classes.items()}
            return cls(d["design"], law, reps, dict(provenance), pair, by_class, parsed)
        except ValueError as exc:
            raise ValueError(f"{source}: skin {name}: {exc}") from None


_RESULT_NUMBERS = ("rms_error_pct_of_2N", "max_error_pct_of_2N", "step_us", "fit_s")
_RESULT_OPTIONAL = ("mass_sensitivity_pct", "relaxation_error_pct")


def _parse_representation(rep: str, r: Any, law: SkinLaw, key: str
                          ) -> tuple[RepresentationResult, Any]:
    """One calibrated representation, every value checked; and its parsed parameters."""
    names = ("representation", "params", *_RESULT_NUMBERS, *_RESULT_OPTIONAL)
    check_mapping(key, r, required=names, optional=None)
    if r["representation"] != rep:
        raise ValueError(f"{join(key, 'representation')} = {show(r['representation'])}: "
                         f"expected {rep!r}")
    numbers = {k: check_number(join(key, k), r[k], lo=0.0) for k in _RESULT_NUMBERS}
    optional = {k: None if r[k] is None else check_number(join(key, k), r[k], lo=0.0)
                for k in _RESULT_OPTIONAL}
    pkey = join(key, "params")
    params = check_mapping(pkey, r["params"], optional=None)
    value = get_representation(rep).parse(params, law, key=pkey)
    extra = {k: v for k, v in r.items() if k not in names}
    result = RepresentationResult(rep, dict(params), numbers["rms_error_pct_of_2N"],
                                  numbers["max_error_pct_of_2N"], optional["mass_sensitivity_pct"],
                                  optional["relaxation_error_pct"], numbers["step_us"],
                                  numbers["fit_s"], extra)
    return result, value


def loading_error(out, curve: Curve, *, split: bool = False):
    """RMS and max error (% of 2 N) over the loading ramp, at the rig's actual indentation; with
    ``split``, also `softhand.laws.fit.split_errors` (up to 2 N / above 2 N) as a dict."""
    t_end = curve.time_s[curve.peak_index]
    ramp = out.time_s <= t_end + 1e-12
    _, d, f = loading_ramp(curve)
    target = np.interp(out.displacement_mm[ramp], d, f)
    err = out.force_N[ramp] - target
    rms, mx = float(100 * np.sqrt(np.mean(err**2)) / 2.0), float(100 * np.abs(err).max() / 2.0)
    if split:
        return rms, mx, split_errors(out.force_N[ramp], target)
    return rms, mx


def hold_error(out, curve: Curve) -> float | None:
    if not curve.hold.any():
        return None
    t_end = curve.time_s[curve.peak_index]
    hold = out.time_s > t_end + 1e-12
    err = out.force_N[hold] - np.interp(out.time_s[hold], curve.time_s, curve.force_N)
    return float(100 * np.abs(err).max() / curve.force_N[curve.peak_index])


def _mass_sensitivity(representation: str, curve: Curve, settings: RigSettings,
                      params: Any) -> float:
    """Largest RMS difference (% of 2 N) of the loading curve when the mass changes 100x."""
    t, d, _ = loading_ramp(curve)
    runs = {}
    for factor in (1.0, *MASS_FACTORS):
        st = RigSettings(timestep=settings.timestep, mass_kg=settings.mass_kg * factor,
                         integrator=settings.integrator)
        with warnings.catch_warnings():
            # run_rig places the plate at the target indentation plus the bone's descent every
            # step, so the penetration is prescribed and the free-body stability bound of a
            # light indenter (SkinRangeWarning "unstable at timestep") does not apply here
            warnings.filterwarnings("ignore", message=r"pair 'skin_plate': unstable at timestep",
                                    category=SkinRangeWarning)
            model = build_rig(representation, params, settings=st)
        runs[factor] = run_rig(model, t, d, settings=st)
    ref = runs[1.0]
    worst = 0.0
    for factor in MASS_FACTORS:
        f = np.interp(ref.displacement_mm, runs[factor].displacement_mm, runs[factor].force_N)
        worst = max(worst, float(100 * np.sqrt(np.mean((f - ref.force_N) ** 2)) / 2.0))
    return worst


def posture_sensitivity(soft: SoftContactParams, depth_mm: float) -> float:
    """Largest RMS error (% of 2 N) of the fingertip force against the law, over four postures."""
    from softhand.skin.finger import POSTURES_DEG, press_finger

    worst = 0.0
    for posture in POSTURES_DEG:
        press = press_finger(soft, posture, depth_mm=1.5 * depth_mm)
        on = press.force_N > 0
        err = press.force_N[on] - soft.force(press.displacement_mm[on])
        worst = max(worst, float(100 * np.sqrt(np.mean(err**2)) / 2.0))
    return worst


def social_touch_record(law: SkinLaw, curve: Curve, *, top_N: float = REFERENCE_FORCE_N,
                        hold_s: float = 10.0) -> Curve:
    """A ramp-and-hold record at social-touch forces: ``curve``'s loading ramp up to ``top_N``,
    then ``hold_s`` at that depth with the force of ``law`` (QLV). The relaxation pad is fitted
    and checked on it: its branches are exact for the law, and in holds above about 7 N it went
    unstable for 6 of the 14 skins (hold error 100 %), which the 0-2 N record avoids."""
    t, d, _ = loading_ramp(curve, top_N)
    hold = t[-1] + np.geomspace(0.01, hold_s, 200)
    time_s = np.concatenate([t, hold])
    depth = np.concatenate([d, np.full(hold.size, d[-1])])
    is_hold = np.concatenate([np.zeros(t.size, bool), np.ones(hold.size, bool)])
    return Curve(time_s, depth, law.force(time_s, depth), is_hold,
                 label=f"{curve.label} to {top_N:g} N + law hold")


def _pad_params(law: SkinLaw, scale: tuple[float, ...] = ()) -> PadParams:
    e = law.elastic
    kmax = float(e.stiffness(np.linspace(0.0, e.max_mm, 400)).max()) * 1e3
    ref = e.displacement_at(2.0) if float(e.force(e.max_mm)) >= 2.0 else e.max_mm
    return PadParams(law, ref, PAD_CONTACT_FACTOR * kmax, max_compression_mm=3.0 * e.max_mm,
                     damping_scale=scale)


def fit_pad(law: SkinLaw, curve: Curve, settings: RigSettings
            ) -> tuple[PadParams, int, FitStatus]:
    """Branch damping multipliers by least squares against simulated indentations."""
    n = len(law.prony.g)
    if n == 0:
        return _pad_params(law), 0, FitStatus.CONVERGED
    grid = np.linspace(curve.time_s[0], curve.time_s[-1], 400)
    target = np.interp(grid, curve.time_s, curve.force_N)
    evals = 0

    def residual(logs: np.ndarray) -> np.ndarray:
        nonlocal evals
        evals += 1
        pad = _pad_params(law, tuple(np.exp(logs)))
        out = run_rig(build_rig("soft-contact+relaxation", pad, settings=settings),
                      curve.time_s, curve.displacement_mm, settings=settings)
        return np.interp(grid, out.time_s, out.force_N) - target

    res = least_squares(residual, np.zeros(n), bounds=(np.full(n, -3.0), np.full(n, 3.0)),
                        diff_step=0.05, xtol=1e-3, ftol=1e-4, max_nfev=8)
    status = fit_status(res, f"{law.name}: relaxation pad branch damping")
    return _pad_params(law, tuple(np.exp(res.x))), evals, status


def calibrate_design(design: str, *, fe_dir: str | Path = "calibration/fe",
                     representations: tuple[str, ...] = ("rigid", "soft-contact",
                                                         "soft-contact+relaxation"),
                     settings: RigSettings | None = None,
                     law: SkinLaw | None = None, curves: list[Curve] | None = None,
                     fe_design: str | None = None, tissue_fe_dir: str | Path | None = None
                     ) -> SkinCalibration:
    """Fit the law and every asked representation of ``design``; see the module docstring.

    ``law`` and ``curves`` replace the FE files (reference skins, tests with synthetic data).
    ``settings`` default: the rig at 1 ms with the calibration mass.
    ``fe_design``: the name the curves of ``design`` have in ``fe_dir`` (default ``design``):
    a searched design's curves are written under its FE slot layout's name
    (`softhand.design.skins`). ``tissue_fe_dir``: the FE root whose `TISSUE_FE_FOLDER` holds
    the tissue's FE curves behind its class laws (default ``fe_dir``).
    """
    settings = settings or RigSettings(mass_kg=CALIBRATION_MASS_KG)
    if curves is None:
        fit_curves, val_curves = fe_curves(fe_design or design, fe_dir)
    else:
        fit_curves, val_curves = list(curves), []
    t0 = time.perf_counter()
    if law is None:
        law = fit_skin_law(design, fit_curves, validation=val_curves)
    law_s = time.perf_counter() - t0
    main = fit_curves[0]
    results: dict[str, RepresentationResult] = {}
    own: dict[str, Any] = {}  # parsed parameters, for the pair law
    for rep in representations:
        t0 = time.perf_counter()
        kind = get_representation(rep)
        fitted = kind.fit(law, main, settings)
        fit_s = time.perf_counter() - t0
        params = kind.to_dict(fitted.params)
        if fitted.record is None:  # checked in its own rig (flex)
            e = fitted.errors
            results[rep] = RepresentationResult(rep, params, e["rms_error_pct_of_2N"],
                                                e["max_error_pct_of_2N"], None, None,
                                                e["step_us"], fit_s, dict(fitted.extra))
            continue
        own[rep] = fitted.params
        checked = fitted.record
        out = run_rig(build_rig(rep, fitted.params, settings=settings), checked.time_s,
                      checked.displacement_mm, settings=settings)
        rms, mx, split = loading_error(out, checked, split=True)
        extra = {**fitted.extra, **split}
        relax = hold_error(out, checked)
        sens = None if rep == "rigid" else _mass_sensitivity(rep, checked, settings,
                                                               fitted.params)
        results[rep] = RepresentationResult(rep, params, rms, mx, sens, relax, out.stats["step_us"], fit_s,
                                            extra)
    provenance = {
        "softhand_version": __version__, "mujoco_version": mujoco.__version__,
        "fe_curves": {c.label: c.sha256 for c in fit_curves + val_curves},
        "rig": {"timestep_s": settings.timestep, "mass_kg": settings.mass_kg,
                "mass_factors": list(MASS_FACTORS)},
        "law_fit_s": law_s,
    }
    pair = None  # the pair law is a soft contact: fitted with (and started from) the skin's own
    if "soft-contact" in results:  # the human tissue too: the sensored human hand against the partner
        t0 = time.perf_counter()
        tissue = reference_law(HUMAN)
        initial = own["soft-contact"]  # the skin's own soft contact, fitted above
        top = _law_top(law, float(main.force_N.max()))
        pair = fit_pair_law(law, tissue, skin_top_N=top,
                            skin_data_N=DATA_MAX_N.get(design, top),
                            tissue_top_N=TABLE_MAX_N, tissue_data_N=DATA_MAX_N[HUMAN],
                            reference_mass_kg=settings.mass_kg * MASS_FACTORS[0],
                            initial=initial)
        provenance["pair_law_fit_s"] = time.perf_counter() - t0
        if curves is None or design == HUMAN:  # FE curves of the design or of the tissue:
            t0 = time.perf_counter()  # its laws per contact class too
            by_class = class_pair_laws(design, law, main, fe_dir,
                                       reference_mass_kg=settings.mass_kg * MASS_FACTORS[0],
                                       initial=initial, fe_design=fe_design,
                                       tissue_fe_dir=tissue_fe_dir)
            provenance["pair_laws_fit_s"] = time.perf_counter() - t0
            return SkinCalibration(design, law, results, provenance, pair, by_class)
    return SkinCalibration(design, law, results, provenance, pair)


def _law_top(law: SkinLaw, top_N: float, speed_mm_s: float = 0.5) -> float:
    """``top_N`` (an FE curve's largest force), or just under the largest force of ``law``'s
    ramp at ``speed_mm_s`` where that is less: a law fitted to a curve that ends where a soft
    design's FE stopped (`softhand.design.skins`) ends flat and its ramp may fall a few % short
    of the curve's end. A law fitted to 20 N reaches it (extrapolated past its end): unchanged."""
    e = law.elastic
    d = np.linspace(0.0, e.max_mm / max(law.prony.g_inf, 1e-6) + 1.0, 4000)
    return min(top_N, 0.999 * float(law.force(d / speed_mm_s, d).max()))


def class_folders(design: str, fe_dir: str | Path) -> list[str]:
    """The contact classes besides the plate's whose FE curve of ``design`` the class folders
    of ``fe_dir`` hold, each folder checked against the plate folder's settings.

    Raises:
        ValueError: a class folder without a summary, of another indenter or body, or of other
            settings than the plate folder's (naming the folder).
    """
    from softhand.fem.sweep import read_summary

    plate = read_summary(Path(fe_dir))
    return [key for key in CLASSES if key != PLATE_CLASS
            and _class_folder_curve(design, key, fe_dir, plate) is not None]


def _class_folder_curve(design: str, key: str, fe_dir: str | Path, plate: dict | None
                        ) -> tuple[Curve, str] | None:
    """The FE curve of ``design`` for class ``key`` and its mesh level, checked against its
    folder's summary (the settings of the plate folder but for the indenter, the body and the
    hold), or None."""
    from softhand.fem.sweep import read_summary

    path = class_curve(design, key, fe_dir)
    if not path.exists():
        return None
    summary = read_summary(path.parent)
    if summary is None:
        raise ValueError(f"{path}: its folder has no summary.json: class curves must come from "
                         "`softhand fe sweep`")
    got = summary["provenance"]["settings"]
    body = class_parts(key)[0]
    want, want_body = class_indenter(key), FE_BODY[body]
    if got.get("indenter", "plate") != want or got.get("body", "phalanx") != want_body:
        raise ValueError(f"{path.parent}: holds curves of indenter {got.get('indenter')!r} on "
                         f"body {got.get('body', 'phalanx')!r}; class {key} needs {want!r} on "
                         f"{want_body!r}")
    base = plate["provenance"]["settings"] if plate is not None else {}
    if body == "border":  # the phalanx widened to the border's stand-in, over the plate's own
        geometry = {**base.get("geometry", {}), **BORDER_GEOMETRY}
        if got.get("geometry", {}) != geometry:
            raise ValueError(f"{path.parent}: geometry {got.get('geometry', {})!r}; class {key} "
                             f"needs {geometry!r} (contact_classes.BORDER_GEOMETRY)")
    if plate is not None:
        ignore = {"indenter", "body", "hold_s", "threads", "max_depth_mm"}
        if body != "phalanx":
            ignore.add("mesh")  # another body: its own mesh levels (recorded with the curve)
        if body == "border":
            ignore.add("geometry")  # checked above
        diff = [f"{k} {base[k]!r} (plate) vs {got[k]!r}" for k in sorted(base)
                if k not in ignore and k in got and base[k] != got[k]]
        if diff:
            raise ValueError(f"{path.parent}: settings differ from the plate folder's: "
                             + "; ".join(diff))
    return _recorded_curve(path, f"{design} {key}@0.5mm/s", summary), _mesh_name(got)


def _mesh_name(settings: dict) -> str:
    return settings["mesh"] if isinstance(settings.get("mesh"), str) else "custom"


def tissue_curves(fe_dir: str | Path) -> dict[str, Curve]:
    """The human tissue's FE curves per contact class (`TISSUE_CLASSES`: the crossings' runs
    on the long phalanx too) in ``fe_dir``'s `TISSUE_FE_FOLDER` (written by ``python
    tools/tissue_fe.py --classes``), each checked against the sha256 and the indenter and body
    (and for the crossings the phalanx's length) its summary.json records; {} where the folder
    is not there.

    Raises:
        ValueError: a folder without its summary, a curve it does not record or that differs
            from its record, or a class of another indenter or body.
    """
    import json

    folder = Path(fe_dir) / TISSUE_FE_FOLDER
    if not folder.is_dir():
        return {}
    where = folder / "summary.json"
    try:
        summary = json.loads(where.read_text(encoding="utf-8"))
        runs = summary["provenance"]["settings"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"{where}: not a tissue FE summary ({exc}); write the folder with "
                         "`python tools/tissue_fe.py --classes`") from None
    out = {}
    for key in TISSUE_CLASSES:
        path = folder / tissue_curve_file(key)
        if not path.exists():
            continue
        got = runs.get(key, {})
        want, body = class_indenter(key), FE_BODY[class_parts(key)[0]]
        if got.get("indenter", "plate") != want or got.get("body", "phalanx") != body:
            raise ValueError(f"{where}: class {key} was run with indenter "
                             f"{got.get('indenter')!r} on {got.get('body')!r}; it needs "
                             f"{want!r} on {body!r}")
        length = (got.get("geometry") or {}).get("length_mm")
        crossing = key in (*TISSUE_CROSSING_REFERENCES, *TISSUE_CROSSING_BASES)
        if crossing and length != TISSUE_LONG_PHALANX["length_mm"]:
            raise ValueError(f"{where}: class {key} was run on a phalanx {length} mm long; it "
                             f"needs the long phalanx, {TISSUE_LONG_PHALANX['length_mm']:g} mm")
        if crossing and got.get("mesh") != TISSUE_CROSSING_MESH:
            raise ValueError(f"{where}: class {key} was run on the {got.get('mesh')!r} mesh; the "
                             f"crossings and their reference need one mesh, "
                             f"{TISSUE_CROSSING_MESH!r}")
        out[key] = _recorded_curve(path, f"tissue {key}@0.5mm/s", summary)
    return out


def class_pair_laws(design: str, law: SkinLaw, plate_curve: Curve, fe_dir: str | Path, *,
                    reference_mass_kg: float, initial: SoftContactParams | None = None,
                    fe_design: str | None = None, tissue_fe_dir: str | Path | None = None
                    ) -> dict[str, ClassLaw]:
    """The laws of ``design`` per contact class (`softhand.skin.contact_classes`), each with
    its pair law against the partner's tissue side (`partner_tissue_class`: the tissue's law
    pressed like a finger or a flat). A design's class law is fitted to its FE curve in
    ``fe_dir``'s class folder (``phalanx/flat``: the plate law itself); the human tissue's
    (``design`` `HUMAN`, the sensored human hand) is `tissue_class_law` of the tissue FE's
    curves. A class without its curve, or whose tissue side lacks the tissue FE's curves
    (``tissue_fe_dir``'s `TISSUE_FE_FOLDER`, default ``fe_dir``'s), is left out.
    ``fe_design`` and ``tissue_fe_dir``: as in `calibrate_design`. A pair law is calibrated up
    to where both its laws rest on data: a tissue class law to its force at the depth where the
    tissue's plate data end (`tissue_class_data_range`), a design's to its FE curve's end."""
    from softhand.fem.sweep import read_summary

    root = Path(fe_dir)
    tissue = reference_law(HUMAN)
    tcurves = tissue_curves(root if tissue_fe_dir is None else Path(tissue_fe_dir))
    tplate = tcurves.get(PLATE_CLASS)

    def tissue_law(key: str) -> SkinLaw | None:
        if key == PLATE_CLASS:
            return tissue
        found = tissue_class_curves(key, tcurves)
        return None if found is None else tissue_class_law(tissue, key, *found)

    human = design == HUMAN
    plate = None if human else read_summary(root)
    out: dict[str, ClassLaw] = {}

    def data_range(key: str, law: SkinLaw) -> float:  # the tissue class law's data range
        t_plate, other, cross = tissue_class_curves(key, tcurves) or (tplate, None, None)
        return tissue_class_data_range(tissue, key, law, t_plate, other, cross=cross)

    for key in CLASSES:
        t_key = partner_tissue_class(key)
        t = tissue_law(t_key)
        if human:
            skin = tissue_law(key)  # the plate's: the paper's law itself, its own curve
            curve = plate_curve if key == PLATE_CLASS else tcurves.get(key)
            found = None if skin is None else (curve, "default")
        else:
            found = ((plate_curve, "default" if plate is None else _mesh_name(
                plate["provenance"]["settings"])) if key == PLATE_CLASS
                     else _class_folder_curve(fe_design or design, key, root, plate))
        if t is None or found is None:
            continue
        curve, mesh = found
        if not human:
            skin = law if key == PLATE_CLASS else fit_class_law(design, key, law, curve)
        top = _law_top(skin, TABLE_MAX_N if human else float(curve.force_N.max()))
        pair = fit_pair_law(skin, t, skin_top_N=top, skin_data_N=data_range(key, skin) if human
                            else DATA_MAX_N.get(design, top), tissue_top_N=TABLE_MAX_N,
                            tissue_data_N=data_range(t_key, t), reference_mass_kg=reference_mass_kg,
                            initial=initial)
        out[key] = ClassLaw(key, skin, pair, class_indenter(key),
                            tissue_counterpart(key), {"label": curve.label,
                                                      "sha256": curve.sha256, "mesh": mesh})
    return out


def law_curve(law: SkinLaw, *, speed_mm_s: float = 0.5, force_N: float = 20.0,
              hold_s: float = 10.0, n: int = 400) -> Curve:
    """A ramp-to-``force_N``-and-hold record made from a law (for skins without FE curves)."""
    depth = law.quasi_static_displacement_at(force_N, speed_mm_s)
    t_ramp = depth / speed_mm_s
    t = np.concatenate([np.linspace(0.0, t_ramp, n), t_ramp + np.geomspace(0.01, hold_s, n // 2)])
    d = np.minimum(t * speed_mm_s, depth)
    hold = t > t_ramp
    return Curve(t, d, law.force(t, d), hold, label=f"{law.name}@{speed_mm_s}mm/s")


def skin_names() -> list[str]:
    """Every skin that ``softhand calibrate`` knows: the 12 designs and the two references."""
    from softhand.fem.geometry import DESIGNS
    from softhand.laws.references import HUMAN, PROSTHETIC

    return [*DESIGNS, HUMAN, PROSTHETIC]


def refit_class_laws(cal: SkinCalibration, fe_dir: str | Path) -> SkinCalibration:
    """``cal`` with its laws per contact class (``pair_laws``) fitted again from the class
    folders of ``fe_dir`` (`class_pair_laws`, as `calibrate_design` fits them after the soft
    contact), everything else as it was: the law, the representations, the plate's pair law.
    For new class curves (a finer palm mesh) without refitting the representations; the
    provenance records it (``pair_laws_from``, ``pair_laws_fit_s``).

    Raises:
        ValueError: ``cal`` has no soft contact (the pair laws start from it), or its design
            has no FE curves in ``fe_dir`` (`HUMAN`: its laws come from the tissue FE's).
    """
    from softhand.fem.geometry import DESIGNS

    if cal.design not in (*DESIGNS, HUMAN):
        raise ValueError(f"skin {cal.design!r}: only the designs and {HUMAN} have laws per "
                         "contact class")
    if "soft-contact" not in cal.representations:
        raise ValueError(f"skin {cal.design!r}: no soft-contact representation to start the "
                         "pair laws from; calibrate it first")
    plate = law_curve(cal.law) if cal.design == HUMAN else fe_curves(cal.design, fe_dir)[0][0]
    t0 = time.perf_counter()
    by_class = class_pair_laws(cal.design, cal.law, plate, fe_dir,
                               reference_mass_kg=CALIBRATION_MASS_KG * MASS_FACTORS[0],
                               initial=cal.soft_contact)
    provenance = {**cal.provenance, "pair_laws_fit_s": time.perf_counter() - t0,
                  "pair_laws_from": "softhand.skin.calibrate.refit_class_laws (`softhand "
                  "calibrate --class-laws-only`): class_pair_laws on this file's law and soft "
                  f"contact and the class folders of the FE curves, softhand {__version__}, "
                  f"MuJoCo {mujoco.__version__}"}
    return SkinCalibration(cal.design, cal.law, dict(cal.representations), provenance,
                           cal.pair_law, by_class)


def calibrate_skin(name: str, *, fe_dir: str | Path = "calibration/fe",
                   representations: tuple[str, ...] = ("rigid", "soft-contact",
                                                       "soft-contact+relaxation"),
                   settings: RigSettings | None = None) -> SkinCalibration:
    """Calibrate a design from its FE curves, or a reference skin from its paper-based law."""
    from softhand.laws.references import HUMAN, PROSTHETIC, reference_law

    if name in (HUMAN, PROSTHETIC):
        law = reference_law(name)
        return calibrate_design(name, fe_dir=fe_dir, representations=representations,
                                settings=settings, law=law, curves=[law_curve(law)])
    if name not in skin_names():
        raise ValueError(f"skin {name!r} is unknown; allowed: {', '.join(skin_names())}")
    return calibrate_design(name, fe_dir=fe_dir, representations=representations,
                            settings=settings)
