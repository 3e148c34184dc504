"""``softhand handshake`` and ``softhand render``: one handshake with the shipped calibration, and
a picture of it."""

from __future__ import annotations

import json
from dataclasses import asdict

import click
import numpy as np

from softhand import __version__
from softhand.cli.app import EXIT_CONVERGENCE, Stopped, _check_gl, main
from softhand.cli.inputs import (
    SENSOR_OPTIONS,
    Number,
    bad,
    checked_file,
    parse_placement_items,
    parse_skin_overrides,
    sensor_flag_message,
    sensor_spec_of,
    with_options,
)

_OPT_CONTACT_LAWS = click.option(
    "--contact-laws", type=click.Choice(["geometry", "plate"]), default="geometry",
    show_default=True,
    help="Laws of the skin pairs: geometry (each pair the law of its contact class: a phalanx or "
         "a palm piece, pressed by a finger or a flat; `--json` and the summary name each law's "
         "share) or plate (every pair the paper's flat-plate law).")


_OPT_HAND = click.option(
    "--hand", type=click.Choice(["prosthetic", "human"]), default="prosthetic", show_default=True,
    help="The sensored hand: the prosthetic hand, or the paper's relaxed human hand (its protocol).")



class _ArmNumber(Number):
    """A `Number` in the range of softhand.hands.config.ARM_RANGES[key], read when a value is
    given: importing softhand.hands here would import mujoco with the command line, before
    ``softhand render`` sets MUJOCO_GL (`_check_gl`)."""

    def __init__(self, key: str, unit: str) -> None:
        super().__init__(unit=unit)
        self.key = key

    def convert(self, value, param, ctx):
        if self.lo is None:
            from softhand.hands.config import ARM_RANGES

            self.lo, self.hi = ARM_RANGES[self.key]
        return super().convert(value, param, ctx)

@main.command("handshake")
@click.option("--design", default=None,
              help="Skin of every region: a skin name, or the path of a calibration file "
                   "(*.json, e.g. a searched design's from `softhand design calibrate`) "
                   "[default: pocket2-sil].")
@click.option("--skin", "skin_items", multiple=True, metavar="REGION=DESIGN[@REPRESENTATION]",
              help="Skin of one region (repeatable), e.g. Index2=rigid or "
                   "Index2=pocket2-pu@soft-contact+relaxation; Palm=DESIGN for the palm's one "
                   "surface (Palm1, Palm2, Back1 and Back2 are its zones and wear one skin).")
@click.option("--representation", default=None,
              help="Representation of every region: soft-contact (default), "
                   "soft-contact+relaxation (relaxation pads) or rigid.")
@click.option("--controller", type=click.Choice(["neutral", "open-loop", "force"]),
              default="neutral", show_default=True,
              help="Controller of the prosthetic hand (neutral: the paper's sensored hand).")
@click.option("--seed", type=click.IntRange(0, 2**32 - 1), default=0, show_default=True,
              help="Seed of the partner, 0 <= seed < 2^32.")
@click.option("--timestep", "timestep_s", type=Number(1e-4, 5e-3, unit="s"), default=0.002,
              show_default=True,
              help="Physics timestep, 0.0001-0.005 s (skins calibrated and tested at "
                   "0.0005-0.002 s). Actions every 10 ms (the most timesteps that fit in it).")
@click.option("--record", "record_path", default=None,
              help="Write a rerun recording here (a .rrd file; a missing folder is created).")
@click.option("--sensor-placement", "placement_items", multiple=True,
              metavar="[REGION=]PLACEMENT",
              help="Where the embedded sensors sit (repeatable): bone, interface or "
                   "pocket-floor, for every region or one [default: interface].")
@click.option("--signal", type=click.Choice(["contact", "sensor"]), default="contact",
              show_default=True,
              help="What the neutral and force controllers feel: the true contact forces or the "
                   "embedded sensors (their calibrated read-out).")
@click.option("--target", "target_N", type=Number(0.05, 20, unit="N"), default=None,
              help="Force the force controller holds on each digit, 0.05-20 N [default: 2.5].")
@with_options(SENSOR_OPTIONS)
@click.option("--partner-size", "partner_size", default=None, metavar="LENGTH_MM,WIDTH_MM",
              help="The partner's hand, within +-2.5 SD of the paper's subjects "
                   "[default: 190,88, the experimenter].")
@_OPT_HAND
@_OPT_CONTACT_LAWS
@click.option("--press", "press_N", type=_ArmNumber("press_n", "N"), default=None,
              help="Each arm's push of its palm towards the other's, 0-10 N [default: 2 N, and 0 "
                   "for the relaxed experimenter of --hand human].")
@click.option("--arm-stiffness", "arm_stiffness", default=None,
              type=_ArmNumber("stiffness_n_per_m", "N/m"),
              help="The sensored hand's arm: its endpoint stiffness, 20-5000 N/m [default: 1000, "
                   "the prosthesis user's; 150 for --hand human, the relaxed experimenter's].")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
def handshake(design, skin_items, representation, controller, seed, timestep_s, record_path,
              placement_items, signal, target_N, partner_size, hand, contact_laws, press_N,
              arm_stiffness, as_json, **sensor_kw) -> None:
    """Shake hands once (shipped calibration, no FE run) and report the force on each region."""
    from softhand.envs.handshake import HandshakeEnv
    from softhand.envs.physics import DivergenceError
    from softhand.envs.run import OVER_N, run_handshake

    if design is not None and not design.strip():
        bad("--design '': expected a skin name, e.g. pocket2-sil")
    design_file, design, calibration_dir = design_of(design)
    overrides = parse_skin_overrides(skin_items)
    record = checked_file(record_path, "--record", ".rrd", need_bytes=_RECORDING_BYTES)
    placement = parse_placement_items(placement_items)
    spec = sensor_spec_of(**sensor_kw)
    settings = {}
    if target_N is not None:
        if controller != "force":
            bad(f"--target {target_N:g}: only the force controller holds a target "
                f"(--controller force); got --controller {controller}")
        settings["target_N"] = target_N
    size = _partner_size(partner_size)
    _check_hand(hand, controller, design=design, skins=skin_items, representation=representation)
    arms = _arms(hand, press_N, arm_stiffness)
    try:  # skins, sensors and their calibration files, before the episode
        env = HandshakeEnv(design=design, skins=overrides, representation=representation,
                           timestep_s=timestep_s, sensor=spec, sensor_placement=placement,
                           partner_size=size, hand=hand, contact_laws=contact_laws,
                           calibration_dir=calibration_dir, **arms)
    except ValueError as exc:
        msg = str(exc)
        if msg.startswith("sensor "):
            bad(sensor_flag_message(msg) if "placement" not in msg
                else f"--sensor-placement: {msg}")
        if msg.startswith("timestep_s = "):  # a timestep the chosen skins cannot take
            bad(f"--timestep {msg.removeprefix('timestep_s = ')}")
        bad(f"--representation / --skin: {exc}" if "representation" in msg else msg)
    try:
        run = run_handshake(controller=controller, seed=seed, env=env, signal=signal,
                            controller_settings=settings)
    except DivergenceError as exc:  # one line, exit 3: the numerical failure and what to try
        raise Stopped(f"error: {exc.summary}; try a smaller --timestep (e.g. "
                      f"{exc.suggested_timestep_s:g})", EXIT_CONVERGENCE) from None
    if record is not None:
        from softhand.viz import record_handshake
        from softhand.viz.recording import HandshakeFrames

        record_handshake(record, run.model, HandshakeFrames.from_run(run))
    summary = run.summary()
    frame_skip = int(env.frame_skip)
    summary["settings"] = {
        "hand": hand, "design": design, "design_file": design_file,
        "skins": dict(overrides or {}),
        "representation": representation, "controller": controller,
        "signal": signal if controller != "open-loop" else None, "target_N": target_N,
        "seed": seed, "timestep_s": timestep_s, "physics_steps_per_env_step": frame_skip,
        "env_step_s": frame_skip * timestep_s, "contact_laws": contact_laws,
        "partner_size_mm": list(summary["episode"]["partner_size_mm"]),
        "sensor_placement": list(placement_items) or None,
        # the arms in use, every field (--press, --arm-stiffness over softhand.hands.constants.ARMS)
        "sensored_arm": asdict(env.config.arm), "partner_arm": asdict(env.config.partner_arm),
        "softhand_version": __version__}
    summary["env_steps_per_s"] = summary["steps_per_s"] / frame_skip
    if as_json:
        click.echo(json.dumps(summary, indent=1))
        return
    ep = summary["episode"]
    designs = sorted(set(run.skins.values()))
    skins_text = (f"{designs[0]} on every region" if len(designs) == 1
                  else f"{len(designs)} skins ({', '.join(designs)})")
    click.echo(_header("handshake", _sensored_hand(ep["hand"], skins_text,
                                                   f"controller {controller}"),
                       f"partner seed {seed}, hand {ep['partner_size_mm'][0]:g} x "
                       f"{ep['partner_size_mm'][1]:g} mm", f"timestep {timestep_s * 1e3:g} ms, "
                       f"an env step every {frame_skip * timestep_s * 1e3:g} ms"))
    click.echo(f"partner's grip {summary['partner_grip']['measured_N']:.1f} N against "
               f"{summary['partner_grip']['target_N']:.1f} N (95th percentile error "
               f"{summary['partner_grip']['p95_error_pct']:.0f} %)\n")
    click.echo("| region | skin | peak N | mean N | peak area mm^2 | > 2 N | sensor | "
               "sensor peak N | sensor mean N |\n|---|---|---|---|---|---|---|---|---|")
    for region, v in summary["regions"].items():
        mark = "yes" if v["peak_N"] > OVER_N else ""
        rep = run.representations.get(region, "soft-contact")
        skin = run.skins[region] + ("" if rep in ("soft-contact", "rigid") else f"@{rep}")
        click.echo(f"| {region} | {skin} | {v['peak_N']:.2f} | {v['mean_N']:.2f} | "
                   f"{v['peak_area_mm2']:.0f} | {mark} | {v['sensor_placement']} | "
                   f"{v['sensor_peak']:.2f} | {v['sensor_mean']:.2f} |")
    chk = summary["grasp_checks"]
    thumbs = chk["thumb_tip_in_other_mm"]
    pp = summary["palm_on_palm"]
    click.echo(f"\npalm on palm while the hands hold each other: {pp['palm_share_pct']:.1f} % of "
               f"the force between the hands ({pp['with_thenars_pct']:.1f} % with the thenars)")
    click.echo(f"grasp at mid-shake (t = {chk['t_mid_shake_s']:.2f} s): palm to palm (thenars "
               f"included) {chk['palm_to_palm_share_pct']:.0f} % of the force between the hands; "
               f"thumb pads {thumbs['partner_on_prosthetic'][2]:.0f} mm (partner's) and "
               f"{thumbs['prosthetic_on_partner'][2]:.0f} mm (prosthetic's) dorsal of the other "
               f"hand's mid-plane; deepest self-penetration "
               f"{max(chk['self_penetration_mm'].values()):.1f} mm; the partner's joints "
               f"{chk['partner_limit_margin_deg']:.1f} deg or more inside their ranges")
    cmp = summary["paper_over_2N"]
    click.echo("\nregions over 2 N, against the paper's Fig. 4 (30 subjects shaking a relaxed "
               "human hand):")
    click.echo(f"  in both: {', '.join(cmp['both']) or '-'}")
    click.echo(f"  only in the paper: {', '.join(cmp['only_paper']) or '-'}")
    click.echo(f"  only in softhand: {', '.join(cmp['only_softhand']) or '-'}")
    click.echo("  " + ("the same protocol as the paper's: a difference is softhand's error"
                       if ep["hand"] == "human" else
                       "the paper measured a relaxed human hand, not a prosthetic hand with a "
                       "controller, so differences are expected; --hand human runs its protocol"))
    acc = summary["force_accounting"]
    share = {k: 100 * acc[f"{k}_Ns"] / acc["total_Ns"] if acc["total_Ns"] else 0.0
             for k in ("skin_law", "tissue_law_only", "bone_on_bone", "no_law")}
    beyond = max(share["skin_law"] - acc["calibrated_share_pct"], 0.0)
    click.echo(f"\nwhere the force between the hands ({acc['total_Ns']:.1f} N s) went:\n"
               "| through | share |\n|---|---|\n"
               f"| a skin law, inside the force range it was calibrated over | "
               f"{acc['calibrated_share_pct']:.1f} % |\n"
               f"| a skin law, beyond that range (extrapolated) | {beyond:.1f} % |\n"
               f"| the partner's tissue law only (rigid regions) | "
               f"{share['tissue_law_only']:.1f} % |\n"
               f"| bone on bone (peak {acc['bone_on_bone_peak_N']:.1f} N) | "
               f"{share['bone_on_bone']:.1f} % |\n"
               f"| no law | {share['no_law']:.1f} % |")
    geo = acc.get("by_geometry")
    if geo:
        click.echo(_geometry_table(geo))
    over = summary["overload"]
    first = (f"first at t = {over['first_overload_time_s']:.2f} s: " + ", ".join(
        f"{k} {v:.1f} N" for k, v in over["first_overload"].items())
        if over["first_overload"] else "none")
    click.echo(f"overload: deepest skin-tissue pair {over['deepest_pair_mm']:.1f} mm "
               f"({over['deepest_pair'] or '-'}, t = {over['deepest_pair_time_s']:.2f} s); "
               f"bone on bone peak {over['bone_on_bone_peak_N']:.1f} N; a region over its "
               f"overload force or a bone bottoming out: {first}")
    hold, twice = summary["hold"], summary["double_count"]
    if hold:
        pads = ("" if hold["qlv_decay_pct"] is None else
                f"; {hold['pad_share_pct']:.0f} % of it through relaxation pads, whose QLV laws "
                f"give {-hold['qlv_decay_pct']:+.1f} %")
        click.echo(f"hold ({hold['hold_s']:.2f} s still, read from {hold['settle_s']:.2f} s in, "
                   "once the shake's swing has died out): the force between the hands "
                   f"{hold['force_start_N']:.1f} -> {hold['force_end_N']:.1f} N "
                   f"({-hold['decay_pct']:+.1f} %){pads}; counted twice at skin seams while "
                   f"the hands hold: {twice['double_share_pct']:.1f} %")
    click.echo(f"skin force no embedded sensor sees: {acc['unsensed_share_pct']:.1f} %; "
               f"contact time beyond a law's range: {acc['out_of_range_time_pct']:.1f} %")
    laws = ", ".join(f"{k} {v:.1f} %" for k, v in sorted(acc["by_law_share_pct"].items(),
                                                       key=lambda kv: -kv[1]))
    click.echo(f"skin pair force by law (--contact-laws {acc['contact_laws']}): {laws or '-'}")
    kin = summary["kinematics"]
    flex = ", ".join(f"{d} {v:.0f}" for d, v in kin["prosthetic_flexion_deg"].items())
    click.echo(f"prosthetic flexion reached (deg): {flex}; thumb rotation "
               f"{max(kin['prosthetic_thumb_rotation_deg'], 0.0):.0f}; regions touched: "
               f"{', '.join(kin['touched']) or '-'}")
    relax = summary.get("relaxation")
    if relax:
        worst = max(relax.items(), key=lambda kv: kv[1]["held_N"])
        click.echo("relaxation pads against the QLV law at their own compression, during the hold "
                   f"(% of the held force; most loaded region {worst[0]}, "
                   f"{worst[1]['held_N']:.2f} N): pad "
                   f"{max(v['pad_error_pct'] for v in relax.values()):.1f} % (worst region), "
                   f"{worst[1]['pad_error_pct']:.1f} % ({worst[0]}); a memoryless soft contact at "
                   f"the same compression {worst[1]['soft_contact_error_pct']:.1f} %")
    click.echo(f"speed: {summary['env_steps_per_s']:.0f} env steps/s ("
               f"{summary['steps_per_s']:.0f} physics steps/s, {frame_skip} per env step), "
               f"{summary['realtime_factor']:.1f}x real time"
               + (f" (the first step, {summary['first_step_s']:.1f} s, compiled the step's "
                  "kernels: once per machine)" if summary["first_step_s"] > 1.0 else "")
               + (f"; recording: {record}" if record else ""))


#: Upper bound of one handshake's recording: 1.7 MB for the default 2.6 s episode, 5 s at most
_RECORDING_BYTES = 10e6


def _header(command: str, *parts: str) -> str:
    """The first line of a command that runs handshakes: softhand's version, the command and
    what it runs, parts separated by ``|``."""
    return " | ".join((f"softhand {__version__} {command}", *parts))


def _sensored_hand(hand: str, skins: str, controllers: str) -> str:
    """The sensored hand of a header: the paper's relaxed human hand, or the prosthetic hand
    with its ``skins`` and ``controllers`` (texts)."""
    return ("the relaxed human hand (the paper's protocol)" if hand == "human"
            else f"prosthetic hand, {skins}, {controllers}")


def design_of(value: str | None) -> tuple[str | None, str | None, str | None]:
    """--design VALUE as (the file, the skin name, the calibration folder): a skin name is
    itself, in the shipped folder (None, name, None); a calibration file's path is read and
    checked now (`softhand.skin.files.skin_file_folder`), one line naming the flag if bad."""
    from softhand.skin.files import is_skin_path, skin_file_folder

    if value is None or not is_skin_path(value):
        return None, value, None
    try:
        name, folder = skin_file_folder(value)
    except ValueError as exc:
        bad(f"--design {value!r}: {exc}")
    return value, name, str(folder)


def _check_hand(hand: str, controller: str, **prosthetic_only) -> None:
    """--hand human takes no prosthetic options: one line naming the first one given."""
    if hand != "human":
        return
    if controller != "neutral":
        bad(f"--controller {controller}: --hand human is the paper's relaxed experimenter, whose "
            "neutral grip is its own (allowed with --hand human: neutral)")
    for flag, value in prosthetic_only.items():
        if value:
            bad(f"--{flag} {value if isinstance(value, str) else ' '.join(value)}: --hand human "
                "wears human tissue on every region; skins are for --hand prosthetic")


def _partner_size(text: str | None) -> tuple[float, float] | None:
    """--partner-size LENGTH_MM,WIDTH_MM, checked against the paper's subjects' range."""
    from softhand.envs.partner import check_partner_size

    if text is None:
        return None
    parts = text.split(",")
    try:
        size = tuple(float(v) for v in parts)
    except ValueError:
        size = ()
    if len(size) != 2:
        bad(f"--partner-size {text!r}: expected LENGTH_MM,WIDTH_MM, e.g. 187.5,89.5")
    try:
        return check_partner_size(size)
    except ValueError as exc:
        bad(f"--partner-size: {exc}")


@main.command("render")
@click.argument("out")
@click.option("--design", default=None, help="Skin of every region [default: pocket2-sil].")
@click.option("--controller", type=click.Choice(["neutral", "open-loop", "force"]),
              default="neutral", show_default=True, help="Controller of the prosthetic hand.")
@click.option("--seed", type=click.IntRange(0, 2**32 - 1), default=0, show_default=True,
              help="Seed of the partner, 0 <= seed < 2^32.")
@click.option("--at", "at_s", type=Number(0, 10, unit="s"), default=None,
              help="Time of the picture, 0-10 s [default: the middle of the shake].")
@click.option("--azimuth", type=Number(-360, 360, unit="deg"), default=150.0, show_default=True)
@click.option("--elevation", type=Number(-90, 90, unit="deg"), default=-30.0, show_default=True)
@click.option("--distance", type=Number(0.05, 5, unit="m"), default=0.3, show_default=True)
@click.option("--size", nargs=2, type=click.IntRange(64, 4096), default=(960, 720),
              show_default=True, help="Width and height in pixels, 64-4096.")
@click.option("--partner-size", "partner_size", default=None, metavar="LENGTH_MM,WIDTH_MM",
              help="The partner's hand, within +-2.5 SD of the paper's subjects.")
@click.option("--sheet", is_flag=True,
              help="A contact sheet instead: at the end of the grip, mid-shake and mid-hold, from "
                   "the back of each hand, from below and from the thumb side, regions coloured "
                   "by force (its own times, views and size: --at and the camera options are "
                   "refused with it).")
@click.option("--video", is_flag=True,
              help="An animated GIF of the whole handshake instead (OUT .gif): the env's "
                   "rgb_array frames from the camera options, 12.5 frames per second of "
                   "simulated time.")
@_OPT_HAND
def render(out, design, controller, seed, at_s, azimuth, elevation, distance, size,
           partner_size, sheet, video, hand) -> None:
    """Run one handshake and render the scene at one moment to OUT (.png), offscreen.

    Needs an OpenGL context: MUJOCO_GL=egl (set here when unset) or osmesa.
    """
    _check_gl()
    from softhand.envs.handshake import HandshakeEnv
    from softhand.envs.physics import DivergenceError
    from softhand.envs.run import run_handshake
    from softhand.envs.skins import DEFAULT_DESIGN
    from softhand.viz.render import (
        CameraView,
        SheetFrame,
        render_sheet,
        render_state,
        write_video,
    )

    if design is not None and not design.strip():
        bad("--design '': expected a skin name, e.g. pocket2-sil")
    if sheet and video:
        bad("--sheet and --video: choose one")
    # an option the chosen picture does not use is refused, not ignored
    given = [name for name in ("at_s", "azimuth", "elevation", "distance", "size")
             if click.get_current_context().get_parameter_source(name)
             is not click.core.ParameterSource.DEFAULT]
    unused = (given if sheet else [n for n in given if n == "at_s"] if video else [])
    if unused:
        flag = {"at_s": "--at"}.get(unused[0], f"--{unused[0]}")
        bad(f"{flag} with {'--sheet' if sheet else '--video'}: "
            + ("the sheet has its own times (the end of the grip, mid-shake and mid-hold), "
               "views and size" if sheet else "the video shows the whole handshake")
            + f"; allowed with {'--sheet' if sheet else '--video'}: no {flag}")
    path = checked_file(out, "OUT", ".gif" if video else ".png")
    size_mm = _partner_size(partner_size)
    _check_hand(hand, controller, design=design)
    view = CameraView(distance_m=distance, azimuth_deg=azimuth, elevation_deg=elevation)
    try:
        env = HandshakeEnv(design=design, partner_size=size_mm, hand=hand,
                           **({"render_mode": "rgb_array", "render_size": tuple(size),
                               "render_view": view} if video else {}))
    except ValueError as exc:
        bad(str(exc))
    when = ("at the end of the grip, mid-shake and mid-hold, 4 views each" if sheet
            else "the whole handshake, 12.5 frames/s" if video
            else "at mid-shake" if at_s is None else f"at t = {at_s:g} s")
    click.echo(_header("render", _sensored_hand(hand, f"{design or DEFAULT_DESIGN} on every "
                                                "region", f"controller {controller}"),
                       f"partner seed {seed}" + ("" if size_mm is None else
                                                 f", hand {size_mm[0]:g} x {size_mm[1]:g} mm"),
                       when))
    if video:
        frames = _video_frames(env, controller, seed)
        write_video(frames, path, fps=VIDEO_FPS)
        click.echo(f"wrote {path} ({len(frames)} frames, {VIDEO_FPS:g} per second)")
        return
    try:
        run = run_handshake(controller=controller, seed=seed, env=env)
    except DivergenceError as exc:  # one line, exit 3 (render runs at the default timestep)
        raise Stopped(f"error: {exc.summary}; softhand handshake --timestep "
                      f"{exc.suggested_timestep_s:g} tries a smaller one", EXIT_CONVERGENCE
                      ) from None
    if sheet:
        grip = [i for i, p in enumerate(run.phase) if p == "grip"]
        shake = [i for i, p in enumerate(run.phase) if p == "shake"]
        hold = [i for i, p in enumerate(run.phase) if p == "hold"]
        frames = []
        for k, what in ((grip[-1], "end of the grip"), (shake[len(shake) // 2], "mid-shake"),
                        (hold[len(hold) // 2], "mid-hold")):
            frames.append(SheetFrame(run.qpos[k], run.mocap_pos[k], run.mocap_quat[k],
                                     f"{what}, t = {run.time_s[k]:.2f} s", _skin_forces(run, k)))
        render_sheet(run.model, frames, path)
        click.echo(f"wrote {path} (end of the grip, mid-shake and mid-hold, 4 views each)")
        return
    if at_s is None:
        shake = [i for i, p in enumerate(run.phase) if p == "shake"]
        k = shake[len(shake) // 2]
    else:
        k = int(np.argmin(np.abs(run.time_s - at_s)))
    render_state(run.model, run.qpos[k], run.mocap_pos[k], run.mocap_quat[k], path,
                 width=size[0], height=size[1], view=view,
                 region_force_N=_skin_forces(run, k),
                 caption=f"prosthetic skin by force: grey < 2 N, orange-red > 2 N; blue: the "
                         f"partner's hand; t = {run.time_s[k]:.2f} s ({run.phase[k]})")
    click.echo(f"wrote {path} (t = {run.time_s[k]:.2f} s, {run.phase[k]})")


def _skin_forces(run, k: int) -> dict[str, float]:
    """Each region's skin geom and its force (N) at frame ``k`` of a HandshakeRun."""
    from softhand.envs.picture import skin_forces  # the CLI imports no mujoco at its top

    return skin_forces(run.model, run.region_names, run.region_force_N[k])


#: Frames per second of simulated time in `softhand render --video` (every 8th env step of 10 ms)
VIDEO_FPS = 12.5


def _video_frames(env, controller: str, seed: int) -> list[np.ndarray]:
    """One handshake of ``env`` (made with ``render_mode="rgb_array"``) under ``controller``,
    and its ``render()`` every 1 / VIDEO_FPS s of simulated time."""
    from softhand.envs.controllers import make_controller
    from softhand.envs.physics import DivergenceError

    policy = make_controller(controller)
    every = max(1, round(1.0 / (VIDEO_FPS * env.frame_skip * float(env.model.opt.timestep))))
    obs, info = env.reset(seed=seed)
    frames, k = [env.render()], 0
    while True:
        obs, _, terminated, truncated, info = env.step(policy(obs, info))
        k += 1
        if info.get("unstable"):
            exc = DivergenceError(env.physics.divergence, skins=env.skins,
                                  representations=env.representations,
                                  timestep_s=float(env.model.opt.timestep))
            raise Stopped(f"error: {exc.summary}; softhand handshake --timestep "
                          f"{exc.suggested_timestep_s:g} tries a smaller one", EXIT_CONVERGENCE)
        if k % every == 0 or terminated or truncated:
            frames.append(env.render())
        if terminated or truncated:
            return frames


def _arms(hand: str, press_N: float | None, stiffness: float | None) -> dict:
    """The env's arm arguments for ``--press`` and ``--arm-stiffness`` (their ranges are
    softhand.hands.config.ARM_RANGES, checked by the options); {} for the defaults."""
    from softhand.hands import ArmConfig

    out = {}
    sensored = {"press_n": press_N, "stiffness_n_per_m": stiffness}
    sensored = {k: v for k, v in sensored.items() if v is not None}
    if sensored:
        out["sensored_arm"] = ArmConfig.of("relaxed" if hand == "human" else "prosthesis-user",
                                           **sensored)
    if press_N is not None:
        out["partner_arm"] = ArmConfig.of("active", press_n=press_N)
    return out


def _geometry_table(geo: dict, rows: int = 6) -> str:
    """The force through each local geometry and whether its law was made for it
    (`softhand.skin.local_geometry.geometry_accounting`): the largest ``rows`` classes."""
    lines = [f"\nthe law against the shapes each contact met (softhand.skin.local_geometry): a "
             f"skin law made for the contact's geometry carried "
             f"{geo['skin_own_class_share_pct']:.1f} % of the force, a tissue law "
             f"{geo['tissue_own_class_share_pct']:.1f} %, both {geo['own_class_share_pct']:.1f} "
             "%\n| what presses the skin, where | share | skin law | made for it |\n"
             "|---|---|---|---|"]
    for c in geo["classes"][:rows]:
        lines.append(f"| {c['contact']} | {c['share_pct']:.1f} % | {c['law']} | "
                     f"{'yes' if c['skin_fits'] else 'no'} |")
    rest = sum(c["share_pct"] for c in geo["classes"][rows:])
    if rest > 0:
        lines.append(f"| {len(geo['classes']) - rows} other classes | {rest:.1f} % | | |")
    return "\n".join(lines)
