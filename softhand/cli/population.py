"""``softhand population``: the paper's experiment over sampled partners, and sweeps over skins
and controllers."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from softhand import __version__
from softhand.cli.app import _end_of_batch, main
from softhand.cli.handshake import (
    _OPT_CONTACT_LAWS,
    _OPT_HAND,
    _check_hand,
    _header,
    _sensored_hand,
    design_of,
)
from softhand.cli.inputs import (
    OPT_CLUSTER,
    bad,
    check_threads_or_cluster,
    checked_dir,
    cpus_allowed,
    progress_bar,
)
from softhand.paper import paper


@main.command("population")
@click.option("--n", "n", type=click.IntRange(1, 10000), default=30, show_default=True,
              help="Partners, 1-10000 (the paper had 30).")
@click.option("--seed", type=click.IntRange(0, 2**32 - 1), default=0, show_default=True,
              help="Seed of the population, 0 <= seed < 2^32.")
@click.option("--design", "designs", multiple=True,
              help="Skin of every region (repeatable: a sweep): a skin name, or the path of a "
                   "calibration file (*.json, e.g. from `softhand design calibrate`) "
                   "[default: pocket2-sil].")
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
    files = {d: design_of(d) for d in designs}  # a calibration file: read and checked now
    folders = {d: {"calibration_dir": f[2]} if f[2] else {} for d, f in files.items()}
    combos = [(d, c) for d in designs for c in controllers]
    sweep = len(combos) > 1
    out = checked_dir(out_dir, "--out", need_bytes=(2e6 + 4e3 * n) * len(combos))
    for design in designs:
        try:
            # the skin and its files, before any work
            HandshakeEnv(design=files[design][1], hand=hand, contact_laws=contact_laws,
                         **folders[design])
        except ValueError as exc:
            bad(str(exc) if design is None else f"--design {design!r}: {exc}")
    partners = sample_partners(n, seed)
    skins = [files[d][1] or DEFAULT_DESIGN for d in designs]
    what = f"{n} partners" + (f" x {len(combos)} combinations" if sweep else "")
    click.echo(_header("population", f"{what}, seed {seed}", _sensored_hand(
        hand, f"{skins[0]} on every region" if len(skins) == 1 else f"skins {', '.join(skins)}",
        f"controller{'s' if len(controllers) > 1 else ''} {', '.join(controllers)}")))
    names = [f"{d}-{c}" for d in skins for c in controllers]
    tasks = [((k, p.index), (p, {"design": files[d][1], "controller": c, "hand": hand,
                                 "contact_laws": contact_laws, **folders[d]}))
             for k, (d, c) in enumerate(combos) for p in partners]  # a combination's in a row
    done = []
    with progress_bar(what, disable=False) as update:
        batch = run_tasks(run_partner, tasks, threads=threads, cluster=cluster,
                          on_done=lambda key, ok: (done.append(key),
                                                   update(len(done) / len(tasks))))
    command = "softhand population " + " ".join(sys.argv[2:])
    listed, missing_all, beside = [], {}, []
    with interrupts_deferred():  # what finished is written whole, Ctrl-C or not
        revision = git_revision()
        for k, ((design, controller), name) in enumerate(zip(combos, names, strict=True)):
            results = [batch.results[(k, p.index)] for p in partners
                       if (k, p.index) in batch.results]
            missing = {str(i): "interrupted" for j, i in batch.missing if j == k}
            missing.update({str(i): str(e) for (j, i), e in batch.errors.items() if j == k})
            missing_all.update({f"{name}/{i}" if sweep else i: why for i, why in missing.items()})
            meta = {"n": n, "seed": seed, "hand": hand,
                    "design": ("human tissue" if hand == "human"
                               else files[design][1] or DEFAULT_DESIGN),
                    "design_file": files[design][0],
                    "controller": controller, "contact_laws": contact_laws,
                    "finished": len(results), "missing": missing,
                    "version": __version__, "git_revision": revision, "command": command}
            summary = {}
            if results:
                target = out / name if sweep else out
                if missing and (target / "results.json").exists():
                    # an incomplete run never replaces an earlier set: it goes beside it
                    target = target.with_name(f"{target.name}.incomplete")
                    beside.append(target)
                summary = _write_population(target, partners, results, meta)
                if sweep:
                    click.echo(f"{name}: {len(results)} of {n} partners")
                _print_population(summary)
                _print_geometry(results)
            listed.append({"design": meta["design"], "design_file": meta["design_file"],
                           "controller": controller,
                           "folder": name if results else None, "finished": len(results),
                           "missing": missing, "regions_over_2N_in_most_partners": [
                               r for r, v in summary.items() if v["over_2N_pct"] > 50]})
        if sweep and batch.results:
            atomic_write_text(out / "sweep.json", json.dumps(
                {"partners": {"n": n, "seed": seed}, "hand": hand, "contact_laws": contact_laws,
                 "combinations": listed, "version": __version__, "git_revision": revision,
                 "command": command}, indent=1))
    _end_of_batch("handshakes" if sweep else "partners", len(batch.results), len(tasks), out,
                  missing_all, batch.interrupted, beside=beside)
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


def _print_geometry(results: list[dict]) -> None:
    """One line: over the partners, the share of the force whose skin law was made for the
    contact's geometry, and the share on a rounded palm border
    (`softhand.skin.local_geometry`; each partner's ``force_accounting.by_geometry``)."""
    import numpy as np

    from softhand.skin.local_geometry import palm_border_share_pct

    geo = [r["force_accounting"].get("by_geometry") for r in results]
    geo = [g for g in geo if g]
    if not geo:
        return
    fits = np.array([g["skin_own_class_share_pct"] for g in geo])
    border = np.array([palm_border_share_pct(g) for g in geo])
    click.echo(f"the law against the shapes each contact met (median over {len(geo)} partners, "
               f"10-90 %): a skin law made for the contact's geometry carried "
               f"{np.median(fits):.1f} % ({np.percentile(fits, 10):.1f}-"
               f"{np.percentile(fits, 90):.1f}) of the force; on a rounded palm border "
               f"{np.median(border):.1f} % ({np.percentile(border, 10):.1f}-"
               f"{np.percentile(border, 90):.1f}); per partner: results.json, "
               "force_accounting.by_geometry")


def _print_population(summary: dict[str, dict]) -> None:
    click.echo("| region | partners over 2 N % | median peak N | 10-90 % peak N | paper |\n"
               "|---|---|---|---|---|")
    for region, v in summary.items():
        click.echo(f"| {region} | {v['over_2N_pct']:.0f} | {v['median_peak_N']:.2f} | "
                   f"{v['p10_peak_N']:.2f}-{v['p90_peak_N']:.2f} | "
                   f"{'> 2 N' if v['paper_over_2N'] else ''} |")
