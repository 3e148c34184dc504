"""The command line speaks to people: long commands say on stderr what they start (stdout stays
the report), and the commands that run handshakes open with a header line. The work itself is
stood in for: each benchmark's first piece of work raises, so that only the lines said before it
are checked, and the commands run on stand-in results."""

from __future__ import annotations

import json
import os
import shutil
from types import SimpleNamespace

import numpy as np
import pytest
from click.testing import CliRunner

from softhand import __version__
from softhand.cli import main
from softhand.paper import paper
from softhand.paths import SENSORS_DIR


class _WorkStartedError(Exception):
    """The stand-in for a benchmark's first piece of work."""


def _said_before_work(monkeypatch, module, work: str, run, *args, **kwargs) -> list[str]:
    """The progress lines ``run(*args, **kwargs)`` says before it first calls ``module.work``
    (which raises here)."""
    def stop(*a, **kw):
        raise _WorkStartedError

    monkeypatch.setattr(module, work, stop)
    lines: list[str] = []
    with pytest.raises(_WorkStartedError):
        run(*args, progress=lines.append, **kwargs)
    return lines


# --- the benchmarks: a line before each part, from the first ----------------------------------

def test_bench_fe_says_each_run_before_it(monkeypatch, tmp_path):
    import softhand.bench.fe as fe

    assert _said_before_work(monkeypatch, fe, "_fresh_run", fe.run_fe_benchmark, tmp_path) == [
        "engines on pocket2-sil, ramp 1 of 3: numpy"]


def test_bench_calibration_says_each_skin_before_it(monkeypatch, tmp_path):
    import softhand.bench.calibration as cal

    assert _said_before_work(monkeypatch, cal, "build_rig", cal.run_calibration_benchmark,
                             tmp_path, skins=["solid-sil", "pocket2-sil"]) == [
        "skin solid-sil (1 of 2), rigid"]


def test_bench_handshake_says_each_part_before_it(monkeypatch, tmp_path):
    import softhand.bench.handshake as hs

    said = [_said_before_work(monkeypatch, hs, "run_handshake", hs.run_handshake_benchmark,
                              tmp_path)]
    for run, args in ((hs._timestep_errors, ()), (hs._sensitivity, (("rigid",), "open-loop")),
                      (hs._representations, ())):  # the later parts, each on its own
        said.append(_said_before_work(monkeypatch, hs, "run_handshake",
                                      lambda *a, progress, run=run: run(*a, progress), *args))
    assert said == [["speed, timestep 2 ms, recording off"],
                    ["timestep errors, controller neutral, seed 0"],
                    ["skins side by side, controller open-loop, rigid"],
                    ["representations on the hand, pocket2-sil, rigid"]]


def test_bench_sensors_says_each_part_before_it(monkeypatch, tmp_path):
    import softhand.bench.sensors as sensors

    monkeypatch.setattr(sensors, "design_table", lambda root, designs: {})
    monkeypatch.setattr(sensors, "plot_transfer_curves", lambda root, path: None)
    assert _said_before_work(monkeypatch, sensors, "_handshake", sensors.run_sensor_table,
                             tmp_path) == [
        "the design table", "the transfer curves", "handshake, sensors at interface"]


def test_sensor_calibration_says_each_speed_and_design_before_it(monkeypatch, tmp_path):
    import softhand.sensors.calibrate as cal

    assert _said_before_work(monkeypatch, cal, "run_sweep", cal.run_sensor_fe, ["pocket2-sil"],
                             tmp_path) == ["FE records at 0.5 mm/s (1 of 2 speeds)"]
    (tmp_path / "fe").mkdir(exist_ok=True)
    shutil.copy(SENSORS_DIR / "fe" / "summary.json", tmp_path / "fe" / "summary.json")
    assert _said_before_work(monkeypatch, cal, "read_records", cal.fit_all, ["pocket2-sil"],
                             tmp_path) == ["transfer laws of pocket2-sil (1 of 1)"]


# --- the commands: those lines on stderr, the report alone on stdout --------------------------

@pytest.mark.parametrize("args, module, function", [
    (["bench", "fe", "--quick"], "softhand.bench.fe", "run_fe_benchmark"),
    (["bench", "calibration"], "softhand.bench.calibration", "run_calibration_benchmark"),
    (["bench", "handshake"], "softhand.bench.handshake", "run_handshake_benchmark"),
    (["bench", "handshake", "--scale"], "softhand.bench.scale", "run_scale_benchmark"),
    (["bench", "sensors"], "softhand.bench.sensors", "run_sensor_table"),
])
def test_bench_commands_print_progress_on_stderr_and_the_report_on_stdout(
        monkeypatch, tmp_path, args, module, function):
    import importlib

    def bench(out, *, progress, **kwargs):
        progress("part one")
        progress("part two")
        return "# report\n"

    monkeypatch.setattr(importlib.import_module(module), function, bench)
    res = CliRunner().invoke(main, [*args, "--out", str(tmp_path)])
    assert res.exit_code == 0, (res.output, res.exception)
    assert res.stdout == "# report\n\n"
    assert res.stderr.splitlines() == ["part one ...", "part two ..."]


def test_sensors_calibrate_prints_progress_on_stderr(monkeypatch, tmp_path):
    import softhand.sensors.calibrate as cal

    out = tmp_path / "sensors"
    shutil.copytree(SENSORS_DIR, out)

    def fit_all(designs, root, *, progress):
        for design in designs:
            progress(f"transfer laws of {design}")
        return {"laws": {}}

    monkeypatch.setattr(cal, "fit_all", fit_all)
    res = CliRunner().invoke(main, ["sensors", "calibrate", "--fit-only", "--design",
                                    "pocket2-sil", "--out", str(out)])
    assert res.exit_code == 0, (res.output, res.exception)
    assert res.stderr.splitlines() == ["transfer laws of pocket2-sil ..."]
    assert res.stdout == f"wrote {out / 'transfer.json'}\n"


# --- headers: what runs, first, on stdout -----------------------------------------------------

@pytest.fixture
def stand_in_partners(monkeypatch):
    """``softhand population`` on stand-in handshakes (in this process with --workers 1)."""
    import softhand.envs.handshake
    import softhand.envs.population

    regions = paper()["handshake"]["regions"]

    def handshake(partner, settings):
        return {"partner": partner.to_dict(), "peak_N": dict.fromkeys(regions, 1.0),
                "mean_N": dict.fromkeys(regions, 0.5), "over_2N": [],
                "force_accounting": {"bone_on_bone_peak_N": 0.0},
                "grip": {"p95_error_pct": 1.0}, "warnings": 0, "wall_s": 0.0}

    monkeypatch.setattr(softhand.envs.population, "run_partner", handshake)
    monkeypatch.setattr(softhand.envs.handshake, "HandshakeEnv", lambda **kw: None)


@pytest.mark.parametrize("args, header", [
    (["--seed", "3"], "2 partners, seed 3 | prosthetic hand, pocket2-sil on every region, "
                      "controller neutral"),
    (["--design", "pocket2-sil", "--design", "solid-pu", "--controller", "neutral",
      "--controller", "force"],
     "2 partners x 4 combinations, seed 0 | prosthetic hand, skins pocket2-sil, solid-pu, "
     "controllers neutral, force"),
    (["--hand", "human"], "2 partners, seed 0 | the relaxed human hand (the paper's protocol)"),
])
def test_population_starts_with_a_header(stand_in_partners, tmp_path, args, header):
    res = CliRunner().invoke(main, ["population", "--n", "2", "--workers", "1", *args,
                                    "--out", str(tmp_path / "pop")])
    assert res.exit_code == 0, (res.output, res.exception)
    assert res.stdout.splitlines()[0] == f"softhand {__version__} population | {header}"
    assert "2 partners" in res.stderr  # the progress bar


@pytest.mark.parametrize("args, header", [
    ([], "prosthetic hand, pocket2-sil on every region, controller neutral | partner seed 0 | "
         "at mid-shake"),
    (["--design", "solid-pu", "--controller", "force", "--seed", "4", "--at", "1.5",
      "--partner-size", "180,85"],
     "prosthetic hand, solid-pu on every region, controller force | partner seed 4, hand "
     "180 x 85 mm | at t = 1.5 s"),
    (["--sheet", "--hand", "human"], "the relaxed human hand (the paper's protocol) | partner "
                                     "seed 0 | at the end of the grip, mid-shake and mid-hold, "
                                     "4 views each"),
])
def test_render_starts_with_a_header(monkeypatch, tmp_path, args, header):
    import softhand.envs.handshake
    import softhand.envs.run
    import softhand.viz.render

    phase = ["reach", "grip", "grip", "shake", "shake", "shake", "hold", "hold", "release"]
    run = SimpleNamespace(phase=phase, time_s=np.linspace(0.0, 3.0, len(phase)),
                          qpos=[None] * len(phase), mocap_pos=[None] * len(phase),
                          mocap_quat=[None] * len(phase), region_names=[],
                          region_force_N=np.zeros((len(phase), 0)), model=None)
    monkeypatch.setattr(softhand.envs.handshake, "HandshakeEnv", lambda **kw: None)
    monkeypatch.setattr(softhand.envs.run, "run_handshake", lambda **kw: run)
    monkeypatch.setattr(softhand.viz.render, "render_state", lambda *a, **kw: None)
    monkeypatch.setattr(softhand.viz.render, "render_sheet", lambda *a, **kw: None)
    res = CliRunner().invoke(main, ["render", str(tmp_path / "x.png"), *args])
    assert res.exit_code == 0, (res.output, res.exception)
    first, *rest = res.stdout.splitlines()
    assert first == f"softhand {__version__} render | {header}"
    assert len(rest) == 1 and rest[0].startswith(f"wrote {tmp_path / 'x.png'}")



def test_the_command_line_imports_no_mujoco_before_render_chooses_its_gl():
    """``softhand render`` sets MUJOCO_GL before mujoco is first imported (MuJoCo reads it then):
    importing the command line must not import mujoco, or the render fails deep inside
    (an OpenGL FatalError) when MUJOCO_GL was not set by the user."""
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    out = subprocess.run([sys.executable, "-c", "import sys, softhand.cli; "
                          "print('mujoco' in sys.modules)"], env=env, capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip() == "False", out.stdout


def test_an_incomplete_population_never_replaces_an_earlier_complete_set(stand_in_partners,
                                                                         monkeypatch, tmp_path):
    """A complete population in --out, then the same command where one handshake fails: the
    earlier complete set stays byte for byte, the finished partners go beside it
    (OUT.incomplete), and the closing line says both (exit 3)."""
    import softhand.envs.population

    out = tmp_path / "pop"
    args = ["population", "--n", "4", "--seed", "7", "--workers", "1", "--out", str(out)]
    assert CliRunner().invoke(main, args).exit_code == 0
    before = {f.name: f.read_bytes() for f in out.iterdir()}
    good = softhand.envs.population.run_partner

    def fails_once(partner, settings):
        if partner.index == 2:
            raise RuntimeError("the physics diverged")
        return good(partner, settings)

    monkeypatch.setattr(softhand.envs.population, "run_partner", fails_once)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 3, res.output
    assert {f.name: f.read_bytes() for f in out.iterdir()} == before
    partial = json.loads((tmp_path / "pop.incomplete" / "results.json").read_text())
    assert len(partial["partners"]) == 3 and partial["settings"]["missing"]
    assert "earlier complete set kept" in res.output and "pop.incomplete" in res.output
