"""Profile the design search's 3D check of one design: where the time goes (issue 38, item 6).

Runs `softhand.design.evaluate.screen_settings` (mode 3d, CHOLMOD) on pocket2-sil or on a winner
of reports/design-search.json, in this process after a small warm-up run, and prints: the wall
time, steps, Newton iterations and failed tries; one line per Newton try (accepted or not) with
its iterations' factorizations (``c`` Cholesky, ``I`` not positive definite: a shifted Cholesky
with the check's settings, SuperLU with ``--fe-newton``) and
residuals; and, with ``--cprofile``, the functions that took the most time.

    python tools/fe_check_profile.py pocket2-sil --threads 1 [--cprofile]
    python tools/fe_check_profile.py 293 --fe-newton   # winner trial 293, the FE's Newton

Timings are indicative (note the load average); the answers are the check's.
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
    a = ap.parse_args()
    s = dataclasses.replace(screen_settings(mode="3d", threads=a.threads,
                                            check_newton=not a.fe_newton), solver="cholmod")
    fe.indent("solid-sil", dataclasses.replace(s, mesh="coarse"))  # load the kernels
    design = "pocket2-sil"
    if a.design != "pocket2-sil":
        winners = json.loads((REPORTS_DIR / "design-search.json").read_text())["winners"]
        row = next(w for w in winners if w["trial"] == int(a.design))
        design, s = fe_design(candidate_of(row), s)

    kinds: list[str] = []
    residuals: list[float] = []
    newton, factorize, residual = fe._Model.newton, linear.TangentSystem.factorize, \
        fe._Model.residual

    def logged_factorize(self, vals, **kw):
        before = self.stats["cholesky"]
        out = factorize(self, vals, **kw)
        kinds.append("c" if self.stats["cholesky"] > before else "I")
        return out

    def logged_residual(self, *args, **kw):
        out = residual(self, *args, **kw)
        residuals.append(out[1])
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
            print(f"d={d:.4f} {what} {time.perf_counter() - t0:.3f}s {''.join(kinds)} "
                  f"res={' '.join(f'{r:.1e}' for r in residuals)}")

    fe._Model.newton, linear.TangentSystem.factorize, fe._Model.residual = \
        logged_newton, logged_factorize, logged_residual
    prof = cProfile.Profile() if a.cprofile else None
    t0 = time.perf_counter()
    if prof:
        prof.enable()
    r = fe.indent(design, s)
    if prof:
        prof.disable()
    wall = time.perf_counter() - t0
    print(f"{a.design}: wall {wall:.2f} s, load average {os.getloadavg()[0]:.2f}, steps "
          f"{len(r.log)}, Newton iterations {sum(x['iterations'] for x in r.log)}, failed tries "
          f"{sum(x['retries'] for x in r.log)}")
    print(f"d(1 N) {r.displacement_at(1.0):.5f} mm, d(2 N) {r.displacement_at(2.0):.5f} mm, "
          f"F(1 mm) {r.force_at(1.0):.5f} N, F(2 mm) {r.force_at(2.0):.5f} N")
    if prof:
        pstats.Stats(prof).sort_stats("tottime").print_stats(15)


if __name__ == "__main__":
    main()
