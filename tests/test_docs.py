"""The README and the docs site: short, built without warnings, and their numbers read from files.

- The docs build with ``mkdocs build --strict`` (mkdocs.yml), offline: a broken link or anchor, a
  missing include, a docstring the API reference cannot render or an unknown generated table fails.
- The README is a front page: at most about 150 lines, the two commands word for word (the test
  command is the one ``.ci/run`` runs), the quickstart that ``docs/quickstart.py`` holds (and that
  runs), a command table that lists every CLI command, and a skin table whose numbers are those
  of ``reports/bench-sensors.md`` and ``calibration/skins/index.json``.
- README, docs and changelog link nothing outside the repository, and every report in
  ``reports/`` is included on some page.
"""

from __future__ import annotations

import json
import os
import re
import runpy
import subprocess
import sys
from pathlib import Path

import click
import pytest

from softhand.cli import main

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
MAIN_COMMAND = "python -m pip install -e . && softhand handshake --record handshake.rrd"
TEST_COMMAND = 'python -m pip install -e ".[test]" && python -m pytest -q'
PAGES = sorted((ROOT / "docs").rglob("*.md"))


def _table(text: str, header: str) -> list[list[str]]:
    """The rows of the Markdown table whose header line starts with ``header``, cells stripped."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(header))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    return rows


def _leaf_commands(command: click.Command, path: tuple[str, ...] = ("softhand",)):
    if isinstance(command, click.Group):
        for name, sub in command.commands.items():
            yield from _leaf_commands(sub, (*path, name))
    else:
        yield " ".join(path)


@pytest.mark.slow
def test_docs_build_strict_offline_with_every_page(tmp_path):
    """``mkdocs build --strict`` passes with no warning at all, and the built site holds the
    included reports, the generated tables and the API reference."""
    site = tmp_path / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}  # mkdocs-material's notice about MkDocs 2
    res = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file",
                          str(ROOT / "mkdocs.yml"), "--site-dir", str(site)], cwd=tmp_path,
                         env=env, capture_output=True, text=True, timeout=600)
    log = res.stdout + res.stderr
    assert res.returncode == 0, log
    assert "WARNING" not in log, log
    fe = (site / "fe" / "index.html").read_text(encoding="utf-8")
    assert "FE benchmark" in fe and "--8&lt;--" not in fe and "--8<--" not in fe  # the include
    designs = (site / "designs" / "index.html").read_text(encoding="utf-8")
    assert "softhand:" not in designs and "pocket2-sil" in designs  # the generated tables
    cli = (site / "cli" / "index.html").read_text(encoding="utf-8")
    assert all(c in cli for c in _leaf_commands(main)) and str(ROOT) not in cli
    api = (site / "api" / "envs" / "index.html").read_text(encoding="utf-8")
    assert "HandshakeEnv" in api
    assert (site / "reports" / "bench-sensors.png").is_file()
    for page in site.rglob("*.html"):  # no fonts, scripts or links from elsewhere
        assert not re.search(r'(?:href|src)="https?://', page.read_text(encoding="utf-8")), page


def test_readme_fits_a_screen_and_a_half():
    assert len(README.splitlines()) <= 150


def test_readme_has_the_two_commands_and_ci_runs_the_test_command():
    assert f"```bash\n{MAIN_COMMAND}\n```" in README
    assert f"```bash\n{TEST_COMMAND}\n```" in README
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    assert TEST_COMMAND in ci  # as a line of its own, word for word


def test_readme_quickstart_is_the_docs_quickstart():
    code = re.search(r"```python\n(.*?)```", README, re.S)
    assert code and code[1] == (ROOT / "docs" / "quickstart.py").read_text(encoding="utf-8")
    assert "sensor" in README[code.end():].split("\n\n")[1]  # the line after it: what obs holds


@pytest.mark.slow
def test_quickstart_runs_and_prints_region_loads(capsys):
    runpy.run_path(str(ROOT / "docs" / "quickstart.py"), run_name="__main__")
    printed = capsys.readouterr().out
    assert "Palm1" in printed and "Back2" in printed


def test_readme_command_table_lists_every_cli_command():
    listed = {row[0].strip("`") for row in _table(README, "| command |")}
    commands = set(_leaf_commands(main))
    assert listed == commands, (sorted(commands - listed), sorted(listed - commands))


def test_readme_skin_table_is_the_reports():
    """Lifelike distance and useful placements of each design as bench sensors reported them;
    the commercial skin's distance from the shipped lifelike ranking."""
    readme = {row[0]: row[1:] for row in _table(README, "| skin |")}
    report = (ROOT / "reports" / "bench-sensors.md").read_text(encoding="utf-8")
    designs = _table(report, "| design | lifelike distance %")
    assert designs, "the design table of reports/bench-sensors.md"
    for row in designs:
        assert readme.pop(row[0]) == [row[1], row[-1]], row[0]
    ranking = json.loads((ROOT / "calibration" / "skins" / "index.json").read_text())["lifelike"]
    commercial = next(e for e in ranking if e["name"] == "prosthetic-102l")
    (name, (distance, _)), = readme.items()
    assert name.startswith("prosthetic-102l") and distance == f"{commercial['distance_pct']:.0f}"


def test_readme_speed_table_is_the_scale_report():
    """The README's speed rows are rows of reports/bench-handshake-scale.md, number for number."""
    readme = _table(README, "| what | env steps/s |")
    report = _table((ROOT / "reports" / "bench-handshake-scale.md").read_text(encoding="utf-8"),
                    "| what | env steps/s |")
    assert len(readme) == 3
    for name, steps, factor in readme:
        match = [row for row in report if row[0].startswith(name)]
        assert len(match) == 1 and match[0][1:] == [steps, factor], (name, match)


def test_readme_docs_and_changelog_link_only_inside_the_repository():
    for path in [ROOT / "README.md", ROOT / "CHANGELOG.md", *PAGES]:
        text = path.read_text(encoding="utf-8")
        assert not re.search(r"https?://|\.\./shared|seed/", text), path
        for target in re.findall(r"\]\(([^)#\s]+)", text):
            resolved = (path.parent / target).resolve()
            docs_site = path.parent.is_relative_to(ROOT / "docs")  # a page may link a published file
            assert resolved.is_relative_to(ROOT), (path, target)
            assert resolved.exists() or docs_site, (path, target)


def test_every_report_is_included_on_a_page():
    included = "\n".join(p.read_text(encoding="utf-8") for p in PAGES)
    for report in sorted((ROOT / "reports").glob("*.md")):
        assert f"<!-- softhand:include reports/{report.name} -->" in included, report.name


def test_the_docs_sources_hold_their_generated_tables_and_read_on_github():
    """Each page's Markdown holds its generated tables between their markers, as fresh as the
    site's (`python docs/_hooks/softhand_docs.py` writes them), and no raw include line: an
    included report stands as a link (GitHub showed build-time placeholders and 24 raw
    `--8<--` lines)."""
    sys.path.insert(0, str(ROOT / "docs" / "_hooks"))
    try:
        from softhand_docs import filled
    finally:
        sys.path.pop(0)
    stale = [p.name for p in PAGES
             if filled(p.read_text(encoding="utf-8"), p.relative_to(ROOT / "docs").as_posix())
             != p.read_text(encoding="utf-8")]
    assert not stale, f"run python docs/_hooks/softhand_docs.py: {stale} are out of date"
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        assert not re.search(r'^-{1,}8<-{1,}\s+"', text, re.MULTILINE), page.name
        for marker in re.findall(r"^<!-- softhand:([a-z-]+) -->$", text, re.MULTILINE):
            assert f"<!-- /softhand:{marker} -->" in text, (page.name, marker)


def test_the_pair_and_geom_counts_in_the_docs_are_the_shipped_scenes():
    """docs/handshake.md and models/mjcf/README.md state the shipped scene's pair count and its
    skin and tissue geom counts; they must be the model's (they once said 399, 323 and 304)."""
    import mujoco

    model = mujoco.MjModel.from_xml_path(str(ROOT / "models" / "mjcf" / "handshake_scene.xml"))
    names = [model.geom(g).name for g in range(model.ngeom)]
    skins = sum(n.startswith("pro_skin_") for n in names)
    tissues = sum(n.startswith("hum_tissue_") for n in names)
    assert skins * tissues == model.npair
    page = (ROOT / "docs" / "handshake.md").read_text(encoding="utf-8")
    assert (f"each of the prosthetic's {skins} skin geoms" in page
            and f"each of the partner's {tissues} tissue geoms" in page
            and f"`<pair>` ({model.npair} pairs)" in page.replace("\n  ", " "))
    models = (ROOT / "models" / "mjcf" / "README.md").read_text(encoding="utf-8")
    assert f"{model.npair} in all" in models
    counts = {int(n) for n in re.findall(r"(\d+) in all", models)}
    assert counts == {model.npair}, counts


def test_the_controllers_page_has_the_phases_and_their_times():
    """docs/controllers.md lists every phase with the default timeline's start and end (a first
    controller written from the docs closed during the reach and held 0 N)."""
    from softhand.envs.partner import PHASES, Timeline

    rows = _table((ROOT / "docs" / "controllers.md").read_text(encoding="utf-8"),
                  "| phase | from s |")
    assert [r[0].strip("`") for r in rows] == list(PHASES)
    ends = [0.0, *Timeline().ends]
    for k, row in enumerate(rows[:-1]):
        assert float(row[1]) == pytest.approx(ends[k], abs=0.005), row
        assert float(row[2]) == pytest.approx(ends[k + 1], abs=0.005), row


def test_citation_and_type_marker_ship():
    """CITATION.cff cites the paper by its DOI; softhand ships py.typed (PEP 561)."""
    cff = (ROOT / "CITATION.cff").read_text(encoding="utf-8")
    assert "doi: \"10.1186/1743-0003-8-16\"" in cff and "cff-version: 1.2.0" in cff
    assert (ROOT / "softhand" / "py.typed").exists()
    assert '"py.typed"' in (ROOT / "pyproject.toml").read_text(encoding="utf-8")
