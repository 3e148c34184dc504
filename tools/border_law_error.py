"""What the palm's rounded border costs: the laws the scene uses there against an FE of it.

    python tools/border_law_error.py [--out reports/border-law-error] [--designs all]

`reports/contact-geometry.md` finds 94 % of the default handshake's force on a rounded border of
the prosthetic palm's one convex surface (radius 8-23 mm, median 13.6, p10-p90), pressed by the
partner's fingers and carried by the palm/finger law: an FE cylinder of radius 9 mm across a flat
slab of the design's layers over the metacarpals. No FE curve of a rounded border exists yet
(issue 36, item 2), so this runs the nearest body the FE has: the phalanx section widened to a
border, width 20 mm and height 8 mm (a half ellipse, n = 2: radius a^2 / b = 12.5 mm at its top,
the median border's; the design's layers and pocket as on the phalanx; 8 mm of skin over a flat
bone, the palm model's 9 mm over the crest), under the same 9 mm cylinder across it, to 20 N on
the 3D quarter model. Against it, each skin's two laws that could carry a finger there: the
palm/finger law the pair carries and the phalanx/finger law (its elastic force on the FE's ramp
history, with its relaxation), as the RMS and largest difference in % of 2 N over the FE's
0-2 N and 0-20 N. Beside pocket2-sil, the border's radius moved: width 20 mm, height 7.7 mm
(13.0 mm) and 9 mm (11.1 mm); a flatter section leaves its flanks too tight for a 2 mm pocket's
layers, so the FE's phalanx reaches no larger radius. Writes ``OUT.md`` and ``OUT.json``.

``--handshake`` adds what the palm's law does to the handshake: the default handshake (neutral,
seeds 0-2) as shipped against the same with every palm/finger pair given its skin's
phalanx/finger pair law instead (the class the border follows to 2 N, too soft beyond it): a
what-if that swaps calibrated pair parameters in `softhand.envs.skins.pair_choices`, not a law
of the border (there is none yet).
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
from softhand.skin.files import load_calibration

BORDER = {"width_mm": 20.0, "height_mm": 8.0}
RADII = ({"width_mm": 20.0, "height_mm": 7.7}, {"width_mm": 20.0, "height_mm": 9.0})
FINGER = "cylinder:9@90"
LAWS = ("palm/finger", "phalanx/finger")


def _fe(design: str, geometry: dict) -> dict:
    s = IndentationSettings(mode="3d", indenter=FINGER, geometry=geometry, max_force_N=20.0,
                            hold_s=0.0)
    try:
        r = indent(design, s)
    except ConvergenceError as exc:
        return {"error": str(exc)[:200]}
    ramp = ~r.hold
    return {"time_s": r.time_s[ramp].tolist(), "displacement_mm": r.displacement_mm[ramp].tolist(),
            "force_N": r.force_N[ramp].tolist(), "status": r.status.value,
            "d_2N_mm": r.displacement_at(2.0)}


def _errors(fe: dict, design: str) -> dict:
    cal = load_calibration(design)
    t, d, f = (np.asarray(fe[k]) for k in ("time_s", "displacement_mm", "force_N"))
    out = {}
    for key in LAWS:
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


def _swap_palm_finger(original):
    """`pair_choices` with each palm/finger pair carrying its skin's phalanx/finger pair law."""
    from softhand.envs import skins as sk

    def choices(model, skins, representations=None, *, directory=sk.SKINS_DIR,
                contact_laws="geometry"):
        out = original(model, skins, representations, directory=directory,
                       contact_laws=contact_laws)
        tissue = sk.series_law("rigid", str(directory))
        for name, c in out.items():
            if c.law != "palm/finger":
                continue
            _, skin = sk.skin_of_pair(name, skins)
            law = load_calibration(skin, directory, require=("soft-contact",)
                                   ).pair_laws["phalanx/finger"]
            rep = sk.get_representation(sk.DEFAULT_REPRESENTATION)
            out[name] = sk.PairChoice(c.contact, "phalanx/finger (what-if)",
                                      rep.hand_pair_law(law.pair.params, tissue),
                                      float(law.pair.calibrated_max_N))
        return out
    return choices


def _handshakes() -> list[dict]:
    from softhand.envs import skins as sk
    from softhand.envs.run import run_handshake

    rows = []
    for seed in (0, 1, 2):
        for what in ("shipped", "palm/finger pairs on the phalanx/finger law"):
            original = sk.pair_choices
            if what != "shipped":
                sk.pair_choices = _swap_palm_finger(original)
            try:
                r = run_handshake(seed=seed)
            finally:
                sk.pair_choices = original
            table = r.table()
            over = r.overload()
            acc = r.force_accounting()
            rows.append({"seed": seed, "what": what,
                         "peak_N": {k: v["peak_N"] for k, v in table.items()},
                         "over_2N": r.over_2n, "total_Ns": acc["total_Ns"],
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
    args = ap.parse_args()
    out = Path(args.out)
    if args.handshake_only:
        data = json.loads(out.with_suffix(".json").read_text(encoding="utf-8"))
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
    if args.handshake:
        data["handshakes"] = _handshakes()
    atomic_write_json(out.with_suffix(".json"), data)
    atomic_write_text(out.with_suffix(".md"), markdown(data))
    print(markdown(data))


def _cell(e: dict | None, top: str) -> str:
    if e is None:
        return "n/a"
    r = e[f"to_{top}N"]
    return f"{r['rms_pct_of_2N']:.0f} / {r['max_pct_of_2N']:.0f} ({r['mean_signed_pct_of_2N']:+.0f})"


def markdown(d: dict) -> str:
    lines = ["# The palm's rounded border against the laws that carry it", "",
             "`python tools/border_law_error.py --out reports/border-law-error`: the FE's nearest "
             f"body to the palm's rounded border (the phalanx section widened to width "
             f"{d['border']['width_mm']:g} mm, height {d['border']['height_mm']:g} mm: a "
             "12.5 mm top radius, the median border the partner's fingers press in the default "
             f"handshake, `reports/contact-geometry.md`) under the finger ({d['finger']}), 3D, to "
             "20 N, against the palm/finger law the scene's pair carries there and the "
             "phalanx/finger law: RMS / largest difference in % of 2 N (mean signed: the law "
             "above the FE is +), over the FE's 0-2 N and 0-20 N.", "",
             machine_line(d["machine"]), "",
             "| design | FE d(2 N) mm | palm/finger law, 0-2 N | 0-20 N | law's force at the "
             "FE's 2 N depth | phalanx/finger law, 0-2 N | 0-20 N |",
             "|---|---|---|---|---|---|---|"]
    for r in d["rows"]:
        fe = r["fe"]
        if "error" in fe:
            lines.append(f"| {r['design']} | FE stopped: {fe['error'][:80]} | | | | | |")
            continue
        e = r["errors"]
        pf = e["palm/finger"]
        at = "n/a" if pf is None else f"{pf['law_force_at_fe_2N_depth_N']:.2f} N"
        lines.append(f"| {r['design']} | {fe['d_2N_mm']:.3f} | {_cell(pf, '2')} | "
                     f"{_cell(pf, '20')} | {at} | {_cell(e['phalanx/finger'], '2')} | "
                     f"{_cell(e['phalanx/finger'], '20')} |")
    lines += ["", "pocket2-sil with the border's radius moved (the same laws):", "",
              "| border (width x height mm) | top radius mm | FE d(2 N) mm | palm/finger law, "
              "0-2 N | phalanx/finger law, 0-2 N |", "|---|---|---|---|---|"]
    for r in d["radii"]:
        g, fe = r["geometry"], r["fe"]
        rad = (g["width_mm"] / 2) ** 2 / g["height_mm"]
        if "error" in fe:
            lines.append(f"| {g['width_mm']:g} x {g['height_mm']:g} | {rad:.1f} | FE stopped | | |")
            continue
        lines.append(f"| {g['width_mm']:g} x {g['height_mm']:g} | {rad:.1f} | "
                     f"{fe['d_2N_mm']:.3f} | {_cell(r['errors']['palm/finger'], '2')} | "
                     f"{_cell(r['errors']['phalanx/finger'], '2')} |")
    if d.get("handshakes"):
        regions = ("Palm1", "Palm2", "Back1", "Back2")
        lines += ["", "What the palm's law does to the handshake (`--handshake`): the default run "
                  "(neutral, pocket2-sil) as shipped and with every palm/finger pair given its "
                  "skin's phalanx/finger pair law (a what-if, not a border law):", "",
                  "| seed | pairs | " + " | ".join(f"{r} peak N" for r in regions)
                  + " | largest other region | over 2 N | force between the hands N s | deepest "
                  "pair mm | bone on bone N |", "|---|---|" + "---|" * (len(regions) + 5)]
        for h in d["handshakes"]:
            others = {k: v for k, v in h["peak_N"].items() if k not in regions}
            top = max(others, key=others.get)
            lines.append(f"| {h['seed']} | {h['what']} | "
                         + " | ".join(f"{h['peak_N'][r]:.1f}" for r in regions)
                         + f" | {top} {others[top]:.1f} | {', '.join(h['over_2N'])} | "
                         f"{h['total_Ns']:.1f} | {h['deepest_pair_mm']:.1f} | "
                         f"{h['bone_on_bone_peak_N']:.1f} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
