"""``softhand sensors calibrate``: FE sensor records and transfer laws per design and placement."""

from __future__ import annotations

import click

from softhand.cli.app import (
    _STOP,
    EXIT_CONVERGENCE,
    EXIT_INTERRUPTED,
    Stopped,
    _folder_bytes,
    _writing,
    main,
)
from softhand.cli.inputs import (
    OPT_CLUSTER,
    OPT_THREADS,
    bad,
    check_threads_or_cluster,
    checked_dir,
    designs_of,
    progress_line,
    with_options,
)
from softhand.paths import SENSORS_DIR, is_shipped


@main.group()
def sensors() -> None:
    """Embedded sensors: FE records and transfer laws."""


@sensors.command("calibrate")
@click.option("--out", "out_dir", default=str(SENSORS_DIR), show_default=True,
              help="Folder for fe/ (records) and transfer.json.")
@click.option("--design", "designs", multiple=True, help="Only these designs (repeatable).")
@click.option("--fit-only", is_flag=True,
              help="Refit the transfer laws from the records already in --out/fe (no FE run).")
@with_options((OPT_THREADS, OPT_CLUSTER))
@click.option("--force", is_flag=True,
              help="Allow writing into the shipped calibration/ (replaced only when the run "
                   "completes).")
def sensors_calibrate(out_dir, designs, fit_only, threads, cluster, force) -> None:
    """Run the FE sensor records (0.5 and 2 mm/s to 20 N, 10 s hold) and fit the transfer laws."""
    from softhand.fem.geometry import DESIGNS
    from softhand.io import staged_folder
    from softhand.sensors import calibrate as cal

    check_threads_or_cluster(threads, cluster)
    names = designs_of(dict.fromkeys(designs or DESIGNS))
    shipped = is_shipped(out_dir) if str(out_dir).strip() else False
    out = checked_dir(out_dir, "--out", force=force,
                      need_bytes=1e6 + (_folder_bytes(out_dir) if shipped else 0))
    if fit_only:
        for n in names:
            try:
                cal.read_records(out, n)
            except (OSError, ValueError, KeyError) as exc:
                bad(f"--out {str(out)!r}: {exc} (run without --fit-only to make the records)")
    kept = "the shipped set is unchanged" if shipped else f"the finished ones are in {out / 'fe'}"
    with staged_folder(out, stage=shipped) as staged, _writing(
            out, "the FE records written before the failure; transfer.json is the old one"):
        if not fit_only:
            _, missing, interrupted = cal.run_sensor_fe(names, staged.path, threads=threads,
                                                        cluster=cluster, progress=progress_line)
            if interrupted:
                raise Stopped(f"interrupted ({_STOP['by']}): {kept}; missing: "
                              f"{', '.join(missing)}; no law was fitted", EXIT_INTERRUPTED)
            if missing:
                raise Stopped(f"error: {len(missing)} FE records did not finish "
                              f"({', '.join(missing)}); {kept}; no law was fitted",
                              EXIT_CONVERGENCE)
        # atomically: Ctrl-C leaves the old file
        data = cal.fit_all(names, staged.path, progress=progress_line)
        staged.commit()
    for design, per in data["laws"].items():
        errs = ", ".join(f"{v['placement']} {v['fitted'][0]['rms_pct']:.2f}/"
                         f"{(v['validated'] or [{'rms_pct': float('nan')}])[0]['rms_pct']:.2f} %"
                         for v in per.values())
        click.echo(f"{design}: RMS error fit/validation, % of the reading at 20 N: {errs}")
    click.echo(f"wrote {out / 'transfer.json'}")
