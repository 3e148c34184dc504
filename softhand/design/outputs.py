"""What a search leaves in its folder: the 3D check of the winners, a table, a picture, STLs.

* ``designs.json`` / ``designs.md``: the Pareto set of the 2D screen; for the checked winners
  (up to ``check`` designs spread along the part of the front more lifelike than pocket2-sil in
  2D, or along the whole front where none is) the same objectives from the 3D quarter model
  and the differences 3D - 2D; the paper's pocket2-sil beside them, run the same way.
* ``pareto.png``: every trial's two objectives, the front, the 3D values of the winners, and
  pocket2-sil's lifelike distance.
* ``curves.png``: each winner's force against indentation (2D and 3D) and pocket2-sil's,
  against the human middle phalanges: the paper's means and SDs at 2 N (Little2, Ring2, Middle2,
  flat and curled), its "more than 2 mm" at 1 N, and the human reference law through them
  (`softhand.laws.references.human_law`).
* ``stl/{rank}-trial{n}.stl``: each checked winner as a watertight solid for a mould
  (`softhand.design.stl`), with its checks in ``designs.json``; beside it
  ``{rank}-trial{n}-materials.json``, with which the ``softhand fe indent`` line in
  ``designs.json`` (``fe_indent``) runs the winner again.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from softhand.design.evaluate import evaluate, fe_indent_command, fe_materials, screen_settings
from softhand.design.search import (
    candidate_of,
    completed,
    pareto_evaluations,
    study_contact_points,
)
from softhand.design.space import Candidate
from softhand.design.stl import write_stl
from softhand.io import atomic_open, atomic_write_json, atomic_write_text
from softhand.parallel import available_cpus, run_tasks

__all__ = ["BASELINE", "check_in_3d", "choose_winners", "fe_threads", "plot_curves", "plot_front",
           "write_outputs"]

#: the paper's most lifelike design (pocket2-sil, Table 3's SIL, the default geometry)
BASELINE = Candidate(outer_layer_mm=0.8, pocket_roof_mm=1.4, pocket_height_mm=2.0,
                     pocket_half_width_mm=5.0, inner="sil", outer="sil")


def choose_winners(front: list[dict[str, Any]], k: int, *, below: float | None = None
                   ) -> list[dict[str, Any]]:
    """Up to ``k`` designs spread along the front (sorted by lifelike distance): the ends and
    evenly spaced ones between, the most lifelike first. ``below``: only the designs more
    lifelike than that distance (%), e.g. pocket2-sil's, where the front has any."""
    pool = [r for r in front if below is None or r["lifelike_distance_pct"] < below] or front
    if len(pool) <= k:
        return list(pool)
    idx = np.unique(np.round(np.linspace(0, len(pool) - 1, k)).astype(int))
    return [pool[i] for i in idx]


def fe_threads(workers: int | None, cluster: str | None = None) -> int:
    """Threads of each 3D check's element kernels: this machine's CPUs shared among its
    ``workers`` local processes (one on a cluster, whose workers have their own machines)."""
    if cluster is not None:
        return 1
    return max(1, available_cpus() // max(1, workers or 1))


def _delta(a: float | None, b: float | None) -> float | None:
    return None if a is None or b is None else b - a


def check_in_3d(rows: list[dict[str, Any]], *, mesh: str = "default", max_force_N: float = 2.0,
                threads: int | None = 1, cluster: str | None = None,
                contact_points: int | None = None) -> dict[str, Any]:
    """The 3D quarter model of each row's candidate and of `BASELINE` (2D and 3D), with the
    differences 3D - 2D of each objective and of the indentation at 2 N.

    ``threads`` local worker processes run the designs; each 3D run's element kernels take this
    machine's CPUs shared among them (`fe_threads`), so that one worker's check uses them all.
    """
    s3 = screen_settings(mode="3d", mesh=mesh, max_force_N=max_force_N,
                         contact_points=contact_points, threads=fe_threads(threads, cluster))
    s2 = screen_settings(mode="2d", mesh=mesh, max_force_N=max_force_N,
                         contact_points=contact_points)
    tasks = [(f"trial-{r['trial']}", (candidate_of(r), s3)) for r in rows]
    tasks += [("baseline-3d", (BASELINE, s3)), ("baseline-2d", (BASELINE, s2))]
    out = run_tasks(evaluate, tasks, threads=None if cluster else threads, cluster=cluster)
    checked = []
    for r in rows:
        key = f"trial-{r['trial']}"
        ev = out.results.get(key)
        row = {**r, "check_3d": None if ev is None else ev.to_dict()}
        if ev is not None:
            row["difference_3d_minus_2d"] = {
                "lifelike_distance_pp": _delta(r["lifelike_distance_pct"],
                                               ev.lifelike_distance_pct),
                "durability_usage": _delta(r["durability_usage"], ev.durability_usage),
                "displacement_at_2N_pct": (None if ev.displacement_mm[1] is None else
                                           100 * (ev.displacement_mm[1] / r["displacement_mm"][1]
                                                  - 1))}
        else:
            row["check_error"] = str(out.errors.get(key, "interrupted"))
        checked.append(row)
    base = {m: out.results[f"baseline-{m}"].to_dict() if f"baseline-{m}" in out.results else None
            for m in ("2d", "3d")}
    return {"winners": checked, "baseline": base, "interrupted": out.interrupted}


def plot_front(trials: list[dict[str, Any]], front: list[dict[str, Any]],
               winners: list[dict[str, Any]], baseline: dict[str, Any], path: Path) -> None:
    """Lifelike distance against durability usage: trials, front, 3D checks, pocket2-sil."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    x = [t["lifelike_distance_pct"] for t in trials]
    y = [t["durability_usage"] for t in trials]
    ax.scatter(x, y, s=12, c="0.7", label=f"2D trials ({len(trials)})")
    fx = [t["lifelike_distance_pct"] for t in front]
    fy = [t["durability_usage"] for t in front]
    ax.plot(fx, fy, "o-", color="tab:blue", ms=5, label=f"Pareto front, 2D ({len(front)})")
    for i, w in enumerate(winners, 1):
        c3 = w.get("check_3d")
        ax.annotate(str(i), (w["lifelike_distance_pct"], w["durability_usage"]),
                    textcoords="offset points", xytext=(4, 4), fontsize=8)
        if c3 and c3["lifelike_distance_pct"] is not None and c3["durability_usage"] is not None:
            ax.plot([w["lifelike_distance_pct"], c3["lifelike_distance_pct"]],
                    [w["durability_usage"], c3["durability_usage"]], "-", color="tab:red", lw=0.8)
            ax.plot(c3["lifelike_distance_pct"], c3["durability_usage"], "s", color="tab:red",
                    ms=6, label="3D check" if i == 1 else None)
    for mode, style in (("2d", ":"), ("3d", "--")):
        b = baseline.get(mode)
        if b and b["lifelike_distance_pct"] is not None:
            ax.axvline(b["lifelike_distance_pct"], color="k", ls=style, lw=1,
                       label=f"pocket2-sil ({mode.upper()}): {b['lifelike_distance_pct']:.1f} %")
    ax.set_xlabel("lifelike distance from the human middle phalanx (%)")
    ax.set_ylabel("durability usage: peak strain / elongation at break")
    ax.set_title("Design search: 2D screen and 3D check (both objectives minimised)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    with atomic_open(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110)
    plt.close(fig)


def plot_curves(winners: list[dict[str, Any]], baseline: dict[str, Any], path: Path) -> None:
    """Winners' ramps against the human corridors (module docstring)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from softhand.laws.references import human_law
    from softhand.paper import paper

    fig, ax = plt.subplots(figsize=(8, 5.5))
    law = human_law().source
    d = np.linspace(0.0, np.log1p(2.2 / law["a_N"]) / law["b_per_mm"], 100)
    ax.plot(d, law["a_N"] * np.expm1(law["b_per_mm"] * d), color="k", lw=2,
            label="human reference law")
    human = paper()["human_displacement_at_2N_mm"]
    for i, (name, (mean, sd)) in enumerate((k, v) for k, v in human.items()
                                           if isinstance(v, list)):
        ax.errorbar(mean, 2.0 + 0.03 * (i - 2.5), xerr=sd, fmt="o", color="0.45", ms=4,
                    capsize=2, label="paper, human 2 N: mean and SD" if i == 0 else None)
        ax.annotate(name, (mean + sd, 2.0 + 0.03 * (i - 2.5)), fontsize=6, color="0.45",
                    xytext=(3, -2), textcoords="offset points")
    ax.axvspan(human["at_1N_more_than_mm"], 7.0, ymin=0, ymax=0.02, color="0.6")
    ax.plot([human["at_1N_more_than_mm"]], [1.0], ">", color="0.45", ms=7,
            label=f"paper, human 1 N: more than {human['at_1N_more_than_mm']:g} mm")
    colours = plt.cm.tab10(np.arange(len(winners)))
    for i, (w, c) in enumerate(zip(winners, colours, strict=True), 1):
        ax.plot(w["curve"]["displacement_mm"], w["curve"]["force_N"], "--", color=c, lw=1)
        c3 = w.get("check_3d")
        if c3:
            ax.plot(c3["curve"]["displacement_mm"], c3["curve"]["force_N"], "-", color=c, lw=2,
                    label=f"{i}: {w['label']} (3D; dashed 2D)")
    b3 = baseline.get("3d")
    if b3:
        ax.plot(b3["curve"]["displacement_mm"], b3["curve"]["force_N"], "-", color="tab:gray",
                lw=1.5, label="pocket2-sil (3D)")
    ax.set_xlabel("indentation (mm)")
    ax.set_ylabel("force (N)")
    ax.set_xlim(0, 5)
    ax.set_ylim(0, 2.2)
    ax.set_title("Winners against the human middle phalanges (plate, 0.5 mm/s)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    with atomic_open(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110)
    plt.close(fig)


def _fmt(v: float | None, f: str) -> str:
    return "" if v is None else format(v, f)


def table_markdown(data: dict[str, Any]) -> str:
    """The design table: winners with 2D and 3D objectives, geometry and materials."""
    lines = ["| # | trial | inner / outer | pocket h x half-width mm | roof / outer mm | floor mm "
             "| d(1 N), d(2 N) mm 2D | lifelike % 2D / 3D | usage 2D / 3D | pocket closes N "
             "| useful sensors |", "|" + "---|" * 11]
    for i, w in enumerate(data["winners"], 1):
        c, c3 = w["candidate"], w.get("check_3d") or {}
        d = w["displacement_mm"]
        lines.append(
            f"| {i} | {w['trial']} | {c['inner']} / {c['outer']} | "
            f"{c['pocket_height_mm']:.2f} x {c['pocket_half_width_mm']:.2f} | "
            f"{c['pocket_roof_mm']:.2f} / {c['outer_layer_mm']:.2f} | {c['floor_mm']:.2f} | "
            f"{_fmt(d[0], '.2f')}, {_fmt(d[1], '.2f')} | "
            f"{_fmt(w['lifelike_distance_pct'], '.1f')} / "
            f"{_fmt(c3.get('lifelike_distance_pct'), '.1f')} | "
            f"{_fmt(w['durability_usage'], '.3f')} / {_fmt(c3.get('durability_usage'), '.3f')} | "
            f"{_fmt(w['pocket_closes_at_N'], '.2f')} | {', '.join(w['useful_sensors']) or 'none'} |")
    b2, b3 = data["baseline"]["2d"] or {}, data["baseline"]["3d"] or {}
    d = b2.get("displacement_mm", [None, None])
    lines.append(f"| - | pocket2-sil | sil / sil | 2.00 x 5.00 | 1.40 / 0.80 | 5.60 | "
                 f"{_fmt(d[0], '.2f')}, {_fmt(d[1], '.2f')} | "
                 f"{_fmt(b2.get('lifelike_distance_pct'), '.1f')} / "
                 f"{_fmt(b3.get('lifelike_distance_pct'), '.1f')} | n/a (no elongation at break "
                 f"for GLS 40) | {_fmt(b2.get('pocket_closes_at_N'), '.2f')} | "
                 f"{', '.join(b2.get('useful_sensors', [])) or 'none'} |")
    return "\n".join(lines)


def write_outputs(study, out: str | Path, *, check: int = 3, mesh: str = "default",
                  max_force_N: float = 2.0, threads: int | None = 1,
                  cluster: str | None = None, extra: dict[str, Any] | None = None,
                  contact_points: int | None = None) -> dict[str, Any]:
    """The 3D check of up to ``check`` winners, then ``designs.{json,md}``, ``pareto.png`` and
    the STLs into ``out`` (each file written whole). ``contact_points``: None, the study's own
    (`study_contact_points`)."""
    out = Path(out)
    if contact_points is None:
        contact_points = study_contact_points(study)
    trials = completed(study)
    front = pareto_evaluations(study)
    base_2d = evaluate(BASELINE, screen_settings(mode="2d", mesh=mesh, max_force_N=max_force_N,
                                                 contact_points=contact_points))
    winners = choose_winners(front, check, below=base_2d.lifelike_distance_pct)
    checked = check_in_3d(winners, mesh=mesh, max_force_N=max_force_N, threads=threads,
                          cluster=cluster, contact_points=contact_points)
    (out / "stl").mkdir(parents=True, exist_ok=True)
    for i, w in enumerate(checked["winners"], 1):
        cand = candidate_of(w)
        w["stl"] = write_stl(cand.geometry(), out / "stl" / f"{i}-trial{w['trial']}.stl")
        mats = out / "stl" / f"{i}-trial{w['trial']}-materials.json"
        atomic_write_json(mats, fe_materials(cand))
        w["fe_indent"] = fe_indent_command(cand, str(mats), contact_points=contact_points)
    data = {**(extra or {}), "n_trials_complete": len(trials), "front": front,
            "winners": checked["winners"], "baseline": checked["baseline"],
            "check_interrupted": checked["interrupted"]}
    atomic_write_json(out / "designs.json", json.loads(json.dumps(data, default=float)))
    atomic_write_text(out / "designs.md", table_markdown(data) + "\n")
    plot_front(trials, front, checked["winners"], checked["baseline"], out / "pareto.png")
    if all(w.get("check_3d") for w in checked["winners"]) and checked["baseline"]["3d"]:
        plot_curves(checked["winners"], checked["baseline"], out / "curves.png")
    return data
