"""``softhand bench fe | calibration | handshake | flex | sensors``: the benchmarks, written to
reports/."""

from __future__ import annotations

import click

from softhand.cli.app import main
from softhand.cli.inputs import (
    bad,
    checked_dir,
    progress_bar,
    progress_line,
)
from softhand.paths import REPORTS_DIR


@main.group()
def bench() -> None:
    """Benchmarks: speed against error, written to a report (never run as tests)."""


_OPT_REPORTS = click.option("--out", "out_dir", default=str(REPORTS_DIR), show_default=True,
                            help="Folder for the report files.")


@bench.command("fe")
@_OPT_REPORTS
@click.option("--quick", is_flag=True,
              help="Skip the 3D fine-mesh reference runs (~40 min); keep those of the last report.")
def bench_fe(out_dir, quick) -> None:
    """Time one 3D design (idle and next to CPU load), the sweeps and 2D; errors vs fine mesh."""
    from softhand.bench.fe import run_fe_benchmark

    click.echo(run_fe_benchmark(checked_dir(out_dir, "--out"), quick=quick,
                                progress=progress_line))


@bench.command("handshake")
@_OPT_REPORTS
@click.option("--scale", is_flag=True,
              help="Only the speed at scale (~3 min): one env, the vector env at 2-128 worlds, "
                   "the physics ceiling and the Python per stage (bench-handshake-scale.md).")
@click.option("--worlds", default=None, metavar="N,N,...",
              help="With --scale: the vector env's worlds, each 1-1024 [default: 2,8,32,128].")
def bench_handshake(out_dir, scale, worlds) -> None:
    """Handshake speed (recording off/on, 0.5-2 ms) and the skins side by side; --scale: the
    speed of one env, the vector env and the physics ceiling."""
    if worlds is not None and not scale:
        bad(f"--worlds {worlds!r}: only with --scale (the vector env is measured there)")
    counts = None  # the benchmark's own default
    if worlds is not None:
        try:
            if not all(v.strip().isdigit() for v in worlds.split(",")):  # no "1_0", "+2", "2.0"
                raise ValueError(worlds)
            counts = tuple(int(v) for v in worlds.split(","))
        except ValueError:
            counts = ()
        if not counts or not all(1 <= n <= 1024 for n in counts):
            bad(f"--worlds {worlds!r}: expected integers 1-1024 separated by commas, e.g. 2,8,32")
    out = checked_dir(out_dir, "--out")
    if scale:
        from softhand.bench.scale import run_scale_benchmark

        click.echo(run_scale_benchmark(out, worlds=counts, progress=progress_line))
        return
    from softhand.bench.handshake import run_handshake_benchmark

    click.echo(run_handshake_benchmark(out, progress=progress_line))


@bench.command("sensors")
@_OPT_REPORTS
@click.option("--design", "designs", multiple=True,
              help="Designs of the table (repeatable) [default: all 12].")
@click.option("--no-handshake", is_flag=True,
              help="Only the design table and the transfer curves (no handshakes, ~2 min).")
def bench_sensors(out_dir, designs, no_handshake) -> None:
    """Embedded sensors: design table, transfer curves, handshake and controllers on sensors."""
    from softhand.bench.sensors import run_sensor_table
    from softhand.fem.geometry import DESIGNS

    out = checked_dir(out_dir, "--out")
    for d in designs:
        if d not in DESIGNS:
            bad(f"--design {d!r} is unknown; allowed: {', '.join(DESIGNS)}")
    click.echo(run_sensor_table(out, designs=tuple(dict.fromkeys(designs)) or None,
                                handshakes=not no_handshake, progress=progress_line))


@bench.command("flex")
@_OPT_REPORTS
def bench_flex(out_dir) -> None:
    """A flex pad on the prosthetic fingertip against the flex rig and the FE (~5 min)."""
    from softhand.bench.flex import markdown, run_flex_bench

    out = checked_dir(out_dir, "--out")
    with progress_bar("bench flex", disable=False) as update:
        data = run_flex_bench(out, progress=update)
    click.echo(markdown(data))


@bench.command("calibration")
@_OPT_REPORTS
@click.option("--skin", "skins", multiple=True, help="Skins to measure (repeatable) "
              "[default: every shipped skin].")
def bench_calibration(out_dir, skins) -> None:
    """Each representation's error against FE and cost per step relative to rigid, one run."""
    from softhand.bench.calibration import run_calibration_benchmark
    from softhand.skin.files import shipped_skins

    out = checked_dir(out_dir, "--out")
    known = shipped_skins()
    for s in skins:
        if s not in known:
            bad(f"--skin {s!r} has no shipped calibration; allowed: {', '.join(known)}")
    click.echo(run_calibration_benchmark(out, skins=list(dict.fromkeys(skins)) or None,
                                         progress=progress_line))
