"""softhand skin apply: a calibrated skin on the geoms of an MJCF hand softhand did not build.

The hand is tests/data/menagerie_style_hand.xml, written by hand in the style of MuJoCo Menagerie
(default classes, a fixed tendon and joint equalities coupling the finger joints, position
actuators). A plate (mocap) presses the skinned fingertip along the distal phalanx at 0.5 mm/s,
the FE's speed, in two postures; the force at each penetration is compared with the design's FE
loading curve up to 2 N.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from softhand.paths import FE_DIR
from softhand.skin.apply import apply_skin, skin_law_error, write_skinned
from softhand.skin.calibrate import fe_curves
from softhand.skin.representations import loading_ramp
from softhand.skin.rig import pair_law_values

HAND = Path(__file__).resolve().parent / "data" / "menagerie_style_hand.xml"


def _press(model: mujoco.MjModel, geom: str, flexion: float) -> tuple[np.ndarray, np.ndarray]:
    """Close the index finger to ``flexion`` (its tendon servo's target / 2, rad), let it settle,
    then press the plate onto the tip along the distal phalanx at 0.5 mm/s until 2.2 N. Returns
    the pair's penetration (mm) and normal force (N) while it touches."""
    data = mujoco.MjData(model)
    data.ctrl[model.actuator("index").id] = 2 * flexion
    for _ in range(1500):
        mujoco.mj_step(model, data)
    g, plate = model.geom(geom).id, model.geom("plate").id
    body = model.geom_bodyid[g]
    rot = data.xmat[body].reshape(3, 3)
    axis = rot[:, 0]
    tip = data.xpos[body] + axis * 0.016  # the distal capsule ends 16 mm from the DIP
    start = tip + axis * (model.geom_size[g][0] + 0.002 + 0.001)
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.column_stack([rot[:, 2], np.cross(axis, rot[:, 2]),
                                              axis]).ravel())
    data.mocap_quat[0] = quat
    depth, force, f6 = [], [], np.zeros(6)
    t = 0.0
    while t < 12.0:
        t += model.opt.timestep
        data.mocap_pos[0] = start - axis * 5e-4 * t
        mujoco.mj_step(model, data)
        f, pen = 0.0, 0.0
        for i in range(data.ncon):
            c = data.contact[i]
            if plate in (c.geom1, c.geom2):
                assert g in (c.geom1, c.geom2), "the plate touched another geom"
                mujoco.mj_contactForce(model, data, i, f6)
                f, pen = f + f6[0], max(pen, -c.dist)
        if f > 0:
            depth.append(1e3 * pen)
            force.append(f)
        if f > 2.2:
            break
    return np.array(depth), np.array(force)


def _rms_pct_of_2n(design: str, depth: np.ndarray, force: np.ndarray) -> float:
    _, d, f = loading_ramp(fe_curves(design, FE_DIR)[0][0])
    keep = force <= 2.0
    ref = np.interp(depth[keep], d, f)
    return float(100 * np.sqrt(np.mean((force[keep] - ref) ** 2)) / 2.0)


@pytest.mark.parametrize("design, max_force, bound", [
    ("solid-pu", None, 3.0),     # measured 0.92 / 0.90 % (law vs FE up to 2 N: 0.9 %)
    ("pocket2-sil", 5.0, 3.0),   # measured 1.49 / 1.51 % (the shipped 0-20 N law: 3.86 %)
])
def test_skinned_fingertip_reproduces_the_fe_loading_curve_in_two_postures(tmp_path, design,
                                                                         max_force, bound):
    """The written MJCF, loaded with plain MuJoCo: the plate's force at each penetration follows
    the design's FE loading curve within 3 % RMS of 2 N, extended and flexed (the law is
    mass-compensated per pair, so the finger's posture and masses do not change it)."""
    spec = mujoco.MjSpec.from_file(str(HAND))
    skinned = apply_skin(spec, [f"index_tip={design}"], max_force_N=max_force)
    assert [s.pairs for s in skinned] == [("skin_index_tip__plate",)]
    path = write_skinned(spec, skinned, HAND, tmp_path / "skinned.xml")
    model = mujoco.MjModel.from_xml_path(str(path))  # plain MuJoCo, no softhand
    assert model.geom_contype[model.geom("index_tip").id] == 0
    errors = []
    for flexion in (0.0, 0.7):
        depth, force = _press(model, "index_tip", flexion)
        assert force.max() > 2.0 and (force <= 2.0).sum() > 100
        errors.append(_rms_pct_of_2n(design, depth, force))
        # the simulated force is the law's at the penetration, to 0.1 % of 2 N
        law = skinned[0].law.force(depth)
        assert np.sqrt(np.mean((force - law) ** 2)) < 0.002
    assert max(errors) < bound, errors
    assert skin_law_error(design, skinned[0].law) < bound


def test_default_counterparts_are_the_collidable_geoms_outside_the_hand():
    spec = mujoco.MjSpec.from_file(str(HAND))
    skinned = apply_skin(spec, {"index_tip": "pocket2-pu", "thumb_tip": "solid-sil@rigid"})
    assert {s.geom: s.pairs for s in skinned} == {
        "index_tip": ("skin_index_tip__plate",), "thumb_tip": ("skin_thumb_tip__plate",)}
    assert skinned[1].law is None  # rigid: the stock contact, kept as a pair
    self_contact = apply_skin(mujoco.MjSpec.from_file(str(HAND)), ["index_tip=pocket2-pu"],
                              against=["palm_collision", "plate"])
    assert self_contact[0].pairs == ("skin_index_tip__palm_collision", "skin_index_tip__plate")


@pytest.mark.parametrize("geoms, kwargs, needle", [
    (["nope=pocket2-sil"], {}, "geom 'nope' is not in the model"),
    (["index_tip=pocket9-sil"], {}, "skin 'pocket9-sil' for geom index_tip is unknown"),
    (["index_tip=pocket2-sil@flex"], {}, "representation 'flex' for geom index_tip"),
    (["index_tip=pocket2-sil@jelly"], {}, "representation 'jelly' is unknown"),
    (["index_tip"], {}, "expected GEOM=DESIGN"),
    (["index_tip=pocket2-sil"], {"max_force_N": 50.0}, "max_force_N = 50.0"),
    (["index_tip=pocket2-sil"], {"against": ["floor"]}, "--against geom 'floor'"),
    ([], {}, "no geom to skin"),
])
def test_bad_input_names_the_value_and_changes_nothing(geoms, kwargs, needle):
    spec = mujoco.MjSpec.from_file(str(HAND))
    before = spec.to_xml()
    with pytest.raises(ValueError, match=needle.replace("(", r"\(").replace("[", r"\[")):
        apply_skin(spec, geoms, **kwargs)
    assert spec.to_xml() == before


def test_each_pair_takes_the_law_of_its_contact_class():
    """A round skinned geom (a fingertip capsule) pressed by the box plate takes the shipped plate
    law; pressed by a finger-sized capsule (the hand's own thumb, named with --against), the
    skin's finger law, softer at equal depth (FE: 0.72-0.81x the plate's for pocket2-sil). The
    choice is recorded per pair."""
    from softhand.skin.files import load_calibration

    spec = mujoco.MjSpec.from_file(str(HAND))
    (tip,) = apply_skin(spec, {"index_tip": "pocket2-sil"}, against=["plate", "thumb_tip"])
    assert tip.pair_laws == {"skin_index_tip__plate": "phalanx/flat",
                             "skin_index_tip__thumb_tip": "phalanx/finger"}
    from softhand.paths import SKINS_DIR
    from softhand.skin.apply import _class_law

    cal = load_calibration("pocket2-sil")
    key, finger = _class_law("pocket2-sil", "phalanx/finger", None, SKINS_DIR)
    assert key == "phalanx/finger"
    # at 2-3 mm, where both 0-20 N soft contacts follow their laws (below 1 mm a single soft
    # contact cannot follow a pocket's soft start: docs/mujoco.md, "What one soft contact can and cannot do")
    d = np.array([2.0, 2.5, 3.0])
    assert np.all(finger.force(d) < cal.soft_contact.force(d))
    model = spec.compile()
    for name, law in (("skin_index_tip__plate", cal.soft_contact),
                      ("skin_index_tip__thumb_tip", finger)):
        solref, solimp = pair_law_values(model, name, law)
        np.testing.assert_allclose(spec.pair(name).solref, solref, rtol=1e-12)
        np.testing.assert_allclose(spec.pair(name).solimp, solimp, rtol=1e-12)


def test_a_pairs_law_follows_the_skin_whatever_the_pairs_geom_order():
    """MuJoCo's compiler puts a world geom first in a pair: a fingertip pressed by a box fixed
    to the world (a table, a fixed plate) still takes the fingertip's plate law (phalanx/flat),
    not the law of a palm pressed by a finger, with the same solref/solimp as the same box on a
    mocap body."""
    spec = mujoco.MjSpec.from_file(str(HAND))
    spec.worldbody.add_geom(name="table", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.05, 0.05, 0.01],
                            pos=[0.0, 0.0, -0.3])
    (tip,) = apply_skin(spec, {"index_tip": "pocket2-sil"}, against=["plate", "table"])
    model = spec.compile()
    pid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_PAIR, "skin_index_tip__table")
    assert model.geom(int(model.pair_geom1[pid])).name == "table"  # the order this is about
    assert tip.pair_laws["skin_index_tip__table"] == "phalanx/flat"
    assert tip.pair_laws["skin_index_tip__plate"] == "phalanx/flat"


# --- what skin apply writes: the user's file with only the listed changes ------------------

#: A user's hand in their own style: a leading comment and comments between elements, tab
#: indentation, attributes in an unusual order, on several lines and in single quotes, default
#: classes, an include (the plate), a character reference, and a <contact> section of its own.
USER_HAND = """<?xml version="1.0" encoding="utf-8"?>
<!-- my hand: keep this comment -->
<mujoco model='user hand'>
\t<compiler autolimits="true" angle="radian"/>
\t<option cone="elliptic" timestep="0.002"/>
\t<default>
\t\t<default class="skin">
\t\t\t<geom type="capsule" contype="1" conaffinity="1" friction="0.7 0.01 0.001"/>
\t\t</default>
\t</default>

\t<worldbody>
\t\t<!-- the finger -->
\t\t<body pos="0 0 0.5" name="finger">
\t\t\t<joint axis="0 1 0" name="mcp" damping="0.05" range="-0.3 1.6"/>
\t\t\t<geom size="0.009" fromto="0 0 0 0.04 0 0" mass="0.03" class="skin" name="proximal"/>
\t\t\t<body name="distal" pos="0.04 0 0">
\t\t\t\t<joint name="dip" axis="0 1 0" damping="0.05" range="0 1.2"/>
\t\t\t\t<geom mass="0.03"
\t\t\t\t      name='tip'   class='skin'
\t\t\t\t      fromto='0 0 0 0.02 0 0' size='0.0075'   contype='1'/>
\t\t\t</body>
\t\t</body>
\t</worldbody>
\t<include file="plate_part.xml"/>

\t<contact>
\t\t<!-- the user's own exclusion &#169; -->
\t\t<exclude body1="finger" body2="distal"/>
\t</contact>
\t<actuator><position joint="mcp" kp="3" name="mcp"/></actuator>
</mujoco>
"""

PLATE_PART = """<mujoco>
  <worldbody>
    <body name="plate" mocap="true" pos="0.3 0 0.5">
      <geom name="plate" type="box" size="0.006 0.006 0.002"/>
    </body>
  </worldbody>
</mujoco>
"""


def _user_hand(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "plate_part.xml").write_text(PLATE_PART)
    path = folder / "user_hand.xml"
    path.write_text(USER_HAND)
    return path


def _tree(path: Path):
    import xml.etree.ElementTree as ET

    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    return ET.parse(path, parser=parser).getroot()


def _same_tree(a, b, where="mujoco") -> None:
    """Tags, attributes in order, comments and non-blank text equal, recursively."""
    assert a.tag == b.tag, where
    assert list(a.attrib.items()) == list(b.attrib.items()), where
    assert (a.text or "").strip() == (b.text or "").strip(), where
    assert len(a) == len(b), where
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        _same_tree(x, y, f"{where}/{getattr(x.tag, '__name__', x.tag)}[{i}]")


def test_written_file_is_the_source_with_only_the_listed_changes(tmp_path):
    """Parsed, the output is the input plus the pairs and the skinned geoms' flags; as text,
    every line outside the header comment, the changed geom tags and the new pairs is the
    input's, in order; the changes listed are exactly those."""
    import difflib

    source = _user_hand(tmp_path)
    spec = mujoco.MjSpec.from_file(str(source))
    skinned = apply_skin(spec, ["tip=pocket2-sil", "proximal=solid-pu"])
    written = write_skinned(spec, skinned, source, tmp_path / "skinned.xml")
    assert [str(c) for c in written.changes] == [
        '<geom name="tip">: contype 1 -> 0, conaffinity 1 -> 0 (it touches its counterparts '
        'only through its pairs)',
        '<geom name="proximal">: contype 1 -> 0, conaffinity 1 -> 0 (it touches its '
        'counterparts only through its pairs)',
        '<pair name="skin_tip__plate">: added: tip against plate, pocket2-sil soft contact, '
        'phalanx/flat law',
        '<pair name="skin_proximal__plate">: added: proximal against plate, solid-pu soft '
        'contact, phalanx/flat law']
    # parsed: undo the documented changes on the output, then it is the input
    before, after = _tree(source), _tree(written.path)
    for geom in after.iter("geom"):
        if geom.get("name") == "tip":  # contype was written (in place), conaffinity added
            assert list(geom.attrib)[-2:] == ["contype", "conaffinity"]
            assert geom.get("contype") == geom.get("conaffinity") == "0"
            geom.set("contype", "1")
            del geom.attrib["conaffinity"]
        if geom.get("name") == "proximal":
            assert list(geom.attrib)[-2:] == ["contype", "conaffinity"]
            del geom.attrib["contype"], geom.attrib["conaffinity"]
    (contact,) = after.findall("contact")
    pairs = contact.findall("pair")
    assert [(p.get("name"), p.get("geom1"), p.get("geom2")) for p in pairs] == [
        ("skin_tip__plate", "tip", "plate"), ("skin_proximal__plate", "proximal", "plate")]
    for p in pairs:
        np.testing.assert_array_equal(np.fromstring(p.get("solref"), sep=" "),
                                      spec.pair(p.get("name")).solref)
        contact.remove(p)
    _same_tree(before, after)
    # as text: the diff holds the header comment, the two geom lines and the pairs, no more
    old = source.read_text().splitlines()
    new = written.path.read_text().splitlines()
    head_end = new.index("-->")
    assert new[head_end + 1:head_end + 3] == old[1:3] and new[0] == old[0]  # declaration kept
    changed = []
    for op, i1, i2, j1, j2 in difflib.SequenceMatcher(None, old, new, autojunk=False).get_opcodes():
        if op == "equal":
            continue
        changed += [("-", line) for line in old[i1:i2]] + [("+", j, new[j]) for j in range(j1, j2)]
    removed = [c[1] for c in changed if c[0] == "-"]
    added = [c[1:] for c in changed if c[0] == "+"]
    assert removed == [
        '\t\t\t<geom size="0.009" fromto="0 0 0 0.04 0 0" mass="0.03" class="skin" name="proximal"/>',
        "\t\t\t\t      fromto='0 0 0 0.02 0 0' size='0.0075'   contype='1'/>"]
    # the header: one comment block right after the XML declaration
    assert [j for j, _ in added[:head_end]] == list(range(1, head_end + 1))
    outside_header = [line for j, line in added if j > head_end]
    assert outside_header[:2] == [
        '\t\t\t<geom size="0.009" fromto="0 0 0 0.04 0 0" mass="0.03" class="skin" name="proximal"'
        ' contype="0" conaffinity="0"/>',
        "\t\t\t\t      fromto='0 0 0 0.02 0 0' size='0.0075'   contype='0' conaffinity='0'/>"]
    assert len(outside_header) == 4  # and the two pairs, after the user's <exclude>
    assert all(line.startswith('\t\t<pair name="skin_') for line in outside_header[2:])
    assert new[new.index(outside_header[2]) - 1] == '\t\t<exclude body1="finger" body2="distal"/>'
    # the file loads in plain MuJoCo and is the skinned model
    model = mujoco.MjModel.from_xml_path(str(written.path))
    assert model.geom_contype[model.geom("tip").id] == 0
    assert model.npair == 2 and model.nexclude == 1


def test_a_file_written_elsewhere_gets_absolute_paths_and_says_so(tmp_path):
    source = _user_hand(tmp_path / "src")
    mesh = tmp_path / "src" / "meshes"
    mesh.mkdir()
    (mesh / "knob.obj").write_text("v 0 0 0\nv 0.01 0 0\nv 0 0.01 0\nv 0 0 0.01\n"
                                   "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    text = source.read_text().replace(
        "\t<worldbody>", '\t<asset><mesh name="knob" file="meshes/knob.obj"/></asset>\n'
        '\t<worldbody>\n\t\t<geom type="mesh" mesh="knob" pos="0 0.3 0" contype="0" '
        'conaffinity="0"/>')
    source.write_text(text)
    spec = mujoco.MjSpec.from_file(str(source))
    skinned = apply_skin(spec, ["tip=solid-pu"])
    written = write_skinned(spec, skinned, source, tmp_path / "elsewhere" / "skinned.xml")
    src = (tmp_path / "src").resolve()
    assert [str(c) for c in written.changes][-2:] == [
        f'<include file="plate_part.xml">: file made absolute: {src / "plate_part.xml"}',
        f"<compiler>: meshdir added: {src} (the source's folder, where its relative asset "
        "files are)"]
    model = mujoco.MjModel.from_xml_path(str(written.path))
    assert model.nmesh == 1 and model.npair == 1


def test_a_geom_only_in_an_included_file_is_refused_before_any_work(tmp_path):
    from softhand.skin.apply import check_skinnable

    source = _user_hand(tmp_path)
    with pytest.raises(ValueError, match=r"geom 'plate' is not written by name in "
                                         r"user_hand.xml \(it is in the included file "
                                         r"'plate_part.xml'\)"):
        check_skinnable(source, ["tip", "plate"])


def test_cli_lists_the_changes_and_writes_them(tmp_path):
    import json

    from click.testing import CliRunner

    from softhand.cli import main

    source = _user_hand(tmp_path)
    out = tmp_path / "skinned.xml"
    res = CliRunner().invoke(main, ["skin", "apply", str(source), str(out),
                                    "--geom", "tip=pocket2-sil"])
    assert res.exit_code == 0, res.output
    lines = res.output.splitlines()
    assert lines[1] == "changed in user_hand.xml (everything else is kept as written):"
    assert lines[2].split() == ['<geom', 'name="tip">', "contype", "1", "->", "0,",
                                "conaffinity", "1", "->", "0", "(it", "touches", "its",
                                "counterparts", "only", "through", "its", "pairs)"]
    assert lines[3].startswith('  <pair name="skin_tip__plate">  added: tip against plate')
    assert lines[-1] == f"wrote {out}"
    assert "warning" not in res.output  # a 2 ms step: the contact is stable (issue 24)
    header = out.read_text().split("-->")[0]
    assert '<pair name="skin_tip__plate">: added: tip against plate' in header
    res = CliRunner().invoke(main, ["skin", "apply", str(source), str(out), "--json",
                                    "--geom", "tip=pocket2-sil"])
    doc = json.loads(res.output)
    assert [c["element"] for c in doc["changes"]] == ['<geom name="tip">',
                                                      '<pair name="skin_tip__plate">']
    res = CliRunner().invoke(main, ["skin", "apply", str(source), str(tmp_path / "x.xml"),
                                    "--geom", "plate=pocket2-sil"])
    assert res.exit_code != 0 and "Traceback" not in res.output
    assert "geom 'plate' is not written by name in user_hand.xml" in res.output
    assert not (tmp_path / "x.xml").exists()


def test_skinning_a_geom_of_the_world_says_why_nothing_is_left_to_press_it():
    """A skin on a world geom (a floor plane) made every geom of the model part of the "hand",
    and the message said "no collidable geom outside the hand"; now it says the skinned geoms
    meet only in the world body and points at --against (with which it works)."""
    import mujoco

    from softhand.skin.apply import apply_skin

    xml = """<mujoco><worldbody><geom name="floor" type="plane" size="1 1 0.1"/>
      <body name="b" pos="0 0 0.1"><freejoint/><geom name="box" type="box" size=".01 .01 .01"/>
      </body></worldbody></mujoco>"""
    with pytest.raises(ValueError, match=r"the skinned geoms floor meet only in the world body.*"
                                         r"name the counterparts with --against"):
        apply_skin(mujoco.MjSpec.from_string(xml), {"floor": "pocket2-sil"})
    skinned = apply_skin(mujoco.MjSpec.from_string(xml), {"floor": "pocket2-sil"},
                         against=["box"])
    assert [s.geom for s in skinned] == ["floor"]


def test_skin_apply_at_the_scene_s_grasp_gives_each_pair_the_scene_s_class():
    """One path from a pair's geometry to its class (issue 36, item 4): skin apply on the shipped
    handshake scene's MJCF, at its ``grasp`` keyframe, gives each pair of the palm's skin and a
    partner tissue geom the class the scene gave the same pair (`softhand.envs.skins
    .pair_choices`: the border's, at the finger's crossing, where the grasp puts the finger on
    the palm's rounded border; the geoms' otherwise), and its law; at qpos0, where the partner's
    hand lies elsewhere, no pair is a border's."""
    from softhand.envs.skins import GRASP_KEY, pair_choices, parse_skins
    from softhand.paths import SKINS_DIR
    from softhand.skin.apply import _class_law

    xml = Path(__file__).resolve().parents[1] / "models" / "mjcf" / "handshake_scene.xml"
    scene = mujoco.MjModel.from_xml_path(str(xml))
    choices = pair_choices(scene, parse_skins()[0])
    palm = {}
    for pid in range(scene.npair):
        g1, g2 = (scene.geom(int(g)).name for g in (scene.pair_geom1[pid], scene.pair_geom2[pid]))
        if "pro_skin_Palm" in (g1, g2):
            palm[g2 if g1 == "pro_skin_Palm" else g1] = choices[scene.pair(pid).name].contact
    assert len(palm) >= 10
    borders = {o for o, key in palm.items() if key.startswith("border/finger")}
    assert {f"hum_tissue_{f}_proximal" for f in ("index", "middle", "ring", "little")} <= borders
    assert {"border/finger@60", "border/finger@30"} <= set(palm.values())

    spec = mujoco.MjSpec.from_file(str(xml))
    (skin,) = apply_skin(spec, {"pro_skin_Palm": "pocket2-sil"}, against=list(palm),
                         keyframe=GRASP_KEY)
    got = {name.removeprefix("skin_pro_skin_Palm__"): law
           for name, law in skin.pair_laws.items()}
    assert got == palm  # each the class's own law: pocket2-sil has every class
    model = spec.compile()
    for other, key in palm.items():
        name = f"skin_pro_skin_Palm__{other}"
        want = pair_law_values(model, name, _class_law("pocket2-sil", key, None, SKINS_DIR)[1])
        np.testing.assert_allclose(spec.pair(name).solref, want[0], rtol=1e-12)

    spec = mujoco.MjSpec.from_file(str(xml))
    (skin,) = apply_skin(spec, {"pro_skin_Palm": "pocket2-sil"}, against=list(palm))
    assert not any(k.startswith("border") for k in skin.pair_laws.values())


def test_a_skin_without_a_border_law_takes_the_scene_s_fallback_and_says_so(tmp_path):
    """A skin with no border laws (a design search's winner has none): its border pairs take the
    law the scene would give them (`softhand.skin.contact_classes.law_class`: the palm face's),
    and the written file's header names the class and the law it took instead."""
    import json

    from softhand.envs.skins import GRASP_KEY
    from softhand.paths import SKINS_DIR

    cal = json.loads((SKINS_DIR / "pocket2-sil.json").read_text())
    cal["pair_laws"] = {k: v for k, v in cal["pair_laws"].items() if not k.startswith("border")}
    skins = tmp_path / "skins"
    skins.mkdir()
    (skins / "pocket2-sil.json").write_text(json.dumps(cal))
    xml = Path(__file__).resolve().parents[1] / "models" / "mjcf" / "handshake_scene.xml"
    spec = mujoco.MjSpec.from_file(str(xml))
    against = ["hum_tissue_index_proximal", "hum_tissue_little_proximal", "hum_tissue_palm"]
    (skin,) = apply_skin(spec, {"pro_skin_Palm": "pocket2-sil"}, against=against,
                         keyframe=GRASP_KEY, skins_dir=skins)
    laws = {name.removeprefix("skin_pro_skin_Palm__"): law for name, law in skin.pair_laws.items()}
    assert laws["hum_tissue_index_proximal"] == "border/finger@60: palm/finger law"
    assert laws["hum_tissue_little_proximal"] == "border/finger@30: palm/finger law"
    assert laws["hum_tissue_palm"] == "palm/flat"
    written = write_skinned(spec, [skin], xml, tmp_path / "out.xml")
    text = written.path.read_text()
    assert "pocket2-sil soft contact, border/finger@60: palm/finger law" in text
    assert "law law" not in text
