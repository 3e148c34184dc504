"""Profile the design search's 3D check of one design: where the time goes (issue 38, item 6).

Runs `softhand.design.evaluate.screen_settings` (mode 3d, CHOLMOD) on pocket2-sil or on a trial
of reports/design-search.json's winners or Pareto front, in this process after a small warm-up
run, and prints: the wall time, steps, Newton iterations and failed tries; one line per Newton
try (accepted or not) with its iterations' factorizations (``c`` Cholesky, ``I`` not positive
definite: a shifted Cholesky with the check's settings, SuperLU with ``--fe-newton``) and
residuals; and, with ``--cprofile``, the functions that took the most time. ``--set KEY=VALUE``
(repeatable; VALUE in JSON, e.g. ``max_indefinite=3``, ``max_indefinite=null``) overrides an
`IndentationSettings` field of the check; ``--quiet`` drops the per-try lines; ``--json`` ends
with one JSON line of the counts (steps, Newton iterations, failed tries, residual evaluations,
CHOLMOD numeric factorizations, those not positive definite among them), the CPU and wall
time, and the four answers (reports/fe-check-trial293.md is made from it).

    python tools/fe_check_profile.py pocket2-sil --threads 1 [--cprofile]
    python tools/fe_check_profile.py 293 --fe-newton   # winner trial 293, the FE's Newton
    python tools/fe_check_profile.py 293 --quiet --json --set max_indefinite=3

Timings are indicative (note the load average); the counts and the answers are the check's.
"""

from __future__ import annotations

import argparse
import cProfile
import dataclasses
import json
import os
import pstats
import time

from softhand.design.evaluate import fe_design, screen_settings
from softhand.design.search import candidate_of
from softhand.fem import linear
from softhand.fem import solver as fe
from softhand.paths import REPORTS_DIR


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("design", help="pocket2-sil or a winner's trial number")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--fe-newton", action="store_true",
                    help="the FE's Newton settings (the check before CHECK_NEWTON)")
    ap.add_argument("--cprofile", action="store_true")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override a field of the check's IndentationSettings (VALUE in JSON)")
    ap.add_argument("--quiet", action="store_true", help="no line per Newton try")
    ap.add_argument("--json", action="store_true", help="end with the counts as one JSON line")
    a = ap.parse_args()
    given = {}
    for item in a.set:
        key, sep, value = item.partition("=")
        if not sep or key not in fe.IndentationSettings.__dataclass_fields__:
            ap.error(f"--set {item!r}: expected KEY=VALUE with KEY a field of "
                     "IndentationSettings")
        given[key] = json.loads(value)
    s = dataclasses.replace(screen_settings(mode="3d", threads=a.threads,
                                            check_newton=not a.fe_newton), solver="cholmod",
                            **given)
    fe.indent("solid-sil", dataclasses.replace(s, mesh="coarse"))  # load the kernels
    design = "pocket2-sil"
    if a.design != "pocket2-sil":
        study = json.loads((REPORTS_DIR / "design-search.json").read_text())
        rows = [w for w in study["winners"] + study["front"] if w["trial"] == int(a.design)]
        if not rows:
            ap.error(f"design {a.design!r}: not pocket2-sil nor a trial of the search's "
                     "winners or front (reports/design-search.json)")
        row = rows[0]
        design, s = fe_design(candidate_of(row), s)

    kinds: list[str] = []
    residuals: list[float] = []
    counts = {"residuals": 0, "numeric": 0, "not_positive_definite": 0}
    newton, factorize, residual = fe._Model.newton, linear.TangentSystem.factorize, \
        fe._Model.residual
    numeric = linear._Cholmod.factorize

    def counted_numeric(self, vals):
        counts["numeric"] += 1
        try:
            return numeric(self, vals)
        except ArithmeticError:
            counts["not_positive_definite"] += 1
            raise

    def logged_factorize(self, vals, **kw):
        before = self.stats["cholesky"]
        out = factorize(self, vals, **kw)
        kinds.append("c" if self.stats["cholesky"] > before else "I")
        return out

    def logged_residual(self, *args, **kw):
        out = residual(self, *args, **kw)
        residuals.append(out[1])
        counts["residuals"] += 1
        return out

    def logged_newton(self, u0, state, dt, d, tol, **kw):
        kinds.clear()
        residuals.clear()
        t0 = time.perf_counter()
        try:
            out = newton(self, u0, state, dt, d, tol, **kw)
            what = f"ok   it={out[2]:2d}"
            return out
        except (RuntimeError, FloatingPointError) as exc:
            what = f"FAIL ({str(exc)[:40]})"
            raise
        finally:
            if not a.quiet:
                print(f"d={d:.4f} {what} {time.perf_counter() - t0:.3f}s {''.join(kinds)} "
                      f"res={' '.join(f'{r:.1e}' for r in residuals)}")

    fe._Model.newton, linear.TangentSystem.factorize, fe._Model.residual = \
        logged_newton, logged_factorize, logged_residual
    linear._Cholmod.factorize = counted_numeric
    prof = cProfile.Profile() if a.cprofile else None
    t0, cpu0 = time.perf_counter(), time.process_time()
    if prof:
        prof.enable()
    r = fe.indent(design, s)
    if prof:
        prof.disable()
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    print(f"{a.design}: wall {wall:.2f} s, load average {os.getloadavg()[0]:.2f}, steps "
          f"{len(r.log)}, Newton iterations {sum(x['iterations'] for x in r.log)}, failed tries "
          f"{sum(x['retries'] for x in r.log)}")
    shown = lambda v: "-" if v is None else f"{v:.5f}"  # noqa: E731  (a ramp stopped early)
    print(f"d(1 N) {shown(r.displacement_at(1.0))} mm, d(2 N) {shown(r.displacement_at(2.0))} "
          f"mm, F(1 mm) {shown(r.force_at(1.0))} N, F(2 mm) {shown(r.force_at(2.0))} N")
    if prof:
        pstats.Stats(prof).sort_stats("tottime").print_stats(15)
    if a.json:
        print(json.dumps({"design": a.design, "set": given, "threads": a.threads,
                          "steps": len(r.log),
                          "newton_iterations": sum(x["iterations"] for x in r.log),
                          "failed_tries": sum(x["retries"] for x in r.log), **counts,
                          "wall_s": round(wall, 3), "cpu_s": round(cpu, 3),
                          "load_average": os.getloadavg()[0],
                          "d_1N_mm": r.displacement_at(1.0), "d_2N_mm": r.displacement_at(2.0),
                          "F_1mm_N": r.force_at(1.0), "F_2mm_N": r.force_at(2.0)}))


if __name__ == "__main__":
    main()
