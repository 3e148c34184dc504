"""mkdocs hooks of the softhand docs: measured numbers come from files, never from the page's text.

Three jobs, each so that a number on a page is read from the file that measured it:

- Included Markdown sits under the section that includes it. ``--8<-- "reports/bench-fe.md"``
  (pymdownx.snippets) pastes a report whose title is a level-1 heading; its headings are shifted
  down to one level below the heading the include line follows.
- The pictures of ``reports/`` and the FE curves of ``calibration/fe/`` are published with the
  site under the same paths, so a page links ``reports/bench-sensors.png`` without a copy in
  ``docs/``.
- A line ``<!-- softhand:NAME -->`` is replaced by a table generated from the shipped data or a
  report at build time (``GENERATED`` lists them): the paper comparison from
  ``calibration/fe/summary.json``, the lifelike ranking from ``calibration/skins/index.json``, the
  population from ``reports/population-*.json``, the material library from
  ``softhand/data/materials.json``, the command reference from the CLI itself, the
  env's action and observation tables from ``softhand.envs.spaces`` (the names the env gives).
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Callable
from pathlib import Path

from markdown import Extension, Markdown
from markdown.preprocessors import Preprocessor
from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parents[2]

#: pictures published with the site, by glob, under their path in the repository
PUBLISHED = ("reports/*.png", "calibration/fe/curves.png")

_INCLUDE = re.compile(r'^\s*-{1,}8<-{1,}\s+"(?P<path>[^"]+\.md)"\s*$')
_HEADING = re.compile(r"^(?P<indent>\s*)(?P<hashes>#{1,6})(?P<rest>\s.*)$")
_FENCE = re.compile(r"^\s*(```|~~~)")
_SHIFT = re.compile(r"^<!-- softhand-shift (?P<levels>\d) (?P<edge>start|end) -->$")


def _headings(lines: list[str]) -> list[tuple[int, int]]:
    """(line index, level) of every Markdown heading outside fenced code."""
    found, fenced = [], False
    for i, line in enumerate(lines):
        if _FENCE.match(line):
            fenced = not fenced
        elif not fenced and (m := _HEADING.match(line)):
            found.append((i, len(m["hashes"])))
    return found


class _MarkIncludes(Preprocessor):
    """Before the snippets: fence every Markdown include with the level of its section."""

    def run(self, lines: list[str]) -> list[str]:
        levels = dict(_headings(lines))
        out, level = [], 0
        for i, line in enumerate(lines):
            level = levels.get(i, level)
            if _INCLUDE.match(line):
                out += [f"<!-- softhand-shift {level} start -->", line,
                        f"<!-- softhand-shift {level} end -->"]
            else:
                out.append(line)
        return out


class _ShiftIncluded(Preprocessor):
    """After the snippets: shift the included headings below their section, drop the fences."""

    def run(self, lines: list[str]) -> list[str]:
        out, shift, fenced = [], 0, False
        for line in lines:
            if m := _SHIFT.match(line.strip()):
                shift = int(m["levels"]) if m["edge"] == "start" else 0
                continue
            if _FENCE.match(line):
                fenced = not fenced
            elif shift and not fenced and (m := _HEADING.match(line)):
                line = m["indent"] + "#" * min(6, len(m["hashes"]) + shift) + m["rest"]
            out.append(line)
        return out


class _IncludedHeadings(Extension):
    def extendMarkdown(self, md: Markdown) -> None:  # noqa: N802 (Python-Markdown's name)
        md.preprocessors.register(_MarkIncludes(md), "softhand_mark_includes", 33)  # snippets: 32
        md.preprocessors.register(_ShiftIncluded(md), "softhand_shift_included", 31)


def on_config(config):
    config.markdown_extensions.append(_IncludedHeadings())
    return config


def on_files(files: Files, config) -> Files:
    for pattern in PUBLISHED:
        for path in sorted(ROOT.glob(pattern)):
            files.append(File.generated(config, path.relative_to(ROOT).as_posix(),
                                        abs_src_path=str(path)))
    return files


# -- generated tables -----------------------------------------------------------------------------

def _json(path: str) -> dict:
    return json.loads((ROOT / path).read_text())


def _paper_agreement() -> str:
    from softhand.fem.sweep import paper_error_table
    summary = _json("calibration/fe/summary.json")
    return paper_error_table(summary) + "\n\n" + _source("calibration/fe/summary.json", summary)


def _source(path: str, data: dict) -> str:
    """The line under a generated table: the file it was read from, and how that file was made."""
    prov = data.get("provenance") or data.get("settings") or {}
    made = prov.get("command") or prov.get("created_utc", "")
    rev = prov.get("git_revision", "")
    return f"*Generated from `{path}`*" + (f" (`{made}`" if made else " (") + (
        f", git {rev[:10]})." if rev else ").")


def _paper_details() -> str:
    """Rising slopes of the 2 mm pockets and the layered designs' change, from the sweep."""
    comparison = _json("calibration/fe/summary.json")["comparison"]
    rows = ["| design | rising slope mm/N, paper | softhand | error |", "|---|---|---|---|"]
    for name, c in comparison.items():
        if s := c.get("rising_slope"):
            rows.append(f"| {name} | {s['paper']:.2f} | {s['softhand']:.2f} | "
                        f"{s['error_pct']:+.1f} % |")
    rows += ["", "| layered design | change against its homogeneous inner material | paper |",
             "|---|---|---|"]
    for name, c in comparison.items():
        if lay := c.get("layered_change"):
            paper = (f"{lay['paper_pct']:+.1f} %" if "paper_pct" in lay
                     else f"within ±{lay['paper_within_abs_pct']:.0f} %")
            rows.append(f"| {name} | {lay['softhand_pct']:+.1f} % | {paper} |")
    return "\n".join(rows) + "\n\n*Generated from `calibration/fe/summary.json`.*"


def _lifelike() -> str:
    index = _json("calibration/skins/index.json")
    rows = ["| rank | skin | d(1 N) mm | d(2 N) mm | distance from the human phalanx % |",
            "|---|---|---|---|---|"]
    for rank, entry in enumerate(index["lifelike"]):
        d1, d2 = entry["displacement_mm"]
        rows.append(f"| {rank or 'reference'} | {entry['name']} | {d1:.2f} | {d2:.2f} | "
                    f"{entry['distance_pct']:.0f} |")
    return "\n".join(rows) + "\n\n" + _source("calibration/skins/index.json", index)


def _skin_laws() -> str:
    """Each shipped skin's law against its FE curves, and its pair law against the exact series."""
    index = _json("calibration/skins/index.json")
    rows = ["| skin | law, fitted: RMS to 2 N % of 2 N / above 2 N % of F / hold max % | "
            "law, 2 mm/s (not fitted) | pair law: RMS to 2 N % of 2 N / above 2 N % of F | "
            "calibrated to N |", "|---|---|---|---|---|"]

    def worst(records: list[dict]) -> str:
        if not records:
            return "-"
        keys = ("rms_pct_of_2N_to_2N", "rms_pct_above_2N", "hold_max_pct")
        return " / ".join(f"{max(r[k] for r in records):.2f}" for k in keys)

    for name in index["skins"]:
        skin = _json(f"calibration/skins/{name}.json")
        law, pair = skin["law"], skin["pair_law"]
        above = pair.get("rms_pct_above_2N")
        rows.append(f"| {name} | {worst(law['fitted'])} | {worst(law['validated'])} | "
                    f"{pair['rms_pct_of_2N_to_2N']:.2f} / "
                    f"{'-' if above is None else f'{above:.2f}'} | {pair['calibrated_max_N']:g} |")
    return "\n".join(rows) + "\n\n" + _source("calibration/skins/*.json", index)


#: the population runs compared on the handshake page, column title -> report
POPULATIONS = {
    "human hand, tissue class laws": "reports/population-human.json",
    "human hand, seed 7": "reports/population-human-seed7.json",
    "pocket2-sil, geometry laws": "reports/population-pocket2-sil-geometry-laws.json",
    "pocket2-sil, seed 7": "reports/population-pocket2-sil-geometry-laws-seed7.json",
    "pocket2-sil, plate laws": "reports/population-pocket2-sil-plate-laws.json",
    "rigid skin, plate laws": "reports/population-rigid.json",
    "rigid skin, seed 7": "reports/population-rigid-seed7.json",
}


def _command(settings: dict) -> str:
    """The command a report was made with, without its output folder (a path on that machine)."""
    return re.sub(r" --out \S+", "", settings["command"])


def _population() -> str:
    runs = {title: _json(path) for title, path in POPULATIONS.items()}
    first = next(iter(runs.values()))["summary"]
    rows = ["| region | paper, Fig. 4 | " + " | ".join(runs) + " |",
            "|---|---|" + "---|" * len(runs)]
    for region, s in first.items():
        cells = [f"{r['summary'][region]['over_2N_pct']:.0f} "
                 f"({r['summary'][region]['median_peak_N']:.1f})" for r in runs.values()]
        rows.append(f"| {region} | {'> 2 N' if s['paper_over_2N'] else ''} | "
                    + " | ".join(cells) + " |")
    rows += ["", "| over the partners | " + " | ".join(runs) + " |", "|---|" + "---|" * len(runs)]
    stats = {
        "partners": lambda p: f"{len(p)}",
        "grip error against its target, 95th percentile, worst partner %":
            lambda p: f"{max(x['grip']['p95_error_pct'] for x in p):.1f}",
        "force through a skin law inside its calibrated range, worst partner %":
            lambda p: f"{min(x['force_accounting']['calibrated_share_pct'] for x in p):.0f}",
        "bone-on-bone peak, worst partner N":
            lambda p: f"{max(x['force_accounting']['bone_on_bone_peak_N'] for x in p):.1f}",
    }
    for what, stat in stats.items():
        rows.append(f"| {what} | " + " | ".join(stat(r["partners"]) for r in runs.values()) + " |")
    sources = "; ".join(f"{title}: `{path}` (`{_command(runs[title]['settings'])}`)"
                        for title, path in POPULATIONS.items())
    return "\n".join(rows) + f"\n\n*Generated from {sources}.*"


def _cli() -> str:
    import click

    from softhand.cli import main

    parts = []

    def walk(command: click.Command, path: list[str], parent: click.Context | None) -> None:
        ctx = click.Context(command, info_name=path[-1], parent=parent, max_content_width=100,
                            terminal_width=100)
        if path[1:]:
            # default folders print as this checkout's absolute paths: show them
            # repository-relative, before click wraps the help (so that the page does not
            # depend on where the checkout lies)
            here = f"{ROOT}{os.sep}"
            saved = [(p, p.default) for p in command.params
                     if isinstance(p.default, str) and here in p.default]
            try:
                for p, default in saved:
                    p.default = default.replace(here, "")
                text = command.get_help(ctx).replace(here, "")
            finally:
                for p, default in saved:
                    p.default = default
            parts.append(f"{'#' * min(4, len(path))} `{' '.join(path)}`\n\n```text\n{text}\n```\n")
        if isinstance(command, click.Group):
            for name in command.list_commands(ctx):
                walk(command.get_command(ctx, name), [*path, name], ctx)

    walk(main, ["softhand"], None)
    return "\n".join(parts)


def _actions() -> str:
    from softhand.envs.spaces import action_table
    return action_table(markdown=True) + "\n\n*Generated from `softhand.envs.spaces`.*"


def _observations() -> str:
    from softhand.envs.spaces import observation_table
    return observation_table(markdown=True) + "\n\n*Generated from `softhand.envs.spaces`.*"


def _material_source(m) -> str:
    if m.modulus_100_MPa is None:  # Table 3
        return m.sources["hyperelastic"].split(";")[0]
    return "datasheet fit: 100 % modulus and tensile strength (nu, Prony assumed)"


def _materials() -> str:
    from softhand.fem.library import library

    rows = ["| material | Shore | mu_i MPa | alpha_i | nu | elongation at break % | tensile MPa | "
            "tear N/mm | hyperelastic constants from |", "|---|---|---|---|---|---|---|---|---|"]
    for m in library().values():
        c = m.constants
        num = (lambda v, f: "n/a" if v is None else format(v, f))  # noqa: E731
        rows.append(f"| {m.name} | {m.shore} | {', '.join(f'{v:.4g}' for v in c['mu_MPa'])} | "
                    f"{', '.join(f'{v:.4g}' for v in c['alpha'])} | {c['nu']:g} | "
                    f"{num(m.elongation_at_break_pct, 'g')} | "
                    f"{num(m.tensile_strength_MPa, '.3g')} | {num(m.tear_strength_N_mm, '.3g')} | "
                    f"{_material_source(m)} |")
    return ("\n".join(rows) + "\n\n*Generated from `softhand/data/materials.json` "
            "(`softhand materials` prints every source).*")


def _quickstart() -> str:
    return "```python\n" + (ROOT / "docs" / "quickstart.py").read_text().rstrip() + "\n```"


GENERATED: dict[str, Callable[[], str]] = {
    "quickstart": _quickstart,
    "materials": _materials,
    "paper-agreement": _paper_agreement,
    "paper-details": _paper_details,
    "lifelike": _lifelike,
    "skin-laws": _skin_laws,
    "population": _population,
    "cli": _cli,
    "actions": _actions,
    "observations": _observations,
}
_MARKER = re.compile(r"^<!-- softhand:(?P<name>[a-z-]+) -->$", re.MULTILINE)
#: a generated region as the Markdown source keeps it (so that GitHub shows the table too)
_REGION = re.compile(r"^<!-- softhand:(?P<name>[a-z-]+) -->\n.*?^<!-- /softhand:(?P=name) -->$",
                     re.MULTILINE | re.DOTALL)
#: an included report as the source keeps it: a comment naming the file, then a link to it (what
#: GitHub shows); the site pastes the file there (pymdownx.snippets)
_INCLUDE_LINK = re.compile(r"^<!-- softhand:include (?P<path>\S+\.md) -->\n\[[^\]\n]*\]\([^)\n]*\)$",
                           re.MULTILINE)
_LEGACY_INCLUDE = re.compile(r'^-{1,}8<-{1,}\s+"(?P<path>[^"]+\.md)"\s*$', re.MULTILINE)


def filled(markdown: str, where: str = "page") -> str:
    """``markdown`` with every generated region (``<!-- softhand:NAME -->`` ... ``<!--
    /softhand:NAME -->``, or a lone opening line) holding its fresh table, and every report
    include written as a comment and a link: what the sources keep, so that a page reads on
    GitHub as on the site (`python docs/_hooks/softhand_docs.py` writes it; a test checks the
    sources are up to date)."""
    def region(m: re.Match) -> str:
        name = m["name"]
        if name not in GENERATED:
            raise ValueError(f"{where}: <!-- softhand:{name} --> is unknown; allowed: "
                             f"{', '.join(GENERATED)}")
        return f"<!-- softhand:{name} -->\n\n{GENERATED[name]()}\n\n<!-- /softhand:{name} -->"

    depth = where.count("/")  # a page in docs/: its links to the repository go up one level

    def include(m: re.Match) -> str:
        path = m["path"]
        up = "../" * (depth + 1)
        return f"<!-- softhand:include {path} -->\n[{path}]({up}{path})"

    text = _REGION.sub(lambda m: f"<!-- softhand:{m['name']} -->", markdown)
    text = _MARKER.sub(region, text)
    return _LEGACY_INCLUDE.sub(include, text)


_REGION_EDGE = re.compile(r"^<!-- /?softhand:[a-z-]+ -->\n", re.MULTILINE)


def on_page_markdown(markdown: str, page, config, files) -> str:
    text = filled(markdown, page.file.src_uri)
    # the site pastes each report where its link stands, and drops the regions' edges
    text = _INCLUDE_LINK.sub(lambda m: f'--8<-- "{m["path"]}"', text)
    return _REGION_EDGE.sub("", text)


def main() -> int:
    """Write every page's generated regions and includes into its Markdown source."""
    changed = []
    for path in sorted((ROOT / "docs").rglob("*.md")):
        text = path.read_text(encoding="utf-8")
        new = filled(text, path.relative_to(ROOT / "docs").as_posix())
        if new != text:
            path.write_text(new, encoding="utf-8")
            changed.append(path.relative_to(ROOT).as_posix())
    print(("rewrote " + ", ".join(changed)) if changed else "the docs are up to date")
    return 0


if __name__ == "__main__":
    import sys

    sys.path.insert(0, str(ROOT))
    sys.exit(main())
