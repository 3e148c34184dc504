"""Tests of the CalculiX deck (softhand.fem.calculix via write_deck(fmt="ccx")), coarse meshes.

The structural tests need no CalculiX; the run test needs ``ccx`` (CalculiX 2.20) on PATH.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from dataclasses import replace

import numpy as np
import pytest
from test_abaqus import Block, find, mesh_of, one, parse

from softhand.fem.abaqus import C3D20_NATURAL, corner_volumes, inp_text, write_deck
from softhand.fem.calculix import CCX_STEP_MM, read_ccx_dat
from softhand.fem.geometry import parse_design
from softhand.fem.solver import IndentationSettings, indent
from softhand.paper import paper

COARSE = IndentationSettings(mesh="coarse")
DEPTH = 1.0


def ccx_deck(design: str, settings: IndentationSettings = COARSE) -> str:
    return inp_text(design, settings, depth_mm=DEPTH, dialect="calculix")


@pytest.fixture(scope="module", params=["solid-pu", "pocket2-sil-pu"])
def deck(request) -> tuple[str, str, list[Block]]:
    text = ccx_deck(request.param)
    return request.param, text, parse(text)


def test_no_keyword_calculix_lacks(deck) -> None:
    """No ENCASTRE/XSYMM/ZSYMM, C3D20H, analytical surface, friction card, HARD, Prony."""
    _, text, blocks = deck
    for word in ("ENCASTRE", "XSYMM", "ZSYMM", "C3D20H", "CYLINDER", "ANALYTICAL", "HARD",
                 "MODULI", "OP=MOD", "*OUTPUT"):
        assert all(word not in line for line in text.splitlines() if not line.startswith("**"))
    for keyword in ("FRICTION", "VISCO", "VISCOELASTIC", "NODE OUTPUT"):
        assert not find(blocks, keyword), keyword
    assert max(len(line) for line in text.splitlines()) <= 132  # CalculiX's line length


def test_skin_elements_and_boundary(deck) -> None:
    name, _, blocks = deck
    mesh = mesh_of(name)
    X = np.array([[float(v) for v in r[1:]] for r in one(blocks, "NODE", NSET="SKIN_NODES").data])
    np.testing.assert_allclose(X, mesh.X, atol=1e-10)
    skin = one(blocks, "ELEMENT", ELSET="SKIN")
    assert skin.params["TYPE"] == "C3D20"
    conn = [r[1:] for r in skin.data]
    assert len(conn) == mesh.n_elements and all(len(r) == 20 for r in conn)
    bc = find(blocks, "BOUNDARY")[0].data
    assert bc == [["BASE", "1", "3"], ["XSYM", "1", "1"], ["ZSYM", "3", "3"],
                  ["PLATE_RP", "1", "1"], ["PLATE_RP", "3", "3"], ["PLATE_ROT", "1", "3"]]
    assert any(len(set(row)) < 20 for row in conn)  # collapsed bricks kept (ccx accepts them)


def test_plate_is_a_rigid_grid_of_bricks_facing_the_skin(deck) -> None:
    name, _, blocks = deck
    geom = parse_design(name).geometry()
    nodes = {int(r[0]): [float(v) for v in r[1:]] for b in find(blocks, "NODE") for r in b.data}
    el = one(blocks, "ELEMENT", ELSET="PLATE")
    assert el.params["TYPE"] == "C3D8"
    conn = np.array([[int(v) for v in r[1:]] for r in el.data])
    P = np.array([[nodes[n] for n in row] for row in conn])
    assert (corner_volumes(P) > 0).all()
    assert np.all(P[:, :4, 1] == geom.height_mm) and np.all(P[:, 4:, 1] > geom.height_mm)
    assert P[..., 0].min() < 0 and P[..., 0].max() > geom.width_mm / 2
    assert P[..., 2].min() < 0 and P[..., 2].max() > geom.length_mm / 2
    plate = one(blocks, "SURFACE", NAME="PLATE")
    assert plate.data == [[r[0], "S1"] for r in el.data]  # S1 = nodes 1-4 = y = height
    assert np.allclose(np.array(C3D20_NATURAL[:4])[:, 2], -1)
    rp = int(one(blocks, "NODE", NSET="PLATE_RP").data[0][0])
    rot = int(one(blocks, "NODE", NSET="PLATE_ROT").data[0][0])
    assert nodes[rp] == [0.0, geom.height_mm, 0.0]
    rigid = one(blocks, "RIGID BODY")
    assert rigid.params == {"NSET": "PLATE_NODES", "REF NODE": str(rp), "ROT NODE": str(rot)}
    plate_nodes = [int(r[0]) for r in one(blocks, "NODE", NSET="PLATE_NODES").data]
    assert sorted(plate_nodes) == sorted(set(conn.ravel().tolist()))


def test_contact_is_linear_penalty_face_to_face(deck) -> None:
    name, _, blocks = deck
    pairs = find(blocks, "CONTACT PAIR")
    assert all(p.params == {"INTERACTION": "PENALTY", "TYPE": "SURFACE TO SURFACE"}
               for p in pairs)
    expected = [[["SKIN", "PLATE"]]] + ([[["ROOF", "FLOOR"]]] if "pocket" in name else [])
    assert [p.data for p in pairs] == expected
    behavior = one(blocks, "SURFACE BEHAVIOR")
    assert behavior.params == {"PRESSURE-OVERCLOSURE": "LINEAR"}
    assert float(behavior.data[0][0]) == COARSE.penalty_N_mm3
    stiff = parse(ccx_deck(name, replace(COARSE, penalty_N_mm3=750.0)))
    assert one(stiff, "SURFACE BEHAVIOR").data == [["750."]]


def test_one_static_step_driven_by_the_reference_node(deck) -> None:
    _, _, blocks = deck
    assert len(find(blocks, "STEP")) == 1 and one(blocks, "STEP").params["NLGEOM"] is None
    static = one(blocks, "STATIC").data[0]
    dt0, period, _, dt_max = (float(v) for v in static)
    assert period == pytest.approx(DEPTH / COARSE.speed_mm_s)
    assert dt0 == dt_max <= CCX_STEP_MM / COARSE.speed_mm_s * (1 + 1e-12)
    assert find(blocks, "BOUNDARY")[1].data == [["PLATE_RP", "2", "2", "-1."]]
    assert one(blocks, "NODE PRINT", NSET="PLATE_RP").data == [["U", "RF"]]
    controls = one(blocks, "CONTROLS", PARAMETERS="FIELD")
    r_n, q_u = float(controls.data[0][0]), float(controls.data[0][3])
    assert r_n * q_u * 4 == pytest.approx(COARSE.tol_N)  # softhand's tolerance, whole phalanx


def test_always_elastic_and_says_so() -> None:
    """Viscous settings still give the hyperfoam-only elastic deck, with the reason in the header."""
    s = IndentationSettings(mesh="coarse", hold_s=10.0, moduli="instantaneous",
                            materials={"pu": {"mu_MPa": [0.3, 0.05]}})
    text = ccx_deck("pocket2-sil-pu", s)
    head = text.split("*NODE")[0]
    assert "CalculiX has no Prony viscoelasticity for hyperfoam" in head
    assert "elastic_only=True" in head and "elastic_only: True" in head
    assert "** plate travel 1 mm: given" in head
    blocks = parse(text)
    hyper = {b.params["NAME"]: blocks[blocks.index(b) + 1] for b in find(blocks, "MATERIAL")}
    assert all(h.keyword == "HYPERFOAM" and "MODULI" not in h.params for h in
               (hyper["SIL"], hyper["PU"]))
    sil = paper()["materials"]["sil"]
    assert [float(v) for v in hyper["PU"].data[0]] == [0.3, 5.5, 0.05, 8.25, 0.47, 0.47]
    # sil's alpha_1 = 0.001 is raised to 0.03 (CalculiX diverges with it), and the header says so
    assert [float(v) for v in hyper["SIL"].data[0]] == [sil["mu_MPa"][0], 0.03, sil["mu_MPa"][1],
                                                        sil["alpha"][1], 0.49, 0.49]
    assert "sil: |alpha_i| < 0.03 written as 0.03" in head
    assert "written as" not in ccx_deck("solid-pu").split("*NODE")[0]


DAT = """
 displacements (vx,vy,vz) for set PLATE_RP and time  0.2000000E-01

       426  0.000000E+00 -1.000000E-02  0.000000E+00

 forces (fx,fy,fz) for set PLATE_RP and time  0.2000000E-01

       426  1.0E-19 -2.500000E-03  3.0E-29

 displacements (vx,vy,vz) for set OTHER and time  0.4000000E-01

       1  0.000000E+00 -9.000000E+00  0.000000E+00

 displacements (vx,vy,vz) for set PLATE_RP and time  0.4000000E-01

       426  0.000000E+00 -2.000000E-02  0.000000E+00

 forces (fx,fy,fz) for set PLATE_RP and time  0.4000000E-01

       426  1.0E-19 -6.000000E-03  3.0E-29
"""


def test_read_ccx_dat(tmp_path) -> None:
    path = tmp_path / "job.dat"
    path.write_text(DAT)
    d, f = read_ccx_dat(path)
    np.testing.assert_allclose(d, [0.0, 0.01, 0.02])
    np.testing.assert_allclose(f, [0.0, 0.01, 0.024])
    path.write_text("nothing\n")
    with pytest.raises(ValueError, match="no U and RF of node set 'PLATE_RP'"):
        read_ccx_dat(path)


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")
def test_ccx_run_matches_softhands_elastic_run(tmp_path) -> None:
    """Coarse solid-pu to softhand's d(2 N): CalculiX's force within 2 % at 0.25 and 0.5 mm.

    Measured (CalculiX 2.20, 0.01 mm increments): +0.67 % and -0.69 %; ccx 28 s on one core.
    """
    info = write_deck("solid-pu", tmp_path / "job.inp", COARSE, fmt="ccx")
    assert info.depth_source == "softhand" and 0.5 < info.depth_mm < 1.0
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    t0 = time.perf_counter()
    run = subprocess.run(["ccx", "-i", "job"], cwd=tmp_path, env=env, capture_output=True,
                         text=True, timeout=600, check=False)
    wall = time.perf_counter() - t0
    assert run.returncode == 0 and "Job finished" in run.stdout, run.stdout[-2000:]
    d, f = read_ccx_dat(tmp_path / "job.dat")
    assert d[-1] == pytest.approx(info.depth_mm, rel=1e-6)
    ref = indent("solid-pu", IndentationSettings(mesh="coarse", elastic_only=True,
                                                 max_step_mm=0.025))
    for x in (0.25, 0.5):
        ccx_f, soft_f = float(np.interp(x, d, f)), ref.force_at(x)
        print(f"F({x} mm): ccx {ccx_f:.4f} N, softhand {soft_f:.4f} N, "
              f"{100 * (ccx_f / soft_f - 1):+.2f} %; ccx wall {wall:.1f} s")
        assert ccx_f == pytest.approx(soft_f, rel=0.02)
    assert f[-1] == pytest.approx(2.0, rel=0.02)


def run_ccx(folder, timeout: float = 1200.0) -> tuple[np.ndarray, np.ndarray]:
    """Run CalculiX on ``folder/job.inp`` (one thread) and read the plate's travel and force."""
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    run = subprocess.run(["ccx", "-i", "job"], cwd=folder, env=env, capture_output=True,
                         text=True, timeout=timeout, check=False)
    assert run.returncode == 0 and "Job finished" in run.stdout, run.stdout[-2000:]
    return read_ccx_dat(folder / "job.dat")


@pytest.mark.parametrize("indenter", ["sphere:7.4", "cylinder:7.4@90", "cylinder:10.7@0",
                                      "cylinder:1000@90"])
def test_round_indenter_is_a_rigid_curved_grid_of_bricks_on_its_surface(indenter) -> None:
    """Right-handed bricks; the faces meeting the skin (S1, nodes 1-4) lie on the cylinder or
    sphere of radius R that touches the top (y = 9) at travel 0, the far faces inside it; the
    grid covers the top centre; arcs cut in faces of at most ROUND_ELEMENT_MM (a sphere's cube
    map: up to 5 % more off its central lines; the generators of a
    cylinder: 3 mm, as the plate's grid)."""
    from softhand.fem.calculix import ROUND_ELEMENT_MM
    from softhand.fem.indenter import parse_indenter

    ind = parse_indenter(indenter)
    blocks = parse(inp_text("solid-pu", replace(COARSE, indenter=indenter), depth_mm=DEPTH,
                            dialect="calculix"))
    nodes = {int(r[0]): [float(v) for v in r[1:]] for b in find(blocks, "NODE") for r in b.data}
    el = one(blocks, "ELEMENT", ELSET="PLATE")
    conn = np.array([[int(v) for v in r[1:]] for r in el.data])
    P = np.array([[nodes[n] for n in row] for row in conn])
    assert (corner_volumes(P) > 0).all()
    R, height = ind.radius_mm, parse_design("solid-pu").geometry().height_mm
    centre = np.array([0.0, height + R, 0.0])

    def distance(Q):
        r = Q - centre
        if ind.axis is not None:
            r = r - (r @ ind.axis)[..., None] * ind.axis
        return np.linalg.norm(r, axis=-1)

    np.testing.assert_allclose(distance(P[:, :4]), R, rtol=1e-9)
    assert np.all(distance(P[:, 4:]) < R - 0.4)
    low = P[:, :4]
    assert low[..., 0].min() < 0 < low[..., 0].max() and low[..., 2].min() < 0 < low[..., 2].max()
    assert low[..., 1].min() == pytest.approx(height, abs=1e-3)
    edge = np.linalg.norm(np.diff(low[:, [0, 1, 2, 3, 0]], axis=1), axis=-1)
    assert edge.max() <= max(ROUND_ELEMENT_MM * 1.05, 3.01 if ind.angle_deg is not None else 0)
    surf = one(blocks, "SURFACE", NAME="INDENTER")
    assert surf.data == [[r[0], "S1"] for r in el.data]
    assert find(blocks, "CONTACT PAIR")[0].data == [["SKIN", "INDENTER"]]
    assert not find(blocks, "SURFACE", NAME="PLATE")


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")
def test_ccx_run_with_a_cylinder_matches_softhand(tmp_path) -> None:
    """Coarse solid-pu, cylinder R = 7.4 mm across the phalanx, 0.5 mm: CalculiX's force within
    2 % of softhand's elastic run at 0.25 and 0.5 mm.

    Measured (CalculiX 2.20): +0.31 % and +0.05 %; ccx 57 s on one core.
    """
    s = replace(COARSE, indenter="cylinder:7.4@90")
    write_deck("solid-pu", tmp_path / "job.inp", s, fmt="ccx", depth_mm=0.5)
    d, f = run_ccx(tmp_path)
    ref = indent("solid-pu", replace(s, elastic_only=True, max_step_mm=0.025, max_depth_mm=0.5,
                                     max_force_N=50.0))
    for x in (0.25, 0.5):
        assert float(np.interp(x, d, f)) == pytest.approx(ref.force_at(x), rel=0.02)


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")
def test_ccx_closing_pocket_is_nearer_the_sliding_contact(tmp_path) -> None:
    """Coarse pocket2-sil to 2.4 mm, past the pocket's closing (about 2 mm): CalculiX's
    face-to-face roof/floor contact slides, as `pocket_contact="sliding"` does. After the
    closing (2.2 and 2.4 mm) the sliding contact is nearer CalculiX than the paired one, and
    within 3 % of it.

    Measured (CalculiX 2.20, 0.01 mm increments, 110 s on one core): at 2.2 / 2.4 mm paired
    -6.0 / -4.6 %, sliding -2.1 / -2.0 %; at 1 mm (open pocket) both -3.3 %
    (reports/pocket-contact.md).
    """
    write_deck("pocket2-sil", tmp_path / "job.inp", COARSE, fmt="ccx", depth_mm=2.4)
    d, f = run_ccx(tmp_path)
    runs = {kind: indent("pocket2-sil", replace(COARSE, elastic_only=True, max_step_mm=0.025,
                                                max_depth_mm=2.4, max_force_N=50.0,
                                                pocket_contact=kind))
            for kind in ("paired", "sliding")}
    for x in (2.2, 2.4):
        ccx_f = float(np.interp(x, d, f))
        paired, sliding = runs["paired"].force_at(x), runs["sliding"].force_at(x)
        print(f"F({x} mm): ccx {ccx_f:.4f}, paired {paired:.4f}, sliding {sliding:.4f} N")
        assert abs(sliding - ccx_f) < abs(paired - ccx_f)
        assert sliding == pytest.approx(ccx_f, rel=0.03)
