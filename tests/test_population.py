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
        with pytest.raises(ValueError, match=r"allowed \d+(\.\d+)?-\d+(\.\d+)? mm"):
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


@pytest.fixture
def no_work(monkeypatch):
    def forbidden(*args, **kwargs):
        raise AssertionError("work started before the input was rejected")

    import softhand.parallel

    monkeypatch.setattr(softhand.parallel, "run_tasks", forbidden)


@pytest.mark.parametrize("args, needle", [
    (["--design", "pocket2-sil", "--design", "pocket3-sil"], "--design 'pocket3-sil': skin "
                                                             "design 'pocket3-sil' is unknown"),
    (["--design", "solid-pu", "--design", " "], "--design ''"),
    (["--controller", "neutral", "--controller", "grab"], "'grab' is not one of"),
    (["--hand", "human", "--controller", "neutral", "--controller", "force"],
     "--controller force"),
])
def test_a_bad_sweep_input_is_refused_before_any_work(args, needle, no_work, tmp_path):
    """Every --design and --controller of a sweep is checked before the first handshake: a bad
    second one is one line naming the flag and the value, and nothing is written."""
    res = CliRunner().invoke(main, ["population", "--n", "2", *args, "--out",
                                    str(tmp_path / "p")])
    assert res.exit_code == 2, (res.output, res.exception)
    lines = [line for line in res.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and needle in lines[0], res.output
    assert "Traceback" not in res.output
    assert not (tmp_path / "p").exists() or not any((tmp_path / "p").iterdir())


def test_a_sweep_writes_a_folder_per_combination_and_keeps_them_on_ctrl_c(monkeypatch,
                                                                          tmp_path):
    """The sweep's layout and its Ctrl-C, on stand-in handshakes (in this process, --workers 1):
    one subfolder DESIGN-CONTROLLER per combination with the files of a single run, sweep.json
    beside them; one combination writes straight into --out, as before; Ctrl-C in the second
    combination keeps the first whole and the second's finished partner, and lists the rest."""
    import softhand.envs.handshake
    import softhand.envs.population

    regions = paper()["handshake"]["regions"]
    ran, stop_at = [], []

    def handshake(partner, settings):
        ran.append((settings["design"], settings["controller"], partner.index))
        if len(ran) == stop_at[0]:
            raise KeyboardInterrupt
        force = 1.0 + partner.index + (settings["design"] == "solid-pu")
        return {"partner": partner.to_dict(), "peak_N": dict.fromkeys(regions, force),
                "mean_N": dict.fromkeys(regions, force / 2), "over_2N": [],
                "force_accounting": {"bone_on_bone_peak_N": 0.0},
                "grip": {"p95_error_pct": 1.0}, "warnings": 0, "wall_s": 0.0}

    monkeypatch.setattr(softhand.envs.population, "run_partner", handshake)
    monkeypatch.setattr(softhand.envs.handshake, "HandshakeEnv", lambda **kw: None)

    def invoke(out, *args):
        return CliRunner().invoke(main, ["population", "--n", "2", "--workers", "1", *args,
                                         "--out", str(tmp_path / out)])

    stop_at[:] = [0]
    res = invoke("one", "--design", "solid-pu")
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in (tmp_path / "one").iterdir()) == [
        "fig4.png", "partners.json", "results.csv", "results.json"]
    ran.clear()
    res = invoke("sweep", "--design", "pocket2-sil", "--design", "solid-pu")
    assert res.exit_code == 0, res.output
    assert ran == [("pocket2-sil", "neutral", 0), ("pocket2-sil", "neutral", 1),
                   ("solid-pu", "neutral", 0), ("solid-pu", "neutral", 1)]
    sweep = json.loads((tmp_path / "sweep" / "sweep.json").read_text())
    assert sweep["partners"] == {"n": 2, "seed": 0}
    assert [(c["design"], c["controller"], c["folder"], c["finished"])
            for c in sweep["combinations"]] == [("pocket2-sil", "neutral", "pocket2-sil-neutral", 2),
                                                ("solid-pu", "neutral", "solid-pu-neutral", 2)]
    # peaks 1 and 2 N (pocket2-sil), 2 and 3 N (solid-pu): over 2 N in half, not more
    assert all(c["regions_over_2N_in_most_partners"] == [] for c in sweep["combinations"])
    for c in sweep["combinations"]:
        folder = tmp_path / "sweep" / c["folder"]
        assert sorted(p.name for p in folder.iterdir()) == sorted(
            p.name for p in (tmp_path / "one").iterdir())
    one, swept = (json.loads((tmp_path / f / "results.json").read_text())
                  for f in ("one", "sweep/solid-pu-neutral"))
    del one["settings"]["command"], swept["settings"]["command"]
    assert swept == one  # a combination's results are those of a run of it alone

    ran.clear()
    stop_at[:] = [4]  # Ctrl-C in the second combination's second partner
    res = invoke("stopped", "--design", "pocket2-sil", "--controller", "neutral",
                 "--controller", "force")
    assert res.exit_code == 130, res.output
    assert res.output.strip().splitlines()[-1] == (
        f"interrupted (Ctrl-C): wrote 3 of 4 handshakes to {tmp_path / 'stopped'}; missing: "
        "pocket2-sil-force/1")
    sweep = json.loads((tmp_path / "stopped" / "sweep.json").read_text())
    assert [(c["finished"], c["missing"]) for c in sweep["combinations"]] == [
        (2, {}), (1, {"1": "interrupted"})]
    force = json.loads((tmp_path / "stopped" / "pocket2-sil-force" / "results.json").read_text())
    assert [p["partner"]["index"] for p in force["partners"]] == [0]
