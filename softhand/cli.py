"""The ``softhand`` command line.

``softhand fe indent DESIGN``   one FE indentation (``--json`` for machine-readable output)
``softhand fe sweep``           all 12 designs, curves + summary + plot into calibration/fe
``softhand fe export DESIGN``   an Abaqus or CalculiX input deck of the same model
``softhand calibrate [SKIN ...]``  laws + MuJoCo parameters per skin into calibration/skins
``softhand skin apply HAND OUT``  calibrated skin on named geoms of any MJCF hand, as MJCF
``softhand skin flex-press``    a flex pad on one prosthetic phalanx: force, contact area, pressure
``softhand handshake``          one handshake with shipped calibration: region forces, rerun recording
``softhand render OUT.png``     a picture of the handshake (offscreen mujoco.Renderer)
``softhand bench fe``           speed against error of the FE stage, written to a report
``softhand bench calibration``  error against FE and cost per step of each MuJoCo representation
``softhand bench handshake``    handshake speed and the skins side by side
``softhand bench flex``         the flex region on the hand against the flex rig and the FE
``softhand bench sensors``      embedded sensors: the design table, transfer curves, the handshake
``softhand sensors calibrate``  FE sensor records and transfer laws per design and placement

Every argument and input file is checked before any work starts. Exit status:

== ===================================================================================
0  done
1  internal error (one line; ``SOFTHAND_TRACEBACK=1`` shows the traceback)
2  bad input: one line ``error: ...`` naming the flag (or file, skin and key), the value and
   the allowed range; nothing computed, nothing written
3  an FE run or a calibration did not converge, or a handshake diverged (what finished is
   written)
4  an output could not be written during the run (a full disk): one line saying what was kept
130 interrupted by Ctrl-C or SIGTERM: what had finished is written (atomically), nothing partial
== ===================================================================================

Default folders come from `softhand.paths` (the same for every command). Only ``fe sweep``,
``fe indent --out``, ``calibrate`` and ``sensors calibrate`` write into the shipped
``calibration/``, and only with ``--force``: the new set goes into a copy beside it that replaces
it only when the run completes (`softhand.io.staged_folder`).
"""

from __future__ import annotations

import errno
import json
import os
import signal
import sys
import warnings
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, NoReturn

import click
import numpy as np

from softhand import __version__
from softhand.cli_inputs import (
    EXIT_INPUT,
    EXPORT_OPTIONS,
    FE_OPTIONS,
    OPT_CLUSTER,
    OPT_THREADS,
    SENSOR_OPTIONS,
    Number,
    bad,
    check_threads_or_cluster,
    checked_dir,
    checked_file,
    cpus_allowed,
    designs_of,
    make_settings,
    parse_placement_items,
    parse_sensors,
    parse_skin_overrides,
    progress_bar,
    progress_line,
    sensor_flag_message,
    sensor_spec_of,
    with_options,
)
from softhand.io import DeferredInterrupt
from softhand.paper import paper
from softhand.paths import FE_DIR, REPORTS_DIR, SENSORS_DIR, SKINS_DIR, is_shipped

EXIT_CONVERGENCE, EXIT_WRITE, EXIT_INTERRUPTED = 3, 4, 130


class Stopped(click.ClickException):
    """Work that ended early (interrupted, not converged) after writing what finished."""

    def __init__(self, message: str, exit_code: int) -> None:
        super().__init__(message)
        self.exit_code = exit_code


class _Softhand(click.Group):
    """The top-level group: errors become one line on stderr, never a traceback."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        try:
            with _warnings_summarised():  # each kind once, with its count, at the end
                rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.exceptions.NoArgsIsHelpError as exc:
            click.echo(exc.format_message())
            sys.exit(0)
        except click.UsageError as exc:  # bad flag or value: name it, point at --help
            hint = f" (see '{exc.ctx.command_path} --help')" if exc.ctx else ""
            click.echo(f"error: {exc.format_message()}{hint}", err=True)
            sys.exit(EXIT_INPUT)
        except click.ClickException as exc:
            click.echo(("" if isinstance(exc, Stopped) else "error: ") + exc.format_message(),
                       err=True)
            sys.exit(exc.exit_code)
        except (click.Abort, KeyboardInterrupt) as exc:
            # click turns a KeyboardInterrupt into Abort, from it
            _interrupted(written=isinstance(exc.__cause__ or exc, DeferredInterrupt))
        except Exception as exc:
            if _caused_by_interrupt(exc):  # e.g. Ctrl-C during a lazy import, wrapped by it
                _interrupted()
            if os.environ.get("SOFTHAND_TRACEBACK"):
                raise
            if isinstance(exc, OSError) and exc.errno in _WRITE_ERRNOS:
                where = f" {exc.filename}" if exc.filename else ""
                click.echo(f"error: could not write{where} ({exc.strerror}); the files written "
                           "before it are kept, each whole (atomic writes)", err=True)
                sys.exit(EXIT_WRITE)
            click.echo(f"internal error: {type(exc).__name__}: {exc} "
                       "(SOFTHAND_TRACEBACK=1 shows where)", err=True)
            sys.exit(1)
        sys.exit(rv if isinstance(rv, int) else 0)


#: A write that failed for the disk or the file system, not for a bug: exit 4, one line
_WRITE_ERRNOS = {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG, errno.EACCES, errno.EPERM}


def _caused_by_interrupt(exc: BaseException) -> bool:
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def _interrupted(written: bool = False) -> NoReturn:
    """Ctrl-C: one line, exit 130; a second Ctrl-C while exiting is ignored. ``written``: the
    Ctrl-C came while the results that had finished were being written, and was held until they
    were (softhand.io.interrupts_deferred)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    click.echo(f"interrupted ({_STOP['by']}) while writing: what had finished was written, each "
               "file whole" if written else f"interrupted ({_STOP['by']}); nothing was written",
               err=True)
    sys.stdout.flush()
    sys.exit(EXIT_INTERRUPTED)


@click.group(cls=_Softhand)
@click.version_option(__version__, prog_name="softhand")
def main() -> None:
    """softhand: lifelike prosthetic skins, from FE indentation to MuJoCo."""
    warnings.formatwarning = _one_line_warning
    signal.signal(signal.SIGTERM, _terminated)


#: What stopped the command: Ctrl-C, or SIGTERM (a ``kill``, a scheduler's time limit).
_STOP = {"by": "Ctrl-C"}


def _terminated(signum, frame) -> NoReturn:
    """SIGTERM takes Ctrl-C's path: a batch terminates its workers and writes what finished (the
    default action killed this process alone and left the spawned workers running as orphans)."""
    _STOP["by"] = "SIGTERM"
    raise KeyboardInterrupt


def _one_line_warning(message, category, filename, lineno, line=None) -> str:
    """A warning as the command line shows it: one line, its class and message, no source."""
    return f"warning ({category.__name__}): {message}\n"


@contextmanager
def _warnings_summarised() -> Iterator[None]:
    """Collect the command's warnings (under the filters in force: ``-W`` and
    ``PYTHONWARNINGS`` still apply, ``error`` included) and print each kind once when it ends,
    however it ends: ``warning (Kind): message``, or ``warning (Kind) xN: first message (and N-1
    more like it)``. Warnings from worker processes come back to this process
    (softhand.parallel.run_tasks) and are counted here too."""
    with warnings.catch_warnings(record=True) as caught:
        try:
            yield
        finally:
            kinds: dict[str, list[str]] = {}
            for w in caught:
                kinds.setdefault(w.category.__name__, []).append(str(w.message))
            for name, texts in kinds.items():  # _one_line_warning's format, with the count
                n = len(texts)
                more = f" (and {n - 1} more like it)" if n > 1 else ""
                click.echo(f"warning ({name}){f' x{n}' if n > 1 else ''}: {texts[0]}{more}",
                           err=True)


def _check_class_laws_inputs(names: list[str], out: Path, fe_dir: str) -> None:
    """--class-laws-only: each skin's file in --out with a soft contact, and its class folders
    in --fe-dir readable and of the plate folder's settings, before the first fit."""
    from softhand.skin.calibrate import class_folders
    from softhand.skin.files import load_calibration

    for n in names:
        try:
            load_calibration(n, out, require=("soft-contact",))
        except ValueError as exc:
            bad(f"--out {str(out)!r}: {exc}")
        try:
            class_folders(n, fe_dir)
        except ValueError as exc:
            bad(f"--fe-dir {fe_dir!r}: {exc}")


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


def _folder_bytes(path: str | Path) -> int:
    """Bytes of the files under ``path`` (what a staged copy of it takes)."""
    root = Path(path)
    return sum(p.stat().st_size for p in root.rglob("*") if p.is_file()) if root.is_dir() else 0


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


@contextmanager
def _writing(out: Path, kept: str) -> Iterator[None]:
    """Turn a failure to write (disk full, permissions changed) into one line saying what was
    kept, exit 4."""
    try:
        yield
    except OSError as exc:
        what = f"{exc.strerror or exc}" + (f": {exc.filename}" if exc.filename else "")
        kept = ("the shipped data is unchanged" if is_shipped(out) else f"kept in {out}: {kept}")
        raise Stopped(f"error: writing into {out} failed ({what}); {kept}", EXIT_WRITE) from None


def _end_of_batch(what: str, written: int, total: int, out: Path, missing: dict[str, str],
                  interrupted: bool, *, staged: bool = False) -> None:
    """One closing line for a batch that did not finish whole (exit 130 or 3); else nothing.

    ``staged``: the run wrote shipped data beside it, so the incomplete set was dropped."""
    where = (f"the shipped set in {out} is unchanged (an incomplete run never replaces it; the "
             f"{written} finished {what} were dropped: --out DIR keeps them)" if staged
             else f"wrote {written} of {total} {what} to {out}")
    if interrupted:
        raise Stopped(f"interrupted ({_STOP['by']}): {where}; missing: {', '.join(missing)}",
                      EXIT_INTERRUPTED)
    if missing:
        reasons = "; ".join(f"{n}: {why}" for n, why in missing.items())
        raise Stopped(f"error: {len(missing)} {what} failed ({reasons}); {where}",
                      EXIT_CONVERGENCE)


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


@main.command("calibrate")
@click.argument("skins", nargs=-1)
@click.option("--representation", "representations", multiple=True,
              help="rigid, soft-contact, soft-contact+relaxation or flex (repeatable) "
                   "[default: all four].")
@click.option("--out", "out_dir", default=str(SKINS_DIR), show_default=True,
              help="Folder for the calibration files.")
@click.option("--fe-dir", default=str(FE_DIR), show_default=True,
              help="Folder with the FE curves (as written by `softhand fe sweep`).")
@with_options((OPT_THREADS, OPT_CLUSTER))
@click.option("--force", is_flag=True,
              help="Allow writing into the shipped calibration/ (replaced only when the run "
                   "completes).")
@click.option("--class-laws-only", is_flag=True,
              help="Fit only the laws per contact class again (each file's pair_laws, from the "
                   "class folders of --fe-dir: finger/, palm-plate/, palm-finger/), keeping the "
                   "law and the representations of the files in --out. Designs only.")
@click.option("--json", "as_json", is_flag=True, help="Print the errors as JSON.")
def calibrate(skins, representations, out_dir, fe_dir, threads, cluster, force, class_laws_only,
              as_json) -> None:
    """Fit laws and MuJoCo parameters for SKINS (default: the 12 designs and 2 references).

    With --cluster, the workers read the FE curves from --fe-dir: a folder they see at the same
    path (a shared file system, or a cluster on this machine)."""
    from softhand.io import staged_folder
    from softhand.skin.calibrate import fe_curves, skin_names
    from softhand.skin.representations import REPRESENTATIONS
    from softhand.skin.run import calibrate_many, refit_class_laws_many, summary_table

    check_threads_or_cluster(threads, cluster)
    from softhand.fem.geometry import DESIGNS

    known = list(DESIGNS) if class_laws_only else skin_names()
    names = list(dict.fromkeys(skins)) or known
    for n in names:
        if n not in known:
            bad(f"skin {n!r} is unknown; allowed: {', '.join(known)}"
                + (" (--class-laws-only: the designs, which have FE curves per contact class)"
                   if class_laws_only and n in skin_names() else ""))
    if class_laws_only and representations:
        bad(f"--representation {representations[0]!r} with --class-laws-only: the "
            "representations are kept as they are; allowed one of the two")
    reps = tuple(dict.fromkeys(representations)) or tuple(REPRESENTATIONS)
    for r in reps:
        if r not in REPRESENTATIONS:
            bad(f"--representation {r!r} is unknown; allowed: {', '.join(REPRESENTATIONS)}")
    shipped = is_shipped(out_dir) if str(out_dir).strip() else False
    out = checked_dir(out_dir, "--out", force=force,
                      need_bytes=1e6 + (_folder_bytes(out_dir) if shipped else 0))
    if not str(fe_dir).strip():
        bad("--fe-dir '': expected a folder path, got an empty string")
    if not Path(fe_dir).is_dir():
        bad(f"--fe-dir {fe_dir!r}: no such folder (expected the curves of `softhand fe sweep`)")
    if out.resolve() == Path(fe_dir).resolve():
        bad(f"--out {out_dir!r} is --fe-dir: the calibration files go into another folder than "
            "the FE curves they are fitted to")
    for n in names:  # every FE curve is read and checked before the first fit
        if n in DESIGNS:
            try:
                fe_curves(n, fe_dir)
            except (FileNotFoundError, ValueError) as exc:
                bad(f"--fe-dir {fe_dir!r}: {exc}")
    if class_laws_only:
        _check_class_laws_inputs(names, out, fe_dir)
    with staged_folder(out, stage=shipped) as staged, _writing(
            out, "the skin files written before the failure"):
        if class_laws_only:
            run = refit_class_laws_many(names, out_dir=staged.path, fe_dir=fe_dir,
                                        threads=threads, cluster=cluster,
                                        show_progress=not as_json)
        else:
            run = calibrate_many(names, reps, out_dir=staged.path, fe_dir=fe_dir,
                                 threads=threads, cluster=cluster, show_progress=not as_json)
        if run.index is not None and not run.missing:
            staged.commit()
    if run.index is not None:
        click.echo(json.dumps(run.index, indent=1) if as_json else summary_table(run.index))
    _end_of_batch("skins", len(run.written), len(names), out, run.missing, run.interrupted,
                  staged=shipped and not staged.committed)


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
@click.option("--json", "as_json", is_flag=True,
              help="Print the skinned geoms and every change made to HAND as JSON.")
def skin_apply(hand, out, geom_items, against, max_force, as_json) -> None:
    """Give the named geoms of the MJCF HAND a calibrated skin and write the model to OUT (.xml).

    Each skinned geom meets each counterpart through a <pair> with the design's law in
    solref/solimp, mass-compensated; its own contype/conaffinity become 0. OUT is HAND's text
    with only those changes (and absolute asset paths when OUT is in another folder), listed
    here and in a comment at its top; the output loads in plain MuJoCo."""
    import mujoco

    from softhand.skin.apply import apply_skin, check_skinnable, parse_geom_skins, write_skinned
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
    known = {g.name for g in spec.geoms}
    try:
        check_skinnable(source, [g for g in geoms if g in known])
    except ValueError as exc:
        bad(f"--geom: HAND {hand!r}: {exc}")
    try:
        skinned = apply_skin(spec, {g: f"{d}@{r}" for g, (d, r) in geoms.items()},
                             against=list(against) or None, max_force_N=max_force)
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


_OPT_CONTACT_LAWS = click.option(
    "--contact-laws", type=click.Choice(["geometry", "plate"]), default="geometry",
    show_default=True,
    help="Laws of the skin pairs: geometry (each pair the law of its contact class: a phalanx or "
         "a palm piece, pressed by a finger or a flat; `--json` and the summary name each law's "
         "share) or plate (every pair the paper's flat-plate law).")
_OPT_HAND = click.option(
    "--hand", type=click.Choice(["prosthetic", "human"]), default="prosthetic", show_default=True,
    help="The sensored hand: the prosthetic hand, or the paper's relaxed human hand (its protocol).")


@main.command("handshake")
@click.option("--design", default=None, help="Skin of every region [default: pocket2-sil].")
@click.option("--skin", "skin_items", multiple=True, metavar="REGION=DESIGN[@REPRESENTATION]",
              help="Skin of one region (repeatable), e.g. Palm1=rigid or "
                   "Palm2=pocket2-pu@soft-contact+relaxation.")
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
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
def handshake(design, skin_items, representation, controller, seed, timestep_s, record_path,
              placement_items, signal, target_N, partner_size, hand, contact_laws, as_json,
              **sensor_kw) -> None:
    """Shake hands once (shipped calibration, no FE run) and report the force on each region."""
    from softhand.envs.handshake import HandshakeEnv
    from softhand.envs.physics import DivergenceError
    from softhand.envs.run import OVER_N, run_handshake

    if design is not None and not design.strip():
        bad("--design '': expected a skin name, e.g. pocket2-sil")
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
    try:  # skins, sensors and their calibration files, before the episode
        env = HandshakeEnv(design=design, skins=overrides, representation=representation,
                           timestep_s=timestep_s, sensor=spec, sensor_placement=placement,
                           partner_size=size, hand=hand, contact_laws=contact_laws)
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
        "hand": hand, "design": design, "skins": dict(overrides or {}),
        "representation": representation, "controller": controller,
        "signal": signal if controller != "open-loop" else None, "target_N": target_N,
        "seed": seed, "timestep_s": timestep_s, "physics_steps_per_env_step": frame_skip,
        "env_step_s": frame_skip * timestep_s, "contact_laws": contact_laws,
        "partner_size_mm": list(summary["episode"]["partner_size_mm"]),
        "sensor_placement": list(placement_items) or None,
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
    click.echo(f"\ngrasp at mid-shake (t = {chk['t_mid_shake_s']:.2f} s): palm to palm (thenars "
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


def _check_gl() -> None:
    """MUJOCO_GL names a backend MuJoCo has (a wrong one fails deep inside the first render)."""
    value = os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is imported
    if value not in ("egl", "osmesa", "glfw"):
        bad(f"MUJOCO_GL = {value!r}: allowed egl (GPU, headless), osmesa (CPU, headless) or "
            "glfw (a window system)")


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


@main.command("population")
@click.option("--n", "n", type=click.IntRange(1, 10000), default=30, show_default=True,
              help="Partners, 1-10000 (the paper had 30).")
@click.option("--seed", type=click.IntRange(0, 2**32 - 1), default=0, show_default=True,
              help="Seed of the population, 0 <= seed < 2^32.")
@click.option("--design", "designs", multiple=True,
              help="Skin of every region (repeatable: a sweep) [default: pocket2-sil].")
@click.option("--controller", "controllers", type=click.Choice(["neutral", "open-loop", "force"]),
              multiple=True, default=("neutral",), show_default=True,
              help="Controller of the prosthetic hand (repeatable: a sweep).")
@click.option("--workers", "threads", type=click.IntRange(min=1), default=None,
              callback=cpus_allowed,
              help="Worker processes, at most the CPUs available [default: those CPUs, at most "
                   "4].")
@OPT_CLUSTER
@click.option("--out", "out_dir", default="population", show_default=True,
              help="Folder for partners.json, results.json, results.csv and fig4.png; a sweep "
                   "writes them into one subfolder DESIGN-CONTROLLER per combination, and "
                   "sweep.json.")
@_OPT_HAND
@_OPT_CONTACT_LAWS
def population(n, seed, designs, controllers, threads, cluster, out_dir, hand,
               contact_laws) -> None:
    """The paper's handshake experiment: n sampled partners shake the hand; per-region results
    and a Fig. 4-style figure against the paper's set.

    More than one --design or --controller makes a sweep: the same partners shake the hand in
    every combination, each handshake one task of one batch (on this machine's workers or on
    the --cluster), and each combination's files go into its subfolder DESIGN-CONTROLLER of
    --out, with sweep.json listing the combinations and per combination the regions over 2 N
    in more than half the partners:

    \b
    softhand population --design pocket2-sil --design solid-pu \\
        --controller neutral --controller force --cluster tcp://HOST:8786"""
    from softhand.envs.handshake import HandshakeEnv
    from softhand.envs.population import run_partner, sample_partners
    from softhand.envs.skins import DEFAULT_DESIGN
    from softhand.fem.sweep import git_revision
    from softhand.io import atomic_write_text, interrupts_deferred
    from softhand.parallel import run_tasks

    check_threads_or_cluster(threads, cluster, "--workers")
    designs = tuple(dict.fromkeys(designs)) or (None,)  # None: the env's default skin
    controllers = tuple(dict.fromkeys(controllers))
    for design in designs:
        if design is not None and not design.strip():
            bad("--design '': expected a skin name, e.g. pocket2-sil")
    for controller in controllers:
        _check_hand(hand, controller, design=tuple(d for d in designs if d is not None))
    combos = [(d, c) for d in designs for c in controllers]
    sweep = len(combos) > 1
    out = checked_dir(out_dir, "--out", need_bytes=(2e6 + 4e3 * n) * len(combos))
    for design in designs:
        try:
            # the skin and its files, before any work
            HandshakeEnv(design=design, hand=hand, contact_laws=contact_laws)
        except ValueError as exc:
            bad(str(exc) if design is None else f"--design {design!r}: {exc}")
    partners = sample_partners(n, seed)
    skins = [d or DEFAULT_DESIGN for d in designs]
    what = f"{n} partners" + (f" x {len(combos)} combinations" if sweep else "")
    click.echo(_header("population", f"{what}, seed {seed}", _sensored_hand(
        hand, f"{skins[0]} on every region" if len(skins) == 1 else f"skins {', '.join(skins)}",
        f"controller{'s' if len(controllers) > 1 else ''} {', '.join(controllers)}")))
    names = [f"{d}-{c}" for d in skins for c in controllers]
    tasks = [((k, p.index), (p, {"design": d, "controller": c, "hand": hand,
                                 "contact_laws": contact_laws}))
             for k, (d, c) in enumerate(combos) for p in partners]  # a combination's in a row
    done = []
    with progress_bar(what, disable=False) as update:
        batch = run_tasks(run_partner, tasks, threads=threads, cluster=cluster,
                          on_done=lambda key, ok: (done.append(key),
                                                   update(len(done) / len(tasks))))
    command = "softhand population " + " ".join(sys.argv[2:])
    listed, missing_all = [], {}
    with interrupts_deferred():  # what finished is written whole, Ctrl-C or not
        revision = git_revision()
        for k, ((design, controller), name) in enumerate(zip(combos, names, strict=True)):
            results = [batch.results[(k, p.index)] for p in partners
                       if (k, p.index) in batch.results]
            missing = {str(i): "interrupted" for j, i in batch.missing if j == k}
            missing.update({str(i): str(e) for (j, i), e in batch.errors.items() if j == k})
            missing_all.update({f"{name}/{i}" if sweep else i: why for i, why in missing.items()})
            meta = {"n": n, "seed": seed, "hand": hand,
                    "design": "human tissue" if hand == "human" else design or DEFAULT_DESIGN,
                    "controller": controller, "contact_laws": contact_laws,
                    "finished": len(results), "missing": missing,
                    "version": __version__, "git_revision": revision, "command": command}
            summary = {}
            if results:
                summary = _write_population(out / name if sweep else out, partners, results,
                                            meta)
                if sweep:
                    click.echo(f"{name}: {len(results)} of {n} partners")
                _print_population(summary)
            listed.append({"design": meta["design"], "controller": controller,
                           "folder": name if results else None, "finished": len(results),
                           "missing": missing, "regions_over_2N_in_most_partners": [
                               r for r, v in summary.items() if v["over_2N_pct"] > 50]})
        if sweep and batch.results:
            atomic_write_text(out / "sweep.json", json.dumps(
                {"partners": {"n": n, "seed": seed}, "hand": hand, "contact_laws": contact_laws,
                 "combinations": listed, "version": __version__, "git_revision": revision,
                 "command": command}, indent=1))
    _end_of_batch("handshakes" if sweep else "partners", len(batch.results), len(tasks), out,
                  missing_all, batch.interrupted)
    wall = sum(r["wall_s"] for r in batch.results.values())
    files = "partners.json, results.json, results.csv and fig4.png"
    click.echo(f"wrote {files} to {out} ({wall:.0f} s of handshakes)" if not sweep else
               f"wrote {files} for {len(combos)} combinations into {out}/DESIGN-CONTROLLER and "
               f"sweep.json to {out} ({wall:.0f} s of handshakes)")


def _write_population(out: Path, partners: list, results: list[dict], meta: dict) -> dict:
    """One combination's files in ``out`` (created): partners.json, results.json, results.csv and
    fig4.png; returns the population summary."""
    from softhand.envs.population import population_summary
    from softhand.io import atomic_write_text
    from softhand.viz.population import population_figure

    summary = population_summary(results)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "partners.json", json.dumps([p.to_dict() for p in partners], indent=1))
    atomic_write_text(out / "results.json", json.dumps(
        {"settings": meta, "summary": summary, "partners": results}, indent=1))
    regions = list(results[0]["peak_N"])
    rows = ["index,length_mm,width_mm,grip_N,duration_s," + ",".join(
        f"{r}_peak_N" for r in regions) + ",grip_p95_error_pct,bone_on_bone_peak_N"]
    for res in sorted(results, key=lambda r: r["partner"]["index"]):
        p = res["partner"]
        rows.append(",".join(f"{v:.4g}" for v in (
            p["index"], p["hand_length_mm"], p["hand_width_mm"], p["grip_N"],
            p["duration_s"], *(res["peak_N"][r] for r in regions),
            res["grip"]["p95_error_pct"], res["force_accounting"]["bone_on_bone_peak_N"])))
    atomic_write_text(out / "results.csv", "\n".join(rows) + "\n")
    title = (f"{len(results)} partners, the relaxed human hand (human tissue)"
             if meta["hand"] == "human" else f"{len(results)} partners, prosthetic hand, "
             f"{meta['design']}, {meta['controller']} controller")
    population_figure([r["peak_N"] for r in results], paper()["handshake"]["over_2N"],
                      out / "fig4.png", title=title)
    return summary


def _print_population(summary: dict[str, dict]) -> None:
    click.echo("| region | partners over 2 N % | median peak N | 10-90 % peak N | paper |\n"
               "|---|---|---|---|---|")
    for region, v in summary.items():
        click.echo(f"| {region} | {v['over_2N_pct']:.0f} | {v['median_peak_N']:.2f} | "
                   f"{v['p10_peak_N']:.2f}-{v['p90_peak_N']:.2f} | "
                   f"{'> 2 N' if v['paper_over_2N'] else ''} |")


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
              help="A contact sheet instead: at grip and mid-shake, from the back of each hand "
                   "and from below, regions coloured by force (ignores the camera options).")
@_OPT_HAND
def render(out, design, controller, seed, at_s, azimuth, elevation, distance, size,
           partner_size, sheet, hand) -> None:
    """Run one handshake and render the scene at one moment to OUT (.png), offscreen.

    Needs an OpenGL context: MUJOCO_GL=egl (set here when unset) or osmesa.
    """
    _check_gl()
    from softhand.envs.handshake import HandshakeEnv
    from softhand.envs.physics import DivergenceError
    from softhand.envs.run import run_handshake
    from softhand.envs.skins import DEFAULT_DESIGN
    from softhand.viz.render import CameraView, SheetFrame, render_sheet, render_state

    if design is not None and not design.strip():
        bad("--design '': expected a skin name, e.g. pocket2-sil")
    path = checked_file(out, "OUT", ".png")
    size_mm = _partner_size(partner_size)
    _check_hand(hand, controller, design=design)
    try:
        env = HandshakeEnv(design=design, partner_size=size_mm, hand=hand)
    except ValueError as exc:
        bad(str(exc))
    when = ("at the end of the grip and mid-shake, 3 views each" if sheet
            else "at mid-shake" if at_s is None else f"at t = {at_s:g} s")
    click.echo(_header("render", _sensored_hand(hand, f"{design or DEFAULT_DESIGN} on every "
                                                "region", f"controller {controller}"),
                       f"partner seed {seed}" + ("" if size_mm is None else
                                                 f", hand {size_mm[0]:g} x {size_mm[1]:g} mm"),
                       when))
    try:
        run = run_handshake(controller=controller, seed=seed, env=env)
    except DivergenceError as exc:  # one line, exit 3 (render runs at the default timestep)
        raise Stopped(f"error: {exc.summary}; softhand handshake --timestep "
                      f"{exc.suggested_timestep_s:g} tries a smaller one", EXIT_CONVERGENCE
                      ) from None
    if sheet:
        grip = [i for i, p in enumerate(run.phase) if p == "grip"]
        shake = [i for i, p in enumerate(run.phase) if p == "shake"]
        frames = []
        for k, what in ((grip[-1], "end of the grip"), (shake[len(shake) // 2], "mid-shake")):
            forces = {f"pro_skin_{r}": float(run.region_force_N[k, i])
                      for i, r in enumerate(run.region_names)}
            frames.append(SheetFrame(run.qpos[k], run.mocap_pos[k], run.mocap_quat[k],
                                     f"{what}, t = {run.time_s[k]:.2f} s", forces))
        render_sheet(run.model, frames, path)
        click.echo(f"wrote {path} (end of the grip and mid-shake, 3 views each)")
        return
    if at_s is None:
        shake = [i for i, p in enumerate(run.phase) if p == "shake"]
        k = shake[len(shake) // 2]
    else:
        k = int(np.argmin(np.abs(run.time_s - at_s)))
    view = CameraView(distance_m=distance, azimuth_deg=azimuth, elevation_deg=elevation)
    render_state(run.model, run.qpos[k], run.mocap_pos[k], run.mocap_quat[k], path,
                 width=size[0], height=size[1], view=view,
                 caption=f"orange: the prosthetic hand's skin; blue: the partner's hand; "
                         f"t = {run.time_s[k]:.2f} s ({run.phase[k]})")
    click.echo(f"wrote {path} (t = {run.time_s[k]:.2f} s, {run.phase[k]})")


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


def run() -> None:
    """The ``softhand`` console script: `main`, and an exit 130 that stays 130.

    CPython exits by SIGINT (status -2) after a handled Ctrl-C when the interrupt first surfaced
    inside code that C evaluated with ``PyRun_*`` (a Cython module being imported, for one), even
    though the program then exits with its own status. So after Ctrl-C the process flushes its
    output, runs the exit handlers and ends with ``os._exit(130)``; what had to be written is
    closed by then.
    """
    try:
        main()
    except SystemExit as exc:
        if exc.code == EXIT_INTERRUPTED:
            import atexit

            atexit._run_exitfuncs()  # what a normal exit runs (e.g. multiprocessing's clean-up)
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(EXIT_INTERRUPTED)
        raise


if __name__ == "__main__":  # pragma: no cover
    run()
