"""The command line's inputs: typed options and their checks, before any work starts.

Every check raises `InputError` (one line ``error: ...`` naming the flag or file, the
value and the allowed range; exit status 2). `softhand.cli` builds the commands from these.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import NoReturn

import click

from softhand.paths import CALIBRATION_DIR, is_shipped

EXIT_INPUT = 2


class InputError(click.ClickException):
    """Bad input found before any work: one line, exit status 2."""

    exit_code = EXIT_INPUT


def bad(message: str) -> NoReturn:
    raise InputError(message)


class Number(click.ParamType):
    """A finite number in a range; the message names the range and its unit."""

    name = "number"

    def __init__(self, lo: float | None = None, hi: float | None = None, *, lo_open: bool = False,
                 hi_open: bool = False, unit: str = "") -> None:
        self.lo, self.hi, self.lo_open, self.hi_open, self.unit = lo, hi, lo_open, hi_open, unit

    @property
    def allowed(self) -> str:
        left = "" if self.lo is None else f"{self.lo:g} {'<' if self.lo_open else '<='} "
        right = "" if self.hi is None else f" {'<' if self.hi_open else '<='} {self.hi:g}"
        return f"{left}x{right}" + (f" {self.unit}" if self.unit else "")

    def convert(self, value, param, ctx):
        if isinstance(value, float):
            v = value
        else:
            try:
                v = float(value)
            except (TypeError, ValueError):
                self.fail(f"{value!r} is not a number; allowed {self.allowed}", param, ctx)
        below = self.lo is not None and (v <= self.lo if self.lo_open else v < self.lo)
        above = self.hi is not None and (v >= self.hi if self.hi_open else v > self.hi)
        if not math.isfinite(v) or below or above:
            self.fail(f"{value!r} is outside the allowed range {self.allowed}", param, ctx)
        return v


def checked_dir(path: str | None, flag: str, *, force: bool | None = None,
                need_bytes: float = 0.0) -> Path | None:
    """``path`` as a folder this command may write, checked before any work.

    ``force`` is the command's ``--force`` (None: the command has none and never writes shipped
    data); ``need_bytes``: what the run writes, checked against the disk's free space.
    """
    from softhand.io import check_free_space, check_writable_dir

    if path is None:
        return None
    try:
        if str(path).strip():  # shipped first: the writability probe touches the folder
            _check_shipped(Path(path), flag, force)
        out = check_writable_dir(path, name=flag)
        if need_bytes:
            check_free_space(out, need_bytes, name=flag)
    except ValueError as exc:
        bad(str(exc))
    return out


def checked_file(path: str | None, flag: str, suffix: str, *,
                 need_bytes: float = 0.0) -> Path | None:
    """``path`` as a file this command may write (never into the shipped data), before any
    work; ``need_bytes`` as in `checked_dir`."""
    from softhand.io import check_free_space, check_writable_file

    if path is None:
        return None
    try:
        if str(path).strip():
            _check_shipped(Path(path), flag, None)
        out = check_writable_file(path, suffix=suffix, name=flag)
        if need_bytes:
            check_free_space(out, need_bytes, name=flag)
    except ValueError as exc:
        bad(str(exc))
    return out


def _check_shipped(out: Path, flag: str, force: bool | None) -> None:
    """Shipped data is written only with ``--force``, and only by the commands that make it."""
    if not is_shipped(out) or force:
        return
    if force is None:
        bad(f"{flag} {str(out)!r} is inside the shipped calibration data ({CALIBRATION_DIR}), "
            "which this command never writes: write elsewhere")
    bad(f"{flag} {str(out)!r} is the shipped calibration data: add --force to replace it (the "
        "new set replaces the old only when the run completes; an interrupted or failed run "
        "leaves it byte for byte), or write elsewhere with --out DIR")


@contextmanager
def progress_bar(desc: str, *, disable: bool) -> Iterator[Callable[[float], None]]:
    """A percent progress bar on stderr, closed (its line ended) before anything else prints."""
    from tqdm import tqdm

    bar = tqdm(total=100, desc=desc, unit="%", disable=disable, file=sys.stderr)

    def update(frac: float) -> None:
        bar.update(round(100 * frac) - bar.n)

    try:
        yield update
    finally:
        bar.close()


def progress_line(line: str) -> None:
    """A long command's line on what it starts now, on stderr: stdout stays its report."""
    click.echo(line + " ...", err=True)


# --- FE options -----------------------------------------------------------------------------

_OPT_MESH = click.option("--mesh", type=click.Choice(["coarse", "default", "uniform", "fine"]),
                         default="default", show_default=True,
                         help="Mesh: default is graded to the pocket ends; fine doubles every count.")
_OPT_MODE = click.option("--mode", type=click.Choice(["3d", "2d"]), default="3d",
                         show_default=True,
                         help="3D quarter model, or fast 2D plane-strain cross-section.")
_OPT_ELASTIC = click.option("--elastic-only", is_flag=True,
                            help="Hyperfoam only, no Prony relaxation (no hold).")
_OPT_MODULI = click.option("--moduli", type=click.Choice(["long-term", "instantaneous"]),
                           default="long-term", show_default=True,
                           help="How Table 3 moduli are read.")
_OPT_HOLD = click.option("--hold", "hold_s", type=Number(0, 600, unit="s"), default=10.0,
                         show_default=True, help="Hold after the ramp, 0-600 s.")
_OPT_SPEED = click.option("--speed", "speed_mm_s", type=Number(0, 100, lo_open=True, unit="mm/s"),
                          default=0.5, show_default=True, help="Plate speed, (0, 100] mm/s.")
_OPT_FORCE = click.option("--max-force", "max_force_N",
                          type=Number(0, 50, lo_open=True, unit="N"), default=2.0,
                          show_default=True, help="Force that ends the ramp, (0, 50] N.")
_OPT_DEPTH = click.option("--max-depth", "max_depth_mm",
                          type=Number(0, 7, lo_open=True, unit="mm"), default=6.0,
                          show_default=True,
                          help="Plate travel that ends the ramp if the force is not reached "
                               "first, (0, 7] mm (the phalanx is 9 mm high).")
_OPT_GEOMETRY = click.option("--geometry", multiple=True, metavar="KEY=VALUE",
                             help="Override a geometry field, e.g. pocket_roof_mm=1.5 (repeatable).")
_OPT_MATERIALS = click.option("--materials", "materials_path",
                              help="JSON file with material constants replacing Table 3, "
                                   "e.g. {\"sil\": {\"mu_MPa\": [0.08, 0.01]}}.")


class IndenterText(click.ParamType):
    """An indenter: plate, cylinder:R_MM[@ANGLE_DEG] or sphere:R_MM (canonical text out)."""

    name = "indenter"

    def convert(self, value, param, ctx):
        from softhand.fem.indenter import parse_indenter

        try:
            return parse_indenter(value).text
        except ValueError as exc:
            self.fail(f"{value!r}: {str(exc).split(': ', 1)[-1]}", param, ctx)


_OPT_INDENTER = click.option(
    "--indenter", type=IndenterText(), default="plate", show_default=True,
    metavar="plate|cylinder:R_MM[@ANGLE_DEG]|sphere:R_MM",
    help="Rigid indenter: the paper's plate, a cylinder of radius R in [1, 1000] mm with its "
         "axis at ANGLE_DEG in [0, 90] from the phalanx axis (0: along it, 90: across it, the "
         "default; other angles run the full phalanx, 4x the elements, no embedded sensors, "
         "not exportable), or a sphere of radius R in [1, 1000] mm. 2d takes the plate and "
         "cylinder:R@0 only.")


_OPT_BODY = click.option(
    "--body", type=click.Choice(["phalanx", "palm"]), default="phalanx", show_default=True,
    help="What is indented: the paper's phalanx, or the palm (a slab of the design's layers over "
         "a metacarpal; plate, sphere, cylinder at 0 or 90 deg; no embedded sensors).")


_OPT_POCKET = click.option(
    "--pocket-contact", "pocket_contact", type=click.Choice(["paired", "sliding"]),
    default="paired", show_default=True,
    help="The pocket's roof against its floor: paired (the shipped curves': points at the same "
         "place on their faces; the floor passes into the roof once it slides, 0.12 mm on "
         "pocket2-sil at 2 N) or sliding (the floor and side wall projected on the deformed "
         "roof; reports/pocket-contact.md).")


_OPT_POINTS = click.option(
    "--contact-points", "contact_points", type=click.IntRange(2, 6), default=4,
    show_default=True,
    help="Gauss points per face direction of the indenter's and the pocket's contact, 2-6: 4 "
         "gives the shipped curves; 2 (the design search's runs) about halves the Newton "
         "iterations for an indentation within 1 % (softhand bench fe).")


_OPT_ENGINE = click.option(
    "--engine", type=click.Choice(["compiled", "numpy"]), default="compiled", show_default=True,
    help="Element engine: compiled (numba kernels, one Cholesky analysis per run) or numpy (the "
         "reference). The same curves within the Newton tolerance; numpy is about 2x slower.")


_OPT_SOLVER = click.option(
    "--solver", type=click.Choice(["auto", "cholmod", "pardiso"]), default="auto",
    show_default=True,
    help="Sparse Cholesky of the compiled engine: MKL PARDISO (pip install 'softhand[mkl]'; "
         "x86-64 Linux and Windows), CHOLMOD, or auto (PARDISO where installed). The same "
         "curves to rounding; bench fe times both.")


def cpus_allowed(ctx, param, value):
    """--threads / --workers: at most the CPUs this process may run on (more only queue)."""
    from softhand.parallel import available_cpus

    if value is not None and value > available_cpus():
        raise click.BadParameter(f"{value} is more than the {available_cpus()} CPUs this process "
                                 f"may run on; allowed 1-{available_cpus()}", ctx, param)
    return value


OPT_THREADS = click.option("--threads", type=click.IntRange(min=1), default=None,
                           callback=cpus_allowed,
                            help="Cores to use [default: the CPUs this process may run on, at "
                                 "most 4]. One FE run: element threads; a sweep or calibration: "
                                 "designs or skins at once. BLAS stays single-threaded.")


def cluster_reachable(ctx, param, value):
    """--cluster: a Dask scheduler answers at the address (before any work)."""
    if value is None:
        return None
    from softhand.parallel import check_cluster

    try:
        return check_cluster(value, name="--cluster")
    except ValueError as exc:
        bad(str(exc))


OPT_CLUSTER = click.option(
    "--cluster", metavar="tcp://HOST:PORT", default=None, callback=cluster_reachable,
    help="Run the batch on the Dask distributed scheduler at this address (tcp:// or tls://; "
         "pip install 'softhand[cluster]'; its workers need softhand and one thread each, "
         "`dask worker ADDRESS --nthreads 1`) instead of on this machine. Not with --threads "
         "(--workers): the cluster's workers set how many run at once. [default: worker "
         "processes on this machine, no setup]")


def check_threads_or_cluster(threads: int | None, cluster: str | None,
                             flag: str = "--threads") -> None:
    """One of ``--threads`` (``--workers``) and ``--cluster``: both say where the batch runs."""
    if threads is not None and cluster is not None:
        bad(f"{flag} {threads} with --cluster {cluster!r}: the cluster's workers set how many "
            f"tasks run at once; allowed one of the two")


FE_OPTIONS = (_OPT_MESH, _OPT_MODE, _OPT_INDENTER, _OPT_BODY, _OPT_ELASTIC, _OPT_MODULI, _OPT_HOLD,
              _OPT_SPEED, _OPT_FORCE, _OPT_DEPTH, _OPT_GEOMETRY, _OPT_MATERIALS, OPT_THREADS,
              _OPT_ENGINE, _OPT_SOLVER, _OPT_POCKET, _OPT_POINTS)
EXPORT_OPTIONS = (_OPT_MESH, _OPT_INDENTER, _OPT_ELASTIC, _OPT_MODULI, _OPT_HOLD, _OPT_SPEED,
                  _OPT_FORCE, _OPT_GEOMETRY, _OPT_MATERIALS, OPT_THREADS)


def with_options(options):
    def apply(f):
        for opt in reversed(options):
            f = opt(f)
        return f

    return apply


def parse_geometry(items: tuple[str, ...]) -> dict[str, float]:
    out: dict[str, float] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            bad(f"--geometry {item!r}: expected KEY=VALUE, e.g. pocket_roof_mm=1.5")
        try:
            number = float(value)
        except ValueError:
            bad(f"--geometry {item!r}: {value!r} is not a number")
        if not math.isfinite(number):
            bad(f"--geometry {item!r}: {value!r} is not a finite number")
        if key.strip() in out:
            bad(f"--geometry {item!r}: {key.strip()} is given twice ({out[key.strip()]:g}, then "
                f"{number:g}); allowed: each key once")
        out[key.strip()] = number
    return out


def load_materials(path: str | None) -> dict[str, dict]:
    from softhand.io import read_json

    if path is None:
        return {}
    if not str(path).strip():
        bad("--materials '': expected a JSON file path, got an empty string")
    try:
        data = read_json(path, name=f"--materials {path!r}")
    except ValueError as exc:
        bad(str(exc))
    if not isinstance(data, dict):
        bad(f"--materials {path!r}: expected an object keyed by material name (sil, pu), "
             f"got {type(data).__name__}")
    return data


def designs_of(names) -> list[str]:
    from softhand.fem.geometry import parse_design

    out = []
    for name in names:
        try:
            out.append(parse_design(name).name)
        except ValueError as exc:
            bad(str(exc))
    return out


def make_settings(designs: list[str], *, geometry, materials_path, mode="3d", **kw):
    """IndentationSettings from the FE options, every error naming its flag."""
    from dataclasses import replace

    from softhand.fem.geometry import parse_design
    from softhand.fem.indenter import parse_indenter
    from softhand.fem.solver import IndentationSettings

    indenter = kw.get("indenter", "plate")
    try:
        parse_indenter(indenter).check_mode(mode)
    except ValueError as exc:
        bad(f"--indenter {indenter!r} with --mode {mode}: {str(exc).split(': ', 1)[-1]}")
    if kw.get("engine") == "numpy" and kw.get("solver", "auto") != "auto":
        bad(f"--solver {kw['solver']} with --engine numpy: the NumPy engine solves with SuperLU, "
            "a sparse Cholesky is the compiled engine's (allowed with --engine numpy: "
            "--solver auto)")
    try:
        settings = IndentationSettings(mode=mode, **kw)
    except ValueError as exc:  # the option types already checked each number
        if str(exc).startswith("solver = "):
            bad(f"--solver {kw['solver']}: {str(exc).split(': ', 1)[-1]}")
        bad(f"--body {kw['body']}: {exc}" if str(exc).startswith("indenter = ") and
            kw.get("body", "phalanx") != "phalanx" else str(exc))
    materials = load_materials(materials_path)
    try:
        settings = replace(settings, materials=materials)
    except ValueError as exc:
        bad(f"--materials {materials_path!r}: {exc}")
    geom = parse_geometry(geometry)
    items = " ".join(geometry)
    try:
        settings = replace(settings, geometry=geom)
        for name in designs:
            parse_design(name).geometry(**geom)
    except ValueError as exc:
        bad(f"--geometry {items}: {exc}")
    return settings


def parse_sensors(items: tuple[str, ...], design: str, geometry: dict[str, float]):
    """``--sensor PLACEMENT[:WxL][@X,Z]`` items as sensor patches that fit the design's part
    (None when no item: the defaults); every error names the flag and the value."""
    from softhand.fem.geometry import parse_design
    from softhand.fem.sensors import SensorPatch

    if not items:
        return None
    patches = []
    for item in items:
        text, _, where = item.partition("@")
        placement, _, size = text.partition(":")
        kw: dict[str, float] = {}
        try:
            if size:
                w, sep, ln = size.lower().partition("x")
                if not sep:
                    raise ValueError("size")
                kw["width_mm"], kw["length_mm"] = float(w), float(ln)
            if where:
                x, sep, z = where.partition(",")
                if not sep:
                    raise ValueError("centre")
                kw["center_x_mm"], kw["center_z_mm"] = float(x), float(z)
        except ValueError:
            bad(f"--sensor {item!r}: expected PLACEMENT[:WIDTHxLENGTH][@X,Z] in mm, e.g. "
                "bone:4x4 or pocket-floor:3x3@0,1")
        name = item if (size or where) else placement
        try:
            patch = SensorPatch(placement, name=name, **kw)
            patch.check_fits(parse_design(design).geometry(**geometry))
        except ValueError as exc:
            bad(f"--sensor {item!r}: {exc}")
        patches.append(patch)
    names = [p.label for p in patches]
    if len(set(names)) != len(names):
        bad(f"--sensor: the patches {names} are not distinct")
    return tuple(patches)


def parse_skin_overrides(items: tuple[str, ...]) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        region, sep, design = item.partition("=")
        if not sep or not region.strip() or not design.strip():
            bad(f"--skin {item!r}: expected REGION=DESIGN[@REPRESENTATION] (e.g. "
                "Index2=pocket2-pu@soft-contact+relaxation)")
        if region.strip() in out:
            bad(f"--skin {item!r}: {region.strip()} is given twice ({out[region.strip()]}, then "
                f"{design.strip()}); allowed: each region once")
        out[region.strip()] = design.strip()
    return out


# --- embedded sensors (softhand handshake) --------------------------------------------------------

#: SensorSpec field -> its flag
SENSOR_FLAGS = {"noise_N": "--sensor-noise", "latency_s": "--sensor-latency",
                "period_s": "--sensor-period", "threshold_N": "--sensor-threshold",
                "full_scale_N": "--sensor-full-scale", "resolution_N": "--sensor-resolution",
                "hysteresis_pct": "--sensor-hysteresis"}

SENSOR_OPTIONS = (
    click.option("--sensor-noise", "noise_N", type=Number(0, 10, unit="N"), default=None,
                 help="RMS noise of each sample, 0-10 N [default: 0.022, half a 10-bit quantum "
                      "of 44.5 N]."),
    click.option("--sensor-latency", "latency_s", type=Number(0, 1, unit="s"), default=None,
                 help="From a sample to its reading, 0 or at least one env step (0.01 s), up to "
                      "1 s [default: 0.01]."),
    click.option("--sensor-period", "period_s", type=Number(0, 1, lo_open=True, unit="s"),
                 default=None, help="Sampling period, at least one env step (0.01 s), up to 1 s "
                                    "[default: 0.01]."),
    click.option("--sensor-threshold", "threshold_N", type=Number(0, 44.5, hi_open=True, unit="N"),
                 default=None, help="Readings below it are 0 [default: 0.1 N]."),
    click.option("--sensor-full-scale", "full_scale_N", type=Number(0, 1000, lo_open=True,
                                                                    unit="N"),
                 default=None, help="Saturation of the reading [default: 44.5 N, FlexiForce "
                                    "A101]."),
    click.option("--sensor-resolution", "resolution_N", type=Number(0, 100, unit="N"),
                 default=None, help="Quantum of the reading, 0 for none [default: 44.5/1024 N]."),
    click.option("--sensor-hysteresis", "hysteresis_pct", type=Number(0, 50, unit="%"),
                 default=None, help="Hysteresis band in % of full scale, 0-50 [default: 0; the "
                                    "A101's datasheet bound is 4.5]."),
)


def sensor_spec_of(**given):
    """The SensorSpec of the handshake's ``--sensor-*`` flags (unset: the defaults)."""
    from dataclasses import replace

    from softhand.sensors.device import FLEXIFORCE_A101

    values = {k: v for k, v in given.items() if v is not None}
    try:
        return replace(FLEXIFORCE_A101, **values)
    except ValueError as exc:
        bad(sensor_flag_message(str(exc)))


def sensor_flag_message(msg: str) -> str:
    """A SensorSpec message with its field named by the flag that sets it."""
    for key, flag in SENSOR_FLAGS.items():
        msg = msg.replace(f"sensor {key}", flag)
    return msg


def parse_placement_items(items: tuple[str, ...]):
    """``--sensor-placement [REGION=]PLACEMENT`` items: one placement, or region overrides."""
    if not items:
        return None
    out: dict[str, str] = {}
    every = None
    for item in items:
        region, sep, placement = item.rpartition("=")
        if sep and (not region.strip() or not placement.strip()):
            bad(f"--sensor-placement {item!r}: expected [REGION=]PLACEMENT (e.g. Palm1=bone)")
        if sep:
            out[region.strip()] = placement.strip()
        else:
            every = placement.strip()
    if every is None:
        return out
    from softhand.hands.prosthetic import paper_regions

    return {r: out.get(r, every) for r in paper_regions()}
