"""``softhand materials [NAME ...]``: the material library with the source of every number."""

from __future__ import annotations

import json

import click

from softhand.cli.app import main
from softhand.cli.inputs import bad


@main.command("materials")
@click.argument("names", nargs=-1)
@click.option("--check", is_flag=True,
              help="Also run each through the FE's homogeneous compression check (30 % "
                   "uniaxial compression against the closed form).")
@click.option("--json", "as_json", is_flag=True, help="Print the entries as JSON.")
def materials(names, check, as_json) -> None:
    """List the skin materials (Table 3's SIL and PU, softer silicones) with their sources."""
    from dataclasses import asdict

    from softhand.fem.library import check_library_names, compression_check, library

    try:
        chosen = check_library_names(names, key="NAME") if names else list(library())
    except ValueError as exc:
        bad(str(exc))
    rows = []
    for name in chosen:
        m = library()[name]
        row = {**asdict(m), "shear_modulus_MPa": m.shear_modulus_MPa}
        if check:
            row["compression_check"] = asdict(compression_check(name))
        rows.append(row)
    if as_json:
        click.echo(json.dumps(rows, indent=1))
        return
    for r in rows:
        def num(v, fmt):
            return "n/a" if v is None else format(v, fmt)

        c = r["constants"]
        click.echo(f"{r['name']}: {r['product']}, Shore {r['shore']}")
        click.echo(f"  hyperfoam    mu = {c['mu_MPa']} MPa, alpha = {c['alpha']}, nu = {c['nu']} "
                   f"(shear modulus {r['shear_modulus_MPa']:.4g} MPa)")
        click.echo(f"  prony        g = {c['g']}, tau = {c['tau_s']} s")
        click.echo(f"  strength     elongation at break {num(r['elongation_at_break_pct'], 'g')} %, "
                   f"tensile {num(r['tensile_strength_MPa'], '.3g')} MPa, tear "
                   f"{num(r['tear_strength_N_mm'], '.3g')} N/mm")
        for key, text in r["sources"].items():
            click.echo(f"  {key:<13}{text}")
        if check:
            k = r["compression_check"]
            click.echo(f"  check        {'passed' if k['passed'] else 'FAILED'}: stretch "
                       f"{k['stretch']:g}, sigma {k['axial_stress_MPa']:.4g} MPa, stress error "
                       f"{k['stress_error']:.1e}, lateral/axial {k['lateral_stress_ratio']:.1e}")
