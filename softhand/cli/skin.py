"""``softhand skin apply | flex-press``: calibrated skin on any MJCF hand; a flex pad on one
phalanx."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import click
import numpy as np

from softhand.cli.app import _check_gl, main
from softhand.cli.inputs import (
    Number,
    bad,
    checked_file,
    progress_bar,
)


@main.group()
def skin() -> None:
    """Calibrated skins on MuJoCo models."""


@skin.command("apply")
@click.argument("hand")
@click.argument("out")
@click.option("--geom", "geom_items", multiple=True, required=True,
              metavar="GEOM=DESIGN[@REPRESENTATION]",
              help="A geom to skin (repeatable), e.g. index_tip=pocket2-sil; representation "
                   "soft-contact (default) or rigid.")
@click.option("--against", "against", multiple=True, metavar="GEOM",
              help="A counterpart geom (repeatable) [default: every collidable geom outside the "
                   "hand].")
@click.option("--max-force", "max_force", type=Number(0.5, 20.0, unit="N"), default=None,
              help="Fit each skin's soft contact to its FE loading curve up to this force, "
                   "0.5-20 N (more accurate below it) [default: the shipped 0-20 N law].")
@click.option("--keyframe", "keyframe", default=None, metavar="NAME",
              help="Read each pair's contact class at this keyframe of HAND (the posture where "
                   "the hand holds what it touches: a finger on a mesh palm's rounded border "
                   "takes the border's law at its crossing) [default: HAND's qpos0].")
@click.option("--json", "as_json", is_flag=True,
              help="Print the skinned geoms and every change made to HAND as JSON.")
def skin_apply(hand, out, geom_items, against, max_force, keyframe, as_json) -> None:
    """Give the named geoms of the MJCF HAND a calibrated skin and write the model to OUT (.xml).

    Each skinned geom meets each counterpart through a <pair> with the design's law in
    solref/solimp, mass-compensated; its own contype/conaffinity become 0. OUT is HAND's text
    with only those changes (and absolute asset paths when OUT is in another folder), listed
    here and in a comment at its top; the output loads in plain MuJoCo."""
    import mujoco

    from softhand.skin.apply import (
        apply_skin,
        check_keyframe,
        check_skinnable,
        parse_geom_skins,
        write_skinned,
    )
    from softhand.skin.apply import skin_law_error as law_error

    source = Path(hand)
    if not source.is_file():
        bad(f"HAND {hand!r}: no such file (expected an MJCF .xml)")
    target = checked_file(out, "OUT", ".xml")
    if target.resolve() == source.resolve():
        bad(f"OUT {out!r} is HAND itself: write the skinned model to another file")
    try:
        geoms = parse_geom_skins(geom_items)
    except ValueError as exc:
        bad(str(exc))
    try:
        spec = mujoco.MjSpec.from_file(str(source))
        spec.compile()
    except ValueError as exc:
        bad(f"HAND {hand!r} does not load in MuJoCo: {str(exc).splitlines()[0]}")
    try:
        check_keyframe(spec, keyframe)
    except ValueError as exc:
        bad(f"--{exc}")
    known = {g.name for g in spec.geoms}
    try:
        check_skinnable(source, [g for g in geoms if g in known])
    except ValueError as exc:
        bad(f"--geom: HAND {hand!r}: {exc}")
    try:
        skinned = apply_skin(spec, {g: f"{d}@{r}" for g, (d, r) in geoms.items()},
                             against=list(against) or None, max_force_N=max_force,
                             keyframe=keyframe)
    except ValueError as exc:
        bad(f"--geom / --against: {exc}")
    try:
        written = write_skinned(spec, skinned, source, target)
    except ValueError as exc:
        bad(f"OUT {out!r}: {exc}")
    rows = []
    for s in skinned:
        err = None if s.law is None else law_error(s.design, s.law)
        rows.append({"geom": s.geom, "design": s.design, "representation": s.representation,
                     "pairs": dict(s.pair_laws), "law_rms_pct_of_2N_to_2N": err})
    if as_json:
        click.echo(json.dumps({"out": str(written.path), "source": str(source),
                               "skinned": rows,
                               "changes": [c.to_dict() for c in written.changes]}, indent=1))
        return
    for s, row in zip(skinned, rows, strict=True):
        err = row["law_rms_pct_of_2N_to_2N"]
        err = "" if err is None else f"; law vs its FE loading curve up to 2 N: {err:.2f} % RMS of 2 N"
        classes = Counter(s.pair_laws.values())
        laws = ", ".join(f"{n} {k}" for k, n in sorted(classes.items()))
        n = len(s.pairs)
        click.echo(f"{s.geom}: {s.design}@{s.representation}, {n} pair{'s' * (n != 1)} "
                   f"({laws}){err}")
    click.echo(f"changed in {source.name} (everything else is kept as written):")
    width = max(len(c.element) for c in written.changes)
    for c in written.changes:
        click.echo(f"  {c.element:<{width}}  {c.change}")
    click.echo(f"wrote {written.path}")


@skin.command("flex-press")
@click.option("--design", default="pocket2-sil", show_default=True,
              help="Skin whose calibrated flex pad is pressed (any calibrated skin).")
@click.option("--region", default="Index3", show_default=True,
              help="Phalanx region of the prosthetic hand that wears the pad (Thumb1-2, "
                   "Index1-3, Middle1-3, Ring1-3, Little1-3).")
@click.option("--posture", type=click.Choice(["extended", "flexed"]), default="extended",
              show_default=True, help="The digit extended, or its motor at half its range.")
@click.option("--max-force", "max_force", type=Number(0.01, 20.0, unit="N"), default=2.0,
              show_default=True, help="Stop at this plate force, 0.01-20 N.")
@click.option("--speed", "speed", type=Number(0.01, 100.0, unit="mm/s"), default=0.5,
              show_default=True, help="Plate speed, 0.01-100 mm/s (the FE's: 0.5).")
@click.option("--picture", "picture", default=None, metavar="OUT.png",
              help="Also draw the pressed pad at the peak (offscreen, MUJOCO_GL=egl).")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
def skin_flex_press(design, region, posture, max_force, speed, picture, as_json) -> None:
    """Press a plate into a flex pad on one region of the prosthetic hand: force against
    indentation, contact area and pressure (the flex representation, which the handshake
    cannot run: softhand.hands.flex_region)."""
    if picture is not None:
        _check_gl()
    from softhand.hands.flex_region import FLEX_REGIONS, press_flex_region
    from softhand.skin.calibrate import skin_names
    from softhand.skin.files import load_calibration

    if design not in skin_names():
        bad(f"--design {design!r} is unknown; allowed: {', '.join(skin_names())}")
    if region not in FLEX_REGIONS:
        bad(f"--region {region!r}: allowed {', '.join(FLEX_REGIONS)} (the palm and back are "
            "meshes, not phalanges)")
    try:
        params = load_calibration(design).params("flex")
    except (KeyError, ValueError) as exc:
        bad(f"--design {design!r}: no flex calibration ({exc})")
    picture = checked_file(picture, "--picture", ".png")
    with progress_bar(f"{design} flex on {region}", disable=as_json) as update:
        press = press_flex_region(params, region, posture, speed_mm_s=speed,
                                  max_force_N=max_force, progress=update)
    c = press.curve
    peak = float(c.force_N.max())
    marks = [f for f in (0.5, 1.0, 2.0, max_force) if f <= peak]
    out = {"design": design, "region": region, "posture": posture, "speed_mm_s": speed,
           "peak_force_N": peak, "indentation_at_peak_mm": float(c.displacement_mm[-1]),
           "contact_area_mm2": {f"{f:g}": press.area_at(f) for f in dict.fromkeys(marks)},
           "peak_pressure_kPa": float(press.patch.pressure_kPa.max(initial=0.0)),
           "step_us": c.stats["step_us"], "dofs": c.stats["nv"],
           "time_s": c.time_s.tolist(), "indentation_mm": c.displacement_mm.tolist(),
           "force_N": c.force_N.tolist(),
           "pressure_points_mm": press.patch.points_mm.tolist(),
           "pressure_kPa": press.patch.pressure_kPa.tolist()}
    if as_json:
        click.echo(json.dumps(out))
        return
    click.echo(f"{design} flex pad on {region} ({posture}), {speed:g} mm/s: "
               f"{peak:.3f} N at {out['indentation_at_peak_mm']:.3f} mm of indentation"
               + ("" if peak >= max_force * 0.999 else
                  f" (the pad peaked before {max_force:g} N: SVK softens in deep compression)"))
    for f, (lo, hi) in out["contact_area_mm2"].items():
        click.echo(f"  contact area at {f} N: {lo:.1f}-{hi:.1f} mm^2 (the mesh's bounds)")
    click.echo(f"  peak pressure {out['peak_pressure_kPa']:.1f} kPa; {out['step_us']:.0f} us "
               f"per step, {out['dofs']} dofs")
    if picture is not None:
        from softhand.viz.render import CameraView, render_state

        view = CameraView(lookat=tuple(press.lookat_m), distance_m=0.06, azimuth_deg=-90.0,
                          elevation_deg=-10.0)  # from the radial side, the palm down
        empty = np.zeros((0, 3)), np.zeros((0, 4))
        caption = (f"{design} flex pad on {region} ({posture}, seen from the radial side) "
                   f"pressed by the plate (grey) to {peak:.2f} N at "
                   f"{out['indentation_at_peak_mm']:.2f} mm; contacts dark magenta")
        wrote = render_state(press.model, press.qpos, *empty, picture, view=view,
                             caption=caption)
        click.echo(f"wrote {wrote}")
