"""``softhand fe indent | sweep | export``: the FE stage from the command line."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import click

from softhand.cli.app import EXIT_CONVERGENCE, Stopped, _end_of_batch, _folder_bytes, _writing, main
from softhand.cli.inputs import (
    EXPORT_OPTIONS,
    FE_OPTIONS,
    OPT_CLUSTER,
    Number,
    bad,
    check_threads_or_cluster,
    checked_dir,
    checked_file,
    designs_of,
    make_settings,
    parse_sensors,
    progress_bar,
    with_options,
)
from softhand.paths import FE_DIR, is_shipped


@main.group()
def fe() -> None:
    """Finite-element indentation of the paper's phalanx designs."""


@fe.command("indent")
@click.argument("design")
@with_options(FE_OPTIONS)
@click.option("--sensor", "sensor_items", multiple=True, metavar="PLACEMENT[:WxL][@X,Z]",
              help="An embedded sensor patch (repeatable): bone, interface or pocket-floor, its "
                   "size in mm (default 4x4) and centre [default: 4x4 mm under the indenter at "
                   "each placement the design has].")
@click.option("--out", "out_dir", help="Write the curve CSV and summary JSON into this folder.")
@click.option("--force", is_flag=True,
              help="Allow --out inside the shipped calibration/ (replaced only when the run "
                   "completes).")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
def fe_indent(design, sensor_items, out_dir, force, as_json, **kw) -> None:
    """Indent DESIGN (e.g. pocket2-sil, solid-pu-sil) with a rigid plate, cylinder or sphere."""
    from dataclasses import replace

    from softhand.fem.indenter import parse_indenter
    from softhand.fem.solver import ConvergenceError, Status, indent
    from softhand.fem.sweep import write_results
    from softhand.io import staged_folder

    (name,) = designs_of([design])
    settings = make_settings([name], **kw)
    sensors = parse_sensors(sensor_items, name, settings.geometry)
    if sensors and settings.body != "phalanx":
        bad(f"--sensor with --body {settings.body}: embedded sensors are read on the phalanx "
            "only (--body phalanx, the default)")
    if sensors and parse_indenter(settings.indenter).full_model:
        bad(f"--sensor with --indenter {settings.indenter!r}: embedded sensors are read on the "
            "quarter model only (cylinder angles 0 and 90, sphere, plate); this angle runs the "
            "full model")
    if sensors is not None:
        settings = replace(settings, sensors=sensors)
    out = checked_dir(out_dir, "--out", force=force, need_bytes=_FE_BYTES)
    if out is not None:
        _check_fe_folder(out, settings, [name])
    try:
        with progress_bar(name, disable=as_json) as progress:
            result = indent(name, settings, progress=progress)
    except ConvergenceError as exc:
        raise Stopped(f"error: {exc}", EXIT_CONVERGENCE) from None
    if out is not None:
        with staged_folder(out, stage=is_shipped(out)) as staged, _writing(
                out, "the folder's earlier files; summary.json was not updated"):
            write_results({name: result}, staged.path, plot=False)
            staged.commit()
    if result.status is Status.REACHED_DEPTH:
        click.echo(f"warning: the ramp stopped at --max-depth {settings.max_depth_mm:g} mm with "
                   f"{result.force_N[~result.hold][-1]:.3f} N, before --max-force "
                   f"{settings.max_force_N:g} N", err=True)
    summary = result.summary()
    if as_json:
        click.echo(json.dumps(summary))
        return
    _print_result(summary)


def _print_result(s: dict[str, Any]) -> None:
    from softhand.paper import displacement_at_2n, force_at_2mm

    def fmt(v, unit):
        return "not reached" if v is None else f"{v:.3f} {unit}"

    palm = s.get("body", "phalanx") != "phalanx"
    # the paper's numbers are the plate's on the phalanx
    plate = s.get("indenter", "plate") == "plate" and not palm
    click.echo(f"design {s['design']} ({s['mode']}, mesh {s['mesh']}, moduli {s['moduli']}"
               + ("" if s.get("indenter", "plate") == "plate" else f", indenter {s['indenter']}")
               + (f", body {s['body']}" if palm else "") + ")")
    ref = displacement_at_2n(s["design"]) if plate else None
    click.echo(f"  displacement at 2 N : {fmt(s['displacement_at_2N_mm'], 'mm')}"
               + (f"   (paper {ref} mm)" if ref else ""))
    ref = force_at_2mm(s["design"]) if plate else None
    click.echo(f"  force at 2 mm       : {fmt(s['force_at_2mm_N'], 'N')}"
               + (f"   (paper {ref} N)" if ref else ""))
    click.echo(f"  peak / after hold   : {s['peak_force_N']:.3f} N / {s['relaxed_force_N']:.3f} N")
    click.echo(f"  {s['n_elements']} elements, {s['n_dofs']} dofs, {s['n_steps']} steps, "
               f"{s['newton_iterations']} Newton iterations, {s['wall_s']:.1f} s")


#: Bytes an FE folder write takes at most: curves, summary, plot (and their temp copies)
_FE_BYTES = 2e6


def _check_fe_folder(out: Path, settings, designs: list[str]) -> None:
    """The FE folder's summary is readable and of the same settings (or replaced whole)."""
    from softhand.fem.sweep import folder_conflict, read_summary

    try:
        conflict = folder_conflict(read_summary(out), settings, designs)
    except ValueError as exc:
        bad(f"--out: {exc}")
    if conflict:
        bad(f"--out {str(out)!r} holds FE curves of other settings ({conflict}): a folder holds "
            "one setting; write into another folder")


@fe.command("sweep")
@with_options(FE_OPTIONS)
@click.option("--out", "out_dir", default=str(FE_DIR), show_default=True,
              help="Folder for curves, summary.json and curves.png.")
@click.option("--design", "designs", multiple=True, help="Only these designs (repeatable).")
@OPT_CLUSTER
@click.option("--force", is_flag=True,
              help="Allow writing into the shipped calibration/ (replaced only when the run "
                   "completes).")
def fe_sweep(out_dir, designs, cluster, force, threads, **kw) -> None:
    """Indent all 12 designs and compare them with the paper."""
    from softhand.fem.geometry import DESIGNS
    from softhand.fem.sweep import paper_error_table, run_sweep, write_results
    from softhand.io import interrupts_deferred, staged_folder

    check_threads_or_cluster(threads, cluster)
    names = designs_of(dict.fromkeys(designs or DESIGNS))
    settings = make_settings(names, threads=None, **kw)
    shipped = out_dir is not None and is_shipped(out_dir)
    out = checked_dir(out_dir, "--out", force=force,
                      need_bytes=_FE_BYTES + (_folder_bytes(out_dir) if shipped else 0))
    _check_fe_folder(out, settings, names)
    with staged_folder(out, stage=shipped) as staged:
        batch = run_sweep(names, settings, threads=threads, cluster=cluster)
        missing = {n: "interrupted" for n in batch.missing}
        missing.update({n: str(e) for n, e in batch.errors.items()})
        if batch.results:
            with interrupts_deferred(), _writing(
                    out, "the curves written before the failure; summary.json was not updated"):
                summary = write_results(batch.results, staged.path, missing=missing,
                                        plot=not batch.interrupted)  # stop fast: no plot
                if not missing:
                    staged.commit()
            if settings.indenter != "plate" or settings.body != "phalanx":
                click.echo(f"note: indenter {settings.indenter} on the {settings.body}; the "
                           "paper's numbers below are the plate's on the phalanx")
            click.echo(paper_error_table(summary))
    _end_of_batch("designs", len(batch.results), len(names), out, missing, batch.interrupted,
                  staged=shipped and not staged.committed)
    click.echo(f"wrote {len(batch.results)} curves, summary.json and curves.png to {out} "
               f"({summary['total_wall_s']:.0f} s of FE)")


@fe.command("export")
@click.argument("design")
@click.argument("out")
@click.option("--format", "fmt", type=click.Choice(["inp", "ccx"]), default="inp",
              show_default=True,
              help="inp: Abaqus/Standard (hyperfoam + Prony); ccx: CalculiX 2.20 (hyperfoam "
                   "only: CalculiX has no Prony viscoelasticity for it).")
@click.option("--depth", "depth_mm", type=Number(0, 7, lo_open=True, unit="mm"), default=None,
              help="Plate travel of the ramp, (0, 7] mm [default: the travel at which softhand's "
                   "own run of this model reaches --max-force, found by running it].")
@with_options(EXPORT_OPTIONS)
def fe_export(design, out, fmt, depth_mm, **kw) -> None:
    """Write DESIGN as an Abaqus (.inp) or CalculiX (.inp) input deck to OUT."""
    from softhand.fem.abaqus import write_deck
    from softhand.fem.indenter import parse_indenter

    (name,) = designs_of([design])
    settings = make_settings([name], **kw)
    if parse_indenter(settings.indenter).full_model:
        bad(f"--indenter {settings.indenter!r}: the decks are the quarter model (symmetry "
            "planes x = 0, z = 0); a cylinder at another angle than 0 or 90 deg runs on "
            "softhand's full model and is not exported: allowed angles 0 and 90")
    path = checked_file(out, "OUT", ".inp")
    with progress_bar(f"{name}: plate travel", disable=depth_mm is not None) as progress:
        try:
            info = write_deck(name, path, settings, fmt=fmt, depth_mm=depth_mm,
                              progress=progress)
        except ValueError as exc:
            bad(str(exc))
    source = ("--depth" if info.depth_source == "given"
              else f"softhand's own travel to --max-force {settings.max_force_N:g} N")
    click.echo(f"wrote {info.path} ({fmt}, plate travel {info.depth_mm:.4g} mm: {source})")
