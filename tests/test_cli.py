"""The command line: machine-readable output, files with provenance, and bad input."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from softhand.cli import main

FAST = ["--mode", "2d", "--hold", "0"]


def run(args):
    return CliRunner().invoke(main, args, catch_exceptions=False)


def test_indent_json_has_the_contract_keys(tmp_path):
    """--json prints design, d(2 N), F(2 mm), wall_s and the curve; --out writes CSV + summary."""
    res = run(["fe", "indent", "solid-pu", *FAST, "--json", "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    for key in ("design", "displacement_at_2N_mm", "force_at_2mm_N", "wall_s", "time_s",
                "displacement_mm", "force_N", "contact_area_mm2"):
        assert key in data
    assert len(data["contact_area_mm2"]) == len(data["time_s"])
    assert data["design"] == "solid-pu" and data["force_at_2mm_N"] is None
    assert 0.2 < data["displacement_at_2N_mm"] < 0.6
    assert len(data["time_s"]) == len(data["force_N"]) == len(data["displacement_mm"])
    summary = json.loads((tmp_path / "summary.json").read_text())
    prov = summary["provenance"]
    assert prov["solver_version"] and prov["git_revision"] and prov["mesh_sizes"]["solid-pu"]
    assert prov["mesh_spec"]["n_top"] >= 1  # the element counts, not only the level's name
    assert (tmp_path / "solid-pu.csv").read_text().startswith("time_s,displacement_mm,force_N")


@pytest.mark.slow
def test_flex_press_json_reports_force_area_and_pressure():
    res = run(["skin", "flex-press", "--design", "solid-pu", "--speed", "5", "--posture",
               "flexed", "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    assert data["peak_force_N"] >= 2.0 and data["region"] == "Index3"
    assert 0.35 < data["indentation_at_peak_mm"] < 0.5  # the rig's pad: 0.43 mm at 2 N
    lo, hi = data["contact_area_mm2"]["2"]
    assert 0 < lo <= hi
    assert len(data["pressure_kPa"]) == len(data["pressure_points_mm"]) > 0
    assert len(data["force_N"]) == len(data["indentation_mm"]) == len(data["time_s"])


@pytest.mark.slow
def test_sweep_writes_curves_summary_and_plot(tmp_path):
    """fe sweep on two designs: one CSV each, summary.json with the paper comparison, a PNG."""
    res = run(["fe", "sweep", *FAST, "--design", "solid-sil", "--design", "solid-sil-pu",
               "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert set(summary["designs"]) == {"solid-sil", "solid-sil-pu"}
    assert "layered_change" in summary["comparison"]["solid-sil-pu"]
    assert (tmp_path / "curves.png").stat().st_size > 10_000
    assert not list(tmp_path.glob(".*.tmp"))


@pytest.mark.slow
def test_export_writes_an_abaqus_deck(tmp_path):
    """fe export writes a deck with the hyperfoam material and the travel softhand found."""
    out = tmp_path / "deck.inp"
    res = run(["fe", "export", "pocket2-sil", str(out), "--mesh", "coarse"])
    assert res.exit_code == 0, res.output
    assert "*HYPERFOAM" in out.read_text() and "*VISCOELASTIC" in out.read_text()
    assert "softhand's own travel to --max-force 2 N" in res.output


def test_export_calculix_deck_honours_the_options(tmp_path):
    """--format ccx: elastic CalculiX deck, user constants and the given travel in it."""
    out = tmp_path / "deck.inp"
    mat = tmp_path / "mat.json"
    mat.write_text(json.dumps({"pu": {"mu_MPa": [0.2, 0.063]}}))
    res = run(["fe", "export", "solid-pu", str(out), "--mesh", "coarse", "--format", "ccx",
               "--depth", "0.4", "--materials", str(mat)])
    assert res.exit_code == 0, res.output
    text = out.read_text()
    assert "TYPE=SURFACE TO SURFACE" in text and "\n*VISCOELASTIC" not in text
    assert "no Prony viscoelasticity" in text and "0.4 mm: given" in text
    assert "0.2, 5.5" in text  # mu_1 = 0.2 MPa with alpha_1 = 5.5 in the *HYPERFOAM data


def _materials(tmp_path, constants):
    path = tmp_path / "mat.json"
    path.write_text(json.dumps({"sil": constants}))
    return ["--materials", str(path)]


@pytest.mark.parametrize("extra,needle", [
    (["--geometry", "pocket_height_mm=7"], "pocket_height_mm = 7.0"),
    (["--geometry", "outer_layer_mm=9"], "outer_layer_mm = 9.0"),
    (["--geometry", "nonsense=1"], "nonsense"),
    (["--speed", "-1"], "'--speed': '-1' is outside the allowed range 0 < x <= 100 mm/s"),
])
def test_bad_geometry_or_settings_names_the_value_and_writes_nothing(tmp_path, extra, needle):
    """Exit status 2, the bad value in the message, no output folder."""
    out = tmp_path / "out"
    res = run(["fe", "indent", "pocket2-sil", *FAST, "--out", str(out), *extra])
    assert res.exit_code == 2
    assert needle in res.output
    assert not out.exists()


@pytest.mark.parametrize("constants,needle", [
    ({"nu": 0.5}, "sil.nu = 0.5: expected a finite number in (0, 0.5)"),
    ({"nu": -1.2}, "nu = -1.2"),
    ({"mu_MPa": [0.0, 0.01]}, "sil.mu_MPa[0] = 0.0"),
    ({"mu_MPa": [-0.08, 0.01]}, "sil.mu_MPa[0] = -0.08"),
    ({"tau_s": [0.025, 0.0, 0.3]}, "sil.tau_s[1] = 0.0"),
    ({"g": [0.5, 0.3, 0.2]}, "the sum 1 must be < 1"),
    ({"alpha": [0.0, 15.5]}, "alpha[0] = 0.0"),
])
def test_bad_material_constants_name_the_value_and_write_nothing(tmp_path, constants, needle):
    """Each invalid constant: exit 2, message quotes it and the allowed range, no files."""
    out = tmp_path / "out"
    res = run(["fe", "indent", "solid-sil", *FAST, "--out", str(out),
               *_materials(tmp_path, constants)])
    assert res.exit_code == 2
    assert needle in res.output
    assert not out.exists()


def test_unknown_design_lists_the_allowed_names(tmp_path):
    """Unknown design: exit 2, the name and the 12 allowed designs in the message."""
    res = run(["fe", "indent", "pocket3-sil", "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    assert "'pocket3-sil'" in res.output and "pocket2-pu-sil" in res.output
    assert not (tmp_path / "o").exists()


def test_calibrate_json_reports_the_contract_metrics_and_writes_files(tmp_path):
    """calibrate --json: per skin and representation the four error numbers; files + index."""
    res = run(["calibrate", "prosthetic-102l", "--representation", "soft-contact",
               "--representation", "rigid", "--out", str(tmp_path), "--threads", "1", "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    soft = data["skins"]["prosthetic-102l"]["soft-contact"]
    for key in ("rms_error_pct_of_2N", "max_error_pct_of_2N", "mass_sensitivity_pct",
                "relaxation_error_pct"):
        assert key in soft
    assert soft["rms_error_pct_of_2N"] < 1.0 and soft["mass_sensitivity_pct"] < 2.0
    saved = json.loads((tmp_path / "prosthetic-102l.json").read_text())
    assert saved["provenance"]["mujoco_version"] and saved["format_version"] == 2
    assert json.loads((tmp_path / "index.json").read_text())["lifelike"]


@pytest.mark.parametrize("args, needle", [
    (["calibrate", "pocket3-sil"], "skin 'pocket3-sil' is unknown"),
    (["calibrate", "solid-pu", "--representation", "jelly"], "representation 'jelly' is unknown"),
])
def test_calibrate_bad_input_names_the_value(tmp_path, args, needle):
    res = CliRunner().invoke(main, [*args, "--out", str(tmp_path)])
    assert res.exit_code == 2 and needle in res.output
    assert not any(tmp_path.iterdir())


def test_handshake_json_and_recording(tmp_path):
    """handshake --json: per region peak/mean, the over-2-N set, speed; --record writes an .rrd."""
    rrd = tmp_path / "hs.rrd"
    res = run(["handshake", "--design", "pocket2-sil", "--skin", "Palm=rigid", "--seed", "1",
               "--record", str(rrd), "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)  # warnings go to stderr
    # Palm: the palm's one surface, its four zones at once
    assert len(data["regions"]) == 18 and all(data["skins"][z] == "rigid"
                                              for z in ("Palm1", "Palm2", "Back1", "Back2"))
    assert all({"peak_N", "mean_N", "peak_area_mm2", "mean_area_mm2"} <= set(v)
               for v in data["regions"].values())
    assert data["rigid_contact_peak_N"] >= 0.0
    assert set(data["over_2N"]) <= set(data["regions"])
    assert data["steps_per_s"] > 0 and data["realtime_factor"] > 0
    # the speed leaves out the first step (the kernels' one-off compile on a new machine): the
    # real-time factor is that of the timed steps
    assert data["first_step_s"] > 0.0
    assert data["realtime_factor"] == pytest.approx(data["steps_per_s"] * 0.002)
    assert rrd.stat().st_size > 0
    # the JSON says how it was made: seed, version and every setting
    from softhand import __version__

    cfg = data["settings"]
    assert cfg["seed"] == 1 and cfg["softhand_version"] == __version__
    assert cfg["timestep_s"] == 0.002 and cfg["physics_steps_per_env_step"] == 5
    assert cfg["skins"] == {"Palm": "rigid"} and cfg["controller"] == "neutral"
    assert data["env_steps_per_s"] == pytest.approx(data["steps_per_s"] / 5)
    # where it overloaded: the deepest skin-tissue pair with its geoms and time, the bone peak
    over = data["overload"]
    assert 0.0 < over["deepest_pair_mm"] < 20.0 and "/" in over["deepest_pair"], over
    assert over["bone_on_bone_peak_N"] == data["force_accounting"]["bone_on_bone_peak_N"] == 0.0
    # the first overload, where there is one, is a region's reading over 10 N, and its peak holds
    # it (seed 1 with a rigid palm: the partner's thenar on the back's radial border, 11.5 N)
    for region, force in (over["first_overload"] or {}).items():
        assert force > 10.0 and data["regions"][region]["peak_N"] >= force - 1e-9, over
    # the arms in use, every field, in the settings
    assert cfg["sensored_arm"] == {"stiffness_n_per_m": 1000.0, "damping_ns_per_m": 20.0,
                                   "rot_stiffness_nm_per_rad": 3.0, "mass_kg": 0.8,
                                   "press_n": 2.0}
    assert cfg["partner_arm"]["stiffness_n_per_m"] == 1000.0


def test_handshake_arm_options_reach_the_arms_and_bad_values_are_one_line():
    res = run(["handshake", "--press", "3", "--arm-stiffness", "800", "--hand", "human",
               "--json"])
    assert res.exit_code == 0, res.output
    cfg = json.loads(res.stdout)["settings"]
    assert cfg["sensored_arm"]["press_n"] == 3.0 and cfg["partner_arm"]["press_n"] == 3.0
    assert cfg["sensored_arm"]["stiffness_n_per_m"] == 800.0
    assert cfg["sensored_arm"]["rot_stiffness_nm_per_rad"] == 3.0  # the relaxed arm's own
    for args, needle in ((["--press", "11"], "'--press': '11' is outside the allowed range "
                                             "0 <= x <= 10 N"),
                         (["--arm-stiffness", "5"], "'--arm-stiffness': '5' is outside the "
                                                    "allowed range 20 <= x <= 5000 N/m")):
        res = run(["handshake", *args])
        assert res.exit_code == 2 and needle in res.output, res.output
        assert "Traceback" not in res.output


def test_handshake_text_starts_with_a_header_and_explains_fig4():
    res = run(["handshake", "--seed", "2"])
    assert res.exit_code == 0, res.output
    first = res.stdout.splitlines()[0]
    assert first.startswith("softhand ") and "seed 2" in first and "timestep 2 ms" in first
    assert "controller neutral" in first and "pocket2-sil on every region" in first
    assert "the paper measured a relaxed human hand" in res.stdout
    assert "| a skin law, inside the force range it was calibrated over |" in res.stdout
    assert "env steps/s (" in res.stdout


@pytest.mark.parametrize("args, needle", [
    (["handshake", "--skin", "Palm1"], "--skin 'Palm1': expected REGION=DESIGN"),
    (["handshake", "--skin", "Pinky9=rigid"], "region 'Pinky9' is unknown"),
    (["handshake", "--design", "jelly"], "skin design 'jelly' is unknown"),
    (["handshake", "--timestep", "0.05"],
     "'--timestep': '0.05' is outside the allowed range 0.0001 <= x <= 0.005 s"),
    (["handshake", "--timestep", "nan"],
     "'--timestep': 'nan' is outside the allowed range 0.0001 <= x <= 0.005 s"),
])
def test_handshake_bad_input_names_the_value(args, needle):
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2 and needle in res.output


def test_warnings_print_as_one_line_on_the_command_line():
    """A CalibratedRangeWarning (or any warning) reaches a CLI user as one line naming its class,
    without the source line Python shows by default."""
    from softhand.cli import _one_line_warning
    from softhand.envs.skins import CalibratedRangeWarning

    text = _one_line_warning(CalibratedRangeWarning("pair X: 8 N is beyond 7 N"),
                             CalibratedRangeWarning, "/some/file.py", 12, "source line")
    assert text == "warning (CalibratedRangeWarning): pair X: 8 N is beyond 7 N\n"
