"""The palm's rounded border: the laws that could carry it against an FE of it.

    python tools/border_law_error.py [--out reports/border-law-error] [--designs all]
        [--handshake] [--laws-only | --handshake-only]

`reports/contact-geometry.md` finds most of the default handshake's force on a rounded border of
the prosthetic palm's one convex surface (radius 8-23 mm, median 13.6, p10-p90), pressed by the
partner's fingers. Those pairs carry the ``border/finger`` law (`softhand.skin.contact_classes`:
the FE's stand-in of the border, the phalanx section widened to width 20 mm and height 8 mm, a
half ellipse of radius a^2 / b = 12.5 mm at its top, 40 mm long as a palm's border is long
beside a finger, the design's layers and pocket as on the phalanx, 8 mm of skin over a flat
bone, under a cylinder of radius 9 mm across it, to 20 N in 3D: `calibration/fe/border-finger/`).
This runs that FE again for each design and sets three
laws against it: the border/finger law (its own class's), the palm/finger law (an FE cylinder
across a flat slab of the design's layers over the metacarpals: what the border's pairs carried
before they had a law of their own) and the phalanx/finger law (its elastic force on the FE's
ramp history, with its relaxation), as the RMS and largest difference in % of 2 N over the FE's
0-2 N and 0-20 N. For pocket2-sil, the border's radius moved (width 20 mm, height 7.7 mm: 13.0
mm, and 9 mm: 11.1 mm; a flatter section leaves its flanks too tight for a 2 mm pocket's layers),
its length moved (the paper's 10 mm phalanx, the stand-in before, and 60 mm) and the finger
crossing the border at 30, 45, 60 and 90 deg (the handshake's fingers cross it at
30-90 deg; below 90 deg the FE runs the whole phalanx, 4x the elements), set against the same
laws and the border's law of the nearest crossing that has one (`border_class`: the laws at 60
and 30 deg are fitted to `calibration/fe/border-finger-60/` and `-30/`, the same stand-in and
finger). Writes ``OUT.md`` and ``OUT.json``. ``--laws-only`` sets the shipped laws against
OUT.json's FE curves again without running them (after a refit of the laws).

``--handshake`` adds what the border's law does to the handshake: the default handshake (neutral,
seeds 0-2) as shipped against the same with the border's pairs on the palm/finger law, as they
were before the border had a law (`softhand.envs.skins.pair_choices` swapped for the run).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from softhand.bench.common import machine_info, machine_line
from softhand.fem.geometry import DESIGNS
from softhand.fem.solver import ConvergenceError, IndentationSettings, indent
from softhand.io import atomic_write_json, atomic_write_text
from softhand.skin.contact_classes import BORDER_GEOMETRY, FINGER_RADIUS_MM, INDENTERS, border_class
from softhand.skin.files import load_calibration

BORDER = dict(BORDER_GEOMETRY)
#: the border's radius moved, and its length: the paper's 10 mm phalanx (the stand-in before: the
#: finger's contact reaches its free ends) and 60 mm (the 40 mm stand-in has converged)
RADII = ({**BORDER, "height_mm": 7.7}, {**BORDER, "height_mm": 9.0},
         {**BORDER, "length_mm": 10.0}, {**BORDER, "length_mm": 60.0})
FINGER = INDENTERS["finger"]
CROSSINGS_DEG = (30.0, 45.0, 60.0)
LAWS = ("border/finger", "palm/finger", "phalanx/finger")


def _fe(design: str, geometry: dict, indenter: str = FINGER) -> dict:
    s = IndentationSettings(mode="3d", indenter=indenter, geometry=geometry, max_force_N=20.0,
                            hold_s=0.0)
    try:
        r = indent(design, s)
    except ConvergenceError as exc:
        return {"error": str(exc)[:200]}
    ramp = ~r.hold
    return {"time_s": r.time_s[ramp].tolist(), "displacement_mm": r.displacement_mm[ramp].tolist(),
            "force_N": r.force_N[ramp].tolist(), "status": r.status.value,
            "d_2N_mm": r.displacement_at(2.0)}


def _errors(fe: dict, design: str, crossing: float = 90.0) -> dict:
    """Each of `LAWS`, and the border's law of the FE finger's ``crossing`` (`border_class`),
    against the FE ramp ``fe``."""
    cal = load_calibration(design)
    t, d, f = (np.asarray(fe[k]) for k in ("time_s", "displacement_mm", "force_N"))
    out = {}
    for key in (*LAWS, border_class(crossing)):
        law = cal.pair_laws[key].law if key in cal.pair_laws else None
        if law is None:
            out[key] = None
            continue
        g = law.force(t, d)
        row = {}
        for top in (2.0, 20.0):
            sel = f <= top + 1e-9
            diff = 100.0 * (g[sel] - f[sel]) / 2.0
            row[f"to_{top:g}N"] = {"rms_pct_of_2N": float(np.sqrt(np.mean(diff ** 2))),
                                   "max_pct_of_2N": float(np.abs(diff).max()),
                                   "mean_signed_pct_of_2N": float(diff.mean())}
        row["law_force_at_fe_2N_depth_N"] = float(np.interp(fe["d_2N_mm"], d, g))
        out[key] = row
    return out


def _border_on_palm_law(original):
    """`pair_choices` with each border/finger pair carrying its skin's palm/finger pair law (the
    law those pairs carried before the border had its own)."""
    from softhand.envs import skins as sk

    def choices(model, skins, representations=None, *, directory=sk.SKINS_DIR,
                contact_laws="geometry"):
        out = original(model, skins, representations, directory=directory,
                       contact_laws=contact_laws)
        tissue = sk.series_law("rigid", str(directory))
        for name, c in out.items():
            if not c.law.startswith("border/finger"):
                continue
            _, skin = sk.skin_of_pair(name, skins)
            law = load_calibration(skin, directory, require=("soft-contact",)
                                   ).pair_laws["palm/finger"]
            rep = sk.get_representation(sk.DEFAULT_REPRESENTATION)
            out[name] = sk.PairChoice(c.contact, "palm/finger",
                                      rep.hand_pair_law(law.pair.params, tissue),
                                      float(law.pair.calibrated_max_N))
        return out
    return choices


HANDSHAKE_CASES = ("shipped (the border's laws)", "border pairs on the palm/finger law (before)")


def _handshakes() -> list[dict]:
    from softhand.envs import skins as sk
    from softhand.envs import touch
    from softhand.envs.run import run_handshake

    rows = []
    for seed in (0, 1, 2):
        for what in HANDSHAKE_CASES:
            original = sk.pair_choices
            if what != HANDSHAKE_CASES[0]:  # the spec's laws and the env's record of them
                sk.pair_choices = touch.pair_choices = _border_on_palm_law(original)
            try:
                r = run_handshake(seed=seed)
            finally:
                sk.pair_choices = touch.pair_choices = original
            table = r.table()
            over = r.overload()
            acc = r.force_accounting()
            rows.append({"seed": seed, "what": what,
                         "peak_N": {k: v["peak_N"] for k, v in table.items()},
                         "over_2N": r.over_2n, "total_Ns": acc["total_Ns"],
                         "skin_own_class_share_pct":
                             acc["by_geometry"]["skin_own_class_share_pct"],
                         "by_law_share_pct": acc["by_law_share_pct"],
                         "deepest_pair_mm": over["deepest_pair_mm"],
                         "deepest_pair": over["deepest_pair"],
                         "bone_on_bone_peak_N": over["bone_on_bone_peak_N"]})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="reports/border-law-error")
    ap.add_argument("--designs", default="all")
    ap.add_argument("--handshake", action="store_true",
                    help="also the handshake with the palm/finger pairs swapped (a what-if)")
    ap.add_argument("--handshake-only", action="store_true",
                    help="rerun only the what-if, keeping the FE part of OUT.json")
    ap.add_argument("--laws-only", action="store_true",
                    help="set the shipped laws against OUT.json's FE curves again (after the "
                         "laws were refitted), no FE runs; with --handshake the what-if too")
    args = ap.parse_args()
    out = Path(args.out)
    if args.handshake_only or args.laws_only:
        data = json.loads(out.with_suffix(".json").read_text(encoding="utf-8"))
        if args.laws_only:
            for r in (*data["rows"], *data["radii"]):
                if "error" not in r["fe"]:
                    r["errors"] = _errors(r["fe"], r.get("design", "pocket2-sil"))
            for r in data.get("crossings", []):
                if "error" not in r["fe"]:
                    r["errors"] = _errors(r["fe"], "pocket2-sil", r["crossing_deg"])
        if args.handshake_only or args.handshake:
            data["handshakes"] = _handshakes()
        atomic_write_json(out.with_suffix(".json"), data)
        atomic_write_text(out.with_suffix(".md"), markdown(data))
        print(markdown(data))
        return
    designs = list(DESIGNS) if args.designs == "all" else args.designs.split(",")
    data: dict = {"machine": machine_info(), "border": BORDER, "finger": FINGER, "rows": [],
                  "radii": []}
    for design in designs:
        print(design, flush=True)
        fe = _fe(design, BORDER)
        row = {"design": design, "fe": fe}
        if "error" not in fe:
            row["errors"] = _errors(fe, design)
        data["rows"].append(row)
    for geometry in RADII:
        print("pocket2-sil", geometry, flush=True)
        fe = _fe("pocket2-sil", geometry)
        data["radii"].append({"geometry": geometry, "fe": fe,
                              "errors": None if "error" in fe else _errors(fe, "pocket2-sil")})
    data["crossings"] = []
    for angle in CROSSINGS_DEG:
        print("pocket2-sil", angle, "deg", flush=True)
        fe = _fe("pocket2-sil", BORDER, f"cylinder:{FINGER_RADIUS_MM:g}@{angle:g}")
        data["crossings"].append({"crossing_deg": angle, "fe": fe, "errors": None if "error" in fe
                                  else _errors(fe, "pocket2-sil", angle)})
    if args.handshake:
        data["handshakes"] = _handshakes()
    atomic_write_json(out.with_suffix(".json"), data)
    atomic_write_text(out.with_suffix(".md"), markdown(data))
    print(markdown(data))


def _border_share(by_law: dict) -> float:
    """The share (%) of a run's force through the border's laws, every crossing's."""
    return sum(v for k, v in by_law.items() if k.startswith("border/finger"))


def _cell(e: dict | None, top: str) -> str:
    if e is None:
        return "n/a"
    r = e[f"to_{top}N"]
    return f"{r['rms_pct_of_2N']:.0f} / {r['max_pct_of_2N']:.0f} ({r['mean_signed_pct_of_2N']:+.0f})"


def markdown(d: dict) -> str:
    lines = ["# The palm's rounded border against the laws that could carry it", "",
             "`python tools/border_law_error.py --out reports/border-law-error --handshake`: the "
             "FE's stand-in of the palm's rounded border (the phalanx section widened to width "
             f"{d['border']['width_mm']:g} mm, height {d['border']['height_mm']:g} mm, "
             f"{d['border'].get('length_mm', 10.0):g} mm long: a "
             "12.5 mm top radius, the median border the partner's fingers press in the default "
             f"handshake being 13.6 mm, `reports/contact-geometry.md`) under the finger "
             f"({d['finger']}), 3D, to 20 N, against the border/finger law fitted to it (the "
             "law the scene's border pairs carry), the palm/finger law (a finger across a flat "
             "slab: what they carried before) and the phalanx/finger law: RMS / largest "
             "difference in % of 2 N (mean signed: the law above the FE is +), over the FE's "
             "0-2 N and 0-20 N.", "",
             machine_line(d["machine"]), "",
             "| design | FE d(2 N) mm | border/finger law, 0-2 N | 0-20 N | palm/finger law, "
             "0-2 N | 0-20 N | palm/finger law's force at the FE's 2 N depth | phalanx/finger "
             "law, 0-2 N | 0-20 N |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in d["rows"]:
        fe = r["fe"]
        if "error" in fe:
            lines.append(f"| {r['design']} | FE stopped: {fe['error'][:80]} | | | | | | | |")
            continue
        e = r["errors"]
        pf = e["palm/finger"]
        at = "n/a" if pf is None else f"{pf['law_force_at_fe_2N_depth_N']:.2f} N"
        lines.append(f"| {r['design']} | {fe['d_2N_mm']:.3f} | {_cell(e.get('border/finger'), '2')} | "
                     f"{_cell(e.get('border/finger'), '20')} | {_cell(pf, '2')} | "
                     f"{_cell(pf, '20')} | {at} | {_cell(e['phalanx/finger'], '2')} | "
                     f"{_cell(e['phalanx/finger'], '20')} |")
    lines += ["", "pocket2-sil with the border's radius or length moved and with the finger "
              "crossing it at other angles than 90 deg (the same laws, and the border's law of "
              "the nearest crossing angle that has one, `softhand.skin.contact_classes."
              "border_class`: what a pair crossing the border there carries):", "",
              "| border (width x height x length mm) | top radius mm | crossing deg | FE d(2 N) mm | "
              "border/finger law (90 deg), 0-2 N | 0-20 N | the crossing's law | 0-2 N | 0-20 N | "
              "palm/finger law, 0-2 N | phalanx/finger law, 0-2 N |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    cases = ([(r["geometry"], 90.0, r) for r in d["radii"]]
             + [(d["border"], r["crossing_deg"], r) for r in d.get("crossings", [])])
    for g, angle, r in cases:
        fe = r["fe"]
        rad = (g["width_mm"] / 2) ** 2 / g["height_mm"]
        head = (f"| {g['width_mm']:g} x {g['height_mm']:g} x {g.get('length_mm', 10.0):g} | "
                f"{rad:.1f} | {angle:g} |")
        if "error" in fe:
            lines.append(f"{head} FE stopped | | | | | | | |")
            continue
        e = r["errors"]
        own = border_class(angle)
        lines.append(f"{head} {fe['d_2N_mm']:.3f} | {_cell(e.get('border/finger'), '2')} | "
                     f"{_cell(e.get('border/finger'), '20')} | {own} | "
                     f"{_cell(e.get(own), '2')} | {_cell(e.get(own), '20')} | "
                     f"{_cell(e['palm/finger'], '2')} | {_cell(e['phalanx/finger'], '2')} |")
    if d.get("handshakes"):
        regions = ("Palm1", "Palm2", "Back1", "Back2")
        lines += ["", "What the border's law does to the handshake (`--handshake`): the default "
                  "run (neutral, pocket2-sil) as shipped and with the border's pairs on the "
                  "palm/finger law, as before the border had a law; the share of the force "
                  "through the border's laws (every crossing's) and through a skin law made for "
                  "the contact's geometry (`force_accounting.by_geometry`, crossing within 15 "
                  "deg of the law's):", "",
                  "| seed | pairs | " + " | ".join(f"{r} peak N" for r in regions)
                  + " | largest other region | over 2 N | force between the hands N s | through "
                  "the border's laws % | skin law fits % | deepest pair mm | bone on bone N |",
                  "|---|---|" + "---|" * (len(regions) + 7)]
        for h in d["handshakes"]:
            others = {k: v for k, v in h["peak_N"].items() if k not in regions}
            top = max(others, key=others.get)
            lines.append(f"| {h['seed']} | {h['what']} | "
                         + " | ".join(f"{h['peak_N'][r]:.1f}" for r in regions)
                         + f" | {top} {others[top]:.1f} | {', '.join(h['over_2N'])} | "
                         f"{h['total_Ns']:.1f} | "
                         f"{_border_share(h['by_law_share_pct']):.1f} | "
                         f"{h['skin_own_class_share_pct']:.1f} | "
                         f"{h['deepest_pair_mm']:.1f} | {h['bone_on_bone_peak_N']:.1f} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
