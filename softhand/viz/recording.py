"""A rerun recording of a handshake: both hands, region forces on the skin, contacts, skin designs.

One time line, ``sim_time`` (simulated time, s). Lengths in metres, forces in newtons, MuJoCo's
world frame (right-handed, +Z up). Static geometry is logged once; per frame only transforms,
colours, scalars, contacts and text are sent, each series in bulk with ``send_columns``.

| entity path | archetype | logged | what it holds |
|---|---|---|---|
| ``world`` | ViewCoordinates | static | right-handed, +Z up |
| ``world/bodies/{body}`` | Transform3D | per frame | world pose of a ``pro_*``/``hum_*`` body |
| ``world/bodies/{body}/{geom}`` | a shape (1) | static | the geom in its body's frame, colour |
| ``world/bodies/{body}/pro_skin_{key}`` | a shape (1) | colour per frame | see (2) |
| ``world/hands`` | Points3D | per frame | one labelled point at each palm: which hand is which |
| ``world/contacts/points`` | Points3D | per frame | contact points, sized and coloured by force |
| ``world/contacts/normals`` | Arrows3D | per frame | contact normals, ARROW_M_PER_N m per N |
| ``forces/{region}`` | Scalars | per frame | the region's normal force, N |
| ``sensors/{region}`` | Scalars | per frame | its embedded sensor's reading, N on the patch (3) |
| ``skin/designs`` | TextDocument | static | Markdown: the hands, each skin design and its regions |
| ``partner/phase`` | TextLog | at changes | partner phase (``reach``, ``grip``, ...) |

(1) Capsules3D, Ellipsoids3D, Boxes3D, Cylinders3D or Mesh3D (the palm's convex skin and tissue
pieces; colour as its albedo), as the MuJoCo geom type. (2) A region's skin geom (a phalanx's
own, or the palm's one surface for Palm1, Palm2, Back1 and Back2): shape and label ``{region}``
static (meshes: no label), colour force_colors(force) per frame, a skin of several zones by its
most loaded one; whether the label shows is set per frame (see "Labels" below).
``forces/{region}`` also holds a static SeriesLines (its name with the unit, and a colour of its
own: no two regions share one). (3) When the frames carry sensor readings; the series is named
``{region} ({placement})`` and its view stands beside the forces' view, so that a region's reading
and its contact force are read side by side.
Geom and body names are MuJoCo's (``{body}`` e.g. ``pro_index_proximal``, ``hum_base``); unnamed
geoms are called ``geom{id}``. Body poses are world poses, so the body entities are flat (not nested
along the kinematic tree).

Labels: a region's name shows in the 3D view only while it stands out, at
``STANDOUT_FORCE_N`` (2 N) or more, the force at which its colour turns orange-red, and only for the
``LABELLED_MAX`` most loaded such regions of that frame. Labelling every loaded region (a dozen
over a handshake) piled the names of neighbouring phalanges on top of each other; this way the
names that show are those of the few regions the colours point at, and they move as the load
moves. The two hands' names (``world/hands``) always show.

The default blueprint opens where the hands touch: the time panel selects the contact phase
(the frames whose total force is at least 5 % of its peak) and plays it in a loop, the 3D view
looks at the two palms at the peak from ``softhand render``'s default angle
(`softhand.envs.picture.CameraView`), and the force plot lists only the regions that carry
load (over ``LOADED_N``); the regions that never do are named in ``skin/designs``. The plots'
legends are hidden: a dozen series gave a legend as tall as the plot and a third of its width,
over the lines. A line's region shows when the pointer rests on it, and the series keep their
names and colours (the legend can be switched back on in the view's settings). The blueprint
cannot place the time cursor; ``mid_shake_s`` gives the time a picture of the shake should be
taken at (``tools/rerun_screenshot.mjs`` opens the viewer there).
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from rerun.chunk import RrdReader

from softhand.envs.picture import STANDOUT_FORCE_N, CameraView, force_colors, hand_colours
from softhand.hands import regions
from softhand.io import check_writable_file

__all__ = [
    "ARROW_M_PER_N",
    "HAND_PREFIXES",
    "LABELLED_MAX",
    "LOADED_N",
    "STANDOUT_FORCE_N",
    "HandshakeFrames",
    "force_colors",
    "mid_shake_s",
    "read_recording_summary",
    "record_handshake",
]

#: Name prefixes of the bodies drawn: the prosthetic hand and the partner hand.
HAND_PREFIXES: tuple[str, ...] = ("pro_", "hum_")
#: Length of a contact-normal arrow per newton of normal force (m/N).
ARROW_M_PER_N = 0.01
#: Contact point radius (m) at 0 N and its increase at max_force_N (large enough to show through
#: the skin surface they lie on).
_POINT_RADIUS_M = (0.003, 0.004)
_TIMELINE = "sim_time"
#: A region whose force never exceeds this (N) is left out of the force plot and unlabelled.
LOADED_N = 0.05
#: At most this many regions are labelled in the 3D view at once: the most loaded of those at
#: STANDOUT_FORCE_N or more at that frame.
LABELLED_MAX = 3
#: 20 distinct series colours (matplotlib's tab20, dark and light alternating), one per region.
_SERIES_COLOURS = (
    (31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189),
    (140, 86, 75), (227, 119, 194), (127, 127, 127), (188, 189, 34), (23, 190, 207),
    (174, 199, 232), (255, 187, 120), (152, 223, 138), (255, 152, 150), (197, 176, 213),
    (196, 156, 148), (247, 182, 210), (199, 199, 199), (219, 219, 141), (158, 218, 229))
#: Hand names for the labels, by body-name prefix; the palm body that carries each label.
_HANDS = {"pro_": ("prosthetic hand (softhand skin)", "pro_palm"),
          "hum_": ("partner's hand (human tissue)", "hum_palm")}


@dataclass(frozen=True)
class HandshakeFrames:
    """What to record, frame by frame; validated (shapes, finiteness) on construction.

    Attributes:
        time_s: (T,) simulated time of each frame, s, strictly increasing.
        qpos: (T, nq) joint positions.
        mocap_pos: (T, nmocap, 3) mocap body positions, m.
        mocap_quat: (T, nmocap, 4) mocap body quaternions (w, x, y, z).
        region_force_N: (T, R) normal force per region, N, columns in the order of region_names.
        region_names: the R region names (the prosthetic hand's 18 regions).
        skin_designs: region -> skin design name (e.g. ``"pocket2-sil"``, ``"rigid"``).
        contacts: per frame an (n_i, 7) array: position xyz (m), normal xyz, normal force (N).
        phase: per frame the partner's phase (``"reach"``, ``"grip"``, ...), or None.
        sensor_reading_N: (T, R) embedded sensor reading per region (N on its patch), or None.
        sensor_placements: region -> the sensor's placement (labels the series).
    """

    time_s: np.ndarray
    qpos: np.ndarray
    mocap_pos: np.ndarray
    mocap_quat: np.ndarray
    region_force_N: np.ndarray
    region_names: tuple[str, ...]
    skin_designs: dict[str, str]
    contacts: list[np.ndarray]
    phase: list[str] | None = None
    sensor_reading_N: np.ndarray | None = None
    sensor_placements: dict[str, str] | None = None

    @classmethod
    def from_run(cls, run: Any) -> HandshakeFrames:
        """What a recording of a run holds: a `softhand.envs.run.HandshakeRun` (or
        anything with its fields), frame by frame."""
        return cls(run.time_s, run.qpos, run.mocap_pos, run.mocap_quat, run.region_force_N,
                   run.region_names, run.skins, run.contacts, run.phase, run.sensor_reading_N,
                   run.sensor_placements)

    def __post_init__(self) -> None:
        time_s = _checked("time_s", self.time_s, (None,))
        n, steps = time_s.size, np.diff(time_s)
        if n == 0 or np.any(steps <= 0):
            i = int(np.argmax(steps <= 0)) if n else 0
            raise ValueError(
                f"time_s must hold >= 1 strictly increasing times; {time_s[i : i + 2]}"
            )
        names = tuple(self.region_names)
        if not all(isinstance(r, str) for r in names) or len(set(names)) != len(names):
            raise ValueError(f"region_names = {names!r}: expected distinct strings")
        designs = dict(self.skin_designs)
        missing, unknown = sorted(set(names) - set(designs)), sorted(set(designs) - set(names))
        if missing or unknown or not all(isinstance(d, str) and d for d in designs.values()):
            raise ValueError(
                f"skin_designs = {designs!r}: expected one name per region; "
                f"missing {missing}, unknown {unknown}"
            )
        if len(self.contacts) != n:
            raise ValueError(f"contacts: {len(self.contacts)} frames, time_s has {n}")
        contacts = [
            np.reshape(c, (0, 7)) if np.size(c) == 0 else _checked(f"contacts[{i}]", c, (None, 7))
            for i, c in enumerate(self.contacts)
        ]
        for i, c in enumerate(contacts):
            if np.any(c[:, 6] < 0):
                raise ValueError(f"contacts[{i}]: negative normal force {c[:, 6].min()} N")
        phase = None if self.phase is None else list(self.phase)
        if phase is not None and (len(phase) != n or not all(isinstance(p, str) for p in phase)):
            raise ValueError(f"phase: expected {n} strings (one per frame), got {len(phase)}")
        mocap_pos = _checked("mocap_pos", self.mocap_pos, (n, None, 3))
        fields = {
            "time_s": time_s,
            "qpos": _checked("qpos", self.qpos, (n, None)),
            "mocap_pos": mocap_pos,
            "mocap_quat": _checked("mocap_quat", self.mocap_quat, (n, mocap_pos.shape[1], 4)),
            "region_force_N": _checked("region_force_N", self.region_force_N, (n, len(names))),
            "region_names": names,
            "skin_designs": designs,
            "contacts": contacts,
            "phase": phase,
            "sensor_reading_N": None if self.sensor_reading_N is None else
            _checked("sensor_reading_N", self.sensor_reading_N, (n, len(names))),
            "sensor_placements": dict(self.sensor_placements or {}),
        }
        for key, value in fields.items():
            object.__setattr__(self, key, value)


def _checked(name: str, value: Any, shape: tuple[int | None, ...]) -> np.ndarray:
    """``value`` as a finite float array of ``shape`` (None: any length), else ValueError."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{name}: not a numeric array ({err})") from err
    if arr.ndim != len(shape) or any(
        s is not None and s != k for s, k in zip(shape, arr.shape, strict=False)
    ):
        want = ", ".join("*" if s is None else str(s) for s in shape)
        raise ValueError(f"{name}: shape {arr.shape}, expected ({want})")
    if not np.all(np.isfinite(arr)):
        where = tuple(int(i) for i in np.argwhere(~np.isfinite(arr))[0])
        raise ValueError(f"{name}: non-finite value {arr[where]} at index {where}")
    return arr


def _path(*parts: str) -> str:
    """An entity path from raw name parts (escaped where rerun needs it)."""
    return "/".join(rr.escape_entity_path_part(p) for p in parts)


def _xyzw(quat_wxyz: np.ndarray) -> np.ndarray:
    """MuJoCo (w, x, y, z) quaternions -> rerun (x, y, z, w)."""
    return np.asarray(quat_wxyz)[..., [1, 2, 3, 0]]


def _geom_shape(model: mujoco.MjModel, g: int) -> tuple[type, dict[str, Any]] | None:
    """rerun archetype and fields (no colour) of geom ``g`` in its body's frame; None: not drawn."""
    kind, size, pos = int(model.geom_type[g]), model.geom_size[g], model.geom_pos[g]
    rot = np.empty(9)
    mujoco.mju_quat2Mat(rot, model.geom_quat[g])
    rot = rot.reshape(3, 3)
    pose = {"quaternions": [_xyzw(model.geom_quat[g])], "fill_mode": rr.components.FillMode.Solid}
    geom = mujoco.mjtGeom
    if kind in (geom.mjGEOM_SPHERE, geom.mjGEOM_ELLIPSOID):
        half = [size[0]] * 3 if kind == geom.mjGEOM_SPHERE else size
        return rr.Ellipsoids3D, {"half_sizes": [half], "centers": [pos], **pose}
    if kind == geom.mjGEOM_BOX:
        return rr.Boxes3D, {"half_sizes": [size], "centers": [pos], **pose}
    axial = {"lengths": [2 * size[1]], "radii": [size[0]]}  # MuJoCo: radius, half-length
    if kind == geom.mjGEOM_CAPSULE:  # rerun: from the translation along +Z; MuJoCo: centred
        return rr.Capsules3D, {**axial, "translations": [pos - size[1] * rot[:, 2]], **pose}
    if kind == geom.mjGEOM_CYLINDER:
        return rr.Cylinders3D, {**axial, "centers": [pos], **pose}
    if kind == geom.mjGEOM_MESH:  # the palm's convex skin and tissue pieces
        m = model.geom_dataid[g]
        v0, nv = model.mesh_vertadr[m], model.mesh_vertnum[m]
        f0, nf = model.mesh_faceadr[m], model.mesh_facenum[m]
        verts = model.mesh_vert[v0:v0 + nv] @ rot.T + pos
        return rr.Mesh3D, {"vertex_positions": verts, "triangle_indices": model.mesh_face[f0:f0 + nf]}
    return None  # planes, height fields, SDFs: not in the procedural hands


def _colour_field(archetype: type) -> str:
    """The field that carries a shape's colour: meshes have an albedo, the others colours."""
    return "albedo_factor" if archetype is rr.Mesh3D else "colors"


def _validate(path: Path, model: mujoco.MjModel, frames: HandshakeFrames, max_force_N: float):
    check_writable_file(path, suffix=".rrd")
    if not (math.isfinite(max_force_N) and max_force_N > 0):
        raise ValueError(f"max_force_N = {max_force_N}: expected a positive finite force in N")
    if frames.qpos.shape[1] != model.nq:
        raise ValueError(f"qpos: {frames.qpos.shape[1]} columns, model.nq = {model.nq}")
    if frames.mocap_pos.shape[1] != model.nmocap:
        raise ValueError(f"mocap_pos: {frames.mocap_pos.shape[1]} bodies, nmocap = {model.nmocap}")
    expected = set(regions(model, "pro_"))
    names = set(frames.region_names)
    if names != expected:
        raise ValueError(
            f"region_names: {len(names)} regions, the model has {len(expected)}; "
            f"missing {sorted(expected - names)}, unknown {sorted(names - expected)}"
        )


def _body_poses(
    model: mujoco.MjModel, frames: HandshakeFrames, bodies: list[int]
) -> tuple[np.ndarray, np.ndarray]:
    """World positions (T, B, 3) and (x, y, z, w) quaternions (T, B, 4) from mj_kinematics."""
    data = mujoco.MjData(model)
    n = frames.time_s.size
    pos, quat = np.empty((n, len(bodies), 3)), np.empty((n, len(bodies), 4))
    for i in range(n):
        data.qpos[:] = frames.qpos[i]
        data.mocap_pos[:] = frames.mocap_pos[i]
        data.mocap_quat[:] = frames.mocap_quat[i]
        mujoco.mj_kinematics(model, data)
        pos[i], quat[i] = data.xpos[bodies], _xyzw(data.xquat[bodies])
    return pos, quat


def _contact_window(frames: HandshakeFrames) -> tuple[float, float, int]:
    """(first, last) time of the contact phase and the frame of peak total force: the frames
    whose total region force is at least 5 % of its peak (the whole run if none carries any)."""
    total = frames.region_force_N.sum(axis=1)
    peak = int(np.argmax(total))
    on = np.flatnonzero(total >= 0.05 * total[peak]) if total[peak] > 0 else np.arange(total.size)
    return float(frames.time_s[on[0]]), float(frames.time_s[on[-1]]), peak


def _eye(model: mujoco.MjModel, frames: HandshakeFrames, frame: int) -> rrb.EyeControls3D:
    """The 3D view's eye: ``softhand render``'s default angle and distance, looking at the
    midpoint of the two palms at ``frame``."""
    palms = [model.body(name).id for _, name in _HANDS.values()]
    data = mujoco.MjData(model)
    data.qpos[:] = frames.qpos[frame]
    data.mocap_pos[:] = frames.mocap_pos[frame]
    data.mocap_quat[:] = frames.mocap_quat[frame]
    mujoco.mj_kinematics(model, data)
    target = data.xpos[palms].mean(axis=0)
    view = CameraView()
    az, el = math.radians(view.azimuth_deg), math.radians(view.elevation_deg)
    forward = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    return rrb.EyeControls3D(position=target - view.distance_m * forward, look_target=target,
                             eye_up=(0.0, 0.0, 1.0))


def _loaded(frames: HandshakeFrames) -> list[str]:
    """The regions whose force exceeds LOADED_N at some frame."""
    top = frames.region_force_N.max(axis=0)
    return [r for k, r in enumerate(frames.region_names) if top[k] > LOADED_N]


def _labelled(frames: HandshakeFrames, candidates: list[str]) -> np.ndarray:
    """(T, R) booleans, columns in the order of region_names: whether the region's label shows
    at each frame. Among ``candidates`` (the regions whose geom can carry a label), those at
    STANDOUT_FORCE_N or more, the LABELLED_MAX most loaded of them (ties: the earlier region)."""
    forces = frames.region_force_N
    allowed = np.isin(np.asarray(frames.region_names), candidates)
    over = (forces >= STANDOUT_FORCE_N) & allowed[None, :]
    # rank by force among the eligible regions of each frame (stable: ties keep region order)
    order = np.argsort(-np.where(over, forces, -np.inf), axis=1, kind="stable")
    rank = np.empty_like(order)
    np.put_along_axis(rank, order, np.arange(forces.shape[1])[None, :].repeat(len(forces), 0),
                      axis=1)
    return over & (rank < LABELLED_MAX)


def _blueprint(model: mujoco.MjModel | None = None, frames: HandshakeFrames | None = None,
               sensors: bool = False) -> rrb.Blueprint:
    eye, panel, forces = None, None, "$origin/**"
    if model is not None and frames is not None:
        start, end, peak = _contact_window(frames)
        eye = _eye(model, frames, peak)
        window = rr.encodings.AbsoluteTimeRange(round(start * 1e9), round(end * 1e9))
        panel = rrb.TimePanel(timeline=_TIMELINE, play_state="playing", loop_mode="selection",
                              time_selection=window)
        loaded = _loaded(frames)
        forces = [f"$origin/{rr.escape_entity_path_part(r)}" for r in loaded] or "$origin/**"
    series = rrb.TimeSeriesView(origin="forces", contents=forces,
                                name="region forces (N); point at a line for its region",
                                plot_legend=rrb.PlotLegend(visible=False))
    if sensors:
        series = rrb.Horizontal(series, rrb.TimeSeriesView(
            origin="sensors", contents=forces,
            name="embedded sensor readings (N on the 4 x 4 mm patch)",
            plot_legend=rrb.PlotLegend(visible=False)))
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(origin="world", name="handshake (grey < 2 N, orange-red > 2 N)",
                              eye_controls=eye, background=(250, 250, 248)),
            rrb.Vertical(
                series,
                rrb.TextDocumentView(origin="skin", name="hands and skins"),
                rrb.TextLogView(origin="partner", name="partner phase"),
                row_shares=[3, 2, 1],
            ),
            column_shares=[3, 2],
        ),
        *(() if panel is None else (panel,)),
        collapse_panels=True,
    )


def _log_recording(
    rec: rr.RecordingStream, model: mujoco.MjModel, frames: HandshakeFrames, max_force_N: float
) -> None:
    """Log the static scene, then every per-frame series in bulk (strict: errors raise)."""
    log, send = partial(rec.log, strict=True), partial(rec.send_columns, strict=True)
    time = [rr.TimeColumn(_TIMELINE, duration=frames.time_s)]
    info = regions(model, "pro_")
    skin: dict[str, list[str]] = {}  # skin geom -> the regions it carries (the palm: 4 zones)
    for r in frames.region_names:
        skin.setdefault(info[r].geom, []).append(r)
    forces = {r: frames.region_force_N[:, k] for k, r in enumerate(frames.region_names)}
    log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    loaded = set(_loaded(frames))
    labelled = _labelled(frames, [r for r in frames.region_names
                                  if model.geom_type[model.geom(info[r].geom).id]
                                  != mujoco.mjtGeom.mjGEOM_MESH])
    label_on = {r: labelled[:, k] for k, r in enumerate(frames.region_names)}

    bodies = [b for b in range(model.nbody) if model.body(b).name.startswith(HAND_PREFIXES)]
    partner = hand_colours(model, ("hum_tissue_",))
    for g in range(model.ngeom):
        body = model.body(model.geom_bodyid[g]).name
        shape = _geom_shape(model, g) if body.startswith(HAND_PREFIXES) else None
        if shape is None:
            continue
        archetype, fields = shape
        name = model.geom(g).name or f"geom{g}"
        entity = _path("world", "bodies", body, name)
        carried = skin.get(name)
        colour = _colour_field(archetype)
        if carried is None:  # a plain geom: static colour (the partner's tissue blue, as in
            # every picture)
            rgba = np.asarray(partner.get(g, model.geom_rgba[g]))
            fields[colour] = [np.round(255 * rgba).astype(np.uint8)]
            log(entity, archetype.from_fields(**fields), static=True)
            continue
        per_frame: dict[str, Any] = {}
        if archetype is not rr.Mesh3D:  # the label static, whether it shows per frame
            fields["labels"] = ["/".join(carried)]
            per_frame["show_labels"] = np.any([label_on[r] for r in carried], axis=0)
        log(entity, archetype.from_fields(**fields), static=True)
        # a skin of several zones (the palm's surface) shows its most loaded zone
        per_frame[colour] = force_colors(np.max([forces[r] for r in carried], axis=0),
                                         max_force_N=max_force_N)
        send(entity, time, archetype.columns(**per_frame))

    pos, quat = _body_poses(model, frames, bodies)
    for k, b in enumerate(bodies):
        entity = _path("world", "bodies", model.body(b).name)
        send(entity, time, rr.Transform3D.columns(translation=pos[:, k], quaternion=quat[:, k]))
    names = [model.body(b).name for b in bodies]
    palms = [names.index(palm) for _, palm in _HANDS.values() if palm in names]
    if len(palms) == len(_HANDS):
        labels = [label for label, _ in _HANDS.values()]
        log("world/hands", rr.Points3D.from_fields(labels=labels, radii=[0.002, 0.002],
                                                   show_labels=True,
                                                   colors=[(240, 140, 50), (60, 120, 220)]),
            static=True)
        send("world/hands", time, rr.Points3D.columns(
            positions=pos[:, palms].reshape(-1, 3)).partition(np.full(len(frames.time_s), 2)))

    colour_of = {r: _SERIES_COLOURS[k % len(_SERIES_COLOURS)]
                 for k, r in enumerate(frames.region_names)}
    for region, force in forces.items():
        entity = _path("forces", region)
        log(entity, rr.SeriesLines(names=f"{region} (N)", colors=[colour_of[region]], widths=2.0),
            static=True)
        send(entity, time, rr.Scalars.columns(scalars=force))
    if frames.sensor_reading_N is not None:
        for k, region in enumerate(frames.region_names):
            entity = _path("sensors", region)
            where = frames.sensor_placements.get(region, "")
            log(entity, rr.SeriesLines(names=f"{region} ({where}, N)" if where else
                                       f"{region} (N)", colors=[colour_of[region]], widths=2.0),
                static=True)
            send(entity, time, rr.Scalars.columns(scalars=frames.sensor_reading_N[:, k]))

    by_design: dict[str, list[str]] = {}
    for r in frames.region_names:
        by_design.setdefault(frames.skin_designs[r], []).append(r)
    table = ["| skin design | regions |", "|---|---|"]
    table += [f"| {d} | {', '.join(rs) if len(rs) < len(frames.region_names) else 'all'} |"
              for d, rs in by_design.items()]
    idle = [r for r in frames.region_names if r not in loaded]
    text = ("# Hands and skins\n\n"
            "- **prosthetic hand**: the softhand skin; its regions coloured by force, grey "
            "under 2 N, orange to red over 2 N (red at the colour scale's top)\n"
            "- **partner's hand**: human tissue over bones\n\n" + "\n".join(table) + "\n\n"
            + (f"Regions that never carry over {LOADED_N:g} N (left out of the plot): "
               f"{', '.join(idle)}.\n" if idle else "Every region carries load.\n"))
    log("skin/designs", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN), static=True)

    lengths = np.array([len(c) for c in frames.contacts])
    if lengths.sum() > 0:
        c = np.concatenate(frames.contacts)
        force = c[:, 6]
        norm = np.linalg.norm(c[:, 3:6], axis=1, keepdims=True)
        unit = np.divide(c[:, 3:6], norm, out=np.zeros_like(c[:, 3:6]), where=norm > 0)
        colors = force_colors(force, max_force_N=max_force_N)
        radii = _POINT_RADIUS_M[0] + _POINT_RADIUS_M[1] * np.clip(force / max_force_N, 0, 1)
        points = rr.Points3D.columns(positions=c[:, :3], radii=radii, colors=colors)
        arrows = rr.Arrows3D.columns(
            origins=c[:, :3], vectors=unit * force[:, None] * ARROW_M_PER_N, colors=colors
        )
        send("world/contacts/points", time, points.partition(lengths))
        send("world/contacts/normals", time, arrows.partition(lengths))

    if frames.phase is not None:
        changes = [0] + [
            i for i in range(1, len(frames.phase)) if frames.phase[i] != frames.phase[i - 1]
        ]
        send(
            "partner/phase",
            [rr.TimeColumn(_TIMELINE, duration=frames.time_s[changes])],
            rr.TextLog.columns(text=[frames.phase[i] for i in changes]),
        )


def record_handshake(
    path: str | Path,
    model: mujoco.MjModel,
    frames: HandshakeFrames,
    *,
    application_id: str = "softhand_handshake",
    max_force_N: float = 5.0,
) -> Path:
    """Write a rerun recording (.rrd) of a handshake; the entity paths are in the module docstring.

    The file is written atomically: to a temporary file in the same folder, then renamed, so a
    failure leaves no partial file behind.

    Args:
        path: the .rrd file to write (its folder must exist); replaced if present.
        model: the compiled handshake scene (softhand.hands.scene_spec().compile()).
        frames: what to record, frame by frame.
        application_id: rerun application id of the recording.
        max_force_N: force (N) at the red end of the force colours.

    Returns:
        The path written.

    Raises:
        ValueError: if ``frames`` does not fit ``model`` (qpos width, mocap count, regions), the
            path is not a writable .rrd file path (a missing folder is created), or ``max_force_N`` is not positive.
        RuntimeError: if rerun logging is disabled (environment variable ``RERUN=off``).
    """
    path = Path(path)
    _validate(path, model, frames, max_force_N)
    rec = rr.RecordingStream(application_id, send_properties=True)
    if not rec.is_enabled():
        raise RuntimeError("rerun logging is disabled (environment variable RERUN)")
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        rec.save(tmp, default_blueprint=_blueprint(model, frames,
                                                   frames.sensor_reading_N is not None))
        _log_recording(rec, model, frames, max_force_N)
        rec.flush()
        rec.disconnect()
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600
        os.replace(tmp, path)
    except BaseException:
        rec.disconnect()
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def read_recording_summary(path: str | Path) -> dict[str, Any]:
    """What a saved recording holds, per entity path: for tests and for users checking a file.

    Returns:
        ``{"application_id": str, "recording_id": str, "timelines": [names],
        "entities": {path: {"static": [components], "temporal": [components],
        "sim_time_points": number of distinct sim_time values}},
        "texts": {path: text of its static TextDocument},
        "phases": [(sim_time s, partner phase) at each change, in time order]}``; entity paths
        without the leading ``/``, components as ``"Archetype:field"`` (e.g.
        ``"Scalars:scalars"``); ``phases`` is empty when the recording has no partner phase.

    Raises:
        FileNotFoundError: if ``path`` does not exist.
        ValueError: if ``path`` is not a readable rerun recording.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"recording {str(path)!r} not found")
    try:
        reader = RrdReader(path)
        store = reader.recordings()[0]
        chunks = list(reader.stream(store=store))
    except Exception as err:
        raise ValueError(f"{str(path)!r} is not a readable rerun recording: {err}") from err
    entities: dict[str, dict[str, Any]] = {}
    times: dict[str, set[int]] = {}
    texts: dict[str, str] = {}
    phases: list[tuple[float, str]] = []
    timelines: set[str] = set()
    for chunk in chunks:
        entity = chunk.entity_path.lstrip("/")
        batch = chunk.to_record_batch()
        names = set(chunk.timeline_names)
        timelines |= names
        components = [
            c for c in batch.schema.names if c not in names and not c.startswith("rerun.")
        ]
        entry = entities.setdefault(entity, {"static": set(), "temporal": set()})
        entry["static" if chunk.is_static else "temporal"].update(components)
        if _TIMELINE in names:
            values = batch.column(_TIMELINE).to_numpy(zero_copy_only=False).astype("int64")
            times.setdefault(entity, set()).update(values.tolist())
        if chunk.is_static and "TextDocument:text" in components:
            value = batch.column("TextDocument:text").to_pylist()[-1]
            texts[entity] = value[0] if isinstance(value, list) else value
        if entity == "partner/phase" and "TextLog:text" in components and _TIMELINE in names:
            ns = batch.column(_TIMELINE).to_numpy(zero_copy_only=False).astype("int64")
            text = batch.column("TextLog:text").to_pylist()
            phases += [(int(t) / 1e9, p[0] if isinstance(p, list) else p) for t, p in zip(ns, text,
                                                                                      strict=True)]
    for e, entry in entities.items():
        entry.update({k: sorted(entry[k]) for k in ("static", "temporal")})
        entry["sim_time_points"] = len(times.get(e, ()))
    ids = {"application_id": store.application_id, "recording_id": store.recording_id}
    entities = dict(sorted(entities.items()))
    return {**ids, "timelines": sorted(timelines), "entities": entities, "texts": texts,
            "phases": sorted(phases)}


def mid_shake_s(path: str | Path) -> float:
    """The middle of the shake in a saved recording (sim_time, s): halfway between the start of
    the partner's ``shake`` phase and the start of the phase after it (the recording's last
    time if none follows). A picture of the shake is taken here (`tools/rerun_screenshot.mjs`).

    Raises:
        FileNotFoundError: if ``path`` does not exist.
        ValueError: if ``path`` is not a readable rerun recording, or it has no ``shake`` phase.
    """
    summary = read_recording_summary(path)
    phases = summary["phases"]
    starts = [k for k, (_, p) in enumerate(phases) if p == "shake"]
    if not starts:
        raise ValueError(f"{str(path)!r}: no shake phase in partner/phase "
                         f"(phases: {[p for _, p in phases]})")
    k = starts[0]
    start = phases[k][0]
    end = phases[k + 1][0] if k + 1 < len(phases) else _last_time_s(path)
    return 0.5 * (start + end)


def _last_time_s(path: str | Path) -> float:
    """The last sim_time (s) of the forces in a saved recording."""
    reader = RrdReader(Path(path))
    last = 0
    for chunk in reader.stream(store=reader.recordings()[0]):
        if chunk.entity_path.lstrip("/").startswith("forces/") and not chunk.is_static:
            values = chunk.to_record_batch().column(_TIMELINE).to_numpy(zero_copy_only=False)
            last = max(last, int(values.astype("int64").max()))
    return last / 1e9
