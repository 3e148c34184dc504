"""A population of partners like the paper's 30 subjects (softhand.envs.population) and
``softhand population``: the draws follow their published distributions within +-2.5 SD, every
partner at the corners of that range builds and runs, and the command writes what it says."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from click.testing import CliRunner

from softhand.cli import main
from softhand.envs.partner import check_partner_size, partner_size_range
from softhand.envs.population import population_summary, run_partner, sample_partners
from softhand.paper import paper


def test_partners_follow_table1_within_the_range_and_are_reproducible():
    partners = sample_partners(400, seed=3)
    assert partners == sample_partners(400, seed=3)
    subjects = paper()["anthropometry"]
    ranges = partner_size_range()
    for key, attr in (("length", "hand_length_mm"), ("width", "hand_width_mm")):
        values = np.array([getattr(p, attr) for p in partners])
        mean, sd = subjects[f"subjects_hand_{key}_mm"]
        lo, hi = ranges[key]
        assert lo <= values.min() and values.max() <= hi
        # 400 draws of a normal truncated at 2.5 SD: mean within 3 standard errors, SD within 10 %
        assert abs(values.mean() - mean) < 3 * sd / np.sqrt(400)
        assert 0.85 * sd < values.std() < 1.05 * sd
    assert all(check_partner_size((p.hand_length_mm, p.hand_width_mm)) for p in partners)


@pytest.mark.parametrize("size", [(187.5, 89.53), (159.0, 72.4), (216.0, 106.6)])
def test_partner_size_range_is_checked(size):
    ranges = partner_size_range()
    inside = (ranges["length"][0] <= size[0] <= ranges["length"][1]
              and ranges["width"][0] <= size[1] <= ranges["width"][1])
    if inside:
        assert check_partner_size(size) == size
    else:
        with pytest.raises(ValueError, match=r"allowed \d+\.\d-\d+\.\d mm"):
            check_partner_size(size)


@pytest.mark.parametrize("args, needle", [
    (["population", "--n", "0"], "0"),
    (["handshake", "--partner-size", "150,90"], "150"),
    (["handshake", "--partner-size", "190"], "LENGTH_MM,WIDTH_MM"),
    (["population", "--workers", "999"], "999"),
    (["population", "--hand", "robot"], "robot"),
    (["population", "--hand", "human", "--controller", "force"], "--controller force"),
])
def test_bad_population_input_is_one_line_naming_the_value(args, needle, tmp_path):
    res = CliRunner().invoke(main, [*args, *(["--out", str(tmp_path / "p")]
                                             if args[0] == "population" else [])])
    assert res.exit_code == 2, res.output
    lines = [line for line in res.output.splitlines() if line.strip()]
    assert len(lines) == 1 and needle in lines[0], res.output
    assert not (tmp_path / "p").exists() or not any((tmp_path / "p").iterdir())


@pytest.mark.slow
def test_corner_partners_shake_hands():
    """Partners at the four +-2.5 SD corners of Table 1 build, run a whole handshake and hold
    their grip within 15 % (95th percentile); the summary names every region."""
    ranges = partner_size_range()
    results = []
    for length in ranges["length"]:
        for width in ranges["width"]:
            p = sample_partners(1, seed=0)[0]
            p = type(p)(**{**p.to_dict(), "hand_length_mm": length, "hand_width_mm": width})
            res = run_partner(p, {"controller": "neutral"})
            assert res["grip"]["p95_error_pct"] < 15.0, (length, width, res["grip"])
            results.append(res)
    summary = population_summary(results)
    assert set(summary) == set(paper()["handshake"]["regions"])


@pytest.mark.slow
def test_population_command_writes_results_and_figure(tmp_path):
    out = tmp_path / "pop"
    res = CliRunner().invoke(main, ["population", "--n", "2", "--workers", "1", "--out", str(out)])
    assert res.exit_code == 0, res.output
    data = json.loads((out / "results.json").read_text())
    assert data["settings"]["n"] == 2 and len(data["partners"]) == 2
    assert (out / "fig4.png").stat().st_size > 0
    assert len((out / "results.csv").read_text().splitlines()) == 3


def test_population_on_the_vector_env_equals_one_partner_at_a_time():
    """run_population (one vector env, a world per partner) gives run_partner's results to
    1e-9 N (peaks, means, force accounting, grip tracking) and the same warnings; measured
    when written: equal. The partners keep the experimenter's hand size so that the grasp is
    solved once (another size costs ~12 s of grasp solving per partner)."""
    import dataclasses

    from softhand.envs.population import run_population

    partners = [dataclasses.replace(p, hand_length_mm=190.0, hand_width_mm=88.0)
                for p in sample_partners(2, seed=4)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        batched, errors = run_population(partners, {"controller": "neutral"})
        single = [run_partner(p, {"controller": "neutral"}) for p in partners]
    assert errors == {}

    def worst(a, b) -> float:
        if isinstance(a, dict):
            return max([worst(a[k], b[k]) for k in a if k != "wall_s"], default=0.0)
        if isinstance(a, (list, tuple)) and a and isinstance(a[0], str):
            assert a == b
            return 0.0
        if isinstance(a, (list, tuple)):
            return max([worst(x, y) for x, y in zip(a, b, strict=True)], default=0.0)
        if isinstance(a, str):
            assert a == b
            return 0.0
        return 0.0 if np.isnan(a) and np.isnan(b) else abs(a - b)

    for got, ref in zip(batched, single, strict=True):
        assert got["partner"] == ref["partner"] and got["warnings"] == ref["warnings"]
        assert worst(got, ref) <= 1e-9
