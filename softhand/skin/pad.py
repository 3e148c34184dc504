r"""Skin pad with relaxation, from native MuJoCo elements (the ``soft-contact+relaxation`` level).

The skin surface is a *pad* body on a slide joint along the skin's inward normal (coordinate
`x` = compression, m). Its elastic law is the QLV law's long-term part `g_\infty F_e(x)`,
a C2 cubic spline written as a truncated power series

    F(x) = a x + b x^2 + c x^3 + \sum_k c_k (x - t_k)_+^3 \; - \;[\text{quadratic and cubic past } t_n]

that MuJoCo evaluates natively: one fixed tendon per piece with a dead-band ``springlength =
(-inf, t_k)`` and polynomial stiffness (the last one cancels the curvature, so the law continues as
a straight line). The first piece too (`t_0 = 0`): the law acts in compression only. On the
joint, MuJoCo's polynomial `-(a x + b x^2 + c x^3)` would act on both sides, and with
`b > 0` it is not restoring for `x < 0` (pocket2-sil: negative stiffness below
-0.79 mm, pushing outward below -1.46 mm): a pad pushed past its rest from behind ran away.

Relaxation: QLV needs, per Prony term, a hereditary force `h_i` with
`\dot h_i = g_i F_e'(x)\dot x - h_i/\tau_i`. Write `F_e` as a piecewise-linear
`\sum_j k_j (x - t_j)_+` (non-negative slope increments `k_j`, fitted). Then
`h_i = \sum_j h_{ij}` where each `h_{ij}` is a *linear* Maxwell branch that engages at
depth `t_j`: a light slide dof `y_{ij}` with damping `c_{ij} = \tau_i g_i k_j`, tied to
the pad by a tendon `x - y_{ij}` whose spring `g_i k_j` acts past a dead band
`t_j`. The sum obeys exactly the QLV equation for the piecewise-linear law: amount *and*
time constants are right at every depth (single nonlinear or linear branches get one of them wrong
away from one depth: up to 10 % and 14 % in the hold for pocket2-pu, measured). A fitted
multiplier per term on `c_{ij}` absorbs what the rig adds (pad mass, contact compliance).

The pad contacts the world through a stiff calibrated contact (`softhand.skin.soft_contact`,
linear law) and needs the ``discrete`` integrator (light bodies, stiff springs). Units: SI.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from softhand.laws.elastic import ElasticLaw
from softhand.laws.fit import SkinLaw
from softhand.validate import check_mapping, check_number, check_numbers, join

__all__ = ["PadParams", "add_pad", "evaluate_pieces", "spline_pieces"]

BRANCH_MASS_KG = 1e-5
FAR_M = 1e3  # "minus infinity" for the lower end of a dead band


def spline_pieces(law: ElasticLaw, scale: float = 1.0) -> list[tuple[float, float, float, float]]:
    """(knot_m, a, b, c) in SI: ``scale * F(x) = sum a t + b t^2 + c t^3`` with ``t = (x - knot)_+``.

    Exact for the law's cubic spline on [0, max] and its straight continuation past it.
    """
    knots = np.unique(law.knots)  # mm
    force = law._force  # the cubic antiderivative spline
    mids = 0.5 * (knots[:-1] + knots[1:])
    d3 = np.array([float(force(m, 3)) for m in mids])  # constant on each interval
    pieces = [(0.0, float(force(mids[0], 1) - force(mids[0], 2) * mids[0]
                          + 0.5 * d3[0] * mids[0] ** 2),
               float(force(mids[0], 2) - d3[0] * mids[0]) / 2, d3[0] / 6)]
    for k in range(1, len(mids)):
        pieces.append((float(knots[k]), 0.0, 0.0, (d3[k] - d3[k - 1]) / 6))
    curv_end = float(force(mids[-1], 2) + d3[-1] * (knots[-1] - mids[-1]))
    pieces.append((float(knots[-1]), 0.0, -curv_end / 2, -d3[-1] / 6))
    return [(t * 1e-3, a * scale * 1e3, b * scale * 1e6, c * scale * 1e9)
            for t, a, b, c in pieces]


def evaluate_pieces(pieces: list[tuple[float, float, float, float]], x_m) -> np.ndarray:
    """The force (N) of `spline_pieces` at compression ``x_m`` (m), as MuJoCo computes it
    (the pad's tendons: nothing below each knot, so nothing at ``x < 0``)."""
    x = np.asarray(x_m, dtype=float)
    out = np.zeros_like(x)
    for t0, a, b, c in pieces:
        u = np.maximum(x - t0, 0.0)
        out = out + a * u + b * u**2 + c * u**3
    return out


@dataclass(frozen=True)
class PadParams:
    """What the pad needs: the law, its contact, and the fitted branch damping.

    Attributes:
        law: the QLV skin law (elastic spline + Prony).
        reference_mm: depth at which the branch time constants are exact before fitting (the
            2 N depth).
        contact_stiffness: stiffness of the pad's linear contact (N/m at any mass); its
            compliance is taken out of the pad's spring so that pad + contact give the law.
        max_compression_mm: joint limit (the bone under the skin).
        damping_scale: per-branch multipliers of the analytic damping, fitted in the rig.
        pad_mass_kg: mass of the pad body (5 g, about a fingertip pulp; 2 g let the stiff
            contact chatter for one step at the end of a ramp, which a 5 g pad does not).
        n_knots: pieces of the branches' piecewise-linear law (branch dofs per Prony term).
    """

    law: SkinLaw
    reference_mm: float
    contact_stiffness: float
    max_compression_mm: float
    damping_scale: tuple[float, ...] = ()
    pad_mass_kg: float = 5e-3
    n_knots: int = 6

    def __post_init__(self) -> None:
        for name in ("reference_mm", "contact_stiffness", "max_compression_mm", "pad_mass_kg"):
            v = getattr(self, name)
            if name == "contact_stiffness" and v == np.inf:
                continue  # a pad whose contact adds no compliance (the hand pad, in series)
            if not np.isfinite(v) or v <= 0:
                raise ValueError(f"{name} = {v!r} must be finite and > 0")
        scale = tuple(float(x) for x in self.damping_scale) or (1.0,) * len(self.law.prony.g)
        if len(scale) != len(self.law.prony.g) or any(not x > 0 for x in scale):
            raise ValueError(f"damping_scale = {self.damping_scale!r}: one positive value per "
                             f"Prony term ({len(self.law.prony.g)})")
        object.__setattr__(self, "damping_scale", scale)

    def branch_knots(self) -> tuple[list[float], list[float]]:
        """Piecewise-linear law for the branches: knots (m) and slope increments (N/m, >= 0)."""
        from scipy.optimize import nnls

        spring = self.spring_law
        top = spring.max_mm
        knots = np.linspace(0.0, top, self.n_knots + 1)[:-1]
        x = np.linspace(0.0, 1.2 * top, 300)
        A = np.maximum(x[:, None] - knots[None, :], 0.0)
        inc, _ = nnls(A, spring.force(x))
        return [float(t) * 1e-3 for t in knots], [float(k) * 1e3 for k in inc]

    @functools.cached_property
    def spring_law(self) -> ElasticLaw:
        """The pad's instantaneous spring: the law with the contact's compliance taken out (an
        infinite ``contact_stiffness``: the law itself). Computed once per pad."""
        e = self.law.elastic
        if self.contact_stiffness == np.inf:
            return e
        top = e.max_mm
        f = np.linspace(0.0, float(e.force(top)), 400)[1:]
        x = e.displacement_at(f) - f / self.contact_stiffness * 1e3
        if np.any(np.diff(x) <= 0) or x[0] <= 0:
            raise ValueError(f"contact_stiffness = {self.contact_stiffness:.4g} N/m is not stiffer "
                             "than the skin everywhere; raise it")
        return ElasticLaw.fit(np.concatenate([[0.0], x]), np.concatenate([[0.0], f]),
                              n_basis=e.coefficients.size + 4)

    def to_dict(self) -> dict:
        return {"reference_mm": self.reference_mm, "contact_stiffness_N_per_m": self.contact_stiffness,
                "max_compression_mm": self.max_compression_mm,
                "damping_scale": list(self.damping_scale), "pad_mass_kg": self.pad_mass_kg,
                "n_knots": self.n_knots}

    @classmethod
    def from_dict(cls, d: Any, law: SkinLaw, *, key: str = "params") -> PadParams:
        """Parse `to_dict` output for ``law``, checking every value.

        Allowed: ``reference_mm``, ``contact_stiffness_N_per_m``, ``max_compression_mm`` and
        ``pad_mass_kg`` > 0; ``damping_scale`` one number > 0 per Prony term of ``law``;
        ``n_knots`` (optional, default 6) an integer in [1, 50].

        Raises:
            ValueError: ``"{key}.damping_scale = [1.0]: expected a list of 2 numbers ..."``.
        """
        names = ("reference_mm", "contact_stiffness_N_per_m", "max_compression_mm",
                 "damping_scale", "pad_mass_kg")
        check_mapping(key, d, required=names, optional=("n_knots",))
        ref, stiff, comp = (check_number(join(key, n), d[n], lo=0.0, lo_open=True)
                            for n in names[:3])
        n_terms = len(law.prony.g)
        scale = check_numbers(join(key, "damping_scale"), d["damping_scale"], length=n_terms,
                              lo=0.0, lo_open=True, why="(one per Prony term of the law)")
        mass = check_number(join(key, "pad_mass_kg"), d["pad_mass_kg"], lo=0.0, lo_open=True)
        knots = int(check_number(join(key, "n_knots"), d.get("n_knots", 6), lo=1, hi=50,
                                 integer=True))
        try:
            return cls(law, ref, stiff, comp, scale, mass, knots)
        except ValueError as exc:
            raise ValueError(f"{key}: {exc}") from None


def _spring(spec: mujoco.MjSpec, name: str, joint: str, other: str | None,
            pieces: list[tuple[float, float, float, float]]) -> None:
    """Add the pieces as dead-band tendons: ``joint`` (minus ``other``, a branch) past each
    knot. The pad's own spring acts in compression only (a dead band below 0 too); a branch's
    first piece, linear, acts on both sides."""
    for k, (t, a, b, c) in enumerate(pieces):
        ten = spec.add_tendon(name=f"{name}_k{k}")
        ten.wrap_joint(joint, 1.0)
        if other is not None:
            ten.wrap_joint(other, -1.0)
        linear_branch = other is not None and t == 0.0
        ten.springlength = [0.0, 0.0] if linear_branch else [-FAR_M, t]  # dead band below knots
        ten.stiffness = [a, b, c]


def add_pad(spec: mujoco.MjSpec, bone: mujoco.MjsBody, name: str, params: PadParams, *,
            normal=(0.0, 0.0, 1.0), pos=(0.0, 0.0, 0.0)) -> mujoco.MjsBody:
    """Add a pad body under ``bone`` (slide along ``-normal`` = compression) and its branches.

    Returns the pad body; the caller adds the skin geom to it.
    """
    axis = -np.asarray(normal, dtype=float)
    axis = axis / np.linalg.norm(axis)
    pad = bone.add_body(name=f"{name}_pad", pos=list(pos))
    joint = pad.add_joint(name=f"{name}_pad", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=list(axis))
    joint.range = [-1e-4, params.max_compression_mm * 1e-3]
    joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
    joint.armature = 1e-5
    law = params.law
    spring = params.spring_law
    pad.mass = params.pad_mass_kg
    pad.inertia = [1e-9, 1e-9, 1e-9]
    pad.ipos = [0.0, 0.0, 0.0]  # a defined ipos makes the MJCF writer keep the <inertial>
    pad.explicitinertial = True
    _spring(spec, f"{name}_eq", joint.name, None, spline_pieces(spring, law.prony.g_inf))
    knots, slopes = params.branch_knots()
    for i, (g, tau, scale) in enumerate(zip(law.prony.g, law.prony.tau_s, params.damping_scale,
                                            strict=True)):
        for j, (t, k) in enumerate(zip(knots, slopes, strict=True)):
            if k <= 0:
                continue
            branch = bone.add_body(name=f"{name}_b{i}_{j}", pos=list(pos))
            bj = branch.add_joint(name=f"{name}_b{i}_{j}", type=mujoco.mjtJoint.mjJNT_SLIDE,
                                  axis=list(axis))
            bj.damping = [scale * tau * g * k, 0.0, 0.0]
            bj.armature = 1e-6
            branch.mass = BRANCH_MASS_KG
            branch.inertia = [1e-9, 1e-9, 1e-9]
            branch.ipos = [0.0, 0.0, 0.0]
            branch.explicitinertial = True
            _spring(spec, f"{name}_b{i}_{j}", joint.name, bj.name, [(t, g * k, 0.0, 0.0)])
    return pad
