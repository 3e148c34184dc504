"""Tests of the Abaqus input-deck exporter (softhand.fem.abaqus), on coarse meshes."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import pytest

import softhand
import softhand.fem.abaqus as abaqus
from softhand.fem.abaqus import (
    C3D20_FACES,
    C3D20_NATURAL,
    DeckInfo,
    c3d20_connectivity,
    corner_volumes,
    face_label,
    inp_text,
    write_deck,
)
from softhand.fem.geometry import parse_design
from softhand.fem.mesh import Mesh, build_mesh
from softhand.fem.solver import IndentationSettings, indent
from softhand.paper import paper

COARSE = IndentationSettings(mesh="coarse")
DEPTH = 2.0  # given plate travel: no softhand run needed


@dataclass
class Block:
    """One keyword with its parameters and data lines (fields split at commas)."""

    keyword: str
    params: dict[str, str | None]
    data: list[list[str]] = field(default_factory=list)


def parse(text: str) -> list[Block]:
    """Split a deck into keyword blocks; ``**`` lines are comments, a trailing comma continues
    an element data line onto the next line."""
    blocks: list[Block] = []
    pending: list[str] | None = None
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line.startswith("**"):
            continue
        if line.startswith("*"):
            parts = [p.strip() for p in line[1:].split(",")]
            params: dict[str, str | None] = {}
            for p in parts[1:]:
                key, _, value = p.partition("=")
                params[key.strip().upper()] = value.strip() if value else None
            blocks.append(Block(parts[0].upper(), params))
            pending = None
            continue
        fields = [f.strip() for f in line.split(",")]
        if pending is not None:
            pending.extend(fields)
        else:
            blocks[-1].data.append(fields)
            pending = blocks[-1].data[-1] if blocks[-1].keyword == "ELEMENT" else None
        if pending is not None:
            if line.endswith(","):
                pending.pop()  # the empty field after the trailing comma
            else:
                pending = None
    return blocks


def find(blocks: list[Block], keyword: str, **params: str) -> list[Block]:
    return [b for b in blocks if b.keyword == keyword
            and all(b.params.get(k.upper()) == v for k, v in params.items())]


def one(blocks: list[Block], keyword: str, **params: str) -> Block:
    found = find(blocks, keyword, **params)
    assert len(found) == 1, (keyword, params, len(found))
    return found[0]


def ids(block: Block) -> list[int]:
    return [int(v) for row in block.data for v in row if v]


def mesh_of(design: str, settings: IndentationSettings = COARSE) -> Mesh:
    return build_mesh(parse_design(design).geometry(**settings.geometry), settings.mesh_spec)


@pytest.fixture(scope="module", params=["solid-sil", "pocket1-pu", "pocket2-sil-pu"])
def deck(request) -> tuple[str, list[Block], Mesh]:
    name = request.param
    return name, parse(inp_text(name, COARSE, depth_mm=DEPTH)), mesh_of(name)


def model(blocks: list[Block]) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates by Abaqus id (row 0 unused) and element connectivity (1-based ids)."""
    nodes = one(blocks, "NODE", NSET="SKIN_NODES").data
    X = np.full((len(nodes) + 1, 3), np.nan)
    for row in nodes:
        X[int(row[0])] = [float(v) for v in row[1:4]]
    el = one(blocks, "ELEMENT")
    conn = np.array([[int(v) for v in row] for row in el.data])
    assert conn.shape[1] == 21  # id + 20 nodes
    assert (conn[:, 0] == np.arange(1, len(conn) + 1)).all()
    return X, conn[:, 1:]


def tet_volumes(P: np.ndarray) -> np.ndarray:
    """Signed volumes of the 6 tetrahedra around diagonal 1-7 of hexahedra P (n, 8, 3)."""
    tets = [(0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6), (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6)]
    out = [np.linalg.det(np.stack([P[:, b] - P[:, a], P[:, c] - P[:, a], P[:, d] - P[:, a]],
                                  axis=1)) / 6.0 for a, b, c, d in tets]
    return np.stack(out, axis=1)


def test_tet_volume_of_unit_cube() -> None:
    cube = np.array([[(n[0] + 1) / 2, (n[1] + 1) / 2, (n[2] + 1) / 2]
                     for n in C3D20_NATURAL[:8]])[None]
    np.testing.assert_allclose(tet_volumes(cube), 1.0 / 6.0)


def test_mirrored_mesh_takes_the_swapped_axis_order() -> None:
    """A left-handed element grid is renumbered (xi0 <-> xi1) and its face labels follow."""
    mesh = mesh_of("solid-sil")
    mirrored = mesh_of("solid-sil")
    mirrored.X = mirrored.X * np.array([-1.0, 1.0, 1.0])
    for m, v in ((mesh, 0), (mirrored, 1)):
        conn, variant = c3d20_connectivity(m)
        assert (variant == v).all()
        assert (corner_volumes(m.X[conn[:, :8]]) > 0).all()
        assert (tet_volumes(m.X[conn[:, :8]]).sum(axis=1) > 0).all()
        for axis in range(3):
            for side in (0, 2):
                corners = np.array(C3D20_FACES[face_label(v, axis, side)]) - 1
                on_face = m.elements[:, [a for a in range(27) if a // 3**axis % 3 == side]]
                for row, face in zip(conn, on_face, strict=True):
                    assert set(row[corners].tolist()) <= set(face.tolist()), (v, axis, side)


def test_parser_reads_element_continuations() -> None:
    blocks = parse("*ELEMENT, TYPE=C3D20H\n1, " + ", ".join(map(str, range(1, 16))) + ",\n"
                   + "16, 17, 18, 19, 20\n** c\n*NSET, NSET=A\n1, 2\n")
    assert blocks[0].data == [["1"] + [str(i) for i in range(1, 21)]]
    assert blocks[0].params == {"TYPE": "C3D20H"}
    assert ids(blocks[1]) == [1, 2]


def test_heading(deck) -> None:
    name, blocks, _ = deck
    assert blocks[0].keyword == "HEADING"
    text = inp_text(name, COARSE, depth_mm=DEPTH)
    head = text.split("*NODE")[0]
    assert "** plate travel 2 mm: given" in head
    version = getattr(softhand, "__version__", "0.1.0")
    assert name in head and f"softhand {version}" in head
    assert "mm, N, s, MPa" in head
    assert "Quarter model" in head and "symmetry" in head


def test_counts_and_element_sets(deck) -> None:
    _, blocks, mesh = deck
    X, conn = model(blocks)
    assert X.shape[0] - 1 == mesh.X.shape[0]
    np.testing.assert_allclose(X[1:], mesh.X, atol=1e-10)
    assert conn.shape == (mesh.n_elements, 20)
    assert one(blocks, "ELEMENT").params["TYPE"] == "C3D20H"
    inner, outer = ids(one(blocks, "ELSET", ELSET="INNER")), ids(one(blocks, "ELSET", ELSET="OUTER"))
    assert len(inner) == int((mesh.layer == 0).sum())
    assert len(outer) == int((mesh.layer == 1).sum())
    assert sorted(inner + outer) == list(range(1, mesh.n_elements + 1))
    assert np.all(mesh.layer[np.array(outer) - 1] == 1)


def test_corner_hexahedra_are_right_handed(deck) -> None:
    _, blocks, _ = deck
    X, conn = model(blocks)
    vols = tet_volumes(X[conn[:, :8]])
    scale = np.abs(vols).max()
    assert (vols.sum(axis=1) > 0).all()  # every brick, collapsed ones included
    assert (vols > -1e-9 * scale).all()  # no inverted corner tetrahedron either
    collapsed = [len(set(row)) < 20 for row in conn]
    assert any(collapsed)  # the base-centre wedges are kept as collapsed bricks


def test_midside_nodes_lie_on_their_edges(deck) -> None:
    """In softhand's tensor grid, C3D20 node k sits at the Q27 grid point of its natural coords."""
    _, blocks, mesh = deck
    _, conn = model(blocks)
    nat = np.array(C3D20_NATURAL)
    for e, row in enumerate(conn):
        q27 = mesh.elements[e].tolist()
        if len(set(q27)) < 27:
            continue
        p = np.array([[a % 3, a // 3 % 3, a // 9] for a in (q27.index(n - 1) for n in row)])
        # the grid positions are an affine image (axis permutation/reflection) of nat + 1
        A, *_ = np.linalg.lstsq(np.c_[nat, np.ones(20)], p, rcond=None)
        np.testing.assert_allclose(np.c_[nat, np.ones(20)] @ A, p, atol=1e-9)
        assert abs(abs(np.linalg.det(A[:3])) - 1.0) < 1e-9


def face_nodes(conn: np.ndarray, element: int, label: str) -> set[int]:
    return {int(conn[element - 1][c - 1]) - 1 for c in C3D20_FACES[label]}


def check_surface(blocks: list[Block], conn: np.ndarray, name: str, faces: np.ndarray) -> None:
    surf = one(blocks, "SURFACE", NAME=name)
    assert surf.params["TYPE"] == "ELEMENT"
    assert len(surf.data) == len(faces)
    wanted = [set(f.tolist()) for f in faces]
    for (eid, label) in surf.data:
        corners = face_nodes(conn, int(eid), label)
        assert len(corners) == 4
        assert any(corners <= w for w in wanted), (name, eid, label)


def test_surfaces_use_the_right_face_labels(deck) -> None:
    _, blocks, mesh = deck
    _, conn = model(blocks)
    check_surface(blocks, conn, "SKIN", mesh.outer_faces)
    assert {row[1] for row in one(blocks, "SURFACE", NAME="SKIN").data} == {"S4"}
    pairs = find(blocks, "CONTACT PAIR")
    assert pairs[0].data == [["SKIN", "PLATE"]]
    if mesh.floor_faces.size:
        check_surface(blocks, conn, "ROOF", mesh.roof_faces)
        check_surface(blocks, conn, "FLOOR", mesh.floor_faces)
        assert len(pairs) == 2 and pairs[1].data == [["ROOF", "FLOOR"]]
    else:
        assert len(pairs) == 1 and not find(blocks, "SURFACE", NAME="ROOF")
    for p in pairs:
        assert p.params["INTERACTION"] == "FRICTIONLESS"
    assert one(blocks, "SURFACE BEHAVIOR").params["PRESSURE-OVERCLOSURE"] == "HARD"
    assert one(blocks, "FRICTION").data == [["0."]]


def test_boundary_node_sets(deck) -> None:
    _, blocks, _ = deck
    X, conn = model(blocks)
    used = np.unique(conn)
    for name, axis in (("BASE", 1), ("XSYM", 0), ("ZSYM", 2)):
        got = np.array(ids(one(blocks, "NSET", NSET=name)))
        expected = used[np.abs(X[used, axis]) < 1e-9]
        assert sorted(got.tolist()) == sorted(expected.tolist())
    bc = find(blocks, "BOUNDARY")[0].data
    assert ["BASE", "ENCASTRE"] in bc and ["XSYM", "XSYMM"] in bc and ["ZSYM", "ZSYMM"] in bc


@pytest.mark.parametrize("moduli", ["long-term", "instantaneous"])
@pytest.mark.parametrize("design", ["solid-sil-pu", "pocket2-pu-sil"])
def test_material_data_equal_table3(moduli: str, design: str) -> None:
    blocks = parse(inp_text(design, IndentationSettings(mesh="coarse", moduli=moduli),
                            depth_mm=DEPTH))
    table = paper()["materials"]
    for name in ("sil", "pu"):
        i = blocks.index(one(blocks, "MATERIAL", NAME=name.upper()))
        hyper, visco = blocks[i + 1], blocks[i + 2]
        row = table[name]
        assert hyper.keyword == "HYPERFOAM" and hyper.params["N"] == "2"
        assert hyper.params["MODULI"] == ("LONG TERM" if moduli == "long-term" else "INSTANTANEOUS")
        values = [float(v) for v in hyper.data[0]]
        expected = [row["mu_MPa"][0], row["alpha"][0], row["mu_MPa"][1], row["alpha"][1],
                    row["nu"], row["nu"]]
        assert values == pytest.approx(expected, rel=1e-12)
        assert visco.keyword == "VISCOELASTIC" and visco.params["TIME"] == "PRONY"
        prony = np.array([[float(v) for v in r] for r in visco.data])
        expected_prony = [[g, g, t] for g, t in zip(row["g"], row["tau_s"], strict=True)]
        np.testing.assert_allclose(prony, expected_prony, rtol=1e-12)
    sections = {b.params["ELSET"]: b.params["MATERIAL"] for b in find(blocks, "SOLID SECTION")}
    d = parse_design(design)
    assert sections == {"INNER": d.inner.upper(), "OUTER": d.outer.upper()}


def test_homogeneous_design_writes_one_material() -> None:
    blocks = parse(inp_text("pocket1-sil", COARSE, depth_mm=DEPTH))
    assert [b.params["NAME"] for b in find(blocks, "MATERIAL")] == ["SIL"]


def test_steps_viscous() -> None:
    s = IndentationSettings(mesh="coarse", speed_mm_s=0.25, hold_s=4.0)
    blocks = parse(inp_text("pocket2-sil", s, depth_mm=2.5))
    steps = find(blocks, "STEP")
    assert [b.params["NAME"] for b in steps] == ["RAMP", "HOLD"]
    assert all(b.params["NLGEOM"] == "YES" for b in steps)
    visco = find(blocks, "VISCO")
    assert [float(b.data[0][1]) for b in visco] == pytest.approx([2.5 / 0.25, 4.0])
    plate_bc = [r for b in find(blocks, "BOUNDARY") for r in b.data if r[:3] == ["PLATE_RP",
                                                                                   "2", "2"]]
    assert [float(r[3]) for r in plate_bc] == [-2.5, -2.5]
    outputs = find(blocks, "NODE OUTPUT", NSET="PLATE_RP")
    assert len(outputs) == 2 and all(o.data == [["RF2", "U2"]] for o in outputs)
    rigid = one(blocks, "RIGID BODY")
    assert rigid.params == {"ANALYTICAL SURFACE": "PLATE", "REF NODE": "PLATE_RP"}
    rp = one(blocks, "NODE", NSET="PLATE_RP").data[0]
    height = parse_design("pocket2-sil").geometry().height_mm
    assert [float(v) for v in rp[1:]] == [0.0, height, 0.0]
    plate = one(blocks, "SURFACE", NAME="PLATE")
    assert plate.params["TYPE"] == "CYLINDER"
    assert all(float(v) == height for v in (plate.data[0][1], plate.data[0][4], plate.data[1][1]))
    xs = sorted(float(plate.data[k][1]) for k in (2, 3))
    width = parse_design("pocket2-sil").geometry().width_mm
    assert xs[0] <= 0.0 and xs[1] >= width / 2 + 2.0


def test_elastic_only_and_no_hold() -> None:
    blocks = parse(inp_text("solid-pu", IndentationSettings(mesh="coarse", elastic_only=True),
                            depth_mm=DEPTH))
    assert not find(blocks, "VISCOELASTIC") and not find(blocks, "VISCO")
    assert len(find(blocks, "STATIC")) == 1 and len(find(blocks, "STEP")) == 1
    hyper = one(blocks, "HYPERFOAM")
    assert "MODULI" not in hyper.params
    row = paper()["materials"]["pu"]
    assert float(hyper.data[0][0]) == row["mu_MPa"][0]
    blocks = parse(inp_text("solid-pu", IndentationSettings(mesh="coarse", hold_s=0.0),
                            depth_mm=DEPTH))
    assert len(find(blocks, "STEP")) == 1 and len(find(blocks, "VISCO")) == 1


def test_written_deck_equals_inp_text(tmp_path) -> None:
    path = tmp_path / "sub" / "deck.inp"
    out = write_deck("pocket1-pu-sil", path, COARSE, fmt="inp", depth_mm=2.0).path
    assert out == path
    assert path.read_text(encoding="utf-8") == inp_text("pocket1-pu-sil", COARSE, depth_mm=2.0)
    assert sorted(p.name for p in path.parent.iterdir()) == ["deck.inp"]


def no_fe_run(*args, **kwargs):
    raise AssertionError("softhand ran before the inputs were validated")


@pytest.mark.parametrize(
    ("design", "settings", "depth", "fmt", "needle"),
    [
        ("pocket3-sil", COARSE, None, "inp", "pocket3-sil"),
        ("solid-sil", IndentationSettings(mode="2d", mesh="coarse"), None, "inp", "'2d'"),
        ("solid-sil", IndentationSettings(mode="2d", mesh="coarse"), None, "ccx", "'2d'"),
        ("solid-sil", COARSE, 0.0, "inp", r"0\.0 is outside the allowed range \(0, 9\)"),
        ("solid-sil", COARSE, -1.5, "ccx", "-1.5"),
        ("solid-sil", COARSE, float("nan"), "inp", "nan"),
        ("solid-sil", COARSE, 9.0, "inp", r"9\.0 is outside the allowed range \(0, 9\)"),
        ("solid-sil", COARSE, "deep", "inp", "'deep'"),
        ("solid-sil", COARSE, None, "odb", "fmt = 'odb': allowed inp, ccx"),
        ("solid-sil", replace(COARSE, geometry={"pocket_height_mm": 7.0}), None, "inp",
         "pocket_height_mm = 7.0"),
    ],
)
def test_invalid_calls_raise_before_any_run_and_leave_no_file(tmp_path, monkeypatch, design,
                                                               settings, depth, fmt,
                                                               needle) -> None:
    monkeypatch.setattr(abaqus, "indent", no_fe_run)
    path = tmp_path / "bad.inp"
    with pytest.raises(ValueError, match=needle):
        write_deck(design, path, settings, fmt=fmt, depth_mm=depth)
    assert list(tmp_path.iterdir()) == []


def test_a_folder_as_path_is_refused(tmp_path, monkeypatch) -> None:
    monkeypatch.setattr(abaqus, "indent", no_fe_run)
    with pytest.raises(ValueError, match="is a folder"):
        write_deck("solid-sil", tmp_path, COARSE)


def hyperfoam_of(blocks: list[Block], name: str) -> tuple[Block, list[float]]:
    i = blocks.index(one(blocks, "MATERIAL", NAME=name.upper()))
    hyper = blocks[i + 1]
    assert hyper.keyword == "HYPERFOAM"
    return hyper, [float(v) for row in hyper.data for v in row]


@pytest.mark.parametrize("elastic_only", [False, True])
def test_material_constants_reach_the_hyperfoam_data(elastic_only: bool) -> None:
    """--materials: the user's mu, alpha, nu and Prony terms are written, not Table 3's."""
    constants = {"mu_MPa": [0.12, 0.02], "alpha": [2.0, 9.0], "nu": 0.45,
                 "g": [0.1, 0.2, 0.05], "tau_s": [0.5, 2.0, 9.0]}
    s = IndentationSettings(mesh="coarse", elastic_only=elastic_only,
                            materials={"sil": constants})
    blocks = parse(inp_text("pocket2-sil-pu", s, depth_mm=DEPTH))
    _, sil = hyperfoam_of(blocks, "sil")
    assert sil == pytest.approx([0.12, 2.0, 0.02, 9.0, 0.45, 0.45], rel=1e-12)
    _, pu = hyperfoam_of(blocks, "pu")  # the other material keeps Table 3
    assert pu[0] == paper()["materials"]["pu"]["mu_MPa"][0]
    visco = find(blocks, "VISCOELASTIC")
    if elastic_only:
        assert not visco
    else:
        i = blocks.index(one(blocks, "MATERIAL", NAME="SIL"))
        assert blocks[i + 2].data == [[f"{g}", f"{g}", f"{t}"] for g, t in
                                      zip(("0.1", "0.2", "0.05"), ("0.5", "2.", "9."),
                                          strict=True)]


@pytest.mark.parametrize("moduli", ["long-term", "instantaneous"])
def test_moduli_with_user_constants(moduli: str) -> None:
    """MODULI follows the setting and the mu are the values as given (Abaqus reads them so)."""
    s = IndentationSettings(mesh="coarse", moduli=moduli, materials={"pu": {"mu_MPa": [0.2, 0.1]}})
    hyper, values = hyperfoam_of(parse(inp_text("solid-pu", s, depth_mm=DEPTH)), "pu")
    assert hyper.params["MODULI"] == {"long-term": "LONG TERM", "instantaneous": "INSTANTANEOUS"}[moduli]
    assert values[0] == pytest.approx(0.2, rel=1e-12) and values[2] == pytest.approx(0.1, rel=1e-12)


def test_geometry_overrides_move_the_nodes_and_the_plate() -> None:
    s = IndentationSettings(mesh="coarse", geometry={"height_mm": 10.0, "width_mm": 18.0})
    blocks = parse(inp_text("solid-sil", s, depth_mm=DEPTH))
    X, conn = model(blocks)
    used = np.unique(conn)
    assert X[used, 1].max() == pytest.approx(10.0, abs=1e-9)
    assert X[used, 0].max() == pytest.approx(9.0, abs=1e-9)
    np.testing.assert_allclose(X[1:], mesh_of("solid-sil", s).X, atol=1e-10)
    assert [float(v) for v in one(blocks, "NODE", NSET="PLATE_RP").data[0][1:]] == [0, 10, 0]
    plate = one(blocks, "SURFACE", NAME="PLATE")
    assert float(plate.data[0][1]) == 10.0 and float(plate.data[2][1]) == 9.0 + 2.0


def plate_travel_in(blocks: list[Block]) -> list[float]:
    return [float(r[3]) for b in find(blocks, "BOUNDARY") for r in b.data
            if r[:3] == ["PLATE_RP", "2", "2"]]


@pytest.mark.slow
def test_max_force_sets_the_travel_to_softhands_displacement(tmp_path) -> None:
    """No depth: the ramp goes to softhand's own d(max_force_N) for the same (viscous) model."""
    s = IndentationSettings(mesh="coarse", max_force_N=1.0, hold_s=3.0)
    calls: list[float] = []
    info = write_deck("solid-pu", tmp_path / "d.inp", s, progress=calls.append)
    expected = indent("solid-pu", replace(s, hold_s=0.0))
    assert info == DeckInfo(tmp_path / "d.inp", "inp", float(expected.displacement_mm[-1]),
                            "softhand")
    assert expected.force_N[-1] == pytest.approx(1.0, rel=2e-3)
    assert calls and calls[-1] == 1.0
    text = info.path.read_text(encoding="utf-8")
    assert (f"** plate travel {info.depth_mm:.6g} mm: softhand's d(F = 1 N) for this model"
            in text)
    blocks = parse(text)
    assert plate_travel_in(blocks) == pytest.approx([-info.depth_mm] * 2, rel=1e-11)
    assert [float(b.data[0][1]) for b in find(blocks, "VISCO")] == pytest.approx(
        [info.depth_mm / 0.5, 3.0])


def test_given_depth_is_used_as_is(tmp_path, monkeypatch) -> None:
    monkeypatch.setattr(abaqus, "indent", no_fe_run)
    info = write_deck("solid-pu", tmp_path / "d.inp", COARSE, depth_mm=1.25)
    assert (info.depth_mm, info.depth_source) == (1.25, "given")
    text = info.path.read_text(encoding="utf-8")
    assert "** plate travel 1.25 mm: given" in text
    assert plate_travel_in(parse(text)) == [-1.25, -1.25]


@pytest.mark.parametrize(("hold", "speed", "elastic", "steps"), [
    (0.0, 0.5, False, {"RAMP": 4.0}),
    (7.5, 0.25, False, {"RAMP": 8.0, "HOLD": 7.5}),
    (7.5, 0.5, True, {"RAMP": 4.0}),  # elastic: no hold, as in softhand
])
def test_hold_and_speed_set_the_steps(hold: float, speed: float, elastic: bool,
                                      steps: dict[str, float]) -> None:
    s = IndentationSettings(mesh="coarse", hold_s=hold, speed_mm_s=speed, elastic_only=elastic)
    blocks = parse(inp_text("pocket1-pu", s, depth_mm=DEPTH))
    assert [b.params["NAME"] for b in find(blocks, "STEP")] == list(steps)
    proc = find(blocks, "STATIC" if elastic else "VISCO")
    assert [float(b.data[0][1]) for b in proc] == pytest.approx(list(steps.values()))
    assert bool(find(blocks, "VISCOELASTIC")) is not elastic
    assert plate_travel_in(blocks) == [-DEPTH] * len(steps)


@pytest.mark.parametrize("indenter, kind, rows", [
    # sphere: centre and a point above it on the vertical axis; quarter circle equator -> bottom
    ("sphere:7.4", "REVOLUTION", [["0.", "16.4", "0.", "0.", "17.4", "0."], ["START", "7.4", "0."],
                                  ["CIRCL", "0.", "-7.4", "0.", "0."]]),
    # across the phalanx: local x = Z, generator X; lower half circle clockwise in (Z, -Y)
    ("cylinder:7.4@90", "CYLINDER", [["0.", "16.4", "0.", "0.", "16.4", "1."],
                                     ["1.", "16.4", "0."], ["START", "-7.4", "0."],
                                     ["CIRCL", "0.", "7.4", "0.", "0."],
                                     ["CIRCL", "7.4", "0.", "0.", "0."]]),
    # along the phalanx: local x = X, generator Z; lower half circle clockwise in (X, Y)
    ("cylinder:10.7@0", "CYLINDER", [["0.", "19.7", "0.", "1.", "19.7", "0."],
                                     ["0.", "19.7", "1."], ["START", "10.7", "0."],
                                     ["CIRCL", "0.", "-10.7", "0.", "0."],
                                     ["CIRCL", "-10.7", "0.", "0.", "0."]]),
])
def test_round_indenters_are_analytical_rigid_surfaces_touching_the_top(indenter, kind, rows):
    """Radius and centre (height 9 + R above the base: the lowest point on the skin's top)."""
    text = inp_text("solid-pu", IndentationSettings(mesh="coarse", indenter=indenter),
                    depth_mm=DEPTH)
    assert f"{indenter} indentation of solid-pu" in text
    blocks = parse(text)
    surf = one(blocks, "SURFACE", NAME="INDENTER")
    assert surf.params["TYPE"] == kind
    assert surf.data == rows
    assert not find(blocks, "SURFACE", NAME="PLATE")
    rigid = one(blocks, "RIGID BODY")
    assert rigid.params == {"ANALYTICAL SURFACE": "INDENTER", "REF NODE": "PLATE_RP"}
    assert one(blocks, "CONTACT PAIR").data == [["SKIN", "INDENTER"]]
    bc = [r for b in find(blocks, "BOUNDARY") for r in b.data if r[:3] == ["PLATE_RP", "2", "2"]]
    assert [float(r[3]) for r in bc] == [-DEPTH, -DEPTH]


