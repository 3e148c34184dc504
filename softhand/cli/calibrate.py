"""``softhand calibrate``: laws and MuJoCo parameters per skin into calibration/skins."""

from __future__ import annotations

import json
from pathlib import Path

import click

from softhand.cli.app import _end_of_batch, _folder_bytes, _writing, main
from softhand.cli.inputs import (
    OPT_CLUSTER,
    OPT_THREADS,
    bad,
    check_threads_or_cluster,
    checked_dir,
    with_options,
)
from softhand.paths import FE_DIR, SKINS_DIR, is_shipped


def _check_class_laws_inputs(names: list[str], out: Path, fe_dir: str) -> None:
    """--class-laws-only: each skin's file in --out with a soft contact, and the curve of every
    contact class in --fe-dir's class folders, readable and of the plate folder's settings,
    before the first fit (a refit without them would write files without their class laws)."""
    from softhand.laws.references import HUMAN
    from softhand.skin.calibrate import class_folders, tissue_curves
    from softhand.skin.contact_classes import (
        CLASSES,
        FE_FOLDERS,
        PLATE_CLASS,
        TISSUE_FE_FOLDER,
        TISSUE_OPTIONAL,
        class_curve,
        partner_tissue_class,
        tissue_class_needs,
    )
    from softhand.skin.files import load_calibration

    for n in names:
        try:
            load_calibration(n, out, require=("soft-contact",))
        except ValueError as exc:
            bad(f"--out {str(out)!r}: {exc}")
        if n == HUMAN:
            continue  # its class laws come from the tissue FE's curves, checked below
        try:
            found = class_folders(n, fe_dir)
        except ValueError as exc:
            bad(f"--fe-dir {fe_dir!r}: {exc}")
        missing = [k for k in CLASSES if k != PLATE_CLASS and k not in found]
        if missing:
            bad(f"--fe-dir {fe_dir!r}: no curve of {n} for the contact classes "
                + ", ".join(f"{k} ({class_curve(n, k, fe_dir)})" for k in missing)
                + "; --class-laws-only needs every class folder ("
                + ", ".join(f"{FE_FOLDERS[k]}/" for k in CLASSES if k != PLATE_CLASS)
                + "), as `softhand fe sweep --indenter ... --body ...` writes them")
    try:
        tissue = tissue_curves(fe_dir)
    except ValueError as exc:
        bad(f"--fe-dir {fe_dir!r}: {exc}")
    # every class's partner side (partner_tissue_class: the oblique border's crossings too);
    # the human tissue's own laws every class's but the border's oblique crossings
    # (TISSUE_OPTIONAL: its pairs there take its border law across, class_fallback)
    own = [k for k in CLASSES if k not in TISSUE_OPTIONAL] if HUMAN in names else []
    keys = [partner_tissue_class(k) for k in CLASSES] + own
    needed = dict.fromkeys(n for k in keys for n in tissue_class_needs(k))
    lacking = [k for k in needed if k not in tissue]
    if lacking:
        bad(f"--fe-dir {fe_dir!r}: no tissue FE curve of {', '.join(lacking)} in "
            f"{TISSUE_FE_FOLDER}/ (the tissue's class laws); write it "
            f"with `python tools/tissue_fe.py --classes {Path(fe_dir) / TISSUE_FE_FOLDER}`")


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
                   "class folders of --fe-dir: finger/, palm-plate/, palm-finger/, "
                   "border-finger/), keeping the law and the representations of the files in "
                   "--out. The designs and the human tissue (its class laws from "
                   "--fe-dir's tissue/ curves).")
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
    from softhand.laws.references import HUMAN

    known = [*DESIGNS, HUMAN] if class_laws_only else skin_names()
    names = list(dict.fromkeys(skins)) or known
    for n in names:
        if n not in known:
            bad(f"skin {n!r} is unknown; allowed: {', '.join(known)}"
                + (" (--class-laws-only: the designs, which have FE curves per contact class, "
                   "and the human tissue)"
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
