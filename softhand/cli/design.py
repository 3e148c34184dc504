"""``softhand design search | samplers``: the design search of issue 38 from the command line."""

from __future__ import annotations

import click

from softhand.cli.app import EXIT_INTERRUPTED, Stopped, _writing, main
from softhand.cli.inputs import (
    OPT_CLUSTER,
    Number,
    bad,
    check_threads_or_cluster,
    checked_dir,
    cpus_allowed,
    progress_line,
)
from softhand.paths import REPORTS_DIR


@main.group()
def design() -> None:
    """Search pocketed phalanx designs and materials for lifelike, durable skins (issue 38)."""


def _space(bounds: tuple[str, ...], materials: tuple[str, ...]):
    """The design space from --bound and --materials, every error naming its flag."""
    from softhand.design.space import DesignSpace, parse_bound
    from softhand.fem.library import check_library_names

    names = [m.strip() for item in materials for m in item.split(",") if m.strip()]
    try:
        names = check_library_names(names, key="--materials") if names else None
    except ValueError as exc:
        bad(str(exc))
    parsed = {}
    for item in bounds:
        try:
            key, rng = parse_bound(item)
        except ValueError as exc:
            bad(f"--bound {exc}")
        parsed[key] = rng
    try:
        return DesignSpace(bounds=parsed, **({"materials": tuple(names)} if names else {}))
    except ValueError as exc:
        bad(f"--materials {exc}" if str(exc).startswith("materials") else f"--bound {exc}")


_OPT_BOUND = click.option(
    "--bound", "bounds", multiple=True, metavar="NAME=LO:HI",
    help="Bounds of a variable in mm (repeatable): outer_layer_mm (default 0.5:1.5), "
         "pocket_roof_mm (1.0:2.3), pocket_height_mm (0.5:3.5), pocket_half_width_mm (2.0:6.0).")
_OPT_MATERIALS = click.option(
    "--materials", "materials", multiple=True, metavar="NAME[,NAME...]",
    help="Library materials for the inner part and the outer layer (`softhand materials`) "
         "[default: ecoflex-00-30, dragon-skin-10, dragon-skin-20].")
_OPT_MESH = click.option("--mesh", type=click.Choice(["coarse", "default", "fine"]),
                         default="default", show_default=True, help="FE mesh of every run.")


@design.command("search")
@click.option("--trials", type=click.IntRange(min=1), required=True,
              help="Trials of the 2D screen in the study (a --resume counts those done).")
@_OPT_MATERIALS
@_OPT_BOUND
@click.option("--out", "out_dir", default="design-search", show_default=True,
              help="Folder of the study's journal and of its outputs.")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True,
              help="Seed of the sampler.")
@click.option("--resume", is_flag=True, help="Continue the study in --out (after Ctrl-C).")
@click.option("--sampler", type=click.Choice(["tpe", "nsga2"]), default="tpe", show_default=True,
              help="optuna sampler: multivariate TPE, or NSGA-II.")
@_OPT_MESH
@click.option("--max-force", "max_force_N", type=Number(2, 20, unit="N"), default=2.0,
              show_default=True, help="Force of each ramp, [2, 20] N; durability is read there.")
@click.option("--check", "n_check", type=click.IntRange(0, 20), default=3, show_default=True,
              help="Winners along the Pareto front checked in 3D (with an STL each), 0-20.")
@click.option("--threads", type=click.IntRange(min=1), default=None, callback=cpus_allowed,
              help="Local worker processes: trials at once [default: 1, this process].")
@click.option("--contact-points", "contact_points", type=click.Choice(["2", "4"]), default=None,
              help="Contact points per face direction of the plate and the pocket in every FE "
                   "run [default: 2 for a new study; a resumed study keeps its own]: 2, about "
                   "twice as fast as 4, the FE's default, the indentation within 1 % and the "
                   "force within 2 % of 4's (softhand bench fe).")
@OPT_CLUSTER
def search(trials, materials, bounds, out_dir, seed, resume, sampler, mesh, max_force_N, n_check,
           threads, contact_points, cluster) -> None:
    """Run (or --resume) the optuna search: a 2D FE screen, then the 3D check of the front."""
    from tqdm import tqdm

    from softhand.design.outputs import write_outputs
    from softhand.design.search import JOURNAL, run_search, study_contact_points

    check_threads_or_cluster(threads, cluster)
    contact_points = None if contact_points is None else int(contact_points)
    space = _space(bounds, materials)
    out = checked_dir(out_dir, "--out", need_bytes=5e6)
    journal = out / JOURNAL
    if journal.exists() and not resume:
        bad(f"--out {str(out)!r} holds a study ({JOURNAL}): add --resume to continue it, or "
            "choose another --out")
    if resume and not journal.exists():
        bad(f"--resume: --out {str(out)!r} has no {JOURNAL} (nothing to resume); allowed: a "
            "folder of an earlier search")
    bar = tqdm(total=trials, desc="design search (2D)", unit="trial")

    def progress(done: int, total: int) -> None:
        bar.n = done
        bar.refresh()

    try:
        outcome = run_search(space, trials=trials, out=out, seed=seed, sampler=sampler,
                             resume=resume, mesh=mesh, max_force_N=max_force_N,
                             threads=threads, cluster=cluster, progress=progress,
                             contact_points=contact_points)
    except ValueError as exc:
        bad(str(exc))
    finally:
        bar.close()
    done = outcome.done_before + outcome.ran
    if outcome.interrupted:
        raise Stopped(f"interrupted: {done} of {trials} trials are in {journal}; the same "
                      "command with --resume continues the study", EXIT_INTERRUPTED)
    progress_line(f"checking {n_check} winners and pocket2-sil in 3D")
    contact_points = study_contact_points(outcome.study)
    extra = {"trials_asked": trials, "sampler": sampler, "seed": seed, "mesh": mesh,
             "max_force_N": max_force_N, "contact_points": contact_points,
             "screen_wall_s_this_run": outcome.wall_s,
             "failed_this_run": outcome.failed}
    with _writing(out, f"the study's journal ({JOURNAL})"):
        data = write_outputs(outcome.study, out, check=n_check, mesh=mesh,
                             max_force_N=max_force_N, threads=threads, cluster=cluster,
                             extra=extra, contact_points=contact_points)
    click.echo(f"{done} trials ({outcome.ran} this run, {len(outcome.failed)} failed, "
               f"{outcome.wall_s:.0f} s); Pareto front of {len(data['front'])}; wrote "
               f"designs.md, designs.json, pareto.png and {len(data['winners'])} STL to {out}")
    from softhand.design.outputs import table_markdown

    click.echo(table_markdown(data))


@design.command("samplers")
@click.option("--trials", type=click.IntRange(min=1), default=40, show_default=True,
              help="Trials per sampler and seed.")
@click.option("--seeds", default="0,1,2", show_default=True, help="Seeds, comma-separated.")
@_OPT_MATERIALS
@_OPT_MESH
@click.option("--report", "report_dir", default=str(REPORTS_DIR), show_default=True,
              help="Folder of design-search-samplers.{json,md}.")
def samplers(trials, seeds, materials, mesh, report_dir) -> None:
    """Multivariate TPE against NSGA-II on one budget: the hypervolume of each front."""
    import tempfile

    from softhand.design.search import compare_samplers
    from softhand.io import atomic_write_json, atomic_write_text

    try:
        seed_list = tuple(int(s) for s in seeds.split(",") if s.strip())
    except ValueError:
        bad(f"--seeds {seeds!r}: expected integers >= 0 separated by commas, e.g. 0,1,2")
    if not seed_list or min(seed_list) < 0:
        bad(f"--seeds {seeds!r}: expected integers >= 0 separated by commas, e.g. 0,1,2")
    space = _space((), materials)
    report = checked_dir(report_dir, "--report", need_bytes=1e5)
    from softhand.bench.common import machine_info

    machine = machine_info()
    with tempfile.TemporaryDirectory() as work:
        data = compare_samplers(space, trials=trials, seeds=seed_list, out=work, mesh=mesh,
                                progress=progress_line)
    data["machine"] = machine
    atomic_write_json(report / "design-search-samplers.json", data)
    atomic_write_text(report / "design-search-samplers.md", samplers_markdown(data))
    click.echo(samplers_markdown(data))


def samplers_markdown(data) -> str:
    from softhand.bench.common import machine_line

    ref = data["reference"]
    points = data.get("contact_points", 4)  # the shipped report's runs predate the key
    lines = [f"# Design search: sampler against sampler ({data['trials']} trials, seeds "
             f"{', '.join(map(str, data['seeds']))}, 2D {data['mesh']} mesh, {points} contact "
             "points)", "",
             "Hypervolume of the Pareto front (lifelike distance %, durability usage), both "
             f"minimised, up to the reference point ({ref[0]:g} %, {ref[1]:g}); larger is better. "
             f"Materials: {', '.join(data['space']['materials'])}. Written by `softhand design "
             "samplers`.", "", *([machine_line(data["machine"]), ""] if "machine" in data else []),
             "| sampler | hypervolume per seed | mean | best lifelike % per seed | wall s per seed |",
             "|---|---|---|---|---|"]
    for name, r in data["samplers"].items():
        lines.append(f"| {name} | {', '.join(f'{v:.3f}' for v in r['hypervolume'])} | "
                     f"{r['mean']:.3f} | "
                     f"{', '.join('' if v is None else f'{v:.1f}' for v in r['best_lifelike_pct'])}"
                     f" | {', '.join(f'{v:.0f}' for v in r['wall_s'])} |")
    return "\n".join(lines) + "\n"


@design.command("calibrate")
@click.option("--report", "report_path", default=str(REPORTS_DIR / "design-search.json"),
              show_default=True, help="A search's designs.json (its winners are calibrated).")
@click.option("--winner", "ranks", multiple=True, type=click.IntRange(min=1),
              help="Rank of a winner in --report (repeatable) [default: every winner].")
@click.option("--out", "out_dir", default=None,
              help="Folder of the skin files, design-trialN.json, with the FE curves under "
                   "fe/design-trialN/ [default: calibration/designs].")
@click.option("--force", is_flag=True,
              help="Allow writing into the shipped calibration/ (the default --out).")
def calibrate(report_path, ranks, out_dir, force) -> None:
    """A calibrated skin of each winner of a search: its FE curves (3D, the shipped setting,
    to 20 N or as far as the FE reaches), then `softhand calibrate`'s fit (law, MuJoCo
    representations, pair laws), for `softhand handshake --design PATH`."""
    import json
    from pathlib import Path

    from softhand.design.search import candidate_of
    from softhand.design.skins import (
        calibrate_candidate,
        fe_folders_match,
        run_fe_folders,
        skin_name,
    )
    from softhand.io import read_json
    from softhand.paths import CALIBRATION_DIR
    from softhand.skin.files import save_calibration

    path = Path(report_path)
    if not path.is_file():
        bad(f"--report {report_path!r}: no such file (expected a search's designs.json)")
    try:
        data = read_json(path)
        winners = data["winners"]
        rows = [candidate_of(w) for w in winners]
    except (ValueError, KeyError, TypeError) as exc:
        bad(f"--report {report_path!r}: not a design search's designs.json ({exc})")
    if not winners:
        bad(f"--report {report_path!r}: has no winners")
    for r in ranks:
        if r > len(winners):
            bad(f"--winner {r}: --report has {len(winners)} winners; allowed 1-{len(winners)}")
    out = checked_dir(out_dir or str(CALIBRATION_DIR / "designs"), "--out", force=force,
                      need_bytes=2e7)
    for rank in ranks or range(1, len(winners) + 1):
        w, cand = winners[rank - 1], rows[rank - 1]
        name = skin_name(w["trial"])
        fe = out / "fe" / name
        if fe_folders_match(cand, fe):
            progress_line(f"{name}: the FE curves in {fe} are this design's (reused)")
        else:
            progress_line(f"{name}: FE curves into {fe}")
            record = run_fe_folders(cand, fe, progress=progress_line)
            (fe / "record.json").write_text(json.dumps(record, indent=1) + "\n")
        progress_line(f"{name}: calibrating ({cand.label})")
        shown = _in_repo(path)
        cal = calibrate_candidate(cand, name, fe, provenance={
            "search": {"report": shown, "trial": w["trial"], "rank": rank,
                       "seed": data.get("seed"), "sampler": data.get("sampler"),
                       "git_revision": (data.get("machine") or {}).get("git_revision")},
            "command": f"softhand design calibrate --report {shown} --winner {rank}"
                       + (f" --out {_in_repo(Path(out_dir))}" if out_dir else "")
                       + (" --force" if force else "")})
        written = save_calibration(cal, out)
        top = cal.provenance["design"]["calibrated_max_N"]
        soft = cal.representations.get("soft-contact")
        click.echo(f"{written}: law to {top:.3g} N; soft contact RMS "
                   f"{soft.rms_error_pct_of_2N:.2f} % of 2 N; pair laws: "
                   f"{', '.join(cal.pair_laws) or 'none'}")


def _in_repo(path) -> str:
    """``path`` relative to the checkout when it lies inside it (provenance that does not name
    this machine's folders), else as given."""
    from pathlib import Path

    from softhand.paths import REPO_ROOT

    p = Path(path).resolve()
    return str(p.relative_to(REPO_ROOT)) if REPO_ROOT in p.parents else str(path)
