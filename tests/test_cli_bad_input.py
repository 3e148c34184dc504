"""Bad input on the command line: one line naming the flag and the value, exit 2, no work, no file.

Every case of the reliability issue's list (and its neighbours) is here, one parametrised test per
class of input. The work functions are replaced by ones that fail the test if called, so "before
any work starts" is checked, not assumed.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from softhand.cli import main
from softhand.paths import CALIBRATION_DIR, FE_DIR, SKINS_DIR

FAST = ["--mode", "2d", "--hold", "0"]
HAND = str(Path(__file__).resolve().parent / "data" / "menagerie_style_hand.xml")
SCENE = str(Path(__file__).resolve().parents[1] / "models" / "mjcf" / "handshake_scene.xml")


@pytest.fixture(autouse=True)
def no_work(monkeypatch):
    """Any FE run, sweep, calibration or handshake episode fails the test."""
    def forbidden(*args, **kwargs):
        raise AssertionError("work started before the input was rejected")

    import softhand.envs.run
    import softhand.fem.abaqus
    import softhand.fem.solver
    import softhand.fem.sweep
    import softhand.skin.run

    monkeypatch.setattr(softhand.fem.solver, "indent", forbidden)
    monkeypatch.setattr(softhand.fem.sweep, "run_sweep", forbidden)
    monkeypatch.setattr(softhand.fem.abaqus, "write_deck", forbidden)
    monkeypatch.setattr(softhand.skin.run, "calibrate_many", forbidden)
    monkeypatch.setattr(softhand.envs.run, "run_handshake", forbidden)


def rejected(args: list[str], *needles: str, cwd: Path | None = None) -> str:
    """Run the CLI; assert exit 2 and one line holding every needle; return the line."""
    res = CliRunner().invoke(main, args)
    line = res.output.strip()
    assert res.exit_code == 2, (res.exit_code, res.output, res.exception)
    assert "\n" not in line and line.startswith("error: "), res.output
    assert "Traceback" not in res.output and "Usage:" not in res.output
    for needle in needles:
        assert needle in line, (needle, line)
    return line


@pytest.mark.parametrize("args, needles", [
    (["fe", "indent", "solid-pu", "--speed", "nan"], ["'--speed'", "'nan'", "0 < x <= 100 mm/s"]),
    (["fe", "indent", "solid-pu", "--speed", "0"], ["'--speed'", "0 < x <= 100 mm/s"]),
    (["fe", "indent", "solid-pu", "--hold", "-1"], ["'--hold'", "'-1'", "0 <= x <= 600 s"]),
    (["fe", "indent", "solid-pu", "--max-force", "1e6"], ["'--max-force'", "'1e6'", "<= 50 N"]),
    (["fe", "indent", "solid-pu", "--max-depth", "0"], ["'--max-depth'", "<= 7 mm"]),
    (["fe", "indent", "solid-pu", "--threads", "0"], ["'--threads'", "0"]),
    (["fe", "sweep", "--speed", "inf"], ["'--speed'", "'inf'"]),
    (["handshake", "--timestep", "1e-7"], ["'--timestep'", "'1e-7'", "0.0001 <= x <= 0.005 s"]),
    (["handshake", "--timestep", "0.01"], ["'--timestep'", "'0.01'", "0.0001 <= x <= 0.005 s"]),
    (["handshake", "--seed", "-1"], ["'--seed'", "-1"]),
    (["handshake", "--seed", "1.5"], ["'--seed'", "1.5"]),
    (["fe", "export", "solid-pu", "x.inp", "--depth", "-2"], ["'--depth'", "'-2'"]),
    (["bench", "handshake", "--scale", "--worlds", "2,0"], ["--worlds", "'2,0'", "1-1024"]),
    (["bench", "handshake", "--scale", "--worlds", "8,x"], ["--worlds", "'8,x'", "1-1024"]),
    (["bench", "handshake", "--worlds", "8"], ["--worlds", "'8'", "only with --scale"]),
])
def test_numbers_outside_their_range(args, needles):
    rejected(args, *needles)


@pytest.mark.parametrize("args, needles", [
    (["handshake", "--design", ""], ["--design ''"]),
    (["handshake", "--record", ""], ["--record = ''", "empty"]),
    (["fe", "indent", "solid-pu", "--out", ""], ["--out = ''", "empty"]),
    (["fe", "sweep", "--out", ""], ["--out = ''", "empty"]),
    (["fe", "indent", "solid-pu", "--materials", ""], ["--materials ''", "empty"]),
    (["calibrate", "solid-pu", "--fe-dir", "", "--out", "x"], ["--fe-dir ''"]),
    (["fe", "indent", ""], ["design ''"]),
])
def test_empty_strings(args, needles):
    rejected(args, *needles)


def test_paths_that_cannot_be_written(tmp_path):
    plain = tmp_path / "plain.txt"
    plain.write_text("x")
    rejected(["handshake", "--record", str(tmp_path / "x.txt")], "--record", "ending in .rrd")
    rejected(["handshake", "--record", str(tmp_path)], "--record", ".rrd")
    rejected(["handshake", "--record", str(plain / "x.rrd")], "--record", "is a file")
    rejected(["fe", "indent", "solid-pu", "--out", str(plain / "out")], "--out", "is a file")
    rejected(["fe", "indent", "solid-pu", "--out", str(plain)], "--out", "is a file, not a folder")
    rejected(["fe", "sweep", "--out", str(plain / "a" / "b")], "--out", "is a file")
    rejected(["bench", "fe", "--out", str(plain)], "--out", "not a folder")
    rejected(["fe", "export", "solid-pu", str(tmp_path / "deck.txt")], "OUT", ".inp")
    rejected(["fe", "export", "solid-pu", str(plain / "deck.inp")], "OUT", "is a file")
    rejected(["render", str(tmp_path / "hs.jpg")], "OUT", ".png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plain.txt"]


@pytest.mark.parametrize("args, needles", [
    # the commands that make shipped data: only with --force, whatever the settings
    (["fe", "sweep"], ["--out", "is the shipped calibration data", "--force"]),
    (["fe", "sweep", "--design", "solid-pu"], ["shipped calibration data", "--force"]),
    (["fe", "sweep", "--speed", "5"], ["shipped calibration data", "--force"]),
    (["fe", "sweep", "--max-force", "20", "--max-depth", "7"], ["shipped", "--force"]),
    (["fe", "indent", "solid-pu", "--out", str(FE_DIR)], ["shipped", "--force"]),
    (["calibrate"], ["--out", "shipped calibration data", "--force"]),
    (["calibrate", "pocket2-sil"], ["shipped calibration data", "--force"]),
    (["sensors", "calibrate", "--fit-only"], ["--out", "shipped calibration data", "--force"]),
    # the commands that never write shipped data: refused outright
    (["fe", "sweep", "--out", str(SKINS_DIR)], ["--out", "shipped", "--force"]),
    (["fe", "export", "solid-pu", str(FE_DIR / "x.inp")], ["OUT", "never writes"]),
    (["handshake", "--record", str(CALIBRATION_DIR / "x.rrd")], ["--record", "never writes"]),
    (["render", str(SKINS_DIR / "x.png")], ["OUT", "never writes"]),
    (["bench", "handshake", "--out", str(FE_DIR)], ["--out", "never writes"]),
    (["population", "--out", str(CALIBRATION_DIR / "pop")], ["--out", "never writes"]),
    (["skin", "flex-press", "--picture", str(SKINS_DIR / "p.png")], ["--picture", "never writes"]),
])
def test_shipped_data_is_written_only_with_force(args, needles):
    """Every command that can write refuses the shipped calibration/ without --force (issue 20,
    item 2): nothing in calibration/ changes, not even a file's time."""
    before = {p: p.stat().st_mtime_ns for p in CALIBRATION_DIR.rglob("*")}
    rejected(args, *needles)
    assert {p: p.stat().st_mtime_ns for p in CALIBRATION_DIR.rglob("*")} == before


@pytest.mark.parametrize("content, needles", [
    ("{not json", ["not JSON", "line 1"]),
    ("[1, 2]", ["expected an object keyed by material name", "list"]),
    (json.dumps({"sil": {"mu_MPa": 3}}), ["sil.mu_MPa = 3", "list of 2"]),
    (json.dumps({"sil": {"alpha": "x"}}), ["sil.alpha", "'x'"]),
    (json.dumps({"sil": {"nu": [0.3]}}), ["sil.nu"]),
    (json.dumps({"sil": {"viscosity": 1}}), ["viscosity"]),
    (json.dumps({"sil": 5}), ["sil"]),
    (json.dumps({"rubber": {}}), ["rubber"]),
])
def test_material_files(tmp_path, content, needles):
    path = tmp_path / "mat.json"
    path.write_text(content)
    out = tmp_path / "out"
    rejected(["fe", "indent", "solid-sil", *FAST, "--materials", str(path), "--out", str(out)],
             "--materials", str(path), *needles)
    assert not out.exists()


def test_elastic_only_still_checks_the_prony_constants(tmp_path):
    path = tmp_path / "mat.json"
    path.write_text(json.dumps({"sil": {"g": [0.5, 0.4, 0.3]}}))
    rejected(["fe", "indent", "solid-sil", "--elastic-only", "--materials", str(path)],
             "--materials", "sil.g")


@pytest.mark.parametrize("args, needles", [
    (["fe", "indent", "solid-sil", "--geometry", "pocket_height_mm=2"],
     ["--geometry pocket_height_mm=2", "solid-sil has no pocket", "pocket2-sil"]),
    (["fe", "indent", "pocket2-sil", "--geometry", "pocket_height_mm=-1"],
     ["--geometry", "pocket_height_mm = -1"]),
    (["fe", "indent", "pocket2-sil", "--geometry", "height_mm=1e6"],
     ["--geometry height_mm=1e6", "height_mm = 1000000"]),
    (["fe", "indent", "pocket2-sil", "--geometry", "height_mm"], ["--geometry 'height_mm'",
                                                                  "KEY=VALUE"]),
    (["fe", "indent", "pocket2-sil", "--geometry", "height_mm=tall"], ["'tall'", "not a number"]),
    (["fe", "indent", "pocket2-sil", "--geometry", "height_mm=nan"], ["'nan'", "finite"]),
    (["fe", "indent", "pocket2-sil", "--geometry", "wingspan_mm=3"], ["wingspan_mm"]),
    (["fe", "sweep", "--geometry", "pocket_height_mm=1.5", "--out", "x"],
     ["solid-sil has no pocket"]),
])
def test_geometry_overrides(args, needles):
    rejected(args, *needles)


@pytest.mark.parametrize("args, needles", [
    (["fe", "indent", "pocket3-sil"], ["'pocket3-sil'", "pocket2-pu-sil"]),
    (["fe", "sweep", "--design", "jelly", "--out", "x"], ["'jelly'"]),
    (["calibrate", "pocket3-sil", "--out", "x"], ["skin 'pocket3-sil' is unknown"]),
    (["calibrate", "solid-pu", "--representation", "jelly", "--out", "x"],
     ["--representation 'jelly' is unknown", "soft-contact"]),
    (["handshake", "--design", "jelly"], ["'jelly'"]),
    (["handshake", "--skin", "Pinky9=rigid"], ["'Pinky9'"]),
    (["handshake", "--skin", "Palm1"], ["--skin 'Palm1'", "REGION=DESIGN"]),
    (["handshake", "--controller", "telepathy"], ["'--controller'", "'telepathy'"]),
    (["handshake", "--representation", "jelly"], ["--representation", "'jelly'", "soft-contact"]),
    (["handshake", "--representation", "flex"], ["'flex' is not available in the handshake", "flex-press",
                                                  "soft-contact+relaxation"]),
    (["handshake", "--skin", "Palm1=pocket2-pu@jelly"], ["region Palm1 'jelly'"]),
    (["handshake", "--skin", "Palm1=rigid@soft-contact"], ["'rigid'", "only the rigid"]),
    (["handshake", "--skin", "Palm1=rigid"], ["Palm1, Palm2, Back1, Back2 are zones of one palm",
                                              "give them the same"]),
    (["handshake", "--hand", "human", "--sensor-placement", "bone"],
     ["--sensor-placement", "'bone'", "human-middle-phalanx has no FE model"]),
    (["render", "x.png", "--sheet", "--at", "3"], ["--at with --sheet", "no --at"]),
    (["bench", "handshake", "--scale", "--worlds", "1_0"], ["--worlds '1_0'", "integers 1-1024"]),
    (["handshake", "--skin", "Index1=rigid", "--skin", "Index1=solid-pu"],
     ["--skin 'Index1=solid-pu'", "Index1 is given twice (rigid, then solid-pu)", "each region once"]),
    (["fe", "indent", "pocket2-sil", "--geometry", "pocket_roof_mm=1.5", "--geometry",
      "pocket_roof_mm=2"], ["pocket_roof_mm is given twice (1.5, then 2)", "each key once"]),
    (["fe", "indent", "pocket2-sil", "--solver", "cholmod", "--engine", "numpy"],
     ["--solver cholmod with --engine numpy", "SuperLU", "--solver auto"]),
    (["render", "x.png", "--sheet", "--size", "200", "200"], ["--size with --sheet"]),
    (["render", "x.gif", "--video", "--at", "3"], ["--at with --video"]),
    (["fe", "export", "solid-pu", "x.inp", "--mode", "2d"], ["--mode"]),
    (["fe", "export", "solid-pu", "x.inp", "--format", "stl"], ["'--format'", "'stl'"]),
    (["bench", "calibration", "--skin", "jelly"], ["--skin 'jelly'"]),
    (["bench", "sensors", "--design", "jelly"], ["--design 'jelly'", "pocket2-pu"]),
    (["fe", "indent", "pocket2-sil", *FAST, "--sensor", "skin-top"],
     ["--sensor 'skin-top'", "placement 'skin-top' is unknown"]),
    (["fe", "indent", "pocket2-sil", *FAST, "--sensor", "bone:20x4"],
     ["--sensor 'bone:20x4'", "outside the part"]),
    (["fe", "indent", "pocket2-sil", *FAST, "--sensor", "pocket-floor:12x3"],
     ["outside the pocket's floor"]),
    (["fe", "indent", "solid-pu", *FAST, "--sensor", "pocket-floor"], ["has no pocket"]),
    (["fe", "indent", "pocket2-sil", *FAST, "--sensor", "bone:4"], ["PLACEMENT[:WIDTHxLENGTH]"]),
    (["fe", "indent", "pocket2-sil", *FAST, "--sensor", "bone:-2x3"], ["width_mm = -2.0"]),
    (["skin", "apply", HAND, "x.xml", "--geom", "nope=solid-pu"],
     ["geom 'nope' is not in the model"]),
    (["skin", "apply", HAND, "x.xml", "--geom", "index_tip"],
     ["--geom 'index_tip'", "GEOM=DESIGN"]),
    (["skin", "apply", HAND, "x.xml", "--geom",
      "index_tip=solid-pu", "--max-force", "50"], ["'--max-force'", "0.5 <= x <= 20 N"]),
    (["skin", "apply", "no_such_hand.xml", "x.xml", "--geom", "index_tip=solid-pu"],
     ["HAND 'no_such_hand.xml'"]),
    (["skin", "apply", HAND, "x.xml", "--geom", "index_tip=solid-pu", "--keyframe", "grip"],
     ["--keyframe 'grip'", "has no keyframe"]),
    (["skin", "apply", SCENE, "x.xml", "--geom", "pro_skin_Palm=solid-pu", "--keyframe", "grip"],
     ["--keyframe 'grip'", "the keyframes 'grasp'"]),
    (["skin", "flex-press", "--region", "Palm1"], ["--region 'Palm1'", "Index3"]),
    (["skin", "flex-press", "--design", "rubber"], ["--design 'rubber'", "pocket2-sil"]),
    (["skin", "flex-press", "--speed", "0"], ["'--speed'", "0.01 <= x <= 100 mm/s"]),
    (["skin", "flex-press", "--max-force", "25"], ["'--max-force'", "0.01 <= x <= 20 N"]),
])
def test_unknown_names(args, needles):
    rejected(args, *needles)


def _fe_copy(tmp_path: Path, design: str) -> Path:
    fe = tmp_path / "fe"
    fe.mkdir()
    shutil.copy(FE_DIR / f"{design}.csv", fe / f"{design}.csv")
    return fe


def test_truncated_fe_curve_names_the_file_and_line(tmp_path):
    fe = _fe_copy(tmp_path, "solid-pu")
    text = (fe / "solid-pu.csv").read_text()
    (fe / "solid-pu.csv").write_text(text[: len(text) // 2].rsplit(",", 1)[0])
    rejected(["calibrate", "solid-pu", "--fe-dir", str(fe), "--out", str(tmp_path / "out")],
             "--fe-dir", "solid-pu.csv", "line")
    assert not (tmp_path / "out").exists()


def test_fe_curve_with_a_word_for_a_number_names_the_file(tmp_path):
    fe = _fe_copy(tmp_path, "solid-pu")
    lines = (fe / "solid-pu.csv").read_text().splitlines()
    cells = lines[5].split(",")
    lines[5] = ",".join([cells[0], "abc", *cells[2:]])
    (fe / "solid-pu.csv").write_text("\n".join(lines) + "\n")
    rejected(["calibrate", "solid-pu", "--fe-dir", str(fe), "--out", str(tmp_path / "out")],
             "solid-pu.csv", "line 6", "'abc'")


def test_missing_fe_curve_names_the_folder(tmp_path):
    rejected(["calibrate", "solid-pu", "--fe-dir", str(tmp_path), "--out", str(tmp_path / "o")],
             "--fe-dir", "solid-pu.csv", "softhand fe sweep")


def test_fe_curve_cut_at_a_row_boundary_is_caught_by_its_recorded_hash(tmp_path):
    """A curve cut after a whole row still parses; the sweep's recorded sha256 catches it."""
    fe = _fe_copy(tmp_path, "solid-pu")
    shutil.copy(FE_DIR / "summary.json", fe / "summary.json")
    lines = (fe / "solid-pu.csv").read_text().splitlines(keepends=True)
    (fe / "solid-pu.csv").write_text("".join(lines[: len(lines) // 2]))
    rejected(["calibrate", "solid-pu", "--fe-dir", str(fe), "--out", str(tmp_path / "out")],
             "--fe-dir", "solid-pu.csv", "sha256", "changed or truncated")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("args, needles", [
    (["fe", "indent", "solid-pu", "--indenter", "cone:3"],
     ["'--indenter'", "'cone:3'", "cylinder:R_MM[@ANGLE_DEG]", "[1, 1000] mm"]),
    (["fe", "indent", "solid-pu", "--indenter", "sphere:0"], ["'sphere:0'", "[1, 1000] mm"]),
    (["fe", "indent", "solid-pu", "--indenter", "cylinder:0.000001@90"], ["[1, 1000] mm"]),
    (["fe", "sweep", "--indenter", "cylinder:2000"], ["'cylinder:2000'", "[1, 1000] mm"]),
    (["fe", "indent", "solid-pu", "--indenter", "cylinder:5@120"], ["'cylinder:5@120'", "[0, 90]"]),
    (["fe", "indent", "solid-pu", "--hold", "0", "--indenter", "cylinder:5@45", "--sensor", "bone"],
     ["--sensor with --indenter 'cylinder:5@45'", "quarter model only"]),
    (["fe", "export", "solid-pu", "x.inp", "--indenter", "cylinder:5@45"],
     ["--indenter 'cylinder:5@45'", "allowed angles 0 and 90", "full model"]),
    (["fe", "indent", "solid-pu", "--mode", "2d", "--indenter", "sphere:5"],
     ["--indenter 'sphere:5' with --mode 2d", "plane-strain", "cylinder:R@0"]),
    (["fe", "export", "solid-pu", "x.inp", "--indenter", "sphere:5@90"],
     ["'--indenter'", "takes no angle"]),
])
def test_indenters(args, needles):
    rejected(args, *needles)


def test_a_solver_that_is_not_installed_is_refused_naming_the_flag(monkeypatch):
    import softhand.fem.linear

    monkeypatch.setattr(softhand.fem.linear, "pardiso_available", lambda: False)
    for command in (["fe", "indent", "solid-pu"], ["fe", "sweep", "--design", "solid-pu"]):
        rejected([*command, *FAST, "--solver", "pardiso"], "--solver pardiso",
                 "MKL PARDISO is not installed", "softhand[mkl]", "allowed here: auto, cholmod")


@pytest.mark.parametrize("args", [["handshake", "--record", "{long}.rrd"],
                                  ["fe", "export", "pocket2-sil", "{long}.inp"]])
def test_a_file_name_too_long_for_the_disk_is_one_line_before_any_work(tmp_path, args):
    """A 300-byte file name (longer than the file system takes, with the temporary name the file
    is written through) is refused with the flag, the length and the limit: no OSError."""
    long = str(tmp_path / ("a" * 300))
    line = rejected([a.format(long=long) for a in args], "the file name is 304 bytes long",
                    "allowed at most 241")
    assert not any(tmp_path.iterdir()), line


def test_fe_indent_sensor_on_the_palm_is_one_line():
    """Embedded sensors are read on the phalanx only: --sensor with --body palm is refused by
    the command line itself (it took the internal-error path)."""
    rejected(["fe", "indent", "pocket2-sil", "--body", "palm", "--sensor", "interface"],
             "--sensor with --body palm", "phalanx only")
