"""The design search's report: a 300-trial 2D screen, the 3D check of 3 winners, pocket2-sil beside.

    taskset -c 1 python tools/design_search_report.py [--trials 300] [--work DIR]
        [--contact-points 4]

Runs `softhand design search` (the same functions) on one core, the seven library silicones with
an elongation at break as the materials, and writes ``reports/design-search.{md,json,png}`` and
``reports/design-search-curves.png``: the
wall time of the screen and of the 3D check, the Pareto front, the winners' objectives in 2D and
3D with their differences, their lifelike distance beside pocket2-sil's (this run's 2D and 3D, and
the calibrated skin's in ``calibration/skins/index.json``), and the STL checks. The shipped report
was screened with 4 contact points per face direction, the FE's default; `softhand design
search` now screens with 2 (`SCREEN_CONTACT_POINTS`), so ``--contact-points 4`` (the default
here) reproduces the shipped report. The study, the
STLs and the full tables stay in the work folder (``--work``).
"""

from __future__ import annotations

import argparse
import json
import shutil
import time
from pathlib import Path

from softhand.bench.common import machine_info, machine_line
from softhand.design.evaluate import evaluate, screen_settings
from softhand.design.outputs import BASELINE, table_markdown, write_outputs
from softhand.design.search import JOURNAL, candidate_of, run_search
from softhand.design.space import DesignSpace
from softhand.fem.solver import ConvergenceError
from softhand.io import atomic_write_json, atomic_write_text
from softhand.paths import REPORTS_DIR, SKINS_DIR

MATERIALS = ("ecoflex-00-10", "ecoflex-00-30", "ecoflex-00-50", "dragon-skin-10",
             "dragon-skin-20", "dragon-skin-30", "sorta-clear-40")


def _calibrated_pocket2_sil() -> float | None:
    index = Path(SKINS_DIR) / "index.json"
    rows = json.loads(index.read_text(encoding="utf-8"))["lifelike"] if index.exists() else []
    return next((r["distance_pct"] for r in rows if r["name"] == "pocket2-sil"), None)


def force_limits(winners: list[dict], contact_points: int = 4) -> list[dict]:
    """Each winner (and pocket2-sil) on the 2D ramp to 20 N, the handshake's range: the force
    the FE carries it to, and the durability usage there when it gets to 20 N."""
    rows = []
    for name, cand in [*((f"{i}", candidate_of(w)) for i, w in enumerate(winners, 1)),
                       ("pocket2-sil", BASELINE)]:
        try:
            ev = evaluate(cand, screen_settings(max_force_N=20.0,
                                                contact_points=contact_points))
            rows.append({"winner": name, "reached_N": ev.peak_force_N, "travel_mm": None,
                         "usage": ev.durability_usage, "error": None})
        except ConvergenceError as exc:
            rows.append({"winner": name, "reached_N": exc.diagnostics.get("force_N"),
                         "travel_mm": exc.diagnostics.get("displacement_mm"), "usage": None,
                         "error": str(exc).split(": ", 1)[-1][:120]})
    return rows


def _f(v, fmt: str) -> str:
    return "n/a" if v is None else format(v, fmt)


def markdown(data: dict) -> str:
    b2, b3 = data["baseline"]["2d"], data["baseline"]["3d"]
    cal = data["pocket2_sil_calibrated_pct"]
    points = data.get("contact_points", 4)  # the shipped report's runs predate the key
    lines = [
        f"# Design search: {data['trials_asked']} trials, 2D screen and 3D check", "",
        f"`taskset -c 1 python tools/design_search_report.py --trials {data['trials_asked']} "
        f"--contact-points {points}` (one core): sampler {data['sampler']} (seed {data['seed']}), materials "
        f"{', '.join(data['materials'])}, the paper's ramp to {data['max_force_N']:g} N at 0.5 "
        f"mm/s on the {data['mesh']} mesh, {points} contact points per face direction. "
        "Objectives, both minimised: the lifelike distance from "
        "the human middle phalanx (%) and the durability usage (peak principal strain at the "
        "largest force / elongation at break).", "",
        machine_line(data["machine"]), "",
        f"- 2D screen: {data['screen_wall_s']:.0f} s wall for {data['trials_asked']} trials "
        f"({data['screen_wall_s'] / data['trials_asked']:.2f} s per trial: FE, sampler and "
        f"journal); {data['n_trials_complete']} complete, {len(data['failed_this_run'])} failed"
        + (f" (the first: {next(iter(data['failed_this_run'].values()))[:160]})"
           if data["failed_this_run"] else ""),
        f"- 3D check of {len(data['winners'])} winners and pocket2-sil (2D and 3D): "
        f"{data['check_wall_s']:.0f} s wall",
        f"- Pareto front: {len(data['front'])} designs; most lifelike "
        f"{data['front'][0]['lifelike_distance_pct']:.1f} % (2D), "
        f"{data['front'][0]['candidate']['inner']} / {data['front'][0]['candidate']['outer']}",
        f"- pocket2-sil, run the same way: {_f(b2['lifelike_distance_pct'], '.1f')} % (2D), "
        f"{_f(b3['lifelike_distance_pct'], '.1f')} % (3D); the shipped calibrated skin: "
        f"{_f(cal, '.1f')} % (from its fitted law)", "",
        "Winners: 3 designs spread along the part of the front more lifelike than pocket2-sil in "
        "2D (its two ends and the middle), each run again on the 3D quarter model; the STLs are "
        "in the work folder:", "",
        table_markdown(data), "",
        "2D against 3D (3D - 2D) for each winner:", "",
        "| # | lifelike distance, pp | durability usage | d(2 N) | STL volume error | watertight |",
        "|---|---|---|---|---|---|"]
    for i, w in enumerate(data["winners"], 1):
        d = w.get("difference_3d_minus_2d") or {}
        s = w.get("stl") or {}
        lines.append(f"| {i} | {_f(d.get('lifelike_distance_pp'), '+.1f')} | "
                     f"{_f(d.get('durability_usage'), '+.4f')} | "
                     f"{_f(d.get('displacement_at_2N_pct'), '+.1f')} % | "
                     f"{_f(s.get('volume_error_pct'), '+.3f')} % | {s.get('watertight')} |")
    b_d2 = (None if b2["displacement_mm"][1] is None or b3["displacement_mm"][1] is None
            else 100 * (b3["displacement_mm"][1] / b2["displacement_mm"][1] - 1))
    lines.append(f"| pocket2-sil | {_f(b3['lifelike_distance_pct'] - b2['lifelike_distance_pct'], '+.1f')}"
                 f" | n/a | {_f(b_d2, '+.1f')} % | | |")
    lines += ["", "The handshake's range: each winner on the 2D ramp to 20 N. The FE stops where "
              "Newton finds no equilibrium even at the smallest step (the soft skin squeezed to "
              "about half its height; the messages are in the JSON), so durability at the "
              "handshake's 10-15 N peaks could not be scored for these soft designs:", "",
              "| winner | force reached, N | plate travel there, mm | usage at 20 N |",
              "|---|---|---|---|"]
    for r in data.get("force_limits", []):
        lines.append(f"| {r['winner']} | {_f(r['reached_N'], '.2f')} | "
                     f"{_f(r['travel_mm'], '.2f')} | {_f(r['usage'], '.3f')} |")
    lines += ["", "The pictures: `reports/design-search.png` (the front) and "
              "`reports/design-search-curves.png` (the winners' curves against the human "
              "phalanges), on the design search page.", ""]
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=300)
    ap.add_argument("--work", default="design-search-300")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--resume", action="store_true")
    ap.add_argument("--contact-points", type=int, choices=(2, 4), default=4,
                    help="the FE's contact points per face direction (4: the shipped report's)")
    args = ap.parse_args()
    machine = machine_info()
    work = Path(args.work)
    if (work / JOURNAL).exists() and not args.resume:
        raise SystemExit(f"{work / JOURNAL} exists: --resume, or another --work")
    space = DesignSpace(materials=MATERIALS)
    t0 = time.perf_counter()
    outcome = run_search(space, trials=args.trials, out=work, seed=args.seed, resume=args.resume,
                         contact_points=args.contact_points)
    screen = time.perf_counter() - t0
    if outcome.interrupted:
        raise SystemExit("interrupted: --resume continues")
    t1 = time.perf_counter()
    data = write_outputs(outcome.study, work, check=3, extra={
        "trials_asked": args.trials, "sampler": "tpe", "seed": args.seed, "mesh": "default",
        "max_force_N": 2.0, "materials": list(MATERIALS), "failed_this_run": outcome.failed,
        "contact_points": args.contact_points})
    data.update(machine=machine, screen_wall_s=screen, check_wall_s=time.perf_counter() - t1,
                pocket2_sil_calibrated_pct=_calibrated_pocket2_sil())
    data["force_limits"] = force_limits(data["winners"], args.contact_points)
    REPORTS_DIR.mkdir(exist_ok=True)
    atomic_write_json(REPORTS_DIR / "design-search.json", json.loads(json.dumps(data, default=float)))
    shutil.copyfile(work / "pareto.png", REPORTS_DIR / "design-search.png")
    if (work / "curves.png").exists():
        shutil.copyfile(work / "curves.png", REPORTS_DIR / "design-search-curves.png")
    atomic_write_text(REPORTS_DIR / "design-search.md", markdown(data))
    print(markdown(data))


if __name__ == "__main__":
    main()
