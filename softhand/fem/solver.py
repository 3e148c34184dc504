"""Displacement-driven indentation: ramp at constant speed, then hold.

The indenter (the paper's plate by default; a cylinder or a sphere, `softhand.fem.indenter`,
with the gap of `softhand.fem.contact.RoundGaps`) is called the plate below. The plate
moves down at ``speed_mm_s`` until the reaction reaches ``max_force_N`` (or the plate
reaches ``max_depth_mm``), then stays put for ``hold_s`` while the skin relaxes. Each step solves
the nonlinear equilibrium with Newton's method on the free DOFs (base fixed, symmetry planes),
with penalty contact. Steps adapt: they grow after easy steps, are capped so that the force rises
by at most ``force_step_N`` per step, land on the target force, and are cut back and retried when
Newton fails. When the step falls below ``min_step_mm`` the run stops with a
`ConvergenceError` that carries the step log.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from enum import Enum
from typing import Any

import numpy as np
import scipy.sparse.linalg as spla

from softhand.fem.assembly import ENGINES, Assembler, ElementError, ElementState
from softhand.fem.body import body_mesh, check_body
from softhand.fem.contact import (
    POCKET_CONTACTS,
    GapSet,
    PairedPocket,
    PocketContact,
    RoundGaps,
    plate_gaps,
    pocket_contact,
)
from softhand.fem.geometry import Design, PhalanxGeometry, check_section_length, parse_design
from softhand.fem.indenter import parse_indenter
from softhand.fem.linear import TangentSystem, resolve_solver
from softhand.fem.materials import Material, Moduli, material
from softhand.fem.mesh import MESH_LEVELS, Mesh, MeshSpec, build_mesh, full_model
from softhand.fem.sensors import SensorPatch, SensorReader, default_patches
from softhand.parallel import check_threads, single_threaded_blas

__all__ = [
    "ConvergenceError",
    "IndentationResult",
    "IndentationSettings",
    "Status",
    "indent",
    "interpolate_crossing",
]

SOLVER_VERSION = "3"  # 3: default mesh with two elements through the roof (0.2)
_DEPTH_MARKS_MM = (1.0, 2.0)


#: A pass of `_Model.newton` ends where the pocket's held gaps are within this of the gaps
#: projected afresh at its solution, at every closed point (mm). The penalty's own overlap is
#: about 4e-4 mm at 2 N (pocket2-sil).
POCKET_GAP_TOL_MM = 2e-5
#: A line search (`IndentationSettings.line_searches`) scales only an update after which the
#: residual's largest entry is this many times larger. On the soft designs' buckling roofs the
#: whole update of a nearly singular tangent reached 1e4 to 1e32 times the residual; where a
#: contact point opens or closes, full updates grew it up to 40-fold and still converged
#: quadratically, which a search there slowed (3D checks of pocket2-sil and the design search's
#: trials 245 and 262: 3-4 more iterations).
LINE_SEARCH_GROWTH = 100.0
#: Most passes of the pocket's linearisation in one Newton solve.
POCKET_PASSES = 4
#: A ramp that accepts more than CRAWL_STEPS steps in a row under CRAWL_STEP_MM (mm) stalls at a
#: limit point and stops with a ConvergenceError that says so (the smallest step the paired
#: contact's 2D runs of pocket2-sil, pocket2-pu and solid-sil to 20 N accept: 2.5e-3 mm).
CRAWL_STEP_MM = 1e-4
CRAWL_STEPS = 40


class ConvergenceError(RuntimeError):
    """Newton did not converge even at the smallest allowed step.

    Attributes:
        log: the step records up to the failure (list of dicts).
        diagnostics: the failing step's state (time, plate displacement, residual history).
    """

    def __init__(self, message: str, *, log: list[dict], diagnostics: dict) -> None:
        super().__init__(message)
        self.log = log
        self.diagnostics = diagnostics


class Status(str, Enum):
    REACHED_FORCE = "reached_force"
    REACHED_DEPTH = "reached_depth"


@dataclass(frozen=True)
class IndentationSettings:
    """Everything that defines one indentation run besides the design.

    Attributes:
        mode: ``"3d"`` (quarter model) or ``"2d"`` (plane-strain cross-section, times length).
        mesh: ``"coarse"``, ``"default"``, ``"fine"`` or a `MeshSpec`.
        speed_mm_s: plate speed during the ramp (paper: 0.5), > 0.
        max_force_N: reaction at which the ramp stops (paper: 2 N), > 0.
        max_depth_mm: plate travel at which the ramp stops regardless of force, > 0.
        hold_s: hold after the ramp, >= 0 (0: no hold).
        moduli: Table 3 moduli read as ``"long-term"`` or ``"instantaneous"``.
        elastic_only: drop the Prony series (Table 3 moduli as written, no hold).
        penalty_N_mm3: contact penalty per unit area and penetration, > 0. The default (200,
            about 600x the skins' E / element size) keeps penetration below 1e-3 mm at 2 N;
            2000 changes d(2 N) of pocket2-sil by 0.05 % and costs 2.4x the time.
        force_step_N: largest force increase per step (default max_force_N / 12).
        min_step_mm: smallest plate increment before giving up, > 0.
        max_step_mm: largest plate increment, > 0.
        max_newton: most Newton iterations of one step before it is cut back, >= 1.
        max_indefinite: most tangents in a row that are not positive definite in one step's
            Newton solve before the step is cut back (the compiled engine's sparse Cholesky
            detects them, `softhand.fem.linear`; the NumPy engine's SuperLU does not, and
            ignores this), >= 1; None: no limit (the FE's default). Applies to a step's first
            try only: its retry, a quarter as long, runs up to ``max_newton`` iterations (near
            a limit point even tiny steps meet such tangents and converge). In the soft design
            winners' 3D runs, where a pocket roof buckles, 7 of the 8 steps with two in a row
            failed only after 6-20 iterations.
        indefinite_shift: a tangent that is not positive definite is solved by the Cholesky of
            the tangent with this multiple of its mean absolute diagonal added to its diagonal
            (10x more, up to `softhand.fem.linear.SHIFT_TRIES` tries, then the indefinite
            factorization: `TangentSystem.factorize`), a Levenberg-Marquardt step, > 0; None:
            the indefinite factorization (PARDISO's or SuperLU's, the FE's default). The
            compiled engine only; still counted by ``max_indefinite``. It changes the path of
            Newton's iterations, not the equilibrium they converge to (within ``tol_N``): a
            shifted Cholesky costs about a third of SuperLU's LU, and its step goes downhill
            in the step's energy where the LU's full step on a buckling pocket roof often
            diverged.
        line_searches: most line searches in one Newton solve, >= 0 (0: every update taken
            whole, the FE's default). An update ``du`` from ``u`` overshoots where the
            residual's component along it, ``s(a) = du . r(u + a du)``, changes sign over the
            whole update and grows to more than half its size at the start: ``s(0) < 0 <
            -s(0) / 2 < s(1)``, and the residual's largest entry grows `LINE_SEARCH_GROWTH`
            times; it is then scaled by the secant root ``a = s(0) / (s(0) - s(1))``, at least
            0.1 (one more residual evaluation). On the soft designs' buckling roofs, the whole
            update of a nearly singular tangent reached residuals of 1e4 to 1e32 N; there the
            root is far below 0.1, so such an update is cut to a tenth of itself. The cap
            stops searches that cycle with a contact point opening and closing (without the
            growth condition and unlimited, a 3D step of the design search's trial 262 took 21
            iterations instead of 5). Like ``indefinite_shift``, it changes the path, not the
            equilibrium.
        contact_points: Gauss points per face direction for contact (more: smoother contact).
        tol_N: Newton tolerance on the largest nodal residual, whole-phalanx newtons, plus
            ``tol_rel`` times the plate force, > 0. The default (1e-4 N + 1e-4 F) moves
            pocket2-sil's d(2 N) by 1e-5 relative and F(2 mm) by 3e-4 against 4e-7 N + 1e-6 F,
            and saves a quarter of the Newton iterations.
        tol_rel: relative part of the Newton tolerance, >= 0.
        threads: threads for element evaluation (None: `softhand.parallel.default_threads`,
            the CPUs this process may use, at most 4); BLAS stays single-threaded during the run,
            so these threads are the run's only parallelism. Does not change the result.
        engine: ``"compiled"`` (numba element kernels, `softhand.fem.kernels`, and the
            tangent's fill-reducing ordering computed once per run) or ``"numpy"`` (the
            batched NumPy reference and an ordering per factorization). The same arithmetic:
            curves agree within the Newton tolerance (``softhand bench fe`` runs both).
        solver: the compiled engine's sparse Cholesky (`softhand.fem.linear.SOLVERS`):
            ``"auto"`` (MKL PARDISO where the ``softhand[mkl]`` extra is installed, else
            CHOLMOD), ``"cholmod"`` or ``"pardiso"``. Like ``engine``, not a curve setting: the
            same arithmetic to rounding; the result records the one used.
        geometry: overrides of `PhalanxGeometry` fields.
        sensors: embedded sensor patches (`softhand.fem.sensors.SensorPatch`) read at
            every output time; None: a 4 x 4 mm patch under the indenter at each placement the
            design has (`softhand.fem.sensors.default_patches`); () for none.
        materials: per material name (``sil``, ``pu``), constants replacing Table 3 (keys
            ``nu``, ``mu_MPa``, ``alpha``, ``g``, ``tau_s``).
        indenter: ``"plate"`` (the paper's), ``"cylinder:R_MM[@ANGLE_DEG]"`` or
            ``"sphere:R_MM"`` (`softhand.fem.indenter`; stored in its canonical form, e.g.
            ``"cylinder:7.4@90"``). Each moves as the plate does; the force is the reaction
            along its travel. A cylinder at an angle other than 0 or 90 deg runs on the full
            model (`softhand.fem.mesh.full_model`), which reads no sensor patches.
        body: ``"phalanx"`` (the paper's) or ``"palm"``: the slab of the design's layers over a
            metacarpal (`softhand.fem.palm`, its default geometry and its own mesh levels of
            the same names; no embedded sensor patches).
        pocket_contact: ``"paired"`` (the shipped curves': roof and floor paired at the same
            place on their faces, `softhand.fem.contact.PairedPocket`) or ``"sliding"`` (the
            floor and the pocket's side wall projected on the deformed roof,
            `softhand.fem.contact.PocketContact`; the phalanx's mesh records its side wall,
            the palm's does not). The paired contact lets the floor pass through the roof
            once the roof slides (pocket2-sil, 2D: 0.12 mm at 2 N and 0.67 mm at 20 N, d(2 N)
            2.8 % deeper than sliding); the sliding contact keeps it out (within 0.005 mm to
            20 N in 2D; in 3D pocket2-sil stops at 11 N). reports/pocket-contact.md
            (``python tools/pocket_contact.py``).
    """

    mode: str = "3d"
    mesh: str | MeshSpec = "default"
    speed_mm_s: float = 0.5
    max_force_N: float = 2.0
    max_depth_mm: float = 6.0
    hold_s: float = 10.0
    moduli: Moduli = "long-term"
    elastic_only: bool = False
    penalty_N_mm3: float = 200.0
    force_step_N: float | None = None
    min_step_mm: float = 1e-6
    max_step_mm: float = 0.2
    max_newton: int = 25
    max_indefinite: int | None = None
    indefinite_shift: float | None = None
    line_searches: int = 0
    contact_points: int = 4
    tol_N: float = 1e-4
    tol_rel: float = 1e-4
    threads: int | None = None
    engine: str = "compiled"
    solver: str = "auto"
    geometry: dict[str, float] = field(default_factory=dict)
    materials: dict[str, dict] = field(default_factory=dict)
    sensors: tuple[SensorPatch, ...] | None = None
    indenter: str = "plate"
    body: str = "phalanx"
    pocket_contact: str = "paired"

    def __post_init__(self) -> None:
        if self.mode not in ("3d", "2d"):
            raise ValueError(f"mode = {self.mode!r}: allowed '3d' or '2d'")
        if self.pocket_contact not in POCKET_CONTACTS:
            raise ValueError(f"pocket_contact = {self.pocket_contact!r}: allowed "
                             f"{', '.join(POCKET_CONTACTS)}")
        ind = parse_indenter(self.indenter)
        ind.check_mode(self.mode)
        object.__setattr__(self, "indenter", ind.text)
        check_body(self.body, ind.text)
        if self.body != "phalanx" and self.sensors:
            raise ValueError(f"sensors = {self.sensors!r}: embedded sensors are read on the "
                             f"phalanx only; body = {self.body!r} (allowed: None or () there)")
        if ind.full_model and self.sensors:
            raise ValueError(f"sensors = {self.sensors!r}: embedded sensors are read on the "
                             f"quarter model only; indenter = {ind.text!r} runs the full model "
                             "(allowed: None or () there)")
        if isinstance(self.mesh, str) and self.mesh not in MESH_LEVELS:
            raise ValueError(f"mesh = {self.mesh!r}: allowed {', '.join(MESH_LEVELS)}")
        for name in ("speed_mm_s", "max_force_N", "max_depth_mm", "penalty_N_mm3",
                     "min_step_mm", "max_step_mm", "tol_N"):
            v = getattr(self, name)
            if not np.isfinite(v) or v <= 0:
                raise ValueError(f"{name} = {v!r} must be finite and > 0")
        if not np.isfinite(self.hold_s) or self.hold_s < 0:
            raise ValueError(f"hold_s = {self.hold_s!r} must be finite and >= 0")
        if self.threads is not None:
            check_threads(self.threads)
        if self.engine not in ENGINES:
            raise ValueError(f"engine = {self.engine!r}: allowed {', '.join(ENGINES)}")
        if self.solver != "auto":  # auto is resolved when a run needs it (it loads MKL)
            resolve_solver(self.solver)
        if not np.isfinite(self.tol_rel) or self.tol_rel < 0:
            raise ValueError(f"tol_rel = {self.tol_rel!r} must be finite and >= 0")
        if not isinstance(self.max_newton, int | np.integer) or self.max_newton < 1:
            raise ValueError(f"max_newton = {self.max_newton!r} must be an integer >= 1")
        if self.max_indefinite is not None and (
                not isinstance(self.max_indefinite, int | np.integer) or self.max_indefinite < 1):
            raise ValueError(f"max_indefinite = {self.max_indefinite!r} must be None or an "
                             "integer >= 1")
        if self.indefinite_shift is not None and not (
                np.isfinite(self.indefinite_shift) and self.indefinite_shift > 0):
            raise ValueError(f"indefinite_shift = {self.indefinite_shift!r} must be None or "
                             "finite and > 0")
        if not isinstance(self.line_searches, int | np.integer) or self.line_searches < 0:
            raise ValueError(f"line_searches = {self.line_searches!r} must be an integer >= 0")
        if self.force_step_N is not None and not self.force_step_N > 0:
            raise ValueError(f"force_step_N = {self.force_step_N!r} must be > 0")
        for name in self.materials:  # every constant, Prony terms too, even if elastic_only
            material(name, moduli=self.moduli, elastic_only=False,
                     constants=self.materials.get(name))
        if self.sensors is not None and not all(isinstance(p, SensorPatch)
                                                for p in self.sensors):
            raise ValueError(f"sensors = {self.sensors!r}: expected a tuple of SensorPatch")
        unknown = set(self.geometry) - set(PhalanxGeometry.__dataclass_fields__)
        if unknown:
            raise ValueError(f"geometry fields {sorted(unknown)} are unknown; allowed: "
                             f"{', '.join(PhalanxGeometry.__dataclass_fields__)}")
        length = self.geometry.get("length_mm")  # a number: its range is checked with the design
        if isinstance(length, int | float | np.number) and not isinstance(length, bool):
            check_section_length(float(length), self.mode)

    @property
    def mesh_spec(self) -> MeshSpec:
        return MESH_LEVELS[self.mesh] if isinstance(self.mesh, str) else self.mesh


@dataclass(frozen=True)
class IndentationResult:
    """One indentation curve and how it was obtained.

    Attributes:
        design: design name.
        settings: the settings used.
        time_s, displacement_mm, force_N: the curve (plate displacement, whole-phalanx force).
        hold: True for points of the hold phase.
        status: why the ramp ended.
        log: one record per accepted step (Newton iterations, residual, contact points).
        wall_s: wall-clock time of the run.
        n_dofs, n_elements: model size.
        embedded_sensors: per sensor patch name: ``placement``, ``area_mm2`` and ``force_N``
            (aligned with ``time_s``; `softhand.fem.sensors`).
        contact_area_mm2: the plate's contact area on the whole phalanx (undeformed surface,
            mm^2), aligned with ``time_s``; the contact Gauss points whose gap is closed, so its
            resolution is one point's share of a face (`GapSet.contact_area`).
        plate_pressure: the plate's contact pressure at the end of the ramp (the peak force):
            ``points_mm`` (undeformed positions of the modelled part's plate-face Gauss points,
            x across the width, y up, z along the length in 3D), ``weight_mm2`` (each point's
            undeformed area; mm in 2D), ``pressure_MPa`` at each,
            ``force_N`` and ``displacement_mm`` of that state. Empty if the ramp took no step.
        linear_solver: the sparse solver of the Newton steps (``"pardiso"``, ``"cholmod"``, or
            ``"superlu"`` on the NumPy engine).
        ramp_end_u: the nodal displacements (mm, the modelled part's DOFs in the mesh's order)
            at the end of the ramp, the largest force reached: what strains at the peak are read
            from (`softhand.fem.strain`). None if the ramp took no step.
    """

    design: str
    settings: IndentationSettings
    time_s: np.ndarray
    displacement_mm: np.ndarray
    force_N: np.ndarray
    hold: np.ndarray
    status: Status
    log: list[dict]
    wall_s: float
    n_dofs: int
    n_elements: int
    embedded_sensors: dict[str, dict[str, Any]] = field(default_factory=dict)
    contact_area_mm2: np.ndarray | None = None
    plate_pressure: dict[str, Any] = field(default_factory=dict)
    linear_solver: str = ""
    ramp_end_u: np.ndarray | None = None

    def displacement_at(self, force_N: float) -> float | None:
        """Plate displacement (mm) where the ramp first reaches ``force_N``, or None."""
        ramp = ~self.hold
        return interpolate_crossing(self.force_N[ramp], self.displacement_mm[ramp], force_N)

    def force_at(self, displacement_mm: float) -> float | None:
        """Force (N) on the ramp at plate displacement ``displacement_mm``, or None."""
        ramp = ~self.hold
        d, f = self.displacement_mm[ramp], self.force_N[ramp]
        if displacement_mm > d[-1] + 1e-12:
            return None
        return float(np.interp(displacement_mm, d, f))

    def rising_slope(self) -> float | None:
        """Compliance (mm/N) of the rising part before a pocket closes, or None without pocket.

        Least-squares slope of displacement against force over the ramp points below 90 % of
        the pocket height (the paper's "rising slope", Effect of varying the layers).
        """
        h = parse_design(self.design).geometry(**self.settings.geometry).pocket_height_mm
        ramp = ~self.hold
        d, f = self.displacement_mm[ramp], self.force_N[ramp]
        sel = d <= 0.9 * h
        if h <= 0 or sel.sum() < 3:
            return None
        return float(np.polyfit(f[sel], d[sel], 1)[0])

    def summary(self) -> dict[str, Any]:
        """The machine-readable result (the CLI's ``--json``)."""
        s = self.settings
        return {
            "design": self.design,
            "mode": s.mode,
            "mesh": s.mesh if isinstance(s.mesh, str) else asdict(s.mesh),
            "moduli": s.moduli,
            "elastic_only": s.elastic_only,
            "indenter": s.indenter,
            "body": s.body,
            "status": self.status.value,
            "displacement_at_2N_mm": self.displacement_at(2.0),
            "displacement_at_1N_mm": self.displacement_at(1.0),
            "force_at_2mm_N": self.force_at(2.0),
            "rising_slope_mm_per_N": self.rising_slope(),
            "peak_force_N": float(self.force_N.max()),
            "relaxed_force_N": float(self.force_N[-1]),
            "wall_s": self.wall_s,
            "n_dofs": self.n_dofs,
            "n_elements": self.n_elements,
            "n_steps": len(self.log),
            "newton_iterations": int(sum(r["iterations"] for r in self.log)),
            "solver_version": SOLVER_VERSION,
            "engine": s.engine,
            "linear_solver": self.linear_solver,
            "time_s": self.time_s.tolist(),
            "displacement_mm": self.displacement_mm.tolist(),
            "force_N": self.force_N.tolist(),
            "contact_area_mm2": (None if self.contact_area_mm2 is None
                                 else self.contact_area_mm2.tolist()),
            "embedded_sensors": {name: {"placement": v["placement"], "area_mm2": v["area_mm2"],
                                        "force_N": np.asarray(v["force_N"]).tolist()}
                                 for name, v in self.embedded_sensors.items()},
        }


def interpolate_crossing(x: np.ndarray, y: np.ndarray, level: float) -> float | None:
    """y where x first rises through ``level`` (linear interpolation), or None if it never does."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    above = np.flatnonzero(x >= level)
    if above.size == 0:
        return None
    k = int(above[0])
    if k == 0:
        return float(y[0])
    t = (level - x[k - 1]) / (x[k] - x[k - 1])
    return float(y[k - 1] + t * (y[k] - y[k - 1]))


class _Model:
    """Mesh, assembler and contact sets of one run, with a Newton solver for one step."""

    def __init__(self, design: Design, geom: PhalanxGeometry, settings: IndentationSettings,
                 mesh: Mesh | None = None):
        self.settings = settings
        mats = [_material(design.inner, settings), _material(design.outer, settings)]
        ind = parse_indenter(settings.indenter)
        whole = mesh is None and ind.full_model
        if mesh is None and settings.body != "phalanx":
            mesh = body_mesh(settings.body, design, settings.mesh,
                             dim=3 if settings.mode == "3d" else 2, indenter=settings.indenter)
        if mesh is None:
            self.mesh: Mesh = build_mesh(geom, settings.mesh_spec,
                                         dim=3 if settings.mode == "3d" else 2)
            top = geom.height_mm
            if whole:
                self.mesh = full_model(self.mesh)
        else:
            self.mesh, top = mesh, float(mesh.X[:, 1].max())
        self.asm = Assembler(self.mesh, mats, threads=settings.threads, engine=settings.engine)
        n_gauss = settings.contact_points
        self.plate: GapSet | None = None
        self.round: RoundGaps | None = None
        if ind.kind == "plate":
            self.plate = plate_gaps(self.mesh, top, n_gauss)
        else:
            self.round = RoundGaps(self.mesh, top, ind.radius_mm, ind.axis, n_gauss)
        self.pocket: PairedPocket | PocketContact | None = pocket_contact(
            self.mesh, n_gauss, settings.pocket_contact)
        free = np.ones(self.mesh.n_dofs, dtype=bool)
        free[self.mesh.fixed] = False
        self.free = np.flatnonzero(free)
        self.scale = self.mesh.symmetry_factor * self.mesh.length_mm
        self.penalty = settings.penalty_N_mm3
        patches = default_patches(geom) if settings.sensors is None else settings.sensors
        if mesh is not None or whole:
            patches = ()  # sensor patches are placed on the phalanx's quarter mesh only
        self.sensors = SensorReader(self.mesh, geom, patches, n_gauss, self.penalty)
        self._system: TangentSystem | None = None  # the compiled engine's, on first use
        self._pocket_G = None  # the pocket's gap matrix as last linearised


    def read_sensors(self, u: np.ndarray) -> dict[str, float]:
        """Each sensor patch's force at the state of the last converged Newton step."""
        outer = self.asm.force_of(self.sensors.outer_elements())
        internal = self.asm.force_of(np.arange(self.mesh.n_elements))
        gaps = self.pocket.floor_gaps(u) if self.pocket is not None else None
        return self.sensors.read(outer, internal, gaps)

    def contact(self, u: np.ndarray, d: float) -> tuple[GapSet, float]:
        """The indenter's gap set at state u (linearised there for a round indenter), and the
        shift that places it at travel d."""
        if self.plate is not None:
            return self.plate, -d
        return self.round.linearised(u, d), 0.0

    def plate_force(self, u: np.ndarray, d: float) -> float:
        if self.plate is not None:
            return self.plate.force(u, self.penalty, -d) * self.scale
        return self.round.force(u, d, self.penalty) * self.scale

    def plate_area(self, u: np.ndarray, d: float) -> float:
        """Contact area on the whole phalanx, mm^2 (2D: the contact width times the length)."""
        gaps, shift = self.contact(u, d)
        return gaps.contact_area(u, shift) * self.scale

    def plate_pressure(self, u: np.ndarray, d: float, F: float) -> dict[str, Any]:
        gaps, shift = self.contact(u, d)
        return {"points_mm": gaps.points.copy(), "weight_mm2": gaps.weight.copy(),
                "pressure_MPa": gaps.pressure(u, self.penalty, shift),
                "force_N": F, "displacement_mm": d}

    def residual(self, u: np.ndarray, state: ElementState, dt: float, d: float,
                 pocket: GapSet | None = None):
        """The free residual at u (elements and contact), its largest entry, the elements'
        tangent function and new history, the contact sets' stiffness data and closed counts.
        ``pocket``: the pocket's gaps as linearised for this pass (`newton`).

        Raises:
            ElementError: an element is inverted at u.
        """
        f, tangent_of, new_state = self.asm.evaluate(u, state, dt)
        gaps, shift = self.contact(u, d)
        rp, kw_p, n_plate = gaps.penalty_forces(u, self.penalty, shift)
        f += rp
        n_pocket, kw_c = 0, None
        if pocket is not None:
            rc, kw_c, n_pocket = pocket.penalty_forces(u, self.penalty)
            f += rc
        r = f[self.free]
        return r, float(np.abs(r).max()), tangent_of, new_state, (gaps, kw_p, kw_c, pocket), \
            (n_plate, n_pocket)

    def newton(self, u0: np.ndarray, state: ElementState, dt: float, d: float, tol_N: float,
               first_try: bool = False):
        """Solve one step; return (u, new_state, iterations, residual history, contact counts).
        ``first_try``: the step's first try, which ``settings.max_indefinite`` may cut short.

        An update that inverts an element is halved, up to 5 times; the evaluation that finds
        a trial state admissible is that of the next iteration (no separate inversion check).

        The pocket's contact (`PocketContact`) is linearised at the start of a pass and held
        through its iterations, so that the iterations see a smooth problem (projected afresh
        at every iterate, a floor point under a kink of the roof jumps between its faces and
        Newton cycles). At convergence the gaps are projected again; where a closed point's
        gap differs from the held one by more than `POCKET_GAP_TOL_MM`, a new pass starts from
        there (at most `POCKET_PASSES` passes, within ``max_newton`` iterations), unless the
        points project as they did in an earlier pass (a cycle: the solution stands).
        """
        u = u0.copy()
        history: list[float] = []
        pocket = self._linearise_pocket(u)
        passes, seen = 1, set()  # the roof faces the passes' points projected on
        current = self.residual(u, state, dt, d, pocket)
        s = self.settings
        indefinite = 0  # tangents in a row that were not positive definite (max_indefinite)
        searches = 0  # line searches so far (line_searches)
        for it in range(1, s.max_newton + 1):
            r, res, tangent_of, new_state, (gaps, kw_p, kw_c, _), closed = current
            history.append(res)
            if not np.isfinite(res):
                raise ElementError("residual is not finite")
            # the residual includes the contact forces at u itself, so a small residual is an
            # equilibrium of the penalty problem whatever the closed set did on the way here
            if res <= tol_N:
                if pocket is not None and passes < POCKET_PASSES:
                    exact, held = self.pocket.gaps(u), pocket.gaps(u)
                    off = np.abs(exact - held)[np.minimum(exact, held) < 0.0]
                    if off.size and off.max() > POCKET_GAP_TOL_MM:
                        seen.add(self.pocket.assigned.tobytes())
                        again = self._linearise_pocket(u)
                        if self.pocket.assigned.tobytes() in seen:
                            # the projections cycle (a point on the edge between two roof
                            # faces, taken by each in turn): this pass's solution stands
                            return u, new_state, it, history, closed
                        pocket = again
                        passes += 1
                        current = self.residual(u, state, dt, d, pocket)
                        continue
                return u, new_state, it, history, closed
            if it == self.settings.max_newton:
                break
            if self.settings.engine == "compiled":
                contacts = [(kw_p, gaps.G.data)]
                if kw_c is not None:
                    contacts.append((kw_c, pocket.G.data))
                system = self.tangent_system()
                before = system.stats["cholesky"]
                du = system.factorize(system.values(tangent_of(raw=True), contacts),
                                      shift=s.indefinite_shift)(-r)
                indefinite = 0 if system.stats["cholesky"] > before else indefinite + 1
                if (first_try and s.max_indefinite is not None
                        and indefinite >= s.max_indefinite):
                    raise _StepCutError(f"{indefinite} tangents in a row not positive "
                                        "definite")
            else:
                Kff = tangent_of(self.free) + _block(gaps.stiffness(kw_p), self.free)
                if kw_c is not None:
                    Kff = Kff + _block(pocket.stiffness(kw_c), self.free)
                du = _factor(Kff).solve(-r)
            if not np.all(np.isfinite(du)):
                raise ElementError("linear solve returned non-finite values")
            step = 1.0
            for halvings in range(6):  # backtrack only if the update inverts an element
                trial = u.copy()
                trial[self.free] += step * du
                try:
                    current = self.residual(trial, state, dt, d, pocket)
                    break
                except ElementError:
                    if halvings == 5:
                        raise
                    step *= 0.5
            if searches < s.line_searches:
                searched = self._line_search(u, du * step, r, current[0], state, dt, d, pocket)
                if searched is not None:
                    searches += 1
                    trial, current = searched
            u = trial
        raise ElementError(f"no convergence in {self.settings.max_newton} iterations "
                           f"(residual {history[-1]:.3g} N > {tol_N:.3g} N)")

    def _line_search(self, u: np.ndarray, du: np.ndarray, r0: np.ndarray, r1: np.ndarray,
                     state: ElementState, dt: float, d: float, pocket: GapSet | None):
        """The state at the secant root of ``s(a) = du . r(u + a du)`` and its residual
        (`residual`'s tuple) where the update ``du`` (free dofs) overshoots, with ``r0``, ``r1``
        the free residuals at ``a = 0`` and 1 (`IndentationSettings.line_searches`); None
        where it does not, where the residual's largest entry grew less than
        `LINE_SEARCH_GROWTH` times, or where the root's state is inadmissible."""
        s0, s1 = float(du @ r0), float(du @ r1)
        if not (s0 < 0.0 < -0.5 * s0 < s1):
            return None
        if np.abs(r1).max() < LINE_SEARCH_GROWTH * np.abs(r0).max():
            return None
        trial = u.copy()
        trial[self.free] += max(0.1, s0 / (s0 - s1)) * du
        try:
            return trial, self.residual(trial, state, dt, d, pocket)
        except ElementError:
            return None

    def _linearise_pocket(self, u: np.ndarray) -> GapSet | None:
        """The pocket's contact linearised at ``u`` for a Newton pass; the compiled tangent's
        pattern follows the roof faces its points now project on."""
        if self.pocket is None:
            return None
        before = self.pocket.assigned
        pocket = self.pocket.linearised(u)
        self._pocket_G = pocket.G
        if (self.settings.engine == "compiled" and self._system is not None
                and not np.array_equal(before, self.pocket.assigned)):
            self._system.set_contact(1, pocket.G)
        return pocket

    def linear_solver(self) -> str:
        """The sparse solver this run's tangents go to (SuperLU on the NumPy engine)."""
        if self.settings.engine != "compiled":
            return "superlu"
        return resolve_solver(self.settings.solver)

    def close(self) -> None:
        """Stop the element threads and free the factorization."""
        self.asm.close()
        if self._system is not None:
            self._system.close()

    def tangent_system(self) -> TangentSystem:
        """The compiled engine's fixed-pattern tangent (`softhand.fem.linear`), built on
        first use: the elements' pattern and every contact set's couplings."""
        if self._system is None:
            template = (self.plate.G if self.plate is not None
                        else self.round.linearised(np.zeros(self.mesh.n_dofs), 0.0).G)
            if self.pocket is not None and self._pocket_G is None:
                self._linearise_pocket(np.zeros(self.mesh.n_dofs))
            contacts = [template] + ([self._pocket_G] if self.pocket is not None else [])
            rows, cols, entries = self.asm.pattern()
            self._system = TangentSystem(rows, cols, self.free, self.mesh.n_dofs, contacts,
                                         entries, solver=self.settings.solver,
                                         threads=self.asm.threads)
        return self._system


class _StepCutError(RuntimeError):
    """A Newton solve given up early (`IndentationSettings.max_indefinite`): the step is cut
    back like one that did not converge."""


def _block(K, free: np.ndarray):
    """The free-free block of a sparse contact tangent, in CSC."""
    return K.tocsr()[free][:, free].tocsc()


def _factor(K):
    """SuperLU factors of the symmetric tangent (symmetric mode, no pivoting)."""
    return spla.splu(K, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                     options={"SymmetricMode": True})


def _material(name: str, s: IndentationSettings) -> Material:
    return material(name, moduli=s.moduli, elastic_only=s.elastic_only,
                    constants=s.materials.get(name))


def indent(
    design: str | Design,
    settings: IndentationSettings | None = None,
    *,
    progress: Callable[[float], None] | None = None,
    mesh: Mesh | None = None,
) -> IndentationResult:
    """Indent one design with a rigid indenter and return its force-displacement-time curve.

    Args:
        design: a design name such as ``"pocket2-sil"`` or a `Design`.
        settings: run settings (defaults: 3D, default plate, mesh, 0.5 mm/s to 2 N, 10 s hold).
        progress: called with the fraction done (0..1) after each accepted step.
        mesh: a prebuilt mesh instead of the design's phalanx (e.g. the test block of
            `softhand.fem.block.block_mesh`): the design then only names the materials
            (layer 0 inner, 1 outer), the indenter starts at the mesh's highest node, and no
            sensor patches are read. Its dimension must match ``settings.mode``.

    Raises:
        ValueError: unknown design or invalid settings/geometry (before any work is done).
        ConvergenceError: equilibrium could not be found even at the smallest step.
    """
    t_start = time.perf_counter()
    design = parse_design(design) if isinstance(design, str) else design
    s = settings or IndentationSettings()
    geom = design.geometry(**s.geometry)
    if mesh is not None and mesh.dim != (3 if s.mode == "3d" else 2):
        raise ValueError(f"mesh of dimension {mesh.dim} does not match mode = {s.mode!r}")
    with single_threaded_blas():  # the element threads own the cores (softhand.parallel)
        model = _Model(design, geom, s, mesh)
        try:
            return _run(design, s, model, t_start, progress)
        finally:
            model.close()


def _run(design: Design, s: IndentationSettings, model: _Model, t_start: float,
         progress: Callable[[float], None] | None) -> IndentationResult:
    """The ramp and the hold of `indent` on a built model."""
    do_hold = s.hold_s > 0 and not s.elastic_only
    f_step = s.force_step_N or s.max_force_N / 12.0
    tol = lambda F: (s.tol_N + s.tol_rel * abs(F)) / model.scale  # noqa: E731  (modelled part)

    u = np.zeros(model.mesh.n_dofs)
    u_old = u.copy()
    state = model.asm.initial_state()
    t, d, F = 0.0, 0.0, 0.0
    times, disps, forces, holds, areas = [0.0], [0.0], [0.0], [False], [0.0]
    pressure: dict[str, Any] = {}
    readings = {p.label: [0.0] for p in model.sensors.patches}
    log: list[dict] = []
    dd, dd_prev, k_est = 0.02, None, None
    status = Status.REACHED_DEPTH

    retries = 0
    crawl = 0  # accepted ramp steps in a row under CRAWL_STEP_MM

    def record(phase: str, it: int, hist: list[float], closed: tuple[int, int], inc: float):
        """Log the accepted step and append its point to the curve."""
        nonlocal retries
        log.append({"step": len(log) + 1, "phase": phase, "time_s": t, "displacement_mm": d,
                    "force_N": F, "iterations": it, "residual_N": hist[-1] * model.scale,
                    "plate_points": closed[0], "pocket_points": closed[1], "increment": inc,
                    "retries": retries})
        retries = 0
        times.append(t)
        disps.append(d)
        forces.append(F)
        holds.append(phase == "hold")
        areas.append(model.plate_area(u, d))
        for name, value in model.read_sensors(u).items():
            readings[name].append(value)

    # --- ramp ----------------------------------------------------------------------------
    while True:
        if s.max_force_N * (1 - 1e-9) <= F:
            status = Status.REACHED_FORCE
            break
        if d >= s.max_depth_mm - 1e-12:
            break
        if k_est is not None and k_est > 0:
            dd = min(dd, f_step / k_est)
            if F + k_est * dd > s.max_force_N:
                dd = max((s.max_force_N - F) / k_est * 1.01, 1e-4 * (s.max_force_N / k_est))
        dd = min(dd, s.max_step_mm, s.max_depth_mm - d)
        dd_free = dd
        for mark in _DEPTH_MARKS_MM:  # land exactly on the depths the paper reports forces at
            if d < mark - 1e-9 < d + dd:
                dd = mark - d
        guess = u + (dd / dd_prev) * (u - u_old) if dd_prev else u
        try:
            u_new, st_new, it, hist, closed = model.newton(
                guess, state, dd / s.speed_mm_s if not s.elastic_only else 0.0, d + dd, tol(F),
                first_try=retries == 0)
        except (ElementError, FloatingPointError, RuntimeError) as exc:
            retries += 1
            dd *= 0.25
            if dd < s.min_step_mm:
                raise ConvergenceError(
                    f"{design.name}: no equilibrium at plate displacement {d:.4f} mm "
                    f"(t = {t:.3f} s, F = {F:.4f} N) even with a {dd * 4:.2e} mm step: {exc}",
                    log=log, diagnostics={"time_s": t, "displacement_mm": d, "force_N": F,
                                          "last_error": str(exc)},
                ) from exc
            continue
        u_old, u, state = u, u_new, st_new
        d_prev_val, F_prev = d, F
        d += dd
        t = d / s.speed_mm_s
        F = model.plate_force(u, d)
        k_est = (F - F_prev) / (d - d_prev_val) if F_prev < F and d > d_prev_val else k_est
        dd_prev = dd
        record("ramp", it, hist, closed, dd)
        dd = max(dd, dd_free)  # a landing does not shrink the next step
        dd *= 1.5 if it <= 4 else (1.0 if it <= 8 else 0.6)
        # a run of slow steps must not shrink the step to nothing (0.6^n: a plate crawling
        # towards a buckle reached increments of 1e-16 mm and a zero division), nor crawl on
        crawl = crawl + 1 if dd_prev < CRAWL_STEP_MM else 0
        if crawl > CRAWL_STEPS:
            raise ConvergenceError(
                f"{design.name}: the plate stalls at {d:.4f} mm (t = {t:.3f} s, F = {F:.4f} N): "
                f"{crawl} steps in a row under {CRAWL_STEP_MM:g} mm, each needing many Newton "
                "iterations (a limit point of the structure, or of its contact)",
                log=log, diagnostics={"time_s": t, "displacement_mm": d, "force_N": F,
                                      "last_error": "stall"})
        dd = max(dd, 4.0 * s.min_step_mm)
        if progress:
            progress(0.8 * min(1.0, max(F / s.max_force_N, d / s.max_depth_mm)))

    ramp_end_u = None
    if len(times) > 1:
        pressure = model.plate_pressure(u, d, F)
        ramp_end_u = u.copy()
    # --- hold ----------------------------------------------------------------------------
    if do_hold:
        t_end = t + s.hold_s
        dt = min(0.01, s.hold_s)
        t0 = t
        while t < t_end - 1e-12:
            dt = min(dt, t_end - t)
            try:
                u_new, st_new, it, hist, closed = model.newton(u, state, dt, d, tol(F))
            except (ElementError, FloatingPointError, RuntimeError) as exc:
                retries += 1
                dt *= 0.25
                if dt < 1e-6:
                    raise ConvergenceError(
                        f"{design.name}: hold at {d:.4f} mm failed at t = {t:.3f} s: {exc}",
                        log=log, diagnostics={"time_s": t, "displacement_mm": d,
                                              "last_error": str(exc)},
                    ) from exc
                continue
            u, state = u_new, st_new
            t += dt
            F = model.plate_force(u, d)
            record("hold", it, hist, closed, dt)

            dt *= 1.6
            if progress:
                progress(0.8 + 0.2 * (t - t0) / s.hold_s)
    if progress:
        progress(1.0)
    return IndentationResult(
        design=design.name, settings=s, time_s=np.array(times), displacement_mm=np.array(disps),
        force_N=np.array(forces), hold=np.array(holds), status=status, log=log,
        wall_s=time.perf_counter() - t_start, n_dofs=model.mesh.n_dofs,
        n_elements=model.mesh.n_elements,
        embedded_sensors={p.label: {"placement": p.placement,
                                    "area_mm2": model.sensors.area_mm2[p.label],
                                    "force_N": np.array(readings[p.label])}
                          for p in model.sensors.patches},
        contact_area_mm2=np.array(areas), plate_pressure=pressure,
        linear_solver=model.linear_solver(), ramp_end_u=ramp_end_u,
    )
