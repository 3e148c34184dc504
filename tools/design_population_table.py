"""The population of the design search's winners beside pocket2-sil: one table per region.

Reads ``reports/population-pocket2-sil.json`` and ``reports/population-design-*.json`` (each the
``results.json`` of ``softhand population --n 30 --design PATH``) and writes
``reports/design-search-population.md``: per region the share of partners over 2 N and the
median peak force, each winner beside pocket2-sil, and per run the force accounting (share
through calibrated laws, bone on bone, time beyond a law's range).

    python tools/design_population_table.py [--out reports/design-search-population.md] \
        [--conditions "how the runs ran"]
"""

from __future__ import annotations

import argparse
import json
import statistics
from pathlib import Path

REPORTS = Path(__file__).resolve().parents[1] / "reports"


def _load(path: Path) -> dict:
    return json.loads(path.read_text())


def _accounting(data: dict) -> dict[str, float]:
    acc = [p["force_accounting"] for p in data["partners"]]
    med = statistics.median
    return {"calibrated": med(a["calibrated_share_pct"] for a in acc),
            "bone": med(a["bone_on_bone_peak_N"] for a in acc),
            "beyond": med(a["out_of_range_time_pct"] for a in acc),
            "warned": sum(1 for p in data["partners"] if p["warnings"])}


def table(base: dict, winners: list[tuple[str, dict, dict]], conditions: str = "") -> str:
    """The markdown page (see the module docstring)."""
    lines = ["# The winners' population beside pocket2-sil", ""]
    cmd = base["settings"]["command"]
    lines += [f"pocket2-sil: `{cmd}` (seed {base['settings']['seed']}, "
              f"{base['settings']['finished']} partners)."]
    for name, data, cal in winners:
        s = data["settings"]
        top = cal["provenance"]["design"]["calibrated_max_N"]
        lines.append(f"{name} ({cal['provenance']['design']['label']}): `{s['command']}` "
                     f"(seed {s['seed']}, {s['finished']} partners); its law and pair law are "
                     f"calibrated to {top:.2f} N, where its FE stopped.")
    if conditions:
        lines += ["", conditions]
    lines += ["", "Each winner's calibrated skin (`softhand design calibrate`, "
              "calibration/designs/): how far its 3D FE went in each folder (the ramp reruns to "
              "95 % of the plate travel where Newton found no equilibrium), the range of its "
              "plate law, and the soft contact's error against its FE curve:", "",
              "| winner | plate 0.5 mm/s | 5 mm/s | 2 mm/s | finger | palm plate | "
              "palm finger | pair laws calibrated to N | soft contact RMS % of 2 N |",
              "|---|---|---|---|---|---|---|---|---|"]
    for name, _, cal in winners:
        f = cal["provenance"]["design"]["fe_folders"]
        cells = [f"{f[k]['peak_force_N']:.2f} N at {f[k]['max_depth_mm']:.2f} mm" if k in f
                 else "n/a" for k in (".", "speed-5", "speed-2", "finger", "palm-plate",
                                      "palm-finger")]
        pairs = ", ".join(f"{k} {v['pair_law']['calibrated_max_N']:.2f}"
                          for k, v in cal.get("pair_laws", {}).items())
        rms = cal["representations"]["soft-contact"]["rms_error_pct_of_2N"]
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {pairs} | {rms:.2f} |")
    lines += ["", "Every region of the prosthetic hand wears the design: the phalanges, and the "
              "palm's one surface (Palm1, Palm2, Back1 and Back2 are its zones) with the thenar.",
              "", "Share of partners over 2 N (%) and median peak force (N) per region:", ""]
    head = "| region | pocket2-sil |" + "".join(f" {n} |" for n, _, _ in winners)
    lines += [head, "|---|---|" + "---|" * len(winners)]
    for region, b in base["summary"].items():
        cells = [f"{b['over_2N_pct']:.0f} %, {b['median_peak_N']:.2f} N"]
        for _, data, _ in winners:
            w = data["summary"][region]
            cells.append(f"{w['over_2N_pct']:.0f} %, {w['median_peak_N']:.2f} N")
        lines.append(f"| {region} | " + " | ".join(cells) + " |")
    lines += ["", "Force accounting, median over partners: share of contact impulse through "
              "calibrated laws, bone-on-bone peak force, time with a contact beyond its law's "
              "calibrated range; partners whose run warned (a contact beyond range or a bone "
              "bottoming out):", "",
              "| run | calibrated share % | bone-on-bone peak N | time beyond range % | "
              "partners warned |", "|---|---|---|---|---|"]
    for name, data in [("pocket2-sil", base), *[(n, d) for n, d, _ in winners]]:
        a = _accounting(data)
        lines.append(f"| {name} | {a['calibrated']:.1f} | {a['bone']:.2f} | "
                     f"{a['beyond']:.1f} | {a['warned']} of {len(data['partners'])} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(REPORTS / "design-search-population.md"))
    ap.add_argument("--conditions", default="",
                    help="How the winners' populations ran (cores, load average), one sentence.")
    args = ap.parse_args()
    from softhand.paths import CALIBRATION_DIR

    base = _load(REPORTS / "population-pocket2-sil.json")
    winners = []
    for path in sorted(REPORTS.glob("population-design-*.json")):
        data = _load(path)
        name = data["settings"]["design"]
        cal = _load(CALIBRATION_DIR / "designs" / f"{name}.json")
        winners.append((name, data, cal))
    rank = {w["trial"]: i for i, w in enumerate(_load(REPORTS / "design-search.json")["winners"])}
    winners.sort(key=lambda t: rank.get(t[2]["provenance"]["design"]["search"]["trial"], 99))
    Path(args.out).write_text(table(base, winners, args.conditions))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
