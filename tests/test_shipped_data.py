"""Shipped data and output folders (issue 20, items 2 and 3).

Shipped data changes only with ``--force``, and only when the run completes: an interrupted or
failed run leaves every file of the shipped folder byte for byte (sha256). An FE folder holds one
setting: extending it with another is refused naming both, a subset extends it, a corrupt summary
is an error naming the file. Outputs are checked (writable, room on the disk) before any work.

The shipped folder here is a copy of ``calibration/`` in a temporary folder, made "shipped" by
pointing :data:`softhand.paths.CALIBRATION_DIR` at it, so that no test can touch the real one.
"""

from __future__ import annotations

import errno
import hashlib
import json
import re
import shutil
import sys
from collections import namedtuple
from dataclasses import replace
from pathlib import Path

import pytest
from click.testing import CliRunner

import softhand.fem.sweep
import softhand.paths
from softhand.cli import main
from softhand.fem.geometry import DESIGNS
from softhand.paths import CALIBRATION_DIR

FAST = ["--mode", "2d", "--mesh", "coarse", "--hold", "0", "--max-force", "2", "--threads", "1"]
TWO = ("solid-sil", "solid-pu")  # the designs of the shipped fixture's FE folder
BOTH = ["--design", TWO[0], "--design", TWO[1]]


def sha_tree(root: Path) -> dict[str, str]:
    """sha256 of every file under ``root`` (hidden ones too), by relative path."""
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.fixture
def shipped(tmp_path, monkeypatch) -> Path:
    """A copy of the shipped calibration that the commands treat as shipped, its FE folder cut to
    the two designs of :data:`TWO` (so that a sweep of them is a complete set, in seconds)."""
    root = tmp_path / "calibration"
    shutil.copytree(CALIBRATION_DIR, root, ignore=shutil.ignore_patterns("__pycache__"))
    summary = json.loads((root / "fe" / "summary.json").read_text())
    for name in DESIGNS:
        if name not in TWO:
            (root / "fe" / f"{name}.csv").unlink()
            for part in (summary["designs"], summary["provenance"]["curve_sha256"],
                         summary["provenance"]["mesh_sizes"]):
                part.pop(name, None)
    (root / "fe" / "summary.json").write_text(json.dumps(summary, indent=2))
    monkeypatch.setattr(softhand.paths, "CALIBRATION_DIR", root.resolve())
    return root


def invoke(args: list[str]):
    return CliRunner().invoke(main, args)


def interrupted_after(first: int, monkeypatch) -> None:
    """run_sweep finishes ``first`` designs, then stops as Ctrl-C stops it."""
    real = softhand.fem.sweep.run_sweep

    def partial(names, settings, **kw):
        done = real(list(names)[:first], settings, show_progress=False, threads=1)
        return replace(done, missing=list(names)[first:], interrupted=True)

    monkeypatch.setattr(softhand.fem.sweep, "run_sweep", partial)


def test_an_interrupted_forced_sweep_leaves_the_shipped_set_byte_identical(shipped, monkeypatch):
    before = sha_tree(shipped)
    interrupted_after(1, monkeypatch)
    res = invoke(["fe", "sweep", *FAST, *BOTH, "--force", "--out", str(shipped / "fe")])
    assert res.exit_code == 130, res.output
    last = res.output.strip().splitlines()[-1]
    assert "the shipped set in" in last and "is unchanged" in last and "1 finished designs" in last
    assert sha_tree(shipped) == before
    assert sorted(p.name for p in shipped.iterdir()) == sorted(
        p.name for p in CALIBRATION_DIR.iterdir() if p.name != "__pycache__")  # no staging left


def test_a_complete_forced_sweep_replaces_the_shipped_set(shipped):
    res = invoke(["fe", "sweep", *FAST, *BOTH, "--force", "--out", str(shipped / "fe")])
    assert res.exit_code == 0, res.output
    summary = json.loads((shipped / "fe" / "summary.json").read_text())
    assert summary["complete"] and list(summary["designs"]) == list(TWO)
    assert summary["provenance"]["settings"]["mode"] == "2d"
    assert [p.name for p in shipped.iterdir() if p.name.startswith(".")] == []


def test_a_failed_write_keeps_the_shipped_set_and_says_so(shipped, monkeypatch):
    before = sha_tree(shipped)
    real = softhand.fem.sweep.write_results

    def disk_full(results, out, **kw):
        first, *rest = results  # one design written, then the disk fills
        real({first: results[first]}, out, plot=False, missing={n: "disk full" for n in rest})
        raise OSError(errno.ENOSPC, "No space left on device", str(Path(out) / "x.csv"))

    monkeypatch.setattr(softhand.fem.sweep, "write_results", disk_full)
    res = invoke(["fe", "sweep", *FAST, *BOTH, "--force", "--out", str(shipped / "fe")])
    assert res.exit_code == 4, res.output
    line = res.output.strip().splitlines()[-1]
    assert "No space left on device" in line and "the shipped data is unchanged" in line
    assert sha_tree(shipped) == before


def test_a_failed_write_elsewhere_says_what_was_kept(tmp_path, monkeypatch):
    def disk_full(results, out, **kw):
        raise OSError(errno.ENOSPC, "No space left on device", str(Path(out) / "a.csv"))

    monkeypatch.setattr(softhand.fem.sweep, "write_results", disk_full)
    res = invoke(["fe", "sweep", *FAST, "--design", "solid-pu", "--out", str(tmp_path / "fe")])
    assert res.exit_code == 4, res.output
    line = res.output.strip().splitlines()[-1]
    assert line.startswith("error: writing into") and "kept in" in line
    assert "summary.json was not updated" in line


def test_a_subset_extends_a_folder_of_the_same_settings(tmp_path):
    out = tmp_path / "fe"
    assert invoke(["fe", "sweep", *FAST, "--design", "solid-pu", "--design", "solid-sil",
                   "--out", str(out)]).exit_code == 0
    first = json.loads((out / "summary.json").read_text())
    res = invoke(["fe", "sweep", *FAST, "--design", "pocket2-sil", "--out", str(out)])
    assert res.exit_code == 0, res.output
    summary = json.loads((out / "summary.json").read_text())
    assert list(summary["designs"]) == ["solid-sil", "solid-pu", "pocket2-sil"]  # DESIGNS order
    for name in ("solid-sil", "solid-pu"):  # the earlier curves, their records unchanged
        assert (summary["provenance"]["curve_sha256"][name]
                == first["provenance"]["curve_sha256"][name])
    assert summary["complete"] is True


def test_other_settings_are_not_mixed_into_a_folder(tmp_path):
    out = tmp_path / "fe"
    assert invoke(["fe", "sweep", *FAST, "--design", "solid-pu", "--design", "solid-sil",
                   "--out", str(out)]).exit_code == 0
    before = sha_tree(out)
    res = invoke(["fe", "sweep", *FAST, "--speed", "5", "--design", "solid-pu",
                  "--out", str(out)])
    assert res.exit_code == 2
    assert "speed_mm_s 0.5 (the folder) vs 5.0 (this run)" in res.output
    res = invoke(["fe", "indent", "solid-sil", "--mode", "3d", "--mesh", "coarse",
                  "--out", str(out)])
    assert res.exit_code == 2 and "mode '2d' (the folder) vs '3d' (this run)" in res.output
    assert sha_tree(out) == before


def test_calibrate_refuses_mixed_or_corrupt_fe_folders(tmp_path):
    fe = tmp_path / "fe"
    shutil.copytree(CALIBRATION_DIR / "fe", fe)
    summary = json.loads((fe / "speed-2" / "summary.json").read_text())
    summary["provenance"]["settings"]["mode"] = "2d"
    (fe / "speed-2" / "summary.json").write_text(json.dumps(summary))
    res = invoke(["calibrate", "pocket2-sil", "--fe-dir", str(fe), "--out", str(tmp_path / "s")])
    assert res.exit_code == 2, res.output
    assert "FE curves of other settings in one folder: mode '3d'" in res.output
    assert "'2d'" in res.output and "speed-2" in res.output
    (fe / "speed-2" / "summary.json").write_text('{"provenance": ')
    res = invoke(["calibrate", "pocket2-sil", "--fe-dir", str(fe), "--out", str(tmp_path / "s")])
    assert res.exit_code == 2 and "speed-2/summary.json: not JSON" in res.output
    res = invoke(["fe", "sweep", *FAST, "--design", "solid-pu", "--out", str(fe / "speed-2")])
    assert res.exit_code == 2 and "speed-2/summary.json: not JSON" in res.output
    assert not (tmp_path / "s").exists()


def test_calibrate_into_its_own_fe_folder_is_refused(tmp_path):
    fe = tmp_path / "fe"
    shutil.copytree(CALIBRATION_DIR / "fe", fe)
    res = invoke(["calibrate", "pocket2-sil", "--fe-dir", str(fe), "--out", str(fe)])
    assert res.exit_code == 2 and "--out" in res.output and "is --fe-dir" in res.output


def test_a_curve_its_summary_does_not_record_is_refused(tmp_path):
    fe = tmp_path / "fe"
    shutil.copytree(CALIBRATION_DIR / "fe", fe)
    summary = json.loads((fe / "summary.json").read_text())
    del summary["provenance"]["curve_sha256"]["pocket2-sil"]
    (fe / "summary.json").write_text(json.dumps(summary))
    res = invoke(["calibrate", "pocket2-sil", "--fe-dir", str(fe), "--out", str(tmp_path / "s")])
    assert res.exit_code == 2 and "has no record of this curve" in res.output


Usage = namedtuple("Usage", "total used free")


@pytest.mark.parametrize("args", [
    ["fe", "sweep", *FAST, "--out", "{tmp}/fe"],
    ["handshake", "--record", "{tmp}/x.rrd"],
    ["population", "--n", "2", "--out", "{tmp}/pop"],
])
def test_a_full_disk_is_found_before_the_work(tmp_path, monkeypatch, args):
    monkeypatch.setattr(shutil, "disk_usage", lambda path: Usage(10**9, 10**9 - 1000, 1000))
    res = invoke([a.format(tmp=tmp_path) for a in args])
    assert res.exit_code == 2, res.output
    assert "this run writes about" in res.output and "1.0 kB free" in res.output
    assert list(tmp_path.iterdir()) == []


def test_names_longer_than_the_file_system_takes_are_refused(tmp_path):
    res = invoke(["fe", "sweep", *FAST, "--out", str(tmp_path / ("x" * 300))])
    assert res.exit_code == 2
    assert "has 300 bytes; allowed at most 255 bytes a name" in res.output


@pytest.mark.parametrize("content, needle", [
    ("[" * 100000 + "]" * 100000, "nested too deeply"),
    ('{"sil": {"nu": NaN}}', "sil.nu = nan: expected a finite number"),
])
def test_json_inputs_that_would_break_the_parser(tmp_path, content, needle):
    path = tmp_path / "m.json"
    path.write_text(content)
    res = invoke(["fe", "indent", "solid-pu", *FAST, "--materials", str(path)])
    assert res.exit_code == 2 and needle in res.output and "--materials" in res.output


def test_a_device_is_not_read_as_a_file():
    res = invoke(["fe", "indent", "solid-pu", *FAST, "--materials", "/dev/zero"])
    assert res.exit_code == 2 and "not a regular file" in res.output


def test_more_threads_than_cpus_are_refused():
    from softhand.parallel import available_cpus

    n = available_cpus()
    for args in (["fe", "sweep", "--threads", "100000"], ["population", "--workers", str(n + 1)]):
        res = invoke(args)
        assert res.exit_code == 2
        assert f"more than the {n} CPUs this process may run on; allowed 1-{n}" in res.output


def test_an_unknown_gl_backend_is_refused_before_the_run(monkeypatch, tmp_path):
    monkeypatch.setenv("MUJOCO_GL", "bogus")
    res = invoke(["render", str(tmp_path / "x.png")])
    assert res.exit_code == 2 and "MUJOCO_GL = 'bogus'" in res.output and "osmesa" in res.output


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the library check is Linux's")
def test_a_gl_backend_this_machine_cannot_open_is_refused_before_the_run(monkeypatch, tmp_path):
    """MUJOCO_GL=osmesa without libOSMesa, and glfw without a display, ended after the whole
    simulation in an internal error from deep inside the first render; now one line before it."""
    import ctypes.util

    find = ctypes.util.find_library
    monkeypatch.setattr(ctypes.util, "find_library",
                        lambda name: None if name == "OSMesa" else find(name))
    monkeypatch.setenv("MUJOCO_GL", "osmesa")
    res = invoke(["render", str(tmp_path / "x.png")])
    lines = res.output.strip().splitlines()
    assert res.exit_code == 2 and len(lines) == 1, res.output
    assert lines[0].startswith("error: MUJOCO_GL = 'osmesa': libOSMesa is not installed")
    monkeypatch.setenv("MUJOCO_GL", "glfw")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    res = invoke(["render", str(tmp_path / "x.png")])
    assert res.exit_code == 2 and "MUJOCO_GL = 'glfw'" in res.output, res.output
    assert "no display" in res.output
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("edit, needle", [
    (lambda d: d["laws"]["pocket2-sil"]["interface"]["kernel"].update(k_inf=0.5),
     "laws.pocket2-sil.interface.kernel.k_inf = 0.5: it is 1 - sum(c)"),
    (lambda d: d["laws"]["pocket2-sil"]["interface"].update(gain=2.0),
     "laws.pocket2-sil.interface.gain"),
    (lambda d: d.update(extra=1), "extra"),
    (lambda d: d["laws"]["pocket2-sil"]["interface"]["fitted"][0].pop("rms_pct"),
     "fitted[0].rms_pct: missing"),
])
def test_transfer_files_with_unknown_or_inconsistent_keys_are_refused(tmp_path, edit, needle):
    from softhand.sensors.calibrate import load_transfer_laws

    data = json.loads((CALIBRATION_DIR / "sensors" / "transfer.json").read_text())
    edit(data)
    path = tmp_path / "transfer.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"transfer\.json") as info:
        load_transfer_laws(path)
    assert needle in str(info.value)


def test_nan_in_a_transfer_file_is_refused(tmp_path):
    from softhand.sensors.calibrate import load_transfer_laws

    text = (CALIBRATION_DIR / "sensors" / "transfer.json").read_text()
    path = tmp_path / "transfer.json"
    path.write_text(re.sub(r'"dead_band_N": [-0-9.e]+', '"dead_band_N": NaN', text, count=1))
    with pytest.raises(ValueError, match=r"dead_band_N = nan: expected a finite number"):
        load_transfer_laws(path)


def test_any_command_that_meets_a_full_disk_says_so_in_one_line(tmp_path, monkeypatch):
    import softhand.fem.abaqus

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "deck.inp"))

    monkeypatch.setattr(softhand.fem.abaqus, "write_deck", full)
    res = invoke(["fe", "export", "solid-pu", str(tmp_path / "deck.inp"), "--depth", "1"])
    assert res.exit_code == 4, res.output
    assert res.output.strip() == (f"error: could not write {tmp_path / 'deck.inp'} (No space left "
                                  "on device); the files written before it are kept, each whole "
                                  "(atomic writes)")
