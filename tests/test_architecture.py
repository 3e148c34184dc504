"""The data flow of the design is the import graph: a stage imports only the stages before it.

Stages, in order (docs/architecture.md): fem -> laws -> skin -> sensors (branching off the FE) ->
design (the design search) -> hands -> envs -> viz, then the benchmarks and the command line above
them all. The base modules (paths, io, validate, paper, parallel, warn, compiled, the package
itself) may be imported by every stage.
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "softhand"
ORDER = ("fem", "laws", "skin", "sensors", "design", "hands", "envs", "viz", "bench", "cli")
BASE = {"__init__", "paths", "io", "validate", "paper", "parallel", "warn", "compiled", "data",
        "requirements"}
CLI = {"cli"}


def _stage(name: str) -> str:
    return "cli" if name in CLI else name


def _imports(path: Path) -> set[str]:
    """The softhand sub-packages or modules a file imports (their first name below softhand)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        names = []
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        for n in names:
            parts = n.split(".")
            if parts[0] == "softhand":
                out.add(parts[1] if len(parts) > 1 else "__init__")
    return out


def test_every_stage_imports_only_earlier_stages():
    bad = []
    for f in PACKAGE.rglob("*.py"):
        rel = f.relative_to(PACKAGE).parts
        stage = _stage(rel[0][:-3] if len(rel) == 1 else rel[0])
        if stage in BASE:
            allowed = BASE
        else:
            assert stage in ORDER, f"{f}: {stage!r} is not a stage of the data flow"
            allowed = BASE | set(ORDER[:ORDER.index(stage) + 1])
        for target in _imports(f):
            if _stage(target) not in allowed:
                bad.append(f"{f.relative_to(PACKAGE)} imports softhand.{target}")
    assert not bad, "imports against the data flow:\n" + "\n".join(sorted(bad))


def test_base_modules_import_no_stage():
    for name in ("paths", "io", "validate", "paper", "parallel", "warn", "compiled", "requirements"):
        assert _imports(PACKAGE / f"{name}.py") <= BASE, name


def test_every_name_the_tools_and_examples_import_from_softhand_exists():
    """The tools and examples are not run by the suite, so a name removed from softhand would
    break them unseen (tools/contact_geometry.py imported a removed function until the reports
    were regenerated): every ``from softhand... import name`` in them resolves."""
    import importlib

    root = PACKAGE.parent
    missing = []
    for path in sorted([*(root / "tools").glob("*.py"), *(root / "examples").glob("*.py")]):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not (isinstance(node, ast.ImportFrom) and node.level == 0 and node.module
                    and node.module.split(".")[0] == "softhand"):
                continue
            module = importlib.import_module(node.module)
            for alias in node.names:
                if alias.name == "*" or hasattr(module, alias.name):
                    continue
                try:
                    importlib.import_module(f"{node.module}.{alias.name}")
                except ImportError:
                    missing.append(f"{path.name}: {node.module}.{alias.name}")
    assert not missing
