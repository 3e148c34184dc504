"""Tests of softhand.hands: the two hands and the handshake scene, built with MjSpec and compiled.

Checks counts and names against the paper (18 regions, softhand.paper), geometry against the
paper's hand length and width (Table 1) measured on the compiled model, ranges against the
constants, actuation against the commercial closing time, and that models/mjcf is up to date.
"""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from softhand.hands import (
    ArmConfig,
    HandConfig,
    PartnerConfig,
    ProstheticConfig,
    SceneConfig,
    build_partner_hand,
    build_prosthetic_hand,
    hand_layout,
    partner_actuators,
    partner_contact_pose,
    partner_tissue_geoms,
    prosthetic_actuators,
    regions,
    scene_spec,
    write_mjcf,
)
from softhand.hands import constants as const
from softhand.hands.mjcf import MJCF_FILES
from softhand.hands.skeleton import SENSOR_SLOTS, contact_sensor_force
from softhand.paper import paper

MJCF_DIR = Path(__file__).resolve().parents[1] / "models" / "mjcf"
PAPER_REGIONS = tuple(paper()["handshake"]["regions"])
PAPER_LENGTH_M = paper()["anthropometry"]["experimenter_hand_length_mm"] / 1000.0
PAPER_WIDTH_M = paper()["anthropometry"]["experimenter_hand_width_mm"] / 1000.0


@pytest.fixture(scope="module")
def scene() -> tuple[mujoco.MjSpec, mujoco.MjModel]:
    spec = scene_spec()
    return spec, spec.compile()


def _support(model: mujoco.MjModel, data: mujoco.MjData, geom: int, u: np.ndarray) -> float:
    """max over the geom's points p of p . u (world frame)."""
    c, R, size = data.geom_xpos[geom], data.geom_xmat[geom].reshape(3, 3), model.geom_size[geom]
    kind = model.geom_type[geom]
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return c @ u + size[0]
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        return c @ u + size[1] * abs(R[:, 2] @ u) + size[0]
    if kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        return c @ u + np.linalg.norm(size * (R.T @ u))
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        return c @ u + np.sum(size * np.abs(R.T @ u))
    if kind == mujoco.mjtGeom.mjGEOM_MESH:
        mesh = model.geom_dataid[geom]
        start, n = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
        return float(np.max((c + model.mesh_vert[start:start + n] @ R.T) @ u))
    raise AssertionError(f"unexpected geom type {kind}")


def _body_geoms(model: mujoco.MjModel, body: str) -> list[int]:
    b = model.body(body).id
    return [g for g in range(model.ngeom) if model.geom_bodyid[g] == b]


# ------------------------------------------------------------------------------------------------
# Scene and counts
# ------------------------------------------------------------------------------------------------


def test_scene_compiles_with_options(scene):
    _, model = scene
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    assert model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert model.opt.timestep == pytest.approx(0.002)
    np.testing.assert_allclose(model.opt.gravity, [0.0, 0.0, -9.81])
    assert model.nmocap == 1 and model.body("hum_base").mocapid[0] == 0
    # each hand rides its arm: a free wrist body held to an anchor by the arm's weld
    assert model.body("pro_wrist").dofnum[0] == 6 and model.body("hum_arm").dofnum[0] == 6
    assert model.nu == 6 + 18  # 6 prosthetic motors; 16 partner digit joints + 2 wrist servos


def test_eighteen_regions_with_skin_zone_and_contact_sensor(scene):
    spec, model = scene
    info = regions(model, "pro_")
    assert tuple(info) == PAPER_REGIONS and len(info) == 18
    assert tuple(regions(spec, "pro_")) == PAPER_REGIONS
    for region, r in info.items():
        geom, site, sensor = model.geom(r.geom), model.site(r.site), model.sensor(r.sensor)
        palm = r.body == "pro_palm"
        kind = mujoco.mjtGeom.mjGEOM_MESH if palm else mujoco.mjtGeom.mjGEOM_CAPSULE
        assert geom.type[0] == kind, region
        assert geom.contype[0] == 0 and geom.conaffinity[0] == 0, region
        assert geom.bodyid[0] == site.bodyid[0] == model.body(r.body).id, region
        assert site.type[0] == mujoco.mjtGeom.mjGEOM_BOX, region
        # a contact sensor on this skin's contacts inside the zone, 10 slots of (found, force)
        assert sensor.type[0] == mujoco.mjtSensor.mjSENS_CONTACT, region
        assert sensor.objtype[0] == mujoco.mjtObj.mjOBJ_SITE and sensor.objid[0] == site.id
        assert sensor.reftype[0] == mujoco.mjtObj.mjOBJ_GEOM and sensor.refid[0] == geom.id
        assert sensor.dim[0] == 4 * SENSOR_SLOTS, region
    with pytest.raises(ValueError, match="Thumb1"):
        regions(build_partner_hand().compile(), "pro_")


def test_six_prosthetic_actuators(scene):
    _, model = scene
    names = [model.actuator(i).name for i in range(model.nu)]
    assert [n for n in names if n.startswith("pro_")] == list(prosthetic_actuators("pro_"))
    assert len(prosthetic_actuators()) == const.PROSTHETIC["motor_count"] == 6
    assert [n for n in names if n.startswith("hum_")] == list(partner_actuators("hum_"))
    for a in prosthetic_actuators():
        act = model.actuator(a)
        lo, hi = act.forcerange
        assert act.forcelimited[0] and 0.2 < hi == -lo < 5.0, (a, hi)  # N m, from 136 N grip
        assert act.ctrlrange[1] == -act.ctrlrange[0] > 0.0


def test_joint_ranges_within_constants(scene):
    _, model = scene
    checked = 0
    for j in range(model.njnt):
        if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            continue  # the partner's arm (hum_arm), not a hand joint
        name = model.joint(j).name
        prefix, rest = name.split("_", 1)
        digit, short = rest.split("_", 1)
        key = f"{digit}_{short}" if digit in ("thumb", "wrist") else short
        lo, hi = np.degrees(model.jnt_range[j])
        human_lo, human_hi = const.AAOS_RANGE_DEG[key]
        assert human_lo - 1e-6 <= lo < hi <= human_hi + 1e-6, (name, lo, hi)
        if prefix == "pro":
            assert (lo, hi) == pytest.approx(const.PROSTHETIC_RANGE_DEG[key]), name
        else:
            assert (lo, hi) == pytest.approx(const.AAOS_RANGE_DEG[key]), name
        checked += 1
    assert checked == 16 + 18


def test_bones_collide_only_with_the_other_hand(scene):
    _, model = scene

    def collide(a: int, b: int) -> bool:
        return bool(
            model.geom_contype[a] & model.geom_conaffinity[b]
            or model.geom_contype[b] & model.geom_conaffinity[a]
        )

    geoms = {
        p: [g for g in range(model.ngeom) if model.geom(g).name.startswith(p)]
        for p in ("pro_bone_", "hum_bone_", "pro_skin_", "hum_tissue_")
    }
    # 14 phalanges, the palm's one surface (Palm1, Palm2, Back1, Back2 its zones), the thenar
    assert len(geoms["pro_bone_"]) == 4 + 3 + 12 and len(geoms["pro_skin_"]) == 14 + 1 + 1
    for a in geoms["pro_bone_"]:
        assert all(collide(a, b) for b in geoms["hum_bone_"])
        assert not any(collide(a, b) for b in geoms["pro_bone_"])
    for b in geoms["hum_bone_"]:
        assert not any(collide(b, c) for c in geoms["hum_bone_"])
    for g in geoms["pro_skin_"]:
        assert model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0
    # the partner's thumb touches its own fingers' phalanges (not through them), and nothing
    # else collides outside the explicit pairs: not thumb with thumb, finger with finger, the
    # palm or the forearm, either hand's bones or the sensored hand's skin
    thumb = [g for g in geoms["hum_tissue_"] if "_thumb_" in model.geom(g).name]
    phalanges = [g for g in geoms["hum_tissue_"] if model.geom(g).name.split("_")[-1]
                 in ("proximal", "middle", "distal") and g not in thumb]
    assert len(thumb) == 3 and len(phalanges) == 12
    everything = range(model.ngeom)
    for g in thumb:
        assert {c for c in everything if collide(g, c)} == set(phalanges)
    for g in phalanges:
        assert {c for c in everything if collide(g, c)} == set(thumb)
    for g in set(geoms["hum_tissue_"]) - set(thumb) - set(phalanges):
        assert model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0


def test_the_partner_feels_the_other_hand_not_its_own_thumb(scene):
    """The partner's thumb pressed into its own middle fingertip makes a contact with force
    (it does not pass through), and the feel sensors that its grip regulates on do not count it:
    they match contacts with the sensored hand only."""
    spec = mujoco.MjSpec.from_string(scene[0].to_xml())
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    thumb, middle = model.geom("hum_tissue_thumb_distal"), model.geom("hum_tissue_middle_distal")
    body = thumb.bodyid[0]
    # move the thumb's tissue (in its body's frame) onto the middle fingertip, 1 mm into it
    target = data.geom_xpos[middle.id] + data.geom_xmat[middle.id].reshape(3, 3)[:, 0] * (
        model.geom_size[middle.id, 0] + model.geom_size[thumb.id, 0] - 0.001)
    shift = data.xmat[body].reshape(3, 3).T @ (target - data.geom_xpos[thumb.id])
    g = spec.geom("hum_tissue_thumb_distal")
    g.pos = np.asarray(g.pos) + shift  # the MJCF places it by pos and quat
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    pairs = {(int(c.geom1), int(c.geom2)) for c in data.contact[:data.ncon]}
    assert (thumb.id, middle.id) in pairs or (middle.id, thumb.id) in pairs
    i = next(i for i, c in enumerate(data.contact[:data.ncon])
             if {int(c.geom1), int(c.geom2)} == {thumb.id, middle.id})
    force = np.zeros(6)
    mujoco.mj_contactForce(model, data, i, force)
    assert force[0] > 0.0
    for name in ("hum_feel_thumb_distal", "hum_feel_middle_distal"):
        s = model.sensor(name)
        assert np.all(data.sensordata[s.adr[0]:s.adr[0] + s.dim[0]] == 0.0), name


def test_partner_tissues_listed(scene):
    spec, model = scene
    names = partner_tissue_geoms(model, "hum_")
    assert names == partner_tissue_geoms(spec, "hum_")
    # one palm piece (no seam), the thumb's 3, the fingers' 12, and the forearm's
    assert len(names) == 1 + 3 + 12 + 1 and "hum_tissue_palm" in names
    assert names[-1] == "hum_tissue_forearm"
    with pytest.raises(ValueError, match="hum_tissue_palm"):
        partner_tissue_geoms(build_prosthetic_hand().compile(), "hum_")


# ------------------------------------------------------------------------------------------------
# Geometry and mass, measured on the compiled model
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "build, prefix", [(build_prosthetic_hand, "pro_"), (build_partner_hand, "hum_")]
)
def test_hand_length_and_width_match_paper(build, prefix):
    model = build().compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    palm = model.body(f"{prefix}palm").id
    R = data.xmat[palm].reshape(3, 3)  # hand frame in world: columns x distal, y radial, z dorsal
    x, y = R[:, 0], R[:, 1]
    crease = data.site_xpos[model.site(f"{prefix}wrist_crease").id]
    tip = max(_support(model, data, g, x) for g in _body_geoms(model, f"{prefix}middle_distal"))
    length = tip - crease @ x
    # breadth on the skin: the palm's skin / tissue pieces cover its borders
    palm_geoms = [g for g in _body_geoms(model, f"{prefix}palm") if "bone" not in model.geom(g).name]
    skin = hand_layout(HandConfig()).skin_m
    def reach(g, u):
        bone = "bone" in model.geom(g).name
        return _support(model, data, g, u) + (skin if bone else 0.0)
    width = max(reach(g, y) for g in palm_geoms) + max(reach(g, -y) for g in palm_geoms)
    assert length == pytest.approx(PAPER_LENGTH_M, rel=0.03)
    assert width == pytest.approx(PAPER_WIDTH_M, rel=0.03)
    # thumb tip ~56 mm proximal to the index tip ([Chatzioglou24]), hand extended
    tips = {d: data.site_xpos[model.site(f"{prefix}{d}_tip").id] @ x for d in ("thumb", "index")}
    assert tips["index"] - tips["thumb"] == pytest.approx(
        const.FINGERTIP_OFFSET_M["thumb_to_index"], abs=0.002
    )


def test_hand_mass_plausible():
    model = build_prosthetic_hand().compile()
    mass = model.body("pro_palm").subtreemass[0]
    # commercial hands 0.45-0.615 kg ([Belter13]); a 70 kg adult's hand 0.42 kg ([Winter09]).
    assert 0.34 < mass < 0.60, mass
    # the envelope (fingers as wide as their MCP spacing allows, a slender thenar) holds 84 % of
    # the mass Winter's fraction predicts (0.352 of 0.42 kg): within 20 %
    assert mass == pytest.approx(const.HAND_MASS_FRACTION * 70.0, rel=0.20)


def test_flexion_and_opposition_move_tips_palmar():
    model = build_prosthetic_hand().compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    z_tip = {d: data.site_xpos[model.site(f"pro_{d}_tip").id][2] for d in ("index", "thumb")}
    for joint in ("pro_index_mcp", "pro_thumb_rot"):
        data.qpos[:] = 0.0
        data.qpos[model.joint(joint).qposadr[0]] = 0.5
        mujoco.mj_kinematics(model, data)
        digit = joint.split("_")[1]
        assert data.site_xpos[model.site(f"pro_{digit}_tip").id][2] < z_tip[digit] - 0.01, joint


# ------------------------------------------------------------------------------------------------
# Actuation
# ------------------------------------------------------------------------------------------------


def test_full_command_closes_within_commercial_time():
    config = ProstheticConfig()
    model = build_prosthetic_hand(config).compile()
    data = mujoco.MjData(model)
    data.ctrl[:] = model.actuator_ctrlrange[:, 1]
    reached: dict[str, float] = {}
    for _ in range(int(2.0 * config.closing_time_s / model.opt.timestep)):
        mujoco.mj_step(model, data)
        for a in range(model.nu):
            j = model.actuator_trnid[a, 0]
            if model.actuator(a).name not in reached and (
                data.qpos[model.jnt_qposadr[j]] >= 0.95 * model.jnt_range[j, 1]
            ):
                reached[model.actuator(a).name] = data.time
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))
    assert set(reached) == set(prosthetic_actuators())
    for name, t in reached.items():
        assert 0.5 * config.closing_time_s <= t <= 1.5 * config.closing_time_s, (name, t)
    # every joint, coupled ones included, ends flexed to >= 90 % of its upper limit
    assert np.all(data.qpos >= 0.90 * model.jnt_range[:, 1]), np.degrees(data.qpos)


def _same_hand_pairs(model, geoms):
    """Pairs of geoms on different, non-adjacent bodies (a body and its parent share a joint)."""
    import itertools

    for a, b in itertools.combinations(geoms, 2):
        ba, bb = model.geom_bodyid[a], model.geom_bodyid[b]
        if ba == bb or model.body_parentid[ba] == bb or model.body_parentid[bb] == ba:
            continue
        yield a, b


@pytest.mark.parametrize("build, prefix, soft", [(build_prosthetic_hand, "pro_", "skin_"),
                                                 (build_partner_hand, "hum_", "tissue_")])
def test_each_hand_is_one_layer_of_soft_geoms(build, prefix, soft):
    """No point lies inside two of a hand's skin (tissue) geoms at rest, so no indentation is
    resisted by two laws at once: every pair of soft geoms is at distance >= 0 (touching at the
    joints, where consecutive trimmed capsules meet), to 0.05 mm (MuJoCo's convex distance)."""
    model = build().compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    geoms = [g for g in range(model.ngeom) if model.geom(g).name.startswith(prefix + soft)]
    # each palm is one piece; the partner's forearm stub has a tissue too
    assert len(geoms) == (16 if prefix == "pro_" else 17)
    ft = np.zeros(6)
    worst = min((mujoco.mj_geomDistance(model, data, a, b, 0.01, ft), model.geom(a).name,
                 model.geom(b).name) for a in geoms for b in geoms if a < b)
    assert worst[0] > -5e-5, worst


@pytest.mark.parametrize("build, prefix, soft", [(build_prosthetic_hand, "pro_", "skin_"),
                                                 (build_partner_hand, "hum_", "tissue_")])
def test_every_bone_lies_under_the_soft_layer(build, prefix, soft):
    """Skin (tissue) over every bone, ends included: the whole surface of each bone capsule lies
    at least 3 mm inside the hand's soft geoms (measured with trimesh, softhand.hands.checks:
    phalanges and thumb metacarpal 5.9 mm, i.e. the 6 mm skin less the tessellation; thinnest
    3.35 mm, the middle metacarpal's head under the MCP-arch cut). Bones ran joint to joint
    before, and their ends stood 2 mm out of the palm at the MCPs, where a fingertip pressed the
    other hand's metacarpal head bone on bone."""
    from softhand.hands.checks import skin_cover_m

    model = build().compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    bones = [g for g in range(model.ngeom) if "bone_" in model.geom(g).name
             and "forearm" not in model.geom(g).name]
    softs = [g for g in range(model.ngeom) if model.geom(g).name.startswith(prefix + soft)]
    cover = skin_cover_m(model, data, bones, softs)
    assert len(cover) == 19
    thinnest = min(cover.items(), key=lambda kv: kv[1])
    assert thinnest[1] >= 3e-3, thinnest
    phalanges = {k: v for k, v in cover.items() if "metacarpal" not in k}
    assert min(phalanges.values()) >= 5.5e-3, phalanges  # the 6 mm skin, to the tessellation


def _posture_grid(model):
    """Rest, each hinge at each of its limits, and every digit at once at both ends of its range
    with the thumb rotation at both of its ends (fist, open hand, opposed and lateral thumb)."""
    hinges = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE
              and "wrist" not in model.joint(j).name]
    yield "rest", {}
    for j in hinges:
        for end in (0, 1):
            yield f"{model.joint(j).name}[{end}]", {j: model.jnt_range[j, end]}
    rot = next(j for j in hinges if model.joint(j).name.endswith("thumb_rot"))
    for fingers in (0, 1):
        for thumb in (0, 1):
            for r in (0, 1):
                q = {j: model.jnt_range[j, thumb if "thumb" in model.joint(j).name else fingers]
                     for j in hinges}
                q[rot] = model.jnt_range[rot, r]
                yield f"fingers {fingers} thumb {thumb} rotation {r}", q


@pytest.mark.parametrize("build", [build_prosthetic_hand, build_partner_hand])
def test_no_bone_interpenetrates_another_over_a_posture_grid(build):
    """Bones of one hand (not neighbours across a joint) never overlap: at rest, at every single
    joint limit, and with all digits flexed or extended together (the thumb lateral or opposed).
    They may touch (0.2 mm tolerance). The closest: the thumb flexed in the palm plane over a
    closed fist, its distal bone 1.4 mm from the ring's proximal bone (each bone is its skin
    capsule shrunk by the skin thickness, so it ends 6 mm short of its joints; when bones ran
    joint to joint, that posture overlapped by 4.4 mm)."""
    model = build().compile()
    data = mujoco.MjData(model)
    bones = [g for g in range(model.ngeom) if "bone_" in model.geom(g).name
             and "forearm" not in model.geom(g).name]
    ft = np.zeros(6)
    checked = 0
    for label, q in _posture_grid(model):
        data.qpos[:] = 0.0
        for j, v in q.items():
            data.qpos[model.jnt_qposadr[j]] = v
        mujoco.mj_kinematics(model, data)
        for a, b in _same_hand_pairs(model, bones):
            d = mujoco.mj_geomDistance(model, data, a, b, 0.01, ft)
            assert d >= -2e-4, (label, model.geom(a).name, model.geom(b).name, d)
        checked += 1
    assert checked == 1 + 2 * 16 + 8


def test_opposed_thumb_flexes_across_the_palm_never_over_the_back():
    """With the thumb rotated into opposition (palmar abduction), flexing it carries the tip
    ulnarly across the palm, on the palmar side; at no rotation and flexion does the tip pass
    dorsal of the palm's palmar skin plane (hand frame z = -t/2)."""
    model = build_prosthetic_hand().compile()
    data = mujoco.MjData(model)
    t = HandConfig().thickness_m
    ratios = {"mcp": 1.0, "cmc": 15 / 50, "ip": 80 / 50}  # the prosthetic's couplings

    def tip(rot: float, flex: float) -> np.ndarray:
        data.qpos[:] = 0.0
        data.qpos[model.joint("pro_thumb_rot").qposadr[0]] = rot
        for j, r in ratios.items():
            data.qpos[model.joint(f"pro_thumb_{j}").qposadr[0]] = r * flex
        mujoco.mj_kinematics(model, data)
        return data.site_xpos[model.site("pro_thumb_tip").id].copy()  # hand frame = world

    opposed = math.radians(70.0)
    y = [tip(opposed, math.radians(f))[1] for f in (0, 25, 50)]
    assert y[0] > y[1] > y[2] and y[2] < 0.0, y  # ends on the ulnar half of the palm
    for rot in np.radians([0, 35, 70]):
        for flex in np.radians([0, 25, 50]):
            assert tip(rot, flex)[2] <= -0.5 * t + 1e-9, (rot, flex)


def test_touch_sensors_read_skin_pair_contacts():
    spec = scene_spec()
    info = regions(spec)
    tissues = partner_tissue_geoms(spec)
    skins = sorted({r.geom for r in info.values()})  # the palm's one skin carries four zones
    for g in skins:
        for t in tissues:
            spec.add_pair(geomname1=g, geomname2=t)
    model = spec.compile()
    data = mujoco.MjData(model)
    pos, quat = partner_contact_pose(SceneConfig())
    data.mocap_pos[0], data.mocap_quat[0] = pos, quat
    arm = model.jnt_qposadr[model.joint("hum_arm").id]
    data.qpos[arm:arm + 7] = [*pos, *quat]  # the arm starts at its target
    hum = [model.actuator(a).id for a in partner_actuators()[:5]]
    pro = [model.actuator(a).id for a in prosthetic_actuators()[:5]]
    force = np.zeros(6)
    skin_ids = {model.geom(g).id: g for g in skins}
    for i in range(600):  # both hands close their fingers and thumbs around each other
        data.ctrl[hum] = min(i / 300, 1.0) * 0.5 * model.actuator_ctrlrange[hum, 1]
        data.ctrl[pro] = 0.5 * model.actuator_ctrlrange[pro, 1] if i < 400 else 0.0
        mujoco.mj_step(model, data)
        assert np.all(np.isfinite(data.sensordata))
        pair_force = dict.fromkeys(skins, 0.0)
        for c in range(data.ncon):
            skin = skin_ids.get(data.contact[c].geom1, skin_ids.get(data.contact[c].geom2))
            if skin is not None:
                mujoco.mj_contactForce(model, data, c, force)
                pair_force[skin] += force[0]
        if sum(f > 0.05 for f in pair_force.values()) >= 2:
            break  # the compliant arm lets the hands part again later: check while they touch
    assert sum(f > 0.05 for f in pair_force.values()) >= 2, pair_force
    touched = [k for k, r in info.items() if pair_force[r.geom] > 0.05]
    by_skin: dict[str, float] = {}
    for k in touched:  # each sensor reads exactly its skin's contacts inside its zone
        sensor = model.sensor(info[k].sensor)
        slots = data.sensordata[sensor.adr[0]:sensor.adr[0] + sensor.dim[0]].reshape(-1, 4)
        reading = float(contact_sensor_force(slots))
        site = model.site(info[k].site).id
        centre, rot = data.site_xpos[site], data.site_xmat[site].reshape(3, 3)
        inside = 0.0
        for c in range(data.ncon):
            con = data.contact[c]
            if model.geom(info[k].geom).id not in (con.geom1, con.geom2):
                continue
            local = rot.T @ (con.pos - centre)
            if np.all(np.abs(local) <= model.site_size[site] + 1e-12):
                mujoco.mj_contactForce(model, data, c, force)
                inside += force[0]
        assert reading == pytest.approx(inside, abs=1e-9), k
        by_skin[info[k].geom] = by_skin.get(info[k].geom, 0.0) + reading
    for g, read in by_skin.items():  # a skin's zones never read one contact twice
        assert read <= pair_force[g] + 1e-9, (g, read, pair_force[g])


# ------------------------------------------------------------------------------------------------
# Files and configuration errors
# ------------------------------------------------------------------------------------------------


def test_mjcf_files_are_up_to_date(tmp_path):
    """The hands' files and the skinned scene (softhand.envs.models) equal a fresh build."""
    from softhand.envs.models import SCENE_FILE, write_models

    assert sorted(p.name for p in write_mjcf(tmp_path / "hands")) == sorted(MJCF_FILES)
    written = write_models(tmp_path / "all")
    assert sorted(p.name for p in written) == sorted([*MJCF_FILES, SCENE_FILE])
    for path in written:
        shipped = MJCF_DIR / path.name
        assert shipped.exists(), f"{shipped} missing: run write_models('models/mjcf')"
        assert path.read_text() == shipped.read_text(), f"{shipped} is stale: run write_models"
        assert mujoco.MjModel.from_xml_path(str(shipped)).nbody > 1


@pytest.mark.parametrize(
    "make, value",
    [
        (lambda: HandConfig(hand_length_m=-0.19), "-0.19"),
        (lambda: HandConfig(hand_width_m=math.nan), "nan"),
        (lambda: HandConfig(hand_width_m=0.12, hand_length_m=0.13), "0.923"),
        (lambda: HandConfig(skin_thickness_m=0.02), "0.02"),
        (lambda: ProstheticConfig(closing_time_s=0.0), "0.0"),
        (
            lambda: build_prosthetic_hand(
                ProstheticConfig(hand=HandConfig(skin_thickness_m=0.008))
            ),
            "0.008",
        ),
        (lambda: ProstheticConfig(grip_force_n=-5.0), "-5.0"),
        (lambda: PartnerConfig(wrist_torque_nm=1e6), "1000000.0"),
        (lambda: SceneConfig(timestep_s=0.05), "0.05"),
        (lambda: SceneConfig(partner_start_offset_m=(0.1, 0.2)), "(0.1, 0.2)"),
        (lambda: ArmConfig.of("relaxed", stiffness_n_per_m=1e5), "stiffness_n_per_m = 100000"),
        (lambda: ArmConfig.of("active", press_n=-1.0), "press_n = -1"),
        (lambda: ArmConfig.of("active", mass_kg=math.inf), "mass_kg = inf"),
        (lambda: ArmConfig.of("shoulder"), "'shoulder'"),
        (lambda: SceneConfig(partner_arm="relaxed"), "partner_arm = 'relaxed'"),
    ],
)
def test_bad_config_raises_value_error_naming_value(make, value):
    with pytest.raises(ValueError, match=value.replace("(", r"\(").replace(")", r"\)")):
        make()


def test_one_tissue_geom_under_the_partners_ulnar_border():
    """The grasp's fingers wrap the partner's ulnar border, where the palm's palmar and dorsal
    halves used to meet: a finger-sized sphere (8 mm) pressed 2 mm into the border at the palm's
    mid-plane makes one contact with the partner's tissue, 2 mm deep (two halves made two, and
    the same indentation was resisted twice)."""
    layout = hand_layout(HandConfig())
    spec = build_partner_hand()
    probe = spec.worldbody.add_body(name="probe")
    probe.add_freejoint()  # a free body: MuJoCo skips contacts between two static bodies
    probe.add_geom(name="probe", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.008, 0, 0],
                   contype=0, conaffinity=0)
    tissues = partner_tissue_geoms(spec)
    for name in tissues:
        spec.add_pair(geomname1="probe", geomname2=name)
    model = spec.compile()
    data = mujoco.MjData(model)
    little = layout.digits["little"]
    x = 0.5 * (little.cmc_m[0] + little.base_m[0])
    palm, ft = model.geom("hum_tissue_palm").id, np.zeros(6)
    lo, hi = -0.1, 0.0  # y of the probe's centre: far out on the ulnar side .. the mid-line
    for _ in range(60):  # bisect for a 2 mm overlap with the palm at its mid-plane (z = 0)
        y = 0.5 * (lo + hi)
        data.qpos[-7:-4] = [x, y, 0.0]
        mujoco.mj_forward(model, data)
        d = mujoco.mj_geomDistance(model, data, model.geom("probe").id, palm, 0.05, ft)
        lo, hi = (y, hi) if d > -0.002 else (lo, y)
    mujoco.mj_forward(model, data)
    ids = {model.geom(t).id for t in tissues}
    touching = [c for c in data.contact[:data.ncon] if set(c.geom) & ids]
    assert len(touching) == 1, [(model.geom(c.geom[0]).name, model.geom(c.geom[1]).name, c.dist)
                                for c in touching]
    assert touching[0].dist == pytest.approx(-0.002, abs=1e-4)


# ------------------------------------------------------------------------------------------------
# Arms
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("hand", ["prosthetic", "human"])
def test_each_arm_holds_its_wrist_with_its_stated_impedance(hand):
    """A force pushes each wrist, in the air, force / stiffness; a torque turns it torque /
    rot_stiffness (the weld's gains of softhand.hands.scene.add_arm, measured), within 1 %; the
    arms carry their hands' weight (no sag under gravity); press 0 so the rest is the grasp."""
    actuation = "relaxed-human" if hand == "human" else "motors"
    kind = "relaxed" if hand == "human" else "prosthesis-user"
    config = SceneConfig(prosthetic=ProstheticConfig(actuation=actuation),
                         sensored_arm=ArmConfig.of(kind, press_n=0.0),
                         partner_arm=ArmConfig.of("active", press_n=0.0))
    assert config.arm == ArmConfig.of(kind, press_n=0.0)
    model = scene_spec(config).compile()
    data = mujoco.MjData(model)
    for body, arm in (("pro_wrist", config.arm), ("hum_arm", config.partner_arm)):
        b = model.body(body).id
        mujoco.mj_forward(model, data)
        rest = data.xpos[b].copy()
        for _ in range(1500):
            mujoco.mj_step(model, data)
        assert np.linalg.norm(data.xpos[b] - rest) < 1e-6  # weight carried, no drift
        pushes = (((0.0, 2.0, 0.0), (0.0, 0.0, 0.0)), ((1.5, 0.0, -1.0), (0.0, 0.0, 0.0)),
                  ((0.0, 0.0, 0.0), (0.0, 0.1, 0.0)), ((0.0, 0.0, 0.0), (0.08, 0.0, 0.05)))
        for force, torque in pushes:
            mujoco.mj_resetData(model, data)
            mujoco.mj_forward(model, data)
            p0, q0 = data.xpos[b].copy(), data.xquat[b].copy()
            data.xfrc_applied[b, :3], data.xfrc_applied[b, 3:] = force, torque
            for _ in range(4000):
                mujoco.mj_step(model, data)
            turn = np.zeros(3)
            mujoco.mju_subQuat(turn, data.xquat[b], q0)
            if any(force):
                moved = np.linalg.norm(data.xpos[b] - p0)
                assert moved == pytest.approx(np.linalg.norm(force) / arm.stiffness_n_per_m,
                                              rel=0.01), body
            else:
                assert np.linalg.norm(turn) == pytest.approx(
                    np.linalg.norm(torque) / arm.rot_stiffness_nm_per_rad, rel=0.01), body


def test_each_arm_presses_its_palm_with_its_press_force():
    """The anchors lie press / stiffness beyond the hands along their palm normals: the sensored
    arm's spring, held where the hand rests in the grasp, pushes it along +Y (its palm normal)
    with press_n."""
    config = SceneConfig(partner_arm=ArmConfig.of("active", press_n=0.0))
    model = scene_spec(config).compile()
    data = mujoco.MjData(model)
    anchor = model.body("pro_anchor").id
    wrist = model.body("pro_wrist").id
    mujoco.mj_forward(model, data)
    offset = data.xpos[anchor] - data.xpos[wrist]
    np.testing.assert_allclose(offset, [0.0, config.arm.press_n / config.arm.stiffness_n_per_m,
                                        0.0], atol=1e-12)
    # hold the wrist where it rests: the force needed is the press, along -Y
    data.xfrc_applied[wrist, 1] = -config.arm.press_n
    for _ in range(3000):
        mujoco.mj_step(model, data)
    np.testing.assert_allclose(data.xpos[wrist], model.body_pos[wrist], atol=1e-6)


# ------------------------------------------------------------------------------------------------
# One surface per palm: no seam under a finger
# ------------------------------------------------------------------------------------------------

#: Where the prosthetic palm used to be cut into four skins (palmar / dorsal at its borders,
#: proximal / distal at mid-palm): (name, point on the palm in fractions of its bounds, outward
#: normal in the hand frame, the pressing finger's axis). The radial border is the thenar's, a
#: skin of its own on the thumb metacarpal (it moves with the thumb): that seam stays, and is
#: measured in every handshake (`ContactAreas.double_N`).
_FORMER_SEAMS = (
    ("ulnar border, proximal", (0.3, 0.0, 0.5), (0.0, -1.0, 0.0), (1.0, 0.0, 0.0)),
    ("ulnar border, distal", (0.7, 0.0, 0.5), (0.0, -1.0, 0.0), (1.0, 0.0, 0.0)),
    ("palmar face, mid-palm", (0.5, 0.3, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0)),
    ("dorsal face, mid-palm", (0.5, 0.5, 1.0), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
)


@pytest.mark.parametrize("name, where, normal, axis", _FORMER_SEAMS, ids=[s[0] for s in _FORMER_SEAMS])
def test_a_finger_on_a_former_palm_seam_presses_one_skin(name, where, normal, axis):
    """A partner finger (a 9 mm capsule, `constants` finger radii) pressed 2 mm into the
    prosthetic palm where its four skins used to meet makes exactly one contact with the skin,
    2 mm deep: one indentation, one law. With the palm in quarters the borders gave two contacts
    0.1 mm apart, each through a full law (the audit's 20 % of the force counted twice)."""
    spec = build_prosthetic_hand()
    probe = spec.worldbody.add_body(name="probe", mocap=True)
    half = 0.03
    z = np.asarray(axis, float)
    probe.add_geom(name="probe", type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[0.009, half, 0],
                   fromto=[*(-half * z), *(half * z)], contype=0, conaffinity=0)
    skins = [g.name for g in spec.geoms if g.name.startswith("pro_skin_")]
    for s in skins:
        spec.add_pair(geomname1=s, geomname2="probe")
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    palm = model.geom("pro_skin_Palm").id
    verts = model.mesh_vert[model.mesh_vertadr[model.geom_dataid[palm]]:][
        :model.mesh_vertnum[model.geom_dataid[palm]]]
    rot = data.geom_xmat[palm].reshape(3, 3)
    world = data.geom_xpos[palm] + verts @ rot.T  # the hand frame is the world frame here
    lo, hi = world.min(axis=0), world.max(axis=0)
    target = lo + np.asarray(where) * (hi - lo)
    n = np.asarray(normal, float)
    data.mocap_pos[0] = target + 0.05 * n
    ft = np.zeros(6)
    for _ in range(3):  # move the finger along the normal until it is 2 mm into the palm
        mujoco.mj_kinematics(model, data)
        dist = mujoco.mj_geomDistance(model, data, palm, model.geom("probe").id, 0.2, ft)
        data.mocap_pos[0] -= (dist + 0.002) * n
    mujoco.mj_forward(model, data)
    probe_id = model.geom("probe").id
    touched = [(model.geom(int(c.geom1) + int(c.geom2) - probe_id).name, -c.dist)
               for c in (data.contact[i] for i in range(data.ncon))]
    assert len(touched) == 1, (name, touched)
    assert touched[0][0] == "pro_skin_Palm" and touched[0][1] == pytest.approx(0.002, abs=2e-5)


@pytest.mark.parametrize("flex_rad", [0.0, 0.8, 1.4])
def test_a_finger_across_a_knuckle_makes_no_two_contacts_within_a_seam(flex_rad):
    """Issue 35, item 2's knuckles: a partner finger (a 9 mm capsule, 12 mm long, across the
    digit) pressed 2 mm onto each finger and thumb joint of the prosthetic hand (MCP, PIP, DIP;
    the thumb's MCP and IP), from the back and from the palm, straight and flexed, makes no two
    contacts with skins closer than the seam distance (softhand.envs.run.SEAM_M, 2 mm): where it
    touches both sides of a joint those are two indentations, one per phalanx (measured at least
    8.4 mm apart, DIP straight), not one resisted twice. The thenar's seam with the palm is the
    one seam left (test_a_finger_on_a_former_palm_seam_presses_one_skin's docstring)."""
    import itertools

    from softhand.envs.run import SEAM_M

    spec = build_prosthetic_hand()
    probe = spec.worldbody.add_body(name="probe", mocap=True)
    probe.add_geom(name="probe", type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[0.009, 0.006, 0],
                   fromto=[0, -0.006, 0, 0, 0.006, 0], contype=0, conaffinity=0)
    for s in [g.name for g in spec.geoms if g.name.startswith("pro_skin_")]:
        spec.add_pair(geomname1=s, geomname2="probe")
    model = spec.compile()
    data = mujoco.MjData(model)
    probe_id = model.geom("probe").id
    skins = [g for g in range(model.ngeom) if model.geom(g).name.startswith("pro_skin_")]
    for j in range(model.njnt):  # every flexing joint flexed (inside its range); rotation kept
        if (model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE
                and not model.joint(j).name.endswith("rot")):
            lo, hi = model.jnt_range[j]
            data.qpos[model.jnt_qposadr[j]] = np.clip(flex_rad, lo, hi)
    joints = [b for b in range(model.nbody)
              if model.body(b).name.endswith(("_proximal", "_middle", "_distal"))]
    assert len(joints) == 14
    ft, quat = np.zeros(6), np.zeros(4)
    pressed = 0
    for b, side in itertools.product(joints, (1.0, -1.0)):
        mujoco.mj_kinematics(model, data)
        rot = data.xmat[b].reshape(3, 3)
        normal = side * rot[:, 2]  # the segment's back (+) or palm (-) at its joint
        mujoco.mju_mat2Quat(quat, rot.flatten())
        data.mocap_quat[0] = quat  # the probe's axis along the joint's, across the digit
        data.mocap_pos[0] = data.xpos[b] + 0.05 * normal
        for _ in range(12):  # move the finger in until it is 2 mm into the nearest skin
            mujoco.mj_kinematics(model, data)
            dist = min(mujoco.mj_geomDistance(model, data, g, probe_id, 0.2, ft) for g in skins)
            data.mocap_pos[0] -= (dist + 0.002) * normal
        mujoco.mj_forward(model, data)
        contacts = [(int(c.geom1) + int(c.geom2) - probe_id, c.pos.copy(), -c.dist)
                    for c in (data.contact[i] for i in range(data.ncon))]
        where = f"{model.body(b).name}, {'back' if side > 0 else 'palm'}"
        pressed += bool(contacts) and max(c[2] for c in contacts) >= 0.0019
        for a, c in itertools.combinations(contacts, 2):
            if a[0] != c[0]:
                assert np.linalg.norm(a[1] - c[1]) >= SEAM_M, (where, model.geom(a[0]).name,
                                                             model.geom(c[0]).name)
    assert pressed == 28, pressed  # every joint, back and palm, pressed 2 mm into a skin


@pytest.mark.slow
@pytest.mark.xfail(strict=True, raises=AssertionError, reason=(
    "issue 35: the sensored hand has no wrist, and the partner's index middle phalanx presses "
    "the palm's proximal end from behind it (11.0 % of the force between the hands at seed 0, "
    "8.5-11.2 % at seeds 1-4); a skin over the wrist takes it to 0.5 % but waits for tissue "
    "data or FE beyond 11.6 N (item 5; docs/handshake.md, 'A path no hand has')"))
def test_no_partner_finger_presses_the_sensored_hand_from_behind_its_palm():
    """The default handshake (neutral, seed 0): the share of the force between the hands that
    presses the sensored palm's skin within 12 mm of the crease, from behind the palm (where a
    wrist would be), under 1 %. Expected to fail while the palm ends 0-7 mm past the crease
    with nothing behind it (strict: it fails the suite once it passes, so that the mark comes
    off)."""
    from softhand.envs.controllers import make_controller
    from softhand.envs.handshake import HandshakeEnv

    env = HandshakeEnv()
    ctrl = make_controller("neutral")
    obs, info = env.reset(seed=0)
    m, d = env.model, env.data
    skin, palm = m.geom("pro_skin_Palm").id, m.body("pro_palm").id
    f = np.zeros(6)
    total = behind = 0.0
    done = False
    while not done:
        obs, _, term, trunc, info = env.step(ctrl(obs, info))
        done = term or trunc
        for i in range(d.ncon):
            c = d.contact[i]
            names = m.geom(c.geom1).name + m.geom(c.geom2).name
            if "pro_" not in names or "hum_" not in names:
                continue
            mujoco.mj_contactForce(m, d, i, f)
            total += f[0]
            if skin in (c.geom1, c.geom2):
                local = d.xmat[palm].reshape(3, 3).T @ (c.pos - d.xpos[palm])
                behind += f[0] if local[0] < 0.012 else 0.0
    env.close()
    assert total > 0
    assert behind / total < 0.01, behind / total
