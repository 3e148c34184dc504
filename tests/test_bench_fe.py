"""`softhand bench fe`'s report of the design search's runs, from synthetic measurements (the
benchmark itself is timed, not tested)."""

from __future__ import annotations

from softhand.bench.fe import _SCREEN_RUNS, _WINNER_RUNS, _screen_lines


def _run(wall: float, its: int, d2: float, f2: float) -> dict:
    return {"wall_s": wall, "newton_iterations": its, "n_steps": 20,
            "displacement_at_1N_mm": 2.0, "displacement_at_2N_mm": d2,
            "force_at_1mm_N": 0.1, "force_at_2mm_N": f2}


def test_the_check_newton_setting_is_measured_before_and_after_in_one_run():
    assert _SCREEN_RUNS[-1][1]["check_newton"] is True
    assert all(given["check_newton"] is False for _, given, _ in _SCREEN_RUNS[:-1])
    keys = [key for key, _ in _WINNER_RUNS]
    assert keys == ["search", "points2_threads2", "check_newton"]
    winners = [{"winner": 1, "trial": 293, "label": "soft",
                "search": _run(22.0, 363, 3.90, 0.20),
                "points2_threads2": _run(20.0, 255, 3.92, 0.20),
                "check_newton": _run(10.0, 244, 3.92 * 0.9997, 0.20 * 1.001)}]
    lines = _screen_lines({"screen": {"design": "pocket2-sil", "solver": "cholmod",
                                      "labels": {}, "2d": {}, "3d": {}, "winners": winners}})
    row = next(line for line in lines if line.startswith("| 1 (trial 293) | 20.00 |"))
    assert "| 2.00x |" in row and "-0.030 %" in row and "+0.100 %" in row
