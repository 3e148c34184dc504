"""The ``softhand`` command line.

``softhand fe indent DESIGN``   one FE indentation (``--json`` for machine-readable output)
``softhand fe sweep``           all 12 designs, curves + summary + plot into calibration/fe
``softhand fe export DESIGN``   an Abaqus input deck of the same model
``softhand calibrate [SKIN ...]``  laws + MuJoCo parameters per skin into calibration/skins
``softhand handshake``          one handshake with shipped calibration: region forces, rerun recording
``softhand bench fe``           speed against error of the FE stage, written to a report
``softhand bench calibration``  error against FE and cost per step of each MuJoCo representation

Bad input exits with status 2 and one line that names the value and the allowed range; nothing
is written then.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import click

from softhand import __version__

DEFAULT_FE_DIR = Path("calibration") / "fe"


def _fail(exc: Exception) -> None:
    raise click.UsageError(str(exc)) from None


def _parse_geometry(items: tuple[str, ...]) -> dict[str, float]:
    out: dict[str, float] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep:
            raise click.BadParameter(f"{item!r} is not KEY=VALUE", param_hint="--geometry")
        try:
            out[key.strip()] = float(value)
        except ValueError:
            raise click.BadParameter(f"{value!r} in {item!r} is not a number",
                                     param_hint="--geometry") from None
    return out


def _load_materials(path: str | None) -> dict[str, dict]:
    if path is None:
        return {}
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise click.BadParameter(f"{path!r}: {exc}", param_hint="--materials") from None
    if not isinstance(data, dict):
        raise click.BadParameter(f"{path!r} must hold an object keyed by material name",
                                 param_hint="--materials")
    return data


def _settings(**kw: Any):
    from softhand.fem.solver import IndentationSettings

    try:
        return IndentationSettings(**kw)
    except ValueError as exc:
        _fail(exc)


_common_fe = [
    click.option("--mesh", type=click.Choice(["coarse", "default", "uniform", "fine"]),
                 default="default", show_default=True,
                 help="Mesh: default is graded to the pocket ends; fine doubles every count."),
    click.option("--mode", type=click.Choice(["3d", "2d"]), default="3d", show_default=True,
                 help="3D quarter model, or fast 2D plane-strain cross-section."),
    click.option("--elastic-only", is_flag=True, help="Hyperfoam only, no Prony relaxation."),
    click.option("--moduli", type=click.Choice(["long-term", "instantaneous"]),
                 default="long-term", show_default=True,
                 help="How Table 3 moduli are read."),
    click.option("--hold", "hold_s", type=float, default=10.0, show_default=True,
                 help="Hold after the ramp (s)."),
    click.option("--speed", "speed_mm_s", type=float, default=0.5, show_default=True,
                 help="Plate speed (mm/s)."),
    click.option("--max-force", "max_force_N", type=float, default=2.0, show_default=True,
                 help="Force that ends the ramp (N)."),
    click.option("--geometry", multiple=True, metavar="KEY=VALUE",
                 help="Override a geometry field, e.g. pocket_roof_mm=1.5 (repeatable)."),
    click.option("--materials", "materials_path", type=click.Path(dir_okay=False),
                 help="JSON file with material constants replacing Table 3."),
]


def _fe_options(f):
    for opt in reversed(_common_fe):
        f = opt(f)
    return f


def _make_settings(mesh, mode, elastic_only, moduli, hold_s, speed_mm_s, max_force_N,
                   geometry, materials_path):
    return _settings(mesh=mesh, mode=mode, elastic_only=elastic_only, moduli=moduli,
                     hold_s=hold_s, speed_mm_s=speed_mm_s, max_force_N=max_force_N,
                     geometry=_parse_geometry(geometry), materials=_load_materials(materials_path))


@click.group()
@click.version_option(__version__, prog_name="softhand")
def main() -> None:
    """softhand: lifelike prosthetic skins, from FE indentation to MuJoCo."""


@main.group()
def fe() -> None:
    """Finite-element indentation of the paper's phalanx designs."""


@fe.command("indent")
@click.argument("design")
@_fe_options
@click.option("--out", "out_dir", type=click.Path(file_okay=False),
              help="Write the curve CSV and summary JSON here.")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
def fe_indent(design, out_dir, as_json, **kw) -> None:
    """Indent DESIGN (e.g. pocket2-sil, solid-pu-sil) with a rigid plate."""
    from tqdm import tqdm

    from softhand.fem.geometry import parse_design
    from softhand.fem.solver import ConvergenceError, indent
    from softhand.fem.sweep import write_results

    try:
        design = parse_design(design).name
    except ValueError as exc:
        _fail(exc)
    settings = _make_settings(**kw)
    with tqdm(total=100, desc=design, unit="%", disable=as_json, file=sys.stderr) as bar:
        def progress(frac: float) -> None:
            bar.update(round(100 * frac) - bar.n)

        try:
            result = indent(design, settings, progress=progress)
        except ValueError as exc:
            _fail(exc)
        except ConvergenceError as exc:
            click.echo(f"error: {exc}", err=True)
            sys.exit(3)
    if out_dir:
        write_results({design: result}, out_dir, plot=False)
    summary = result.summary()
    if as_json:
        click.echo(json.dumps(summary))
        return
    _print_result(summary)


def _print_result(s: dict[str, Any]) -> None:
    from softhand.paper import displacement_at_2n, force_at_2mm

    def fmt(v, unit):
        return "not reached" if v is None else f"{v:.3f} {unit}"

    click.echo(f"design {s['design']} ({s['mode']}, mesh {s['mesh']}, moduli {s['moduli']})")
    ref = displacement_at_2n(s["design"])
    click.echo(f"  displacement at 2 N : {fmt(s['displacement_at_2N_mm'], 'mm')}"
               + (f"   (paper {ref} mm)" if ref else ""))
    ref = force_at_2mm(s["design"])
    click.echo(f"  force at 2 mm       : {fmt(s['force_at_2mm_N'], 'N')}"
               + (f"   (paper {ref} N)" if ref else ""))
    click.echo(f"  peak / after hold   : {s['peak_force_N']:.3f} N / {s['relaxed_force_N']:.3f} N")
    click.echo(f"  {s['n_elements']} elements, {s['n_dofs']} dofs, {s['n_steps']} steps, "
               f"{s['newton_iterations']} Newton iterations, {s['wall_s']:.1f} s")


@fe.command("sweep")
@_fe_options
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=str(DEFAULT_FE_DIR),
              show_default=True, help="Folder for curves, summary.json and curves.png.")
@click.option("--design", "designs", multiple=True, help="Only these designs (repeatable).")
@click.option("--jobs", type=click.IntRange(min=1), default=None,
              help="Designs run at once, one process each [default: CPU count].")
def fe_sweep(out_dir, designs, jobs, **kw) -> None:
    """Indent all 12 designs and compare them with the paper."""
    from softhand.fem.geometry import DESIGNS, parse_design
    from softhand.fem.solver import ConvergenceError
    from softhand.fem.sweep import paper_error_table, run_sweep, write_results

    settings = _make_settings(**kw)
    try:
        names = [parse_design(d).name for d in (designs or DESIGNS)]
        for n in names:
            parse_design(n).geometry(**settings.geometry)
    except ValueError as exc:
        _fail(exc)
    try:
        results = run_sweep(names, settings, jobs=jobs)
    except ConvergenceError as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(3)
    summary = write_results(results, out_dir)
    click.echo(paper_error_table(summary))
    click.echo(f"wrote {len(results)} curves, summary.json and curves.png to {out_dir} "
               f"({summary['total_wall_s']:.0f} s of FE)")


@fe.command("export")
@click.argument("design")
@click.argument("out", type=click.Path(dir_okay=False))
@click.option("--format", "fmt", type=click.Choice(["inp"]), default="inp", show_default=True,
              help="Abaqus input deck.")
@_fe_options
def fe_export(design, out, fmt, **kw) -> None:
    """Write DESIGN as an Abaqus-format input deck to OUT."""
    from softhand.fem.abaqus import write_inp

    settings = _make_settings(**kw)
    try:
        path = write_inp(design, out, settings)
    except ValueError as exc:
        _fail(exc)
    click.echo(f"wrote {path}")


@main.command("calibrate")
@click.argument("skins", nargs=-1)
@click.option("--representation", "representations", multiple=True,
              help="rigid, soft-contact, soft-contact+relaxation or flex (repeatable) "
                   "[default: all four].")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None,
              help="Folder for the calibration files [default: calibration/skins].")
@click.option("--fe-dir", type=click.Path(file_okay=False), default=None,
              help="Folder with the FE curves [default: calibration/fe].")
@click.option("--jobs", type=click.IntRange(min=1), default=None,
              help="Skins calibrated at once, one process each [default: CPU count].")
@click.option("--json", "as_json", is_flag=True, help="Print the errors as JSON.")
def calibrate(skins, representations, out_dir, fe_dir, jobs, as_json) -> None:
    """Fit laws and MuJoCo parameters for SKINS (default: the 12 designs and 2 references)."""
    from softhand.skin.calibrate import skin_names
    from softhand.skin.rig import REPRESENTATIONS
    from softhand.skin.run import calibrate_many, summary_table

    names = list(skins) or skin_names()
    for n in names:
        if n not in skin_names():
            _fail(ValueError(f"skin {n!r} is unknown; allowed: {', '.join(skin_names())}"))
    reps = tuple(representations) or REPRESENTATIONS
    for r in reps:
        if r not in REPRESENTATIONS:
            _fail(ValueError(f"representation {r!r} is unknown; allowed: "
                             f"{', '.join(REPRESENTATIONS)}"))
    try:
        result = calibrate_many(names, reps, out_dir=out_dir, fe_dir=fe_dir, jobs=jobs,
                                show_progress=not as_json)
    except (FileNotFoundError, ValueError) as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(3)
    if as_json:
        click.echo(json.dumps(result, indent=1))
    else:
        click.echo(summary_table(result))


def _parse_skin_overrides(items: tuple[str, ...]) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        region, sep, design = item.partition("=")
        if not sep or not region or not design:
            raise click.BadParameter(f"{item!r} is not REGION=DESIGN (e.g. Palm1=pocket2-sil)",
                                     param_hint="--skin")
        out[region.strip()] = design.strip()
    return out


@main.command("handshake")
@click.option("--design", default=None, help="Skin of every region [default: pocket2-sil].")
@click.option("--skin", "skin_items", multiple=True, metavar="REGION=DESIGN",
              help="Skin of one region (repeatable), e.g. Palm1=rigid.")
@click.option("--controller", type=click.Choice(["neutral", "open-loop", "force"]),
              default="neutral", show_default=True,
              help="Controller of the prosthetic hand (neutral: the paper's sensored hand).")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the partner.")
@click.option("--timestep", "timestep_s", type=click.FloatRange(0.0, 0.01, min_open=True),
              default=0.002, show_default=True,
              help="Physics timestep (s); skins are calibrated for 0.0005-0.002. Actions stay "
                   "at 100 Hz.")
@click.option("--record", "record_path", type=click.Path(dir_okay=False), default=None,
              help="Write a rerun recording (.rrd) here.")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
def handshake(design, skin_items, controller, seed, timestep_s, record_path, as_json) -> None:
    """Shake hands once (shipped calibration, no FE run) and report the force on each region."""
    from softhand.envs.run import OVER_N, run_handshake
    from softhand.envs.skins import parse_skins

    if not math.isfinite(timestep_s):  # FloatRange lets nan through
        raise click.BadParameter(f"{timestep_s} is not in the range 0.0<x<=0.01",
                                 param_hint="'--timestep'")
    overrides = _parse_skin_overrides(skin_items)
    try:
        parse_skins(design, overrides)
        run = run_handshake(design=design, skins=overrides, controller=controller, seed=seed,
                            timestep_s=timestep_s)
    except ValueError as exc:
        _fail(exc)
    if record_path:
        from softhand.viz import record_handshake
        from softhand.viz.bench import frames_of

        record_handshake(record_path, run.model, frames_of(run))
    summary = run.summary()
    if as_json:
        click.echo(json.dumps(summary, indent=1))
        return
    click.echo("| region | skin | peak N | mean N | peak area mm^2 | > 2 N |\n"
               "|---|---|---|---|---|---|")
    for region, v in summary["regions"].items():
        mark = "yes" if v["peak_N"] > OVER_N else ""
        click.echo(f"| {region} | {run.skins[region]} | {v['peak_N']:.2f} | {v['mean_N']:.2f} | "
                   f"{v['peak_area_mm2']:.0f} | {mark} |")
    cmp = summary["paper_over_2N"]
    click.echo(f"\nover 2 N in both softhand and the paper (Fig. 4): {', '.join(cmp['both']) or '-'}")
    click.echo(f"only in the paper: {', '.join(cmp['only_paper']) or '-'}; "
               f"only in softhand: {', '.join(cmp['only_softhand']) or '-'}")
    click.echo(f"bone on bone (no skin between): peak {summary['rigid_contact_peak_N']:.1f} N")
    click.echo(f"{summary['steps_per_s']:.0f} steps/s, {summary['realtime_factor']:.1f}x real time"
               + (f"; recording: {record_path}" if record_path else ""))


@main.group()
def bench() -> None:
    """Benchmarks: speed against error, written to a report (never run as tests)."""


@bench.command("fe")
@click.option("--out", "out_dir", type=click.Path(file_okay=False),
              default="reports", show_default=True, help="Folder for bench-fe.md/json.")
@click.option("--quick", is_flag=True, help="Skip the fine-mesh reference runs.")
def bench_fe(out_dir, quick) -> None:
    """Time one 3D design, the 12-design sweep and the 2D mode; errors against the fine mesh."""
    from softhand.fem.bench import run_fe_benchmark

    report = run_fe_benchmark(out_dir, quick=quick)
    click.echo(report)


@bench.command("handshake")
@click.option("--out", "out_dir", type=click.Path(file_okay=False),
              default="reports", show_default=True, help="Folder for bench-handshake.md/json.")
def bench_handshake(out_dir) -> None:
    """Handshake speed (recording off/on, 0.5-2 ms) and the skins side by side."""
    from softhand.viz.bench import run_handshake_benchmark

    click.echo(run_handshake_benchmark(out_dir))


@bench.command("calibration")
@click.option("--out", "out_dir", type=click.Path(file_okay=False),
              default="reports", show_default=True,
              help="Folder for bench-calibration.md/json/png.")
@click.option("--skin", "skins", multiple=True, help="Skins to measure (repeatable) "
              "[default: every shipped skin].")
def bench_calibration(out_dir, skins) -> None:
    """Each representation's error against FE and cost per step relative to rigid, one run."""
    from softhand.skin.bench import run_calibration_benchmark

    try:
        report = run_calibration_benchmark(out_dir, skins=list(skins) or None)
    except ValueError as exc:
        _fail(exc)
    click.echo(report)


if __name__ == "__main__":  # pragma: no cover
    main()
