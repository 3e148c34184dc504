"""The handshake recording: what is written to the .rrd, read back with rerun's RrdReader."""

from __future__ import annotations

import dataclasses
import time

import mujoco
import numpy as np
import pytest
import rerun as rr
from rerun.chunk import RrdReader

from softhand.hands import regions, scene_spec
from softhand.paper import paper
from softhand.viz import (
    HandshakeFrames,
    force_colors,
    read_recording_summary,
    record_handshake,
    recording,
)

REGIONS = tuple(paper()["handshake"]["regions"])
N_FRAMES = 100


@pytest.fixture(scope="module")
def model() -> mujoco.MjModel:
    return scene_spec().compile()


def synthetic_frames(model: mujoco.MjModel, n: int) -> HandshakeFrames:
    """qpos0 with the index MCP flexing, the partner base shaking at 4 Hz, sine forces."""
    t = np.arange(n) * 0.01
    qpos = np.tile(model.qpos0, (n, 1))
    qpos[:, model.joint("pro_index_mcp").qposadr[0]] = 0.6 * (1 - np.cos(2 * np.pi * t))
    mocap_pos = np.tile(model.body_pos[model.body("hum_base").id], (n, 1, 1))
    mocap_pos[:, 0, 2] += 0.01 * np.sin(2 * np.pi * 4.0 * t)
    mocap_quat = np.tile(model.body_quat[model.body("hum_base").id], (n, 1, 1))
    k = np.arange(len(REGIONS))
    forces = 2.5 + 2.5 * np.sin(2 * np.pi * t[:, None] + k[None, :])
    contacts = []
    for i in range(n):
        m = i % 4  # 0 to 3 contacts per frame
        c = np.zeros((m, 7))
        c[:, 0] = 0.3 + 0.01 * np.arange(m)
        c[:, 4] = 1.0
        c[:, 6] = 1.0 + i / n
        contacts.append(c)
    phases = ["reach", "grip", "shake", "release"]
    return HandshakeFrames(
        time_s=t,
        qpos=qpos,
        mocap_pos=mocap_pos,
        mocap_quat=mocap_quat,
        region_force_N=forces,
        region_names=REGIONS,
        skin_designs={r: ("rigid" if r.startswith("Back") else "pocket2-sil") for r in REGIONS},
        contacts=contacts,
        phase=[phases[4 * i // n] for i in range(n)],
        sensor_reading_N=0.35 * forces,
        sensor_placements=dict.fromkeys(REGIONS, "interface"),
    )


@pytest.fixture(scope="module")
def recorded(model, tmp_path_factory):
    path = tmp_path_factory.mktemp("rrd") / "handshake.rrd"
    frames = synthetic_frames(model, N_FRAMES)
    assert record_handshake(path, model, frames) == path
    return path, frames


@pytest.fixture(scope="module")
def summary(recorded):
    return read_recording_summary(recorded[0])


def test_file_is_complete_and_alone(recorded, summary):
    path, _ = recorded
    assert [p.name for p in path.parent.iterdir()] == ["handshake.rrd"]
    assert len(RrdReader(path).store()) > 0  # the footer/manifest was written
    assert summary["application_id"] == "softhand_handshake"
    assert "sim_time" in summary["timelines"]


def test_region_force_series(summary):
    for region in REGIONS:
        entry = summary["entities"][f"forces/{region}"]
        assert "Scalars:scalars" in entry["temporal"]
        assert entry["sim_time_points"] == N_FRAMES


def test_sensor_series_beside_the_forces(summary):
    """Each region's embedded-sensor reading is its own series, in its own view beside the
    forces' (the blueprint)."""
    for region in REGIONS:
        entry = summary["entities"][f"sensors/{region}"]
        assert "Scalars:scalars" in entry["temporal"]
        assert entry["sim_time_points"] == N_FRAMES


def test_body_transforms_match_mujoco(model, recorded, summary):
    path, frames = recorded
    body = "pro_index_middle"  # moves with the index MCP
    entity = f"world/bodies/{body}"
    assert "Transform3D:translation" in summary["entities"][entity]["temporal"]
    assert summary["entities"][entity]["sim_time_points"] == N_FRAMES
    (chunk,) = [c for c in RrdReader(path).stream() if c.entity_path == "/" + entity]
    batch = chunk.to_record_batch()
    pos = np.array(batch.column("Transform3D:translation").to_pylist()).reshape(-1, 3)
    quat = np.array(batch.column("Transform3D:quaternion").to_pylist()).reshape(-1, 4)
    data = mujoco.MjData(model)
    want_pos, want_quat = np.empty((N_FRAMES, 3)), np.empty((N_FRAMES, 4))
    for i in range(N_FRAMES):
        data.qpos[:] = frames.qpos[i]
        mujoco.mj_kinematics(model, data)
        want_pos[i], want_quat[i] = data.body(body).xpos, data.body(body).xquat[[1, 2, 3, 0]]
    np.testing.assert_allclose(pos, want_pos, atol=1e-6)
    np.testing.assert_allclose(quat, want_quat, atol=1e-6)
    assert np.ptp(pos, axis=0).max() > 0.01  # the finger moves


def test_skin_geometry_labels_and_colours(model, summary):
    info = regions(model, "pro_")["Index1"]
    entry = summary["entities"][f"world/bodies/{info.body}/{info.geom}"]
    assert "Capsules3D:radii" in entry["static"]
    assert "Capsules3D:labels" in entry["static"]
    assert "Capsules3D:colors" in entry["temporal"]
    assert entry["sim_time_points"] == N_FRAMES
    bones = [e for e in summary["entities"] if e.startswith("world/bodies/hum_") and "bone" in e]
    assert bones and all("Capsules3D:lengths" in summary["entities"][e]["static"] for e in bones)


def test_contacts_designs_and_phase(summary):
    points = summary["entities"]["world/contacts/points"]
    assert "Points3D:positions" in points["temporal"]
    assert points["sim_time_points"] == N_FRAMES
    assert "Arrows3D:vectors" in summary["entities"]["world/contacts/normals"]["temporal"]
    text = summary["texts"]["skin/designs"]
    assert "| rigid | Back1, Back2 |" in text  # one row per design, naming its regions
    assert "| pocket2-sil | Thumb1," in text and "prosthetic hand" in text
    assert "partner's hand" in text
    assert summary["entities"]["partner/phase"]["sim_time_points"] == 4  # one per change


def test_hands_are_labelled_and_series_have_distinct_colours(model, tmp_path):
    """Which hand is which is written in the scene; no two regions share a plot colour; a
    region that never carries load stays out of the plot and is named in the text."""
    frames = synthetic_frames(model, 20)
    forces = frames.region_force_N.copy()
    forces[:, 0] = 0.0  # Thumb1 never touched
    frames = dataclasses.replace(frames, region_force_N=forces)
    path = record_handshake(tmp_path / "h.rrd", model, frames)
    summary = read_recording_summary(path)
    hands = summary["entities"]["world/hands"]
    assert "Points3D:labels" in hands["static"] and "Points3D:positions" in hands["temporal"]
    assert "never carry" in summary["texts"]["skin/designs"]
    assert "Thumb1." in summary["texts"]["skin/designs"]
    assert len(set(recording._SERIES_COLOURS)) == len(recording._SERIES_COLOURS) >= len(REGIONS)
    assert recording._loaded(frames) == list(REGIONS[1:])


def test_recording_opens_on_the_contact_phase(model):
    """The time selection spans the frames carrying >= 5 % of the peak total force."""
    frames = synthetic_frames(model, 50)
    forces = np.zeros_like(frames.region_force_N)
    forces[10:30, 3] = np.linspace(0.0, 4.0, 20)
    frames = dataclasses.replace(frames, region_force_N=forces)
    start, end, peak = recording._contact_window(frames)
    assert peak == 29 and end == pytest.approx(frames.time_s[29])
    assert start == pytest.approx(frames.time_s[11])  # 0.21 N >= 0.2 N, the first over 5 %
    eye = recording._eye(model, frames, peak)
    assert eye is not None


def test_force_colors_stand_out_over_2n():
    colors = force_colors(np.array([0.0, 1.9, 2.1, 5.0, 9.0]), max_force_N=5.0)
    assert colors.shape == (5, 4) and colors.dtype == np.uint8
    assert np.all(colors[0, :3] > 190)  # pale at 0 N
    assert colors[1, 2] > colors[1, 0]  # bluish just below 2 N
    warm = colors[2:]
    assert np.all(warm[:, 0] > warm[:, 2])  # reddish above 2 N
    np.testing.assert_array_equal(colors[3], colors[4])  # saturates at max_force_N


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"region_force_N": np.zeros((N_FRAMES, 17))}, "region_force_N"),
        ({"qpos": np.zeros((N_FRAMES - 1, 34))}, "qpos"),
        ({"contacts": []}, "contacts"),
        ({"phase": ["grip"]}, "phase"),
        ({"time_s": np.zeros(N_FRAMES)}, "time_s"),
    ],
)
def test_bad_frames_raise(model, change, message):
    frames = synthetic_frames(model, N_FRAMES)
    with pytest.raises(ValueError, match=message):
        dataclasses.replace(frames, **change)


def test_bad_input_for_the_model_raises(model, tmp_path):
    frames = synthetic_frames(model, 10)
    few = REGIONS[:-1]
    wrong = dataclasses.replace(
        frames,
        region_names=few,
        region_force_N=frames.region_force_N[:, :-1],
        skin_designs={r: "rigid" for r in few},
        sensor_reading_N=frames.sensor_reading_N[:, :-1],
    )
    with pytest.raises(ValueError, match=r"region_names: 17 regions.*missing \['Back2'\]"):
        record_handshake(tmp_path / "a.rrd", model, wrong)
    with pytest.raises(ValueError, match=f"qpos: {model.nq - 1} columns"):
        record_handshake(
            tmp_path / "b.rrd", model, dataclasses.replace(frames, qpos=frames.qpos[:, 1:])
        )
    with pytest.raises(ValueError, match="max_force_N"):
        record_handshake(tmp_path / "c.rrd", model, frames, max_force_N=0.0)
    with pytest.raises(ValueError, match=r"\.rrd"):
        record_handshake(tmp_path / "d.txt", model, frames)
    assert list(tmp_path.iterdir()) == []  # nothing written, no temporary file left


def test_failed_recording_leaves_no_file(model, tmp_path, monkeypatch):
    def fail(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr(recording, "_log_recording", fail)
    with pytest.raises(RuntimeError, match="disk full"):
        record_handshake(tmp_path / "x.rrd", model, synthetic_frames(model, 5))
    assert list(tmp_path.iterdir()) == []


def test_summary_of_a_bad_file_raises(tmp_path):
    (tmp_path / "junk.rrd").write_bytes(b"not a recording")
    with pytest.raises(ValueError, match="not a readable rerun recording"):
        read_recording_summary(tmp_path / "junk.rrd")
    with pytest.raises(FileNotFoundError):
        read_recording_summary(tmp_path / "missing.rrd")


def test_capsule_ends_match_mujoco(model):
    """rerun capsules start at their translation; MuJoCo's are centred on the geom."""
    g = model.geom("hum_bone_index_proximal").id
    archetype, fields = recording._geom_shape(model, g)
    assert archetype is rr.Capsules3D
    start, length = np.asarray(fields["translations"][0]), fields["lengths"][0]
    x, y, z, w = fields["quaternions"][0]
    rot = np.empty(9)
    mujoco.mju_quat2Mat(rot, [w, x, y, z])
    end = start + rot.reshape(3, 3) @ [0.0, 0.0, length]
    half = model.geom_size[g][1] * rot.reshape(3, 3)[:, 2]
    np.testing.assert_allclose(start, model.geom_pos[g] - half, atol=1e-12)
    np.testing.assert_allclose(end, model.geom_pos[g] + half, atol=1e-12)
    assert fields["radii"][0] == model.geom_size[g][0]


def test_recording_time_4000_frames(model, tmp_path, record_property):
    """Not a speed test: reports how long 4000 frames take (run with -s to see it)."""
    frames = synthetic_frames(model, 4000)
    start = time.perf_counter()
    record_handshake(tmp_path / "long.rrd", model, frames)
    seconds = time.perf_counter() - start
    record_property("record_4000_frames_s", seconds)
    print(f"\nrecord_handshake, 4000 frames: {seconds:.2f} s")
    assert (
        read_recording_summary(tmp_path / "long.rrd")["entities"]["forces/Back2"]["sim_time_points"]
        == 4000
    )


def test_pictures_keep_hidden_geoms_hidden_and_wrap_long_captions(tmp_path):
    """A picture recolours each hand's geoms, but a hidden geom (alpha 0: the skin a flex pad
    replaces) stays hidden; a caption longer than the picture is wide wraps onto more lines
    instead of running off both sides."""
    import mujoco
    from PIL import Image

    from softhand.envs.picture import hand_colours
    from softhand.viz.render import _save

    spec = mujoco.MjSpec()
    body = spec.worldbody.add_body(name="b")
    body.add_geom(name="pro_skin_Index3", size=[0.01, 0, 0], rgba=[0, 0, 0, 0])
    body.add_geom(name="pro_skin_Index2", size=[0.01, 0, 0])
    model = spec.compile()
    assert list(hand_colours(model)) == [model.geom("pro_skin_Index2").id]
    pixels = np.full((100, 200, 3), 200, np.uint8)
    _save(tmp_path / "one.png", pixels, "short")
    _save(tmp_path / "three.png", pixels, " ".join(["word"] * 30))
    one, three = (Image.open(tmp_path / f"{n}.png").size for n in ("one", "three"))
    extra = three[1] - one[1]  # 150 characters at 25 a line: 5 more lines of 18 pixels
    assert one[0] == three[0] == 200 and extra == 5 * 18


def test_pictures_by_force_colour_each_region_by_its_force():
    """softhand render and the contact sheet colour the prosthetic's skin by force: a region under
    2 N grey, over 2 N orange to red, skin without a region grey, a hidden skin geom hidden, the
    partner's tissue blue."""
    import mujoco

    from softhand.envs.picture import HAND_COLOURS, region_colours

    spec = mujoco.MjSpec()
    body = spec.worldbody.add_body(name="b")
    for name in ("pro_skin_Palm1", "pro_skin_Back2", "pro_skin_Thenar", "hum_tissue_palm"):
        body.add_geom(name=name, size=[0.01, 0, 0])
    body.add_geom(name="pro_skin_Index3", size=[0.01, 0, 0], rgba=[0, 0, 0, 0])
    model = spec.compile()
    colours = region_colours(model, {"pro_skin_Palm1": 1.0, "pro_skin_Back2": 6.0,
                                     "pro_skin_Index3": 6.0})
    gid = lambda n: model.geom(n).id  # noqa: E731
    r, g, b, _ = colours[gid("pro_skin_Palm1")]
    assert max(r, g, b) - min(r, g, b) < 0.05  # grey
    r, g, b, _ = colours[gid("pro_skin_Back2")]
    assert r > 0.6 and g < 0.3 and b < 0.3  # red
    assert colours[gid("pro_skin_Thenar")][:3] == (0.75, 0.75, 0.75)
    assert gid("pro_skin_Index3") not in colours
    assert np.allclose(colours[gid("hum_tissue_palm")][:3], HAND_COLOURS["hum_tissue_"][:3])



def test_write_video_is_a_looping_gif_of_the_frames_and_refuses_bad_input(tmp_path):
    """`write_video`: every frame in order at the given rate, one palette, looping; bad input
    named before anything is written."""
    from PIL import Image

    from softhand.viz.render import write_video

    rng = np.random.default_rng(0)
    frames = [np.full((24, 32, 3), (20 * i, 100, 200 - 20 * i), np.uint8) for i in range(5)]
    frames[2][:, :8] = rng.integers(0, 255, (24, 8, 3), dtype=np.uint8)  # some texture
    path = write_video(frames, tmp_path / "hs.gif", fps=12.5)
    with Image.open(path) as gif:
        assert gif.n_frames == 5 and gif.info["duration"] == 80 and gif.info["loop"] == 0
        for i in (0, 4):
            gif.seek(i)
            got = np.asarray(gif.convert("RGB"))
            assert np.abs(got.astype(int) - frames[i]).max() <= 8, i  # palette rounding only
    for kwargs, match in (({"frames": [], "fps": 10}, "at least one picture"),
                          ({"frames": [frames[0], frames[0][:10]], "fps": 10}, "one size"),
                          ({"frames": frames, "fps": 0}, r"fps = 0: expected a number in \(0, 100\]")):
        with pytest.raises(ValueError, match=match):
            write_video(path=tmp_path / "bad.gif", **kwargs)
    assert not (tmp_path / "bad.gif").exists()
    with pytest.raises(ValueError, match=r"\.gif"):
        write_video(frames, tmp_path / "hs.png", fps=10)


def _per_frame(path, entity: str, field: str) -> dict[int, object]:
    """sim_time (ns) -> the value of a temporal component ``field`` (e.g. ``show_labels``) of
    ``entity``, read back from the .rrd."""
    reader = RrdReader(path)
    values: dict[int, object] = {}
    for chunk in reader.stream(store=reader.recordings()[0]):
        if chunk.entity_path.lstrip("/") != entity or chunk.is_static:
            continue
        batch = chunk.to_record_batch()
        column = next(c for c in batch.schema.names if c.endswith(f":{field}"))
        times = batch.column("sim_time").to_numpy(zero_copy_only=False).astype("int64")
        for t, v in zip(times.tolist(), batch.column(column).to_pylist(), strict=True):
            values[t] = v[0] if isinstance(v, list) else v
    return values


def test_region_labels_show_only_on_the_few_most_loaded(model, tmp_path):
    """A phalanx's name shows only at frames where it carries STANDOUT_FORCE_N or more and is
    among the LABELLED_MAX most loaded such phalanges; a palm zone (a mesh, no label) does not
    take a place."""
    frames = synthetic_frames(model, 4)
    forces = np.zeros((4, len(REGIONS)))
    col = {r: REGIONS.index(r) for r in REGIONS}
    forces[1, col["Index1"]] = 3.0  # alone over 2 N
    forces[1, col["Index2"]] = 1.9  # under: no label
    for r, f in {"Index1": 2.5, "Index2": 6.0, "Middle1": 5.0, "Ring1": 4.0, "Little1": 3.0,
                 "Palm1": 9.0}.items():
        forces[2, col[r]] = f  # five phalanges over 2 N: the three most loaded labelled
    frames = dataclasses.replace(frames, region_force_N=forces)
    path = record_handshake(tmp_path / "labels.rrd", model, frames)
    info = regions(model, "pro_")
    ns = np.round(frames.time_s * 1e9).astype("int64").tolist()
    want = {"Index1": [False, True, False, False], "Index2": [False, False, True, False],
            "Middle1": [False, False, True, False], "Ring1": [False, False, True, False],
            "Little1": [False, False, False, False], "Thumb1": [False] * 4}
    for region, shown in want.items():
        got = _per_frame(path, f"world/bodies/{info[region].body}/{info[region].geom}",
                         "show_labels")
        assert [bool(got[t]) for t in ns] == shown, region
    static = read_recording_summary(path)["entities"]
    entry = static[f"world/bodies/{info['Index1'].body}/{info['Index1'].geom}"]
    assert not any(c.endswith(":show_labels") for c in entry["static"])  # would override
    assert recording.LABELLED_MAX == 3


def test_plot_legends_are_hidden(recorded):
    """Both time-series views (forces, sensors) hide their legends, which covered the lines."""
    reader = RrdReader(recorded[0])
    legends, views = [], []
    for chunk in reader.stream(store=reader.blueprints()[0]):
        batch = chunk.to_record_batch()
        if "PlotLegend:visible" in batch.schema.names:
            legends += [v[0] for v in batch.column("PlotLegend:visible").to_pylist()]
        if "ViewBlueprint:class_identifier" in batch.schema.names:
            views += [v[0] if isinstance(v, list) else v
                      for v in batch.column("ViewBlueprint:class_identifier").to_pylist()]
    assert views.count("TimeSeries") == 2
    assert legends == [False, False]


def test_mid_shake_is_read_from_the_recording(model, recorded, tmp_path):
    """Halfway between the start of the shake and the next phase; the last time when the shake
    ends the recording; a clear error when there is no shake."""
    path, _ = recorded
    assert read_recording_summary(path)["phases"] == [
        (0.0, "reach"), (0.25, "grip"), (0.5, "shake"), (0.75, "release")]
    assert recording.mid_shake_s(path) == pytest.approx(0.625)
    short = synthetic_frames(model, 10)
    last = record_handshake(tmp_path / "last.rrd", model, dataclasses.replace(
        short, phase=["grip"] * 4 + ["shake"] * 6))
    assert recording.mid_shake_s(last) == pytest.approx(0.5 * (0.04 + 0.09))
    none = record_handshake(tmp_path / "none.rrd", model,
                            dataclasses.replace(short, phase=["grip"] * 10))
    with pytest.raises(ValueError, match="no shake phase"):
        recording.mid_shake_s(none)
