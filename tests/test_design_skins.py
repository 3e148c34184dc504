"""A searched design's calibrated skin (issue 38, item 5): `softhand design calibrate` and the
handshake and population run by the file's path.

The shipped winners' files (calibration/designs) record the design (its variables as the
search's report lists them, its library materials, the search's seed and trial, the command)
and the force range their FE reached; the pair law is calibrated to that range, not beyond.
Their laws come out of `softhand.skin.calibrate.calibrate_design` on the FE folders beside them
(the shipped designs' path), which a test repeats. ``--design PATH`` takes such a file; a bad
path or a malformed file is one line naming the flag and the value, before any work.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from softhand.cli import main
from softhand.design.search import candidate_of
from softhand.design.skins import (
    FE_SETTINGS,
    calibrate_candidate,
    fe_folders_match,
    skin_name,
)
from softhand.paths import CALIBRATION_DIR, REPORTS_DIR, SKINS_DIR
from softhand.skin.calibrate import SkinCalibration
from softhand.skin.files import skin_file_folder

DESIGNS = CALIBRATION_DIR / "designs"
REPORT = json.loads((REPORTS_DIR / "design-search.json").read_text())
WINNERS = REPORT["winners"]


def _file(w: dict) -> Path:
    return DESIGNS / f"{skin_name(w['trial'])}.json"


@pytest.mark.parametrize("rank", range(1, len(WINNERS) + 1))
def test_shipped_winner_records_its_design_and_range(rank):
    w = WINNERS[rank - 1]
    data = json.loads(_file(w).read_text())
    cal = SkinCalibration.from_dict(data, source=str(_file(w)), require=("soft-contact",))
    info = cal.provenance["design"]
    assert info["variables"] == w["candidate"]
    assert info["materials"]["inner"]["name"] == w["candidate"]["inner"]
    assert info["materials"]["outer"]["name"] == w["candidate"]["outer"]
    assert info["search"]["trial"] == w["trial"] and info["search"]["seed"] == REPORT["seed"]
    assert info["command"].startswith("softhand design calibrate")
    assert fe_folders_match(candidate_of(w), DESIGNS / "fe" / cal.design)
    # the law's range is the FE's reach; the pair law is calibrated to no more than it
    top = info["calibrated_max_N"]
    assert 0.0 < top <= FE_SETTINGS.max_force_N * 1.01
    assert cal.pair_law.calibrated_max_N <= top + 1e-9
    if top < 0.99 * FE_SETTINGS.max_force_N:
        assert "stops short of 20 N" in info["range_note"]
    assert set(cal.representations) >= {"rigid", "soft-contact", "soft-contact+relaxation"}


@pytest.mark.slow
def test_winner_calibration_is_the_shipped_path():
    """Calibrating winner 1 again from its shipped FE folders gives the shipped file's law and
    soft contact (the file is calibrate_design's output, not a copy of another skin's)."""
    w = WINNERS[0]
    shipped = json.loads(_file(w).read_text())
    cal = calibrate_candidate(candidate_of(w), skin_name(w["trial"]),
                              DESIGNS / "fe" / skin_name(w["trial"]))
    again = cal.to_dict()
    assert again["law"]["elastic"] == shipped["law"]["elastic"]
    a = again["representations"]["soft-contact"]["params"]
    b = shipped["representations"]["soft-contact"]["params"]
    for k in b:
        np.testing.assert_allclose(np.asarray(a[k], float), np.asarray(b[k], float), rtol=1e-6)


def test_skin_file_folder_holds_the_file_beside_the_shipped_skins(tmp_path, monkeypatch):
    monkeypatch.setenv("SOFTHAND_CACHE_DIR", str(tmp_path / "cache"))
    name, folder = skin_file_folder(_file(WINNERS[0]))
    assert name == skin_name(WINNERS[0]["trial"])
    assert (folder / f"{name}.json").read_bytes() == _file(WINNERS[0]).read_bytes()
    assert (folder / "human-middle-phalanx.json").is_file()  # the partner's tissue
    # a shipped skin's own file is its folder; a file that shadows a shipped skin is refused
    assert skin_file_folder(SKINS_DIR / "pocket2-sil.json") == ("pocket2-sil", SKINS_DIR)
    data = json.loads((SKINS_DIR / "pocket2-sil.json").read_text())
    data["provenance"]["note"] = "edited"
    (tmp_path / "p.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match="other contents"):
        skin_file_folder(tmp_path / "p.json")


@pytest.mark.parametrize("command", [["handshake"], ["population", "--n", "1"]])
@pytest.mark.parametrize("bad,why", [("missing/skin.json", "no such file"),
                                     ("{}", "format_version"), ("[1]", "not a calibration"),
                                     ("nojson", "not a readable")])
def test_design_path_bad_is_one_line(tmp_path, command, bad, why):
    path = tmp_path / "missing" / "skin.json" if bad == "missing/skin.json" else tmp_path / "s.json"
    if bad != "missing/skin.json":
        path.write_text(bad)
    r = CliRunner().invoke(main, [*command, "--design", str(path), *(
        ["--out", str(tmp_path / "pop")] if command[0] == "population" else [])])
    assert r.exit_code == 2, r.output
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: --design {str(path)!r}"), r.output
    assert why in lines[0]
    assert not (tmp_path / "pop").exists()


@pytest.mark.slow
def test_handshake_with_a_winner_file_runs_and_names_it(tmp_path, monkeypatch):
    monkeypatch.setenv("SOFTHAND_CACHE_DIR", str(tmp_path / "cache"))
    path = _file(WINNERS[0])
    r = CliRunner().invoke(main, ["handshake", "--design", str(path), "--json"])
    assert r.exit_code == 0, r.output
    out, _ = json.JSONDecoder().raw_decode(r.output[r.output.index("{"):])  # warnings after
    assert out["settings"]["design_file"] == str(path)
    assert out["settings"]["design"] == skin_name(WINNERS[0]["trial"])
    assert set(out["skins"].values()) == {skin_name(WINNERS[0]["trial"])}  # every region
    assert max(v["peak_N"] for v in out["regions"].values()) > 0.0
