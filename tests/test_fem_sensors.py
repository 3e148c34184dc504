"""Embedded sensors in the FE phalanx (softhand.fem.sensors): verification against exact answers.

* a patch covering the whole base carries the plate force at equilibrium (every output time);
* a pocket-floor patch reads exactly 0 while the pocket is open, and the roof's force once closed;
* the nodal-force integration is consistent with the quadratic elements (patch test: a uniform
  traction gives exactly pressure x area, at every placement, in 2D and 3D);
* the load spreads with depth: a 4 x 4 mm patch under the indenter reads less on the bone than
  under the outer layer;
* bad input names the value.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from softhand.cli import main
from softhand.fem.contact import _face_geometry
from softhand.fem.geometry import parse_design
from softhand.fem.mesh import MESH_LEVELS, build_mesh
from softhand.fem.sensors import SensorPatch, SensorReader
from softhand.fem.solver import IndentationSettings, indent

FULL_BASE = SensorPatch("bone", width_mm=16.0, length_mm=10.0, name="base")


def _run(design: str, mode: str = "2d", **kw):
    patches = (FULL_BASE, SensorPatch("bone"), SensorPatch("interface"))
    if parse_design(design).geometry().has_pocket:
        patches += (SensorPatch("pocket-floor"),)
    return indent(design, IndentationSettings(mode=mode, hold_s=kw.pop("hold_s", 1.0),
                                              sensors=patches, **kw))


@pytest.fixture(scope="module")
def pocket_run():
    return _run("pocket2-sil")


@pytest.mark.parametrize("design", ["solid-pu", "pocket2-sil", "solid-sil-pu"])
def test_full_base_patch_carries_the_plate_force_at_equilibrium(design, pocket_run):
    """Within 0.5 % of the plate force at the end of the ramp (measured 0.00 %: both are the
    same equilibrium, to the Newton tolerance) and at every output time, ramp and hold."""
    r = pocket_run if design == "pocket2-sil" else _run(design)
    base = r.embedded_sensors["base"]["force_N"]
    end = np.flatnonzero(~r.hold)[-1]
    assert base[end] == pytest.approx(r.force_N[end], rel=5e-3)
    assert np.allclose(base, r.force_N, rtol=5e-3, atol=1e-3)
    assert r.embedded_sensors["base"]["area_mm2"] == pytest.approx(16.0 * 10.0)


def test_pocket_floor_reads_zero_while_the_pocket_is_open(pocket_run):
    r = pocket_run
    floor = r.embedded_sensors["pocket-floor"]["force_N"]
    closed = np.array([0] + [s["pocket_points"] for s in r.log]) > 0
    assert closed.any() and not closed.all()
    assert np.all(floor[~closed] == 0.0)  # exactly: no closed contact point, no force
    first = int(np.argmax(closed))
    assert np.all(floor[first + 1:] > 0.0)
    # once closed, the floor carries part of the load (measured 25 % at 2 N in 2D)
    end = np.flatnonzero(~r.hold)[-1]
    assert 0.1 < floor[end] / r.force_N[end] < 0.5


@pytest.mark.parametrize("mode", ["2d", "3d"])
@pytest.mark.parametrize("placement", ["bone", "interface"])
def test_uniform_traction_gives_pressure_times_area_exactly(mode, placement):
    """Patch test: nodal forces of a uniform traction p on the placement's surface (the
    consistent ones, p times the integral of each shape function) read p x the patch's area, to
    rounding, for a centred and an off-centre patch."""
    geom = parse_design("pocket2-sil").geometry()
    mesh = build_mesh(geom, MESH_LEVELS["coarse"], dim=2 if mode == "2d" else 3)
    patches = (SensorPatch(placement, name="centre"),
               SensorPatch(placement, width_mm=3.0, center_x_mm=2.0, name="off"))
    reader = SensorReader(mesh, geom, patches, 4, 200.0)
    faces = reader._surfaces()[0 if placement == "bone" else 1]
    N, _, _, w = _face_geometry(mesh, faces, 4)
    p = 0.37  # N/mm^2
    f = np.zeros(mesh.n_dofs)
    np.add.at(f, faces.ravel() * mesh.dim + 1, p * np.einsum("qa,fq->fa", N, w).ravel())
    out = reader.read(f, f, None)
    for name in ("centre", "off"):
        assert out[name] == pytest.approx(p * reader.area_mm2[name], rel=1e-12)


def test_the_load_spreads_with_depth(pocket_run):
    """Under the indenter a 4 x 4 mm patch reads less on the bone (9 mm deep) than under the
    outer layer (0.8 mm deep): the skin spreads the load (measured 0.20 against 0.50 N at 2 N)."""
    r = pocket_run
    end = np.flatnonzero(~r.hold)[-1]
    bone = r.embedded_sensors["bone"]["force_N"][end]
    under = r.embedded_sensors["interface"]["force_N"][end]
    assert 0.0 < bone < under < r.force_N[end]


@pytest.mark.parametrize("patch, geometry, needle", [
    (dict(placement="skin-top"), "solid-pu", "placement 'skin-top' is unknown; allowed: bone"),
    (dict(placement="bone", width_mm=20.0), "solid-pu", "10 mm is outside the part"),
    (dict(placement="interface", width_mm=15.0), "solid-pu", "outside the part"),
    (dict(placement="bone", length_mm=4.0, center_z_mm=4.0), "solid-pu", "along it"),
    (dict(placement="pocket-floor"), "solid-pu", "the design has no pocket"),
    (dict(placement="pocket-floor", width_mm=12.0), "pocket2-sil", "outside the pocket's floor"),
    (dict(placement="bone", width_mm=-1.0), "solid-pu", "width_mm = -1.0"),
])
def test_bad_patches_name_the_value(patch, geometry, needle):
    with pytest.raises(ValueError, match=needle.replace("(", r"\(")):
        indent(geometry, IndentationSettings(mode="2d", hold_s=0.0,
                                             sensors=(SensorPatch(**patch),)))


def test_duplicate_names_are_refused():
    with pytest.raises(ValueError, match="not unique"):
        indent("solid-pu", IndentationSettings(mode="2d", hold_s=0.0, sensors=(
            SensorPatch("bone"), SensorPatch("bone", width_mm=2.0))))


@pytest.mark.slow
def test_cli_json_has_the_embedded_sensors_aligned_with_time():
    res = CliRunner().invoke(main, ["fe", "indent", "pocket2-pu", "--mode", "2d", "--hold", "0.5",
                                    "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    sensors = out["embedded_sensors"]
    assert set(sensors) == {"bone", "interface", "pocket-floor"}
    for v in sensors.values():
        assert len(v["force_N"]) == len(out["time_s"]) and v["area_mm2"] > 0
    res = CliRunner().invoke(main, ["fe", "indent", "pocket2-pu", "--mode", "2d", "--hold", "0",
                                    "--sensor", "pocket-floor:3x3", "--sensor", "bone", "--json"])
    assert res.exit_code == 0, res.output
    sensors = json.loads(res.output)["embedded_sensors"]
    assert set(sensors) == {"pocket-floor:3x3", "bone"}
    assert sensors["pocket-floor:3x3"]["area_mm2"] < 16.0


def test_design_table_row_has_the_pocket_dead_band_and_the_relaxation():
    """softhand bench sensors' row for one design (2D here): the floor's dead band brackets the
    plate force at which the pocket closed; every reading relaxes in the hold, the bone's more
    than the plate force (the load moves outward as the PU relaxes: 2D 32 % against 14 % over
    2 s; 3D 31 % against 20 % over 10 s)."""
    from softhand.bench.sensors import sensor_row

    row = sensor_row("pocket2-pu", IndentationSettings(mode="2d", hold_s=2.0))
    floor = row["sensors"]["pocket-floor"]
    lo, hi = floor["dead_band_N"]
    assert 0.0 <= lo < hi < row["plate_N"]
    assert all(s["relaxation_pct"] > 0.0 for s in row["sensors"].values())
    assert row["sensors"]["bone"]["relaxation_pct"] > row["plate_relaxation_pct"] > 0.0
