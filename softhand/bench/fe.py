"""Benchmark of the FE stage: speed against error, written to a report.

Measures, in one process on this machine:

* the design search's two FE runs (`softhand.design.evaluate.screen_settings`): the 2D screen
  and the 3D check of pocket2-sil to 2 N on CHOLMOD (the default install), with the FE's 4
  contact points per face direction on one thread (the shipped search's runs, the reference)
  against 2 threads, 2 contact points (the search's since issue 38's item 6), both, and both
  with the 3D check's Newton settings (`softhand.design.evaluate.CHECK_NEWTON`), interleaved,
  each run in a fresh process, with the answers' differences (indentation at 1 N and 2 N,
  force at 1 mm and 2 mm); the same for the shipped search's three winners in 3D, before and
  after the check's Newton settings;
* the element engines side by side (``IndentationSettings.engine``): the NumPy reference
  (batched NumPy elements, SuperLU ordering and factorizing every tangent) against the compiled
  engine (numba kernels, the run's fixed pattern) on each sparse Cholesky installed here
  (CHOLMOD; MKL PARDISO with the ``softhand[mkl]`` extra), on one 3D design to 2 N, runs
  interleaved (reference, CHOLMOD, PARDISO, reference, ...) so that a drift of the machine hits
  all, each run in a fresh process (so CHOLMOD runs on its own BLAS, not on MKL's); with the
  Newton iterations and the largest difference between their force curves;
* at the default settings (the compiled engine, PARDISO where installed): one 3D design to
  2 N at the default mesh (ramp only), and the same with the 10 s hold;
* the same ramp with every core of the machine busy with other work (an external CPU load of one
  busy process per core, started and stopped by the benchmark), at the default ``--threads`` and
  at one thread: the slow-down should be about the fair share (2x with as many busy processes as
  cores), not the 6-10x that competing BLAS and element threads gave;
* the full 12-design sweep at the default settings (3D, default mesh, ramp + hold);
* the reduced 2D plane-strain mode for all 12 designs;
* 3D fine-mesh references (every element count doubled) for solid-sil and pocket2-sil, and the
  error of coarse, default and 2D results against them (the mesh-convergence study).

Timings are wall-clock seconds; they are reported, never asserted by tests.
"""

from __future__ import annotations

import contextlib
import json
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from softhand.bench.common import machine_info, machine_line
from softhand.fem.geometry import DESIGNS
from softhand.fem.linear import resolve_solver
from softhand.fem.solver import IndentationSettings, indent
from softhand.fem.sweep import compare_with_paper, run_sweep
from softhand.io import atomic_write_json, atomic_write_text
from softhand.parallel import available_cpus, default_threads
from softhand.paths import REPORTS_DIR

__all__ = ["run_fe_benchmark"]

REFERENCE_DESIGNS = ("solid-sil", "pocket2-sil")


def _pct(a: float | None, b: float | None) -> float | None:
    return None if a is None or b is None else 100.0 * (a - b) / b


@contextlib.contextmanager
def cpu_load(n: int) -> Iterator[None]:
    """``n`` busy processes (pure Python loops) for the duration of the block; always stopped."""
    code = "while True:\n    pass"
    procs = [subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.DEVNULL,
                              start_new_session=True) for _ in range(n)]
    try:
        time.sleep(0.5)  # let them start spinning before the timed run
        yield
    finally:
        for p in procs:
            p.kill()
        for p in procs:
            p.wait()


def _complete(outcome) -> dict:
    """The results of a sweep that must be complete inside the benchmark."""
    if outcome.interrupted:
        raise KeyboardInterrupt
    if not outcome.complete:
        raise RuntimeError(f"sweep failed: {outcome.errors}")
    return outcome.results


def run_fe_benchmark(out_dir: str | Path = REPORTS_DIR, *, quick: bool = False,
                     progress: Callable[[str], None] | None = None) -> str:
    """Run the benchmark, write ``bench-fe.json`` and ``bench-fe.md``, return the Markdown.

    ``quick`` skips the 3D fine-mesh references (about 40 min on 2 cores) and keeps those of the
    report already in ``out_dir``, labelled with the git revision that measured them.
    ``progress`` gets a line before each part (the sweeps also count their designs on stderr).
    """
    say = progress or (lambda line: None)
    out = Path(out_dir)
    ramp = IndentationSettings(hold_s=0.0)
    machine = machine_info()
    data: dict[str, Any] = {"machine": machine, "git_revision": machine["git_revision"]}
    data["engines"] = _engines(repeats=2 if quick else 3, say=say)
    data["screen"] = _screen(repeats=3, say=say)
    data["screen"]["winners"] = _winner_checks(say)
    data["solver"] = resolve_solver("auto")  # the default runs below go to it
    say("one 3D design (pocket2-sil) to 2 N, ramp")
    one = indent("pocket2-sil", ramp)
    say("one 3D design (pocket2-sil) to 2 N, ramp + 10 s hold")
    one_hold = indent("pocket2-sil", IndentationSettings())
    data["one_design"] = {"design": "pocket2-sil", "ramp_wall_s": one.wall_s,
                          "ramp_hold_wall_s": one_hold.wall_s, "n_dofs": one.n_dofs}
    n_load = available_cpus()
    with cpu_load(n_load):
        say(f"the same ramp next to {n_load} busy processes, {default_threads()} threads")
        loaded = indent("pocket2-sil", ramp)
        say(f"the same ramp next to {n_load} busy processes, 1 thread")
        loaded_1 = indent("pocket2-sil", IndentationSettings(hold_s=0.0, threads=1))
    say("the same ramp idle, 1 thread")
    idle_1 = indent("pocket2-sil", IndentationSettings(hold_s=0.0, threads=1))
    data["under_load"] = {
        "design": "pocket2-sil", "busy_processes": n_load,
        "default_threads": {"threads": default_threads(), "idle_s": one.wall_s,
                            "loaded_s": loaded.wall_s, "ratio": loaded.wall_s / one.wall_s},
        "one_thread": {"threads": 1, "idle_s": idle_1.wall_s, "loaded_s": loaded_1.wall_s,
                       "ratio": loaded_1.wall_s / idle_1.wall_s},
    }
    say("12-design sweep, 3D, ramp + hold")
    t0 = time.perf_counter()
    sweep = _complete(run_sweep(DESIGNS, IndentationSettings(), show_progress=True))
    sweep_wall = time.perf_counter() - t0
    say("12-design sweep, 2D plane strain, ramp + hold")
    t0 = time.perf_counter()
    sweep2d = _complete(run_sweep(DESIGNS, IndentationSettings(mode="2d"), show_progress=True))
    sweep2d_wall = time.perf_counter() - t0
    s3 = {n: r.summary() for n, r in sweep.items()}
    s2 = {n: r.summary() for n, r in sweep2d.items()}
    data["sweep_3d"] = {"wall_s": sweep_wall, "per_design_s": {n: r.wall_s for n, r in sweep.items()},
                        "comparison": compare_with_paper(s3)}
    data["sweep_2d"] = {"wall_s": sweep2d_wall,
                        "per_design_s": {n: r.wall_s for n, r in sweep2d.items()},
                        "comparison": compare_with_paper(s2)}
    data["designs"] = {n: {"3d_d2N": s3[n]["displacement_at_2N_mm"],
                           "2d_d2N": s2[n]["displacement_at_2N_mm"],
                           "2d_vs_3d_pct": _pct(s2[n]["displacement_at_2N_mm"],
                                                s3[n]["displacement_at_2N_mm"]),
                           "3d_F2mm": s3[n]["force_at_2mm_N"],
                           "relaxed_over_peak": s3[n]["relaxed_force_N"] / s3[n]["peak_force_N"]}
                       for n in DESIGNS}
    conv: dict[str, Any] = {}
    if quick:  # keep the last measured references, labelled with the revision they came from
        with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
            old = json.loads((out / "bench-fe.json").read_text(encoding="utf-8"))
            if old["mesh_convergence"]:
                conv = old["mesh_convergence"]
                data["mesh_convergence_from"] = old.get("mesh_convergence_from",
                                                        old["git_revision"])
    else:
        for name in REFERENCE_DESIGNS:
            row: dict[str, Any] = {}
            say(f"mesh convergence, {name}: 3D fine-mesh reference")
            fine = indent(name, IndentationSettings(mesh="fine", hold_s=0.0))
            ref = fine.displacement_at(2.0)
            row["fine"] = {"d2N": ref, "wall_s": fine.wall_s, "n_dofs": fine.n_dofs}
            for label, st in (("coarse", IndentationSettings(mesh="coarse", hold_s=0.0)),
                              ("default", ramp),
                              ("2d", IndentationSettings(mode="2d", hold_s=0.0))):
                say(f"mesh convergence, {name}: {label}")
                r = indent(name, st)
                row[label] = {"d2N": r.displacement_at(2.0), "wall_s": r.wall_s,
                              "n_dofs": r.n_dofs,
                              "error_vs_fine_pct": _pct(r.displacement_at(2.0), ref)}
            conv[name] = row
    data["mesh_convergence"] = conv
    atomic_write_json(out / "bench-fe.json", data)
    md = _markdown(data)
    atomic_write_text(out / "bench-fe.md", md)
    return md


#: The engines the benchmark compares: (key, engine, sparse solver, label).
_ENGINE_RUNS = (("numpy", "numpy", "auto", "reference (NumPy elements, SuperLU)"),
                ("cholmod", "compiled", "cholmod", "compiled (numba elements, CHOLMOD)"),
                ("pardiso", "compiled", "pardiso", "compiled (numba elements, MKL PARDISO)"))


def _engines(repeats: int, say: Callable[[str], None]) -> dict[str, Any]:
    """The reference engine and the compiled one on each sparse solver installed here, on
    pocket2-sil, 3D default mesh, ramp to 2 N and the ramp with the 10 s hold, interleaved
    ``repeats`` times; median walls. ``say`` gets a line before each run."""
    from softhand.fem.linear import pardiso_available

    runs_of = [r for r in _ENGINE_RUNS if r[0] != "pardiso" or pardiso_available()]
    out: dict[str, Any] = {"design": "pocket2-sil", "repeats": repeats,
                           "threads": default_threads(),
                           "labels": {key: label for key, _, _, label in runs_of}}
    for label, hold in (("ramp", 0.0), ("ramp_hold", 10.0)):
        walls: dict[str, list[float]] = {key: [] for key, *_ in runs_of}
        last: dict[str, Any] = {}
        runs = repeats if label == "ramp" else 1
        for i in range(runs):
            for key, engine, solver, _ in runs_of:
                say(f"engines on pocket2-sil, {label.replace('_', ' + ')} {i + 1} of {runs}: "
                    f"{key}")
                r = _fresh_run(hold, engine, solver)
                walls[key].append(r["wall_s"])
                last[key] = r
        ref = np.asarray(last["numpy"]["force_N"])
        out[label] = {}
        for key, w in walls.items():
            new = last[key]
            force = np.asarray(new["force_N"])
            same_points = ref.shape == force.shape
            out[label][key] = {
                "wall_s": statistics.median(w), "walls_s": w,
                "speedup": statistics.median(walls["numpy"]) / statistics.median(w),
                "newton_iterations": new["newton_iterations"], "steps": new["n_steps"],
                "d2N_mm": new["displacement_at_2N_mm"],
                "max_force_difference_N": (float(abs(ref - force).max())
                                           if same_points else None)}
    return out


#: The design search's runs: (key, keywords of `screen_settings`, label); "search", the
#: reference, is the FE's 4 contact points on one thread, the shipped search's runs. All but
#: the last run Newton with the FE's settings (``check_newton=False``); the last is the 3D
#: check's now (`softhand.design.evaluate.CHECK_NEWTON`; the 2D screen does not use it).
_SCREEN_RUNS = (("search", {"contact_points": 4, "check_newton": False},
                 "4 contact points, 1 thread (the shipped search's runs)"),
                ("threads2", {"contact_points": 4, "threads": 2, "check_newton": False},
                 "4 contact points, 2 threads"),
                ("points2", {"contact_points": 2, "check_newton": False},
                 "2 contact points, 1 thread"),
                ("points2_threads2", {"contact_points": 2, "threads": 2, "check_newton": False},
                 "2 contact points, 2 threads"),
                ("check_newton", {"contact_points": 2, "threads": 2, "check_newton": True},
                 "2 contact points, 2 threads, the check's Newton settings"))
_SCREEN_MARKS = (("d1N_mm", "displacement_at_1N_mm"), ("d2N_mm", "displacement_at_2N_mm"),
                 ("F1mm_N", "force_at_1mm_N"), ("F2mm_N", "force_at_2mm_N"))


def _screen(repeats: int, say: Callable[[str], None]) -> dict[str, Any]:
    """The 2D screen and the 3D check of pocket2-sil (`screen_settings`, CHOLMOD) as the search
    runs them and with each of `_SCREEN_RUNS`' faster settings, interleaved ``repeats`` times
    (the 3D check: 2), each in a fresh process; median walls and the answers' differences."""
    out: dict[str, Any] = {"design": "pocket2-sil", "solver": "cholmod",
                           "labels": {key: label for key, _, label in _SCREEN_RUNS}}
    for mode, name in (("2d", "2D screen"), ("3d", "3D check")):
        runs = repeats if mode == "2d" else min(repeats, 2)
        walls: dict[str, list[float]] = {key: [] for key, *_ in _SCREEN_RUNS}
        last: dict[str, dict[str, Any]] = {}
        for i in range(runs):
            for key, given, label in _SCREEN_RUNS:
                say(f"{name} of pocket2-sil, {i + 1} of {runs}: {label}")
                r = _fresh_screen_run(mode, given)
                walls[key].append(r["wall_s"])
                last[key] = r
        ref = last["search"]
        rows = {}
        for key, w in walls.items():
            r = last[key]
            diff = {}
            for mark, field in _SCREEN_MARKS:
                a, b = ref[field], r[field]
                diff[mark] = None if a is None or b is None else 100.0 * (b - a) / a
            rows[key] = {"wall_s": statistics.median(w), "walls_s": w,
                         "speedup": statistics.median(walls["search"]) / statistics.median(w),
                         "newton_iterations": r["newton_iterations"], "steps": r["n_steps"],
                         **{mark: r[field] for mark, field in _SCREEN_MARKS},
                         "difference_pct": diff}
        out[mode] = rows
    return out


#: The 3D checks of the shipped search's winners: the shipped runs' settings against 2 contact
#: points on 2 threads (one worker of 2 cores) with the FE's Newton settings (the check before
#: `softhand.design.evaluate.CHECK_NEWTON`) and with the check's (the search's now).
_WINNER_RUNS = (("search", {"contact_points": 4, "check_newton": False}),
                ("points2_threads2", {"contact_points": 2, "threads": 2, "check_newton": False}),
                ("check_newton", {"contact_points": 2, "threads": 2, "check_newton": True}))


def _winner_checks(say: Callable[[str], None]) -> list[dict[str, Any]]:
    """The 3D check of each winner of ``reports/design-search.json`` (soft designs: more steps
    than pocket2-sil, near where their ramp stiffens), one fresh-process run per setting."""
    path = Path(REPORTS_DIR) / "design-search.json"
    if not path.exists():
        return []
    rows = []
    for i, w in enumerate(json.loads(path.read_text(encoding="utf-8"))["winners"], 1):
        row: dict[str, Any] = {"winner": i, "trial": w["trial"], "label": w["label"]}
        for key, given in _WINNER_RUNS:
            say(f"3D check of winner {i} (trial {w['trial']}): {given}")
            r = _fresh_screen_run("3d", given, trial=w)
            row[key] = {k: r[k] for k in ("wall_s", "newton_iterations", "n_steps",
                                          "displacement_at_1N_mm", "displacement_at_2N_mm",
                                          "force_at_1mm_N", "force_at_2mm_N")}
        rows.append(row)
    return rows


def _fresh_screen_run(mode: str, given: dict[str, Any],
                      trial: dict[str, Any] | None = None) -> dict[str, Any]:
    """One `screen_settings` run of pocket2-sil (or of a search's ``trial`` row) on CHOLMOD in a
    new Python process (its summary), after a small run that loads the compiled kernels."""
    kw = ", ".join(f"{k}={v!r}" for k, v in given.items())
    setup, design = "", "'pocket2-sil'"
    if trial is not None:
        row = {"candidate": trial["candidate"]}
        setup = ("from softhand.design.evaluate import fe_design\n"
                 "from softhand.design.search import candidate_of\n"
                 f"d, s = fe_design(candidate_of({row!r}), s)\n")
        design = "d"
    code = ("import dataclasses, json, sys\n"
            "from softhand.design.evaluate import screen_settings\n"
            "from softhand.fem.solver import indent\n"
            f"s = dataclasses.replace(screen_settings(mode={mode!r}, {kw}), solver='cholmod')\n"
            "indent('solid-sil', dataclasses.replace(s, mesh='coarse'))\n"
            f"{setup}r = indent({design}, s)\n"
            "json.dump({**r.summary(), 'force_at_1mm_N': r.force_at(1.0)}, sys.stdout)\n")
    return _python_json(code, f"the {mode} screen run {given}")


def _python_json(code: str, what: str) -> dict[str, Any]:
    """Run ``code`` in a new Python process and read the JSON it writes to stdout."""
    done = subprocess.run([sys.executable, "-c", code], stdin=subprocess.DEVNULL,
                          capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{what} failed: {done.stderr.strip()[-500:]}")
    return json.loads(done.stdout)


def _screen_lines(d: dict[str, Any]) -> list[str]:
    e = d.get("screen")
    if not e:
        return []
    lines = [f"The design search's runs of {e['design']} to 2 N on {e['solver'].upper()} (the "
             "default install; `softhand.design.evaluate.screen_settings`), interleaved, each "
             "in a fresh process, median wall; the answers' differences from the first row's "
             "run. The search screens in 2D with 2 contact points, one thread per worker, and "
             "checks in 3D with 2 contact points and the check's Newton settings (the last "
             "row) on this machine's CPUs shared among its workers (2 threads on one worker "
             "of 2 cores; studies from before keep 4):", "",
             "| run | settings | wall (s) | speed-up | Newton iterations | d(1 N) | d(2 N) "
             "| F(1 mm) | F(2 mm) |", "|---|---|---|---|---|---|---|---|---|"]

    def pct(v):
        return "" if v is None else f"{v:+.2f} %"

    for mode, name in (("2d", "2D screen"), ("3d", "3D check")):
        for key, r in e[mode].items():
            dp = r["difference_pct"]
            lines.append(f"| {name} | {e['labels'][key]} | {r['wall_s']:.3f} | "
                         f"{r['speedup']:.2f}x | {r['newton_iterations']} | "
                         + " | ".join("reference" if key == "search" else pct(dp[m])
                                      for m, _ in _SCREEN_MARKS) + " |")
    if e.get("winners"):
        lines += ["", "The 3D checks of the shipped search's winners (reports/design-search.json; "
                  "soft designs, whose ramps stiffen late and take more steps), one fresh-process "
                  "run per setting:", "",
                  "| winner | design | 4 points, 1 thread: wall (s) | iterations | 2 points, "
                  "2 threads: wall (s) | iterations | speed-up | d(1 N) | d(2 N) |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for w in e["winners"]:
            a, b = w["search"], w["points2_threads2"]
            lines.append(
                f"| {w['winner']} (trial {w['trial']}) | {w['label']} | {a['wall_s']:.2f} | "
                f"{a['newton_iterations']} | {b['wall_s']:.2f} | {b['newton_iterations']} | "
                f"{a['wall_s'] / b['wall_s']:.2f}x | "
                + " | ".join(pct(_pct(b[f], a[f])) for f in
                             ("displacement_at_1N_mm", "displacement_at_2N_mm")) + " |")
        lines += _check_newton_lines(e["winners"])
    return lines


def _check_newton_lines(winners: list[dict[str, Any]]) -> list[str]:
    """The winners' 3D check with the check's Newton settings against the same check (2 points,
    2 threads) with the FE's, from the same run: time and the answers' differences."""
    rows = [w for w in winners if "check_newton" in w]
    if not rows:
        return []

    def pct(v):
        return "" if v is None else f"{v:+.3f} %"

    lines = ["", "The same checks (2 contact points, 2 threads) with the FE's Newton settings "
             "(before) and the check's (`softhand.design.evaluate.CHECK_NEWTON`, after), with "
             "the differences of after from before:", "",
             "| winner | before: wall (s) | iterations | after: wall (s) | iterations "
             "| speed-up | d(1 N) | d(2 N) | F(1 mm) | F(2 mm) |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for w in rows:
        a, b = w["points2_threads2"], w["check_newton"]
        lines.append(
            f"| {w['winner']} (trial {w['trial']}) | {a['wall_s']:.2f} | "
            f"{a['newton_iterations']} | {b['wall_s']:.2f} | {b['newton_iterations']} | "
            f"{a['wall_s'] / b['wall_s']:.2f}x | "
            + " | ".join(pct(_pct(b.get(f), a.get(f))) for f in
                         ("displacement_at_1N_mm", "displacement_at_2N_mm", "force_at_1mm_N",
                          "force_at_2mm_N")) + " |")
    return lines


def _fresh_run(hold: float, engine: str, solver: str) -> dict[str, Any]:
    """One pocket2-sil run in a new Python process (its summary, `IndentationResult.summary`),
    so that no engine runs on libraries another one loaded: once MKL has run, its BLAS is
    among the process's global symbols and CHOLMOD would call it (`softhand.fem.linear`)."""
    given = f"engine={engine!r}, solver={solver!r}"
    code = ("import json, sys\n"
            "from softhand.fem.solver import IndentationSettings, indent\n"
            # a small run first: the compiled kernels load from numba's cache, the solver's
            # libraries load, outside the timed run (as in a process that has run before)
            f"indent('solid-sil', IndentationSettings(mesh='coarse', hold_s=0.0, {given}))\n"
            f"r = indent('pocket2-sil', IndentationSettings(hold_s={hold!r}, {given}))\n"
            "json.dump(r.summary(), sys.stdout)\n")
    return _python_json(code, f"the {engine}/{solver} run")


def _engine_lines(d: dict[str, Any]) -> list[str]:
    e = d.get("engines")
    if not e or "labels" not in e:
        return []
    lines = [f"The engines on {e['design']} (3D, default mesh, {e['threads']} threads), "
             f"interleaved, median of {e['repeats']} ramps (the ramp with the hold: one run "
             "each); the compiled engine on each sparse solver installed here:", "",
             "| run | engine | wall (s) | speed-up | Newton iterations "
             "| largest force difference from the reference (N) |",
             "|---|---|---|---|---|---|"]
    for label, name in (("ramp", "ramp to 2 N"), ("ramp_hold", "ramp + 10 s hold")):
        for key, r in e[label].items():
            diff = r["max_force_difference_N"]
            lines.append(f"| {name} | {e['labels'][key]} | {r['wall_s']:.1f} | "
                         f"{r['speedup']:.2f}x | {r['newton_iterations']} | "
                         + ("reference" if key == "numpy" else
                            "different steps" if diff is None else format(diff, ".1e"))
                         + " |")
    return lines


def _markdown(d: dict[str, Any]) -> str:
    def f(v, spec=".3f"):
        return "" if v is None else format(v, spec)

    lines = [
        "# FE benchmark (`softhand bench fe`)", "",
        machine_line({"git_revision": d["git_revision"], **d["machine"]}), "",
        *_engine_lines(d), "",
        *_screen_lines(d), "",
        f"| what (compiled engine, {d.get('solver', 'cholmod')}) | wall (s) |", "|---|---|",
        f"| one 3D design (pocket2-sil) to 2 N, default mesh | {d['one_design']['ramp_wall_s']:.1f} |",
        f"| same with the 10 s hold | {d['one_design']['ramp_hold_wall_s']:.1f} |",
        f"| 12-design sweep, 3D, ramp + hold | {d['sweep_3d']['wall_s']:.1f} |",
        f"| 12-design sweep, 2D plane strain, ramp + hold | {d['sweep_2d']['wall_s']:.1f} |", "",
        *_load_lines(d), "",
        "| design | 3D d(2 N) mm | 2D d(2 N) mm | 2D vs 3D | 3D F(2 mm) N | F after hold / peak |",
        "|---|---|---|---|---|---|",
    ]
    for n, r in d["designs"].items():
        lines.append(f"| {n} | {f(r['3d_d2N'])} | {f(r['2d_d2N'])} | {f(r['2d_vs_3d_pct'], '+.1f')} % "
                     f"| {f(r['3d_F2mm'])} | {f(r['relaxed_over_peak'])} |")
    if d["mesh_convergence"]:
        carried = d.get("mesh_convergence_from")
        lines += ["", "Mesh convergence, displacement at 2 N against the 3D fine mesh "
                  "(every element count doubled), ramp only"
                  + (f" (not rerun with --quick: measured at git {carried})" if carried else "")
                  + ":", "",
                  "| design | model | dofs | d(2 N) mm | error vs fine | wall (s) |",
                  "|---|---|---|---|---|---|"]
        for n, row in d["mesh_convergence"].items():
            lines.append(f"| {n} | 3D fine | {row['fine']['n_dofs']} | {f(row['fine']['d2N'])} "
                         f"| reference | {row['fine']['wall_s']:.1f} |")
            for label in ("default", "coarse", "2d"):
                r = row[label]
                lines.append(f"| {n} | {label} | {r['n_dofs']} | {f(r['d2N'])} | "
                             f"{f(r['error_vs_fine_pct'], '+.2f')} % | {r['wall_s']:.1f} |")
    return "\n".join(lines) + "\n"


def _load_lines(d: dict[str, Any]) -> list[str]:
    u = d.get("under_load")
    if not u:
        return []
    lines = [f"The same ramp (pocket2-sil to 2 N) idle and with {u['busy_processes']} busy "
             "processes beside it (one per available CPU; a fair share is about 2x):", "",
             "| threads | idle (s) | loaded (s) | loaded / idle |", "|---|---|---|---|"]
    for key in ("default_threads", "one_thread"):
        r = u[key]
        lines.append(f"| {r['threads']}{' (default)' if key == 'default_threads' else ''} | "
                     f"{r['idle_s']:.1f} | {r['loaded_s']:.1f} | {r['ratio']:.2f} |")
    return lines
