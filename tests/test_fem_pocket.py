"""The pocket's contact (softhand.fem.contact: PairedPocket, PocketContact).

The sliding contact's gaps are checked against the geometry itself (the distance from the floor
to the roof's deformed curve, sampled densely), not against its own gap function; the paired
contact is shown to miss what the sliding one sees.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from softhand.fem.contact import PocketContact, floor_through_roof_mm, pocket_contact
from softhand.fem.elements import lagrange_1d
from softhand.fem.geometry import parse_design
from softhand.fem.mesh import MESH_LEVELS, build_mesh
from softhand.fem.solver import IndentationSettings, indent
from softhand.fem.sweep import _settings_of

S2D = dict(mode="2d", hold_s=0.0, threads=1)


def _mesh(design: str = "pocket2-sil", dim: int = 2, level: str = "default"):
    return build_mesh(parse_design(design).geometry(), MESH_LEVELS[level], dim=dim)


def _curve(x: np.ndarray, faces: np.ndarray, n: int = 401) -> np.ndarray:
    """Points densely along 2D quadratic faces at nodal positions ``x``."""
    N, _ = lagrange_1d(np.linspace(-1.0, 1.0, n))
    return np.einsum("qa,fad->fqd", N, x[faces]).reshape(-1, 2)


def _distance_to(points: np.ndarray, curve: np.ndarray) -> np.ndarray:
    return np.linalg.norm(points[:, None] - curve[None], axis=-1).min(axis=1)


@pytest.mark.parametrize("dim", [2, 3])
def test_at_rest_every_floor_point_is_the_pocket_height_from_the_roof(dim):
    """Roof and floor are normal offsets of one profile, 2 mm apart: both contacts' floor gaps
    are the pocket's height; the side wall's points are inside the pocket (gap > 0)."""
    mesh = _mesh(dim=dim)
    h = parse_design("pocket2-sil").geometry().pocket_height_mm
    u = np.zeros(mesh.n_dofs)
    sliding = pocket_contact(mesh, 4, "sliding")
    np.testing.assert_allclose(sliding.floor_gaps(u), h, rtol=2e-3)
    np.testing.assert_allclose(pocket_contact(mesh, 4, "paired").floor_gaps(u), h, rtol=2e-3)
    walls = sliding.gaps(u)[sliding.n_floor_points:]
    assert walls.size == len(mesh.wall_faces) * 4 ** (dim - 1)
    assert walls.min() > 0.0


def test_the_side_wall_joins_the_floor_to_the_roof():
    """2D: one wall face per element through the pocket's height; 3D: that times the elements
    along the length. Each wall face meets the floor's and the roof's faces at the pocket's
    edge (shared nodes)."""
    for dim, per in ((2, 1), (3, MESH_LEVELS["default"].n_length)):
        mesh = _mesh(dim=dim)
        assert len(mesh.wall_faces) == MESH_LEVELS["default"].n_pocket * per
        wall = set(mesh.wall_faces.ravel().tolist())
        assert wall & set(mesh.floor_faces.ravel().tolist())
        assert wall & set(mesh.roof_faces.ravel().tolist())


@pytest.mark.parametrize("shift", [(0.6, -1.2), (1.5, -1.9), (-0.4, -1.6)])
def test_sliding_gaps_are_the_distance_to_the_moved_roof(shift):
    """The roof moved rigidly sideways and down (the floor still): every floor point's gap is
    its distance to the roof's curve (sampled at 401 points a face), negative inside the roof,
    within 1e-4 mm. The paired contact's gap misses by more than 0.05 mm somewhere."""
    mesh = _mesh()
    roof_nodes = np.unique(np.concatenate([mesh.roof_faces.ravel(),
                                           mesh.elements[np.isin(mesh.elements,
                                                                 mesh.roof_faces).any(1)]
                                           .ravel()]))
    u = np.zeros((len(mesh.X), 2))
    u[roof_nodes] = shift
    u = u.ravel()
    x = mesh.X + u.reshape(-1, 2)
    sliding = pocket_contact(mesh, 4, "sliding")
    floor_points = sliding.points[:sliding.n_floor_points]
    curve = _curve(x, mesh.roof_faces)
    dist = _distance_to(floor_points, curve)
    g = sliding.floor_gaps(u)
    # inside the roof band: below the curve and above the roof band's lower edge at that x
    inside = g < 0
    np.testing.assert_allclose(np.abs(g), dist, atol=1e-4)
    paired = pocket_contact(mesh, 4, "paired").floor_gaps(u)
    assert np.abs(paired - g).max() > 0.05
    assert inside.any() == (g.min() < 0)


def _penetration_mm(r, design: str = "pocket2-sil", level: str = "default") -> float:
    return floor_through_roof_mm(_mesh(design, 2, level), r.ramp_end_u)


def test_the_floor_stays_under_the_roof_at_2_newton():
    """pocket2-sil, 2D, default mesh, to 2 N: with the sliding contact the floor stays under
    the roof's deformed curve (within 0.002 mm, the penalty's own overlap is about 4e-4 mm);
    the paired contact lets it through by more than 0.05 mm (measured 0.12 mm) and so gives a
    deeper d(2 N) (measured +2.8 %)."""
    paired = indent("pocket2-sil", IndentationSettings(**S2D))
    sliding = indent("pocket2-sil", IndentationSettings(**S2D, pocket_contact="sliding"))
    assert _penetration_mm(sliding) < 0.002
    assert _penetration_mm(paired) > 0.05
    assert paired.displacement_at(2.0) > sliding.displacement_at(2.0) * 1.015


def test_sliding_runs_the_same_on_both_engines():
    """The compiled engine's pattern follows the faces the points project on
    (TangentSystem.set_contact): its curve is the NumPy reference's to the Newton tolerance."""
    s = IndentationSettings(**S2D, mesh="coarse", pocket_contact="sliding")
    a = indent("pocket2-sil", s)
    b = indent("pocket2-sil", dataclasses.replace(s, engine="numpy"))
    assert a.displacement_at(2.0) == pytest.approx(b.displacement_at(2.0), rel=1e-4)
    assert max(e["pocket_points"] for e in a.log) > 0


def test_pocket_contact_setting_is_checked_and_old_folders_read_as_paired():
    with pytest.raises(ValueError, match="pocket_contact = 'glued': allowed paired, sliding"):
        IndentationSettings(pocket_contact="glued")
    old = dataclasses.asdict(IndentationSettings())
    del old["pocket_contact"]
    assert _settings_of(old) == _settings_of(IndentationSettings())
    assert _settings_of(IndentationSettings(pocket_contact="sliding")) != _settings_of(old)


def test_a_sliding_contact_has_one_structure_per_face_it_meets():
    """Each row couples its slave face with one roof face: 2 x 3 nodes x 2 dofs in 2D."""
    mesh = _mesh()
    c = PocketContact(mesh)
    G = c.linearised(np.zeros(mesh.n_dofs)).G
    assert set(np.diff(G.indptr).tolist()) == {12}


@pytest.mark.slow
def test_to_20_newton_the_floor_stays_under_the_roof_on_every_mesh():
    """pocket2-sil, 2D, sliding, to 20 N on the coarse, default and fine meshes: each reaches
    20 N (measured at 3.52, 3.57 and 3.60 mm: converging) with the floor inside the roof by
    under 0.005 mm; the paired contact's default run reaches 20 N only with the floor 0.67 mm
    inside the roof."""
    depths = []
    for level in ("coarse", "default", "fine"):
        r = indent("pocket2-sil", IndentationSettings(**S2D, mesh=level, max_force_N=20.0,
                                                      pocket_contact="sliding"))
        assert r.force_N[-1] >= 20.0
        assert _penetration_mm(r, level=level) < 0.005
        depths.append(r.displacement_at(20.0))
    assert abs(depths[2] - depths[1]) < abs(depths[1] - depths[0])  # refinement converges
    paired = indent("pocket2-sil", IndentationSettings(**S2D, max_force_N=20.0))
    assert _penetration_mm(paired) > 0.3


def test_the_cli_takes_the_pocket_contact_and_refuses_others_in_one_line():
    import json

    from click.testing import CliRunner

    from softhand.cli import main

    args = ["fe", "indent", "pocket2-sil", "--mode", "2d", "--mesh", "coarse", "--hold", "0",
            "--threads", "1", "--json"]
    d = {}
    for kind in ("paired", "sliding"):
        out = CliRunner().invoke(main, [*args, "--pocket-contact", kind])
        assert out.exit_code == 0, out.output
        d[kind] = json.loads(out.output)["displacement_at_2N_mm"]
    assert d["sliding"] < d["paired"]
    out = CliRunner().invoke(main, [*args, "--pocket-contact", "glued"])
    assert out.exit_code == 2
    line = [x for x in out.output.splitlines() if x.strip()]
    assert len(line) == 1 and "--pocket-contact" in line[0] and "paired" in line[0]


def test_the_cli_takes_the_contact_points_as_the_settings_do_and_refuses_others_in_one_line():
    """`--contact-points` reaches `IndentationSettings.contact_points` (the design search's
    winners' `fe_indent` lines name 2): the CLI's run is the Python run, bit for bit."""
    import json
    from dataclasses import replace

    from click.testing import CliRunner

    from softhand.cli import main

    args = ["fe", "indent", "pocket2-sil", "--mode", "2d", "--mesh", "coarse", "--hold", "0",
            "--threads", "1", "--json"]
    out = CliRunner().invoke(main, [*args, "--contact-points", "2"])
    assert out.exit_code == 0, out.output
    got = json.loads(out.output)["displacement_at_2N_mm"]
    s = IndentationSettings(mode="2d", mesh="coarse", hold_s=0.0, threads=1)
    assert got == indent("pocket2-sil", replace(s, contact_points=2)).displacement_at(2.0)
    assert got != indent("pocket2-sil", s).displacement_at(2.0)
    out = CliRunner().invoke(main, [*args, "--contact-points", "7"])
    assert out.exit_code == 2
    line = [x for x in out.output.splitlines() if x.strip()]
    assert len(line) == 1 and "--contact-points" in line[0] and "2<=x<=6" in line[0]
