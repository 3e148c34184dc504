"""The local geometry of a contact (issue 36): shapes read from the geoms at the contact point,
and an accounting that checks them against the law each pair carries."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from softhand.skin.contact_classes import border_class
from softhand.skin.local_geometry import (
    CROSSING_TOLERANCE_DEG,
    FACE_DEG,
    FINGER_BORDER,
    LocalGeometry,
    LocalShape,
    contact_class,
    crossing_bin,
    geometry_accounting,
    law_classes,
    law_fits,
    palm_border_share_pct,
)

EDGE_R = 0.008  # the rounded box's edge radius (m)
HALF = (0.030, 0.025, 0.020)  # its half sizes (m): flat faces at least 24 mm across


def _rounded_box_points() -> np.ndarray:
    """Points whose convex hull is a box with every edge rounded to EDGE_R: spheres of that
    radius at the 8 corners inset by it."""
    n = 400
    k = np.arange(n) + 0.5
    phi, z = np.pi * (1 + 5 ** 0.5) * k, 1 - 2 * k / n
    sphere = np.stack([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z], 1)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    inset = np.array(HALF) - EDGE_R
    return np.concatenate([c * inset + EDGE_R * sphere for c in corners])


@pytest.fixture(scope="module")
def scene():
    spec = mujoco.MjSpec()
    spec.add_mesh(name="box", uservert=_rounded_box_points().ravel().tolist())
    body = spec.worldbody.add_body(name="b", pos=[0.1, -0.2, 0.3], quat=[0.9, 0.1, -0.3, 0.2])
    body.add_geom(name="box", type=mujoco.mjtGeom.mjGEOM_MESH, meshname="box")
    for name, axis in (("cap_a", [0, 0, 1]), ("cap_b", [np.sin(np.radians(30)), 0,
                                                        np.cos(np.radians(30))])):
        quat = np.zeros(4)
        mujoco.mju_quatZ2Vec(quat, np.array(axis, dtype=float))
        spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_CAPSULE,
                                size=[0.009, 0.02, 0], quat=quat)
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    return m, d


def _on_box(m, d, direction_in_body) -> np.ndarray:
    """The world point where the ray from the box's centre along a body-frame direction leaves
    the exact rounded box (computed from HALF and EDGE_R, not from the mesh)."""
    u = np.asarray(direction_in_body, dtype=float)
    u /= np.linalg.norm(u)
    inset = np.array(HALF) - EDGE_R
    # the rounded box is the inset box dilated by EDGE_R: bisect the ray's exit
    lo, hi = 0.0, 0.1
    for _ in range(80):
        t = 0.5 * (lo + hi)
        p = t * u
        outside = np.linalg.norm(np.maximum(np.abs(p) - inset, 0.0)) > EDGE_R
        lo, hi = (lo, t) if outside else (t, hi)
    g = m.geom("box").id
    b = m.geom_bodyid[g]
    return d.xpos[b] + d.xmat[b].reshape(3, 3) @ (lo * u)


def test_a_flat_face_is_a_face_and_a_rounded_edge_a_border_of_its_radius(scene):
    """The box's face centres are faces; the middle of each rounded edge is a border whose
    radius comes out within 20 % of EDGE_R and whose axis lies along the edge."""
    m, d = scene
    g = m.geom("box").id
    local = LocalGeometry(m)
    R = d.xmat[m.geom_bodyid[g]].reshape(3, 3)
    for axis in np.eye(3):
        for sign in (1, -1):
            s = local.shape(d, g, _on_box(m, d, sign * axis))
            assert s.kind == "face" and s.radius_mm is None
    # the edge along y between the +x and +z faces, at 45 deg
    s = local.shape(d, g, _on_box(m, d, [HALF[0] - EDGE_R + 0.7 * EDGE_R, 0.0,
                                           HALF[2] - EDGE_R + 0.7 * EDGE_R]))
    assert s.kind == "border"
    assert s.radius_mm == pytest.approx(1e3 * EDGE_R, rel=0.2)
    assert abs(float(s.axis @ (R @ [0.0, 1.0, 0.0]))) > 0.95


def test_capsules_are_round_with_their_radius_axis_and_crossing_angle(scene):
    m, d = scene
    local = LocalGeometry(m)
    a = local.shape(d, m.geom("cap_a").id, d.geom_xpos[m.geom("cap_a").id])
    b = local.shape(d, m.geom("cap_b").id, d.geom_xpos[m.geom("cap_b").id])
    assert a.kind == b.kind == "round" and a.radius_mm == pytest.approx(9.0)
    assert a.axis == pytest.approx([0.0, 0.0, 1.0], abs=1e-12)
    body, counterpart, crossing = contact_class(a, b)
    assert (body, counterpart) == ("phalanx", "finger")
    assert crossing == pytest.approx(30.0, abs=1e-6)
    assert crossing_bin(31.0) == 2 and crossing_bin(29.0) == 1 and crossing_bin(90.0) == 5
    assert crossing_bin(None) == -1


def test_a_law_fits_only_the_class_it_was_made_for():
    """The law's body and counterpart must be the contact's; a finger law (the FE's cylinder
    across the phalanx or the border) counts within the stated tolerance of 90 deg; only the
    border law fits a rounded palm border."""
    edge = 90.0 - CROSSING_TOLERANCE_DEG
    assert law_fits("phalanx/finger", "phalanx", "finger", 90.0)
    assert law_fits("phalanx/finger", "phalanx", "finger", edge)
    assert not law_fits("phalanx/finger", "phalanx", "finger", edge - 1e-9)
    assert law_fits("phalanx/flat", "phalanx", "flat", None)
    assert law_fits("palm/finger", "palm face", "finger", 10.0)
    assert law_fits("palm/flat", "palm face", "flat", None)
    for law in ("palm/finger", "palm/flat", "phalanx/finger", "phalanx/flat"):
        assert not law_fits(law, "palm border", "finger", 90.0)
        assert not law_fits(law, "palm border", "flat", None)
    assert law_fits("border/finger", "palm border", "finger", 90.0)
    assert law_fits("border/finger", "palm border", "finger", edge)
    assert not law_fits("border/finger", "palm border", "finger", edge - 1e-9)
    assert not law_fits("border/finger", "palm face", "finger", 90.0)
    assert not law_fits("border/finger", "phalanx", "finger", 90.0)
    assert not law_fits("border/finger", "palm border", "flat", None)
    # the border's oblique laws: within the tolerance of their own angle, on either side
    for angle in (60.0, 30.0):
        law = f"border/finger@{angle:g}"
        assert law_fits(law, "palm border", "finger", angle)
        assert law_fits(law, "palm border", "finger", angle + CROSSING_TOLERANCE_DEG)
        assert law_fits(law, "palm border", "finger", angle - CROSSING_TOLERANCE_DEG)
        assert not law_fits(law, "palm border", "finger", angle + CROSSING_TOLERANCE_DEG + 1e-9)
        assert not law_fits(law, "palm border", "finger", angle - CROSSING_TOLERANCE_DEG - 1e-9)
        assert not law_fits(law, "palm face", "finger", angle)
        # the partner's phalanx under it is crossed at the same angle: the tissue's crossing
        tissue = f"phalanx/finger@{angle:g}"
        assert law_classes(law) == (law, tissue)
        assert law_fits(tissue, "phalanx", "finger", angle)
        assert not law_fits(tissue, "phalanx", "finger", 90.0)
    # every crossing from 15 to 90 deg has a border law, the one border_class picks
    for crossing in np.arange(15.0, 90.01, 0.5):
        assert law_fits(border_class(crossing), "palm border", "finger", crossing), crossing
    # a rounded border pressing a phalanx is a finger where its radius is a finger's
    ax = np.array([0.0, 0.0, 1.0])
    assert contact_class(LocalShape("round", 9.0, ax), LocalShape("border", 14.0, ax))[1] \
        == FINGER_BORDER
    assert contact_class(LocalShape("round", 9.0, ax), LocalShape("border", 16.0, ax))[1] \
        == "border"
    assert law_fits("phalanx/finger", "phalanx", FINGER_BORDER, 80.0)
    assert not law_fits("phalanx/finger", "phalanx", FINGER_BORDER, 70.0)
    assert not law_fits("phalanx/finger", "phalanx", "border", 90.0)
    assert not law_fits("phalanx/flat", "phalanx", FINGER_BORDER, None)
    assert not law_fits("palm/finger", "phalanx", "finger", 90.0)
    assert not law_fits("phalanx/flat", "phalanx", "finger", 90.0)
    assert not law_fits("phalanx/flat", "phalanx", "border", None)
    # the tissue's side: a palm presses it like a flat, a phalanx and a border like a finger
    assert law_classes("palm/finger") == ("palm/finger", "phalanx/flat")
    assert law_classes("border/finger") == ("border/finger", "phalanx/finger")
    assert law_classes("phalanx/finger") == ("phalanx/finger", "phalanx/finger")
    for fallback in ("plate", "plate (no palm/finger law)", "plate pad", "tissue"):
        assert law_classes(fallback) == ("phalanx/flat", "phalanx/flat")
    assert FACE_DEG == 15.0  # the audit's test (issue 36)


def test_the_accounting_shares_are_the_forces_whose_laws_fit():
    labels = ("palm/finger", "phalanx/finger")
    sums = {(0, "palm border", "finger", "phalanx", "border", 5): 3.0,
            (0, "palm face", "finger", "phalanx", "flat", -1): 1.0,
            (1, "phalanx", "finger", "phalanx", "finger", 5): 4.0,
            (1, "phalanx", "finger", "phalanx", "finger", 2): 2.0}
    g = geometry_accounting(sums, labels, dt=0.01)
    assert g["total_Ns"] == pytest.approx(0.1)
    assert g["skin_own_class_share_pct"] == pytest.approx(50.0)  # 1 + 4 of 10
    assert g["tissue_own_class_share_pct"] == pytest.approx(50.0)
    assert g["own_class_share_pct"] == pytest.approx(50.0)
    first = g["classes"][0]
    assert (first["contact"], first["law"], first["skin_fits"]) == (
        "finger on phalanx 75-90 deg", "phalanx/finger", True)
    assert first["share_pct"] == pytest.approx(40.0)
    assert sum(c["share_pct"] for c in g["classes"]) == pytest.approx(100.0)


def test_the_prosthetic_palm_is_a_face_at_its_centre_and_a_border_where_fingers_wrap_it():
    """The shipped scene's palm (one convex surface): its palmar face's centre reads as a flat
    face, its ulnar border (where the partner's fingers wrap it) as a rounded border."""
    import gymnasium as gym

    import softhand.envs  # noqa: F401

    env = gym.make("softhand/Handshake-v0").unwrapped
    env.reset(seed=0)
    m, d = env.model, env.data
    g = m.geom("pro_skin_Palm").id
    local = LocalGeometry(m)
    Rb = d.xmat[m.geom_bodyid[g]].reshape(3, 3)
    Rg, pg = d.geom_xmat[g].reshape(3, 3), d.geom_xpos[g]
    # the hull's faces (outward normals n, offsets h: n . x <= h inside), from its vertices
    mesh = int(m.geom_dataid[g])
    v0, nv = int(m.mesh_vertadr[mesh]), int(m.mesh_vertnum[mesh])
    f0, nf = int(m.mesh_faceadr[mesh]), int(m.mesh_facenum[mesh])
    vert, face = m.mesh_vert[v0:v0 + nv], m.mesh_face[f0:f0 + nf]
    centre = vert.mean(axis=0)
    a, b, c = (vert[face[:, i]] for i in range(3))
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1)[:, None]
    n *= np.sign(np.einsum("ij,ij->i", n, a - centre))[:, None]
    h = np.einsum("ij,ij->i", n, a)

    def exit_point(direction_in_body):  # where the ray from the centre leaves the hull
        u = Rg.T @ (Rb @ np.asarray(direction_in_body, dtype=float))
        out = n @ u > 1e-12
        t = float(np.min((h[out] - n[out] @ centre) / (n[out] @ u)))
        return pg + Rg @ (centre + t * u)

    try:
        assert local.shape(d, g, exit_point([0.0, 0.0, -1.0])).kind == "face"
        assert local.shape(d, g, exit_point([0.0, -1.0, 0.0])).kind == "border"
    finally:
        env.close()


@pytest.mark.parametrize("representation", ["soft-contact", "soft-contact+relaxation"])
def test_a_handshake_classifies_every_law_carrying_contact_once(representation):
    """The run's geometry accounting covers the same force as its accounting by law (every
    law-carrying contact of every recorded frame, once: the pads' second look at a frame does
    not count), and its shares are of that force."""
    from softhand.envs.run import run_handshake

    acc = run_handshake(seed=0, representation=representation).force_accounting()
    geo = acc["by_geometry"]
    assert geo["total_Ns"] == pytest.approx(sum(acc["by_law_Ns"].values()), rel=1e-9)
    assert sum(c["share_pct"] for c in geo["classes"]) == pytest.approx(100.0)
    fitting = sum(c["share_pct"] for c in geo["classes"] if c["skin_fits"])
    assert geo["skin_own_class_share_pct"] == pytest.approx(fitting)
    assert 0.0 <= geo["own_class_share_pct"] <= min(geo["skin_own_class_share_pct"],
                                                     geo["tissue_own_class_share_pct"])


def test_the_palm_border_share_counts_the_skin_side_only():
    """A rounded palm border on the skin's side (pressed by a finger or a border), not a
    border that presses a phalanx."""
    g = {"classes": [{"contact": "finger on palm border 60-75 deg", "share_pct": 30.0},
                     {"contact": "border on palm border", "share_pct": 5.0},
                     {"contact": "border on phalanx 45-60 deg", "share_pct": 40.0},
                     {"contact": "finger on palm face", "share_pct": 25.0}]}
    assert palm_border_share_pct(g) == pytest.approx(35.0)


def test_the_border_law_carries_the_fingers_on_the_palms_border():
    """The pairs the grasp puts on the palm's rounded border (`border_pairs`) stay there
    through the default handshake: nearly all the force their border law carries is a finger on
    a rounded palm border (measured 99.9 %), and it carries most of the force on such borders
    (measured 87 %: the rest is distal phalanges that slide onto the border from off the palm)."""
    from softhand.envs.run import run_handshake

    geo = run_handshake(seed=0).force_accounting()["by_geometry"]
    law = [c for c in geo["classes"] if c["law"].startswith("border/finger")]
    carried = sum(c["share_pct"] for c in law)
    on_border = sum(c["share_pct"] for c in law if " on palm border" in c["contact"])
    assert on_border >= 0.98 * carried
    assert carried >= 0.8 * palm_border_share_pct(geo)
