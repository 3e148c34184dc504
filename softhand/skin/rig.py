"""MuJoCo indentation rig: a rigid plate driven down onto one phalanx skin, like the FE and the paper.

The plate (the paper's 20 x 10 mm brass indenter) is a mocap body: its descent is prescribed
exactly. The phalanx skin is an ellipsoid (one contact point against any convex indenter, so the
per-contact law is the skin's law) on a "bone" body that rides a vertical slide joint held by a
load-cell spring: the bone's mass is the effective mass the contact sees (varied by the mass
tests), and the spring is soft enough to be stable with any mass at the timestep. The rig records
the indentation (plate descent minus bone descent: what the skin feels) and the normal contact
force. The plate follows the *indentation* history asked for: each step it is placed at the target
indentation plus the bone's current descent, so the load cell's give does not enter the curve
(the paper's machine is displacement-controlled too). Any representation
(`softhand.skin.representations.REPRESENTATIONS`) of any
calibrated skin runs in the same rig.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from softhand.laws.fit import Curve, paired_arrays
from softhand.skin.representations import StockContact, get_representation
from softhand.skin.soft_contact import SoftContactParams, impedance
from softhand.warn import warn_at_caller

__all__ = ["CHECKED_FORCE_N", "ContactStability", "RangeIssue", "RigSettings", "SkinRangeWarning",
           "build_rig", "contact_stable_timestep", "pair_law_values", "pair_mobility", "run_rig",
           "warn_range_issues"]

SKIN_HALF_AXES_M = (0.005, 0.008, 0.0125)  # phalanx: 10 mm long, 16 mm wide; 25 mm tall so
# that a plate 8.6 mm deep (human tissue at 20 N) is still far from its far side (a convex
# penetration depth is only defined while the plate is inside the near half)
#: The rigid bone's top lies this far under the skin's top: a hard stop below the deepest
#: calibrated indentation (the human law at 20 N, 8.6 mm; the designs reach 4.6 mm at 20 N).
BONE_DEPTH_M = 0.0095
PLATE_HALF_M = (0.010, 0.005, 0.002)  # the paper's 20 x 10 mm indenter, 4 mm thick
INTEGRATORS = ("discrete", "implicitfast", "euler")


@dataclass(frozen=True)
class RigSettings:
    """Simulation settings of the rig.

    Attributes:
        timestep: s, in (0, 0.01].
        mass_kg: mass of the pressed body (the effective mass the contact sees), > 0.
        integrator: ``implicitfast``, ``discrete`` or ``euler``; None: the representation's own
            (``discrete`` for pads, whose light bodies limit-cycle otherwise; else implicitfast).
        load_cell_hz: natural frequency of the load cell (bone mass on its spring), Hz; None:
            100 Hz under explicit-stiffness integrators, 300 Hz under ``discrete`` (implicit).
    """

    timestep: float = 1e-3
    mass_kg: float = 0.2
    integrator: str | None = None
    load_cell_hz: float | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.timestep) and 0 < self.timestep <= 0.01):
            raise ValueError(f"timestep = {self.timestep!r} s must be in (0, 0.01]")
        if not (np.isfinite(self.mass_kg) and self.mass_kg > 0):
            raise ValueError(f"mass_kg = {self.mass_kg!r} must be finite and > 0")
        if self.integrator is not None and self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator = {self.integrator!r}: allowed {', '.join(INTEGRATORS)}")
        if self.load_cell_hz is not None and not (np.isfinite(self.load_cell_hz)
                                                  and self.load_cell_hz >= 0):
            raise ValueError(f"load_cell_hz = {self.load_cell_hz!r} must be finite and >= 0 "
                             "(0: a free indenter, for impact and dead-weight tests)")


def build_rig(representation: str, params: Any = None, *,
              settings: RigSettings = RigSettings()) -> mujoco.MjModel:
    """Compile the rig for ``representation`` with its parameter object ``params`` (what
    `parse` or ``.fit`` gives; ``rigid``:
    None for MuJoCo's stock contact). ``flex`` has its own rig (`softhand.skin.flex`).

    Raises:
        ValueError: an unknown representation, or one that needs parameters given none.
    """
    kind = get_representation(representation)
    if params is None:
        if representation != "rigid":
            raise ValueError(f"{representation} needs its parameters (params=...)")
        params = StockContact()
    spec = mujoco.MjSpec()
    spec.option.timestep = settings.timestep
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    integrator = settings.integrator or kind.rig_integrator
    spec.option.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{integrator.upper()}")
    bone = spec.worldbody.add_body(name="bone")
    load_cell = bone.add_joint(name="load_cell", type=mujoco.mjtJoint.mjJNT_SLIDE,
                               axis=[0.0, 0.0, -1.0])
    hz = settings.load_cell_hz
    if hz is None:
        hz = 300.0 if integrator == "discrete" else 100.0
    w = 2 * np.pi * hz
    load_cell.stiffness = [settings.mass_kg * w**2, 0.0, 0.0]
    load_cell.damping = [2 * settings.mass_kg * w, 0.0, 0.0]
    bone.add_geom(name="bone", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.004, 0.006, 0.001],
                  pos=[0, 0, SKIN_HALF_AXES_M[2] - BONE_DEPTH_M - 0.001], mass=settings.mass_kg,
                  contype=0, conaffinity=0)
    skin_body = kind.add_to_rig(spec, bone, params)
    skin_body.add_geom(name="skin", type=mujoco.mjtGeom.mjGEOM_ELLIPSOID,
                       size=list(SKIN_HALF_AXES_M), contype=0, conaffinity=0, mass=0.0,
                       rgba=[0.9, 0.7, 0.6, 1])
    top = SKIN_HALF_AXES_M[2] + PLATE_HALF_M[2]
    plate = spec.worldbody.add_body(name="plate", pos=[0.0, 0.0, top], mocap=True)
    plate.add_geom(name="plate", type=mujoco.mjtGeom.mjGEOM_BOX, size=list(PLATE_HALF_M),
                   contype=0, conaffinity=0)
    stop = spec.add_pair(name="bone_plate", geomname1="bone", geomname2="plate", condim=3)
    stop.solref = [2 * settings.timestep, 1.0]  # the stiffest critically damped stop the step allows
    pair = spec.add_pair(name="skin_plate", geomname1="skin", geomname2="plate", condim=3)
    law = kind.rig_contact(params)
    if law is None:  # stock contact
        pair.solref, pair.solimp = list(params.solref), list(params.solimp)
    model = spec.compile()
    if law is not None:
        apply_pair_law(model, "skin_plate", law)
    return model


def pair_inverse_inertia(model: mujoco.MjModel, pair_id: int) -> float:
    """The compiler's inverse inertia of a pair's two bodies (what ``efc_diagA`` uses)."""
    b1 = model.geom_bodyid[model.pair_geom1[pair_id]]
    b2 = model.geom_bodyid[model.pair_geom2[pair_id]]
    return float(model.body_invweight0[b1, 0] + model.body_invweight0[b2, 0])


class SkinRangeWarning(UserWarning):
    """A skin is used outside the range its calibration was checked in (one warning for a whole
    model: per kind of problem, the number of pairs and the worst one)."""


CHECKED_TIMESTEPS_S = (0.5e-3, 2e-3)  # the calibration is tested at 0.5, 1 and 2 ms
#: the top of the range a skin's contact is checked for stability up to (the FE curves reach 20 N)
CHECKED_FORCE_N = 20.0


@dataclass(frozen=True)
class RangeIssue:
    """One way a pair law is used outside its calibration.

    Attributes:
        kind: ``timestep`` (outside `CHECKED_TIMESTEPS_S`) or ``stiffness`` (the contact,
            integrated explicitly, is unstable at this timestep somewhere up to
            `CHECKED_FORCE_N`: `contact_stable_timestep`).
        pair: the pair's name.
        severity: how far outside: the timestep over the nearest checked bound (or that bound over
            the timestep, >= 1), or the timestep over the largest stable one.
        message: the one-pair message, starting ``pair 'NAME': ``.
    """

    kind: str
    pair: str
    severity: float
    message: str


def warn_range_issues(issues: list[RangeIssue]) -> None:
    """One `SkinRangeWarning` for all the ``issues`` of a model (none if there are none),
    attributed to the user's code: the pair's message when there is one issue, else the number
    of pairs and, per kind of issue, how many pairs have it and the worst one's message."""
    if not issues:
        return
    if len(issues) == 1:
        warn_at_caller(issues[0].message, SkinRangeWarning)
        return
    kinds: dict[str, list[RangeIssue]] = {}
    for issue in issues:
        kinds.setdefault(issue.kind, []).append(issue)
    parts = []
    for kind, group in kinds.items():
        worst = max(group, key=lambda i: i.severity)
        parts.append(f"{kind}: {len(group)} pair{'s' if len(group) > 1 else ''}, the worst "
                     f"{worst.message}")
    pairs = len({i.pair for i in issues})
    warn_at_caller(f"{pairs} skin pairs are outside their calibrated range; {'; '.join(parts)}",
                   SkinRangeWarning)


def apply_pair_law(model: mujoco.MjModel, pair: str | int, params: SoftContactParams) -> None:
    """Write ``params`` into a compiled pair, scaled by the pair's inverse inertia.

    Warns as `pair_law_values`.
    """
    pid = pair if isinstance(pair, int) else mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_PAIR, pair)
    model.pair_solref[pid], model.pair_solimp[pid] = pair_law_values(model, pid, params)


def pair_mobility(model: mujoco.MjModel, pair: int, data: mujoco.MjData | None = None
                  ) -> float:
    """How much more mobile the pair's bodies are, in their most mobile direction at a possible
    contact point, than the inverse inertia MuJoCo's solver assumes for the pair's rows.

    MuJoCo regularises a contact row with ``efc_diagA``, by default the two bodies'
    ``body_invweight0``: the *direction-averaged* translational inverse inertia at the bodies'
    centres of mass at ``qpos0`` (a third of the trace of ``J M^-1 J^T``). Along the contact
    normal the row's true inverse inertia ``A = J M^-1 J^T`` is up to 3x that for a body free in
    one direction only (a body on a slide joint: 1/m against 1/(3m)). This returns
    ``kappa = (A_1 + A_2) / A_hat``, ``A_i`` the largest eigenvalue of body i's translational
    ``J M^-1 J^T`` at its centre of mass at ``qpos0`` (the sum bounds the relative motion of two
    bodies on separate kinematic trees): between 1 and 3. 1.0 if neither body moves.

    A contact point away from the centre of mass can see more: 3.7x and 9.5x on the two rows of
    a capsule fingertip (10 g) lying on a box, yet that press stayed stable at 2 ms up to 16.6 N
    where a single row with kappa 9.5 would not (the two rows and their friction rows, solved
    together, are not the one-row model of `contact_stable_timestep`): the centre of mass
    is the estimate that the indentation rig confirms (kappa 3, bound to +-5 %).
    """
    g1, g2 = int(model.pair_geom1[pair]), int(model.pair_geom2[pair])
    b1, b2 = int(model.geom_bodyid[g1]), int(model.geom_bodyid[g2])
    a_hat = float(model.body_invweight0[b1, 0] + model.body_invweight0[b2, 0])
    if a_hat <= 0 or model.nv == 0:
        return 1.0
    if data is None:
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
    jac, minv_jt = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    total = 0.0
    for body in (b1, b2):
        if model.body_invweight0[body, 0] <= 0:  # the world, a mocap or a welded body
            continue
        mujoco.mj_jac(model, data, jac, None, data.xipos[body], body)
        mujoco.mj_solveM(model, data, minv_jt, jac)
        total += float(np.linalg.eigvalsh(jac @ minv_jt.T)[-1])
    return total / a_hat


@dataclass(frozen=True)
class ContactStability:
    """Where a calibrated contact is least stable under an explicit integrator, and the largest
    timestep it is stable at (`contact_stable_timestep`).

    Attributes:
        max_timestep_s: the largest stable timestep, s.
        omega: the contact's angular frequency there, rad/s.
        damping_rate: its damping rate there (gamma: the acceleration per unit velocity), 1/s.
        depth_mm: the penetration where the bound is tightest, mm.
        force_N: the law's force at that penetration, N.
        top_N: the force the check went up to, N.
        mobility: kappa of `pair_mobility`.
    """

    max_timestep_s: float
    omega: float
    damping_rate: float
    depth_mm: float
    force_N: float
    top_N: float
    mobility: float


def contact_stable_timestep(params: SoftContactParams, inv_inertia: float, *,
                            mobility: float = 1.0, top_N: float = CHECKED_FORCE_N,
                            n: int = 2000) -> ContactStability:
    r"""The largest timestep at which a pair carrying ``params`` is stable up to ``top_N``.

    MuJoCo solves one contact row so that its acceleration is
    `\ddot r = (1-\beta)\,a_0 + \beta\,a_{ref}`, with `a_0` the unconstrained
    acceleration, `a_{ref} = -b\,\dot r - k\,d(r)\,r` (direct solref `(-S, -B)`:
    `k = S/d_w^2`, `b = B/d_w`; `S = \hat S \hat A`, `B = \hat B \hat A`)
    and `\beta = \kappa d / (\kappa d + 1 - d)`, where `\kappa = A/\hat A` is the
    row's true inverse inertia over the one the solver regularises with
    (`pair_mobility`; `\beta = d` when they agree). Linearised about the static
    equilibrium at penetration `r` (where `a_0` balances the contact), the row is an
    oscillator of angular frequency and damping rate

        \omega^2 = \frac{\kappa k d}{\kappa d + 1 - d}
                   \Big(d + d' r + \frac{d' r}{1 - d}\Big), \qquad
        \gamma = \frac{\kappa d\,b}{\kappa d + 1 - d}

    (`d' = \mathrm{d}d/\mathrm{d}r`: the impedance sigmoid stiffens the contact where it
    rises). `a_{ref}` is evaluated at the step's start (the constraint force is implicit in
    the acceleration only: ``implicitfast``, ``implicit`` and ``Euler`` differentiate passive and
    actuator forces, never contacts), then the velocity and position are updated one after the
    other (semi-implicit Euler). For that map the Jury criterion gives stability iff
    `(\omega h)^2 + 2 \gamma h < 4` (`\omega h < 2` undamped), so

        h_{max} = \min_r \frac{\sqrt{\gamma^2 + 4\omega^2} - \gamma}{\omega^2}

    over the penetrations up to ``top_N``. ``RK4`` is held to the same bound (its own is higher:
    `\omega h < 2\sqrt 2` undamped). Checked in the indentation rig (a free indenter on a
    slide joint, `\kappa = 3`, under a dead weight): pocket2-sil, pocket2-sil-pu on 20 g
    and solid-pu on 2 g at 10 and 20 N hold still at 0.95 `h_{max}` and oscillate
    without bound at 1.05 `h_{max}`.

    Args:
        params: the skin's soft contact.
        inv_inertia: `\hat A`, the compiler's inverse inertia of the pair, 1/kg, > 0.
        mobility: `\kappa`, >= 0 (1: the true inverse inertia is the compiler's).
        top_N: the largest force the contact should carry, N, > 0.
        n: penetrations sampled between 0 and the depth of ``top_N``.
    """
    if not (np.isfinite(inv_inertia) and inv_inertia > 0):
        raise ValueError(f"inv_inertia = {inv_inertia!r}: expected a finite number > 0 (1/kg)")
    if not (np.isfinite(mobility) and mobility >= 0):
        raise ValueError(f"mobility = {mobility!r}: expected a finite number >= 0")
    if not (np.isfinite(top_N) and top_N > 0):
        raise ValueError(f"top_N = {top_N!r}: expected a finite number of newtons > 0")
    r, d, stiffening = _stability_grid(params, float(top_N), int(n))
    dw = params.solimp[1]
    k = params.stiffness * inv_inertia / dw**2
    b = params.damping * inv_inertia / dw
    share = mobility * d / (mobility * d + 1 - d)  # beta
    omega2 = share * k * stiffening
    gamma = share * b
    with np.errstate(divide="ignore", invalid="ignore"):
        h = np.where(omega2 > 0, (np.sqrt(gamma**2 + 4 * omega2) - gamma) / omega2, np.inf)
    h = np.where((omega2 <= 0) & (gamma > 0), 2 / np.maximum(gamma, 1e-300), h)
    i = int(np.argmin(h))
    return ContactStability(float(h[i]), float(np.sqrt(max(omega2[i], 0.0))), float(gamma[i]),
                            float(r[i] * 1e3), float(params.force(r[i] * 1e3)), float(top_N),
                            float(mobility))


@functools.lru_cache(maxsize=256)
def _stability_grid(params: SoftContactParams, top_N: float,
                    n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What `contact_stable_timestep` needs of the law alone (a scene's pairs share a few
    laws): the penetrations up to the depth of ``top_N`` (m), the impedance there, and
    `d + d' r + d' r / (1 - d)`. Read-only arrays."""
    r_top = params.solimp[2]
    while float(params.force(r_top * 1e3)) < top_N:
        r_top *= 2
    lo, hi = 0.0, r_top
    for _ in range(60):  # the law is monotone in r: bisect for the depth of top_N
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if float(params.force(mid * 1e3)) < top_N else (lo, mid)
    r = np.linspace(hi / n, hi, n)
    d = impedance(r, params.solimp)
    d_r = np.gradient(d, r)
    stiffening = d + d_r * r + d_r * r / (1 - d)
    for a in (r, d, stiffening):
        a.flags.writeable = False
    return r, d, stiffening


def pair_law_values(model: mujoco.MjModel, pair: str | int, params: SoftContactParams, *,
                    issues: list[RangeIssue] | None = None,
                    data: mujoco.MjData | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The pair's ``solref`` and ``solimp`` for ``params``, scaled by its inverse inertia.

    ``model`` is the compiled model (its ``body_invweight0``); the values may go into that model
    or into the spec it was compiled from (the inverse inertia does not depend on them).

    The pair is outside its calibrated range (a `RangeIssue`) when the timestep is outside
    the checked range, or when the contact is unstable at the model's timestep somewhere up to
    `CHECKED_FORCE_N` (`contact_stable_timestep`, with the pair's
    `pair_mobility` at ``qpos0``; ``discrete`` integrates it implicitly and is not
    checked). With ``issues`` None this warns at once (`warn_range_issues`); a caller that
    sets many pairs passes a list, which collects the issues, and warns once for all of them
    (`warn_range_issues`); it may also pass ``data``, the model's state at ``qpos0`` after
    ``mj_forward``, made once for all of them (`pair_mobility`).
    """
    pid = pair if isinstance(pair, int) else mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_PAIR, pair)
    if pid < 0:
        raise ValueError(f"pair {pair!r} is not in the model")
    inv = pair_inverse_inertia(model, pid)
    values = (np.asarray(params.solref(inv), dtype=float), np.asarray(params.solimp, dtype=float))
    h = float(model.opt.timestep)
    name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_PAIR, pid) or str(pid)
    found = []
    lo, hi = CHECKED_TIMESTEPS_S
    if not lo <= h <= hi:
        found.append(RangeIssue("timestep", name, max(h / hi, lo / h),
                                f"pair {name!r}: timestep {h * 1e3:g} ms is outside the calibrated "
                                f"range {lo * 1e3:g}-{hi * 1e3:g} ms"))
    if model.opt.integrator != mujoco.mjtIntegrator.mjINT_DISCRETE:
        st = contact_stable_timestep(params, inv, mobility=pair_mobility(model, pid, data))
        if h > st.max_timestep_s:
            found.append(RangeIssue(
                "stiffness", name, h / st.max_timestep_s,
                f"pair {name!r}: unstable at timestep {h * 1e3:g} ms: at {st.depth_mm:.2f} mm "
                f"({st.force_N:.3g} N) the contact (the compiler's effective mass {1 / inv:.3g} kg, "
                f"{st.mobility:.2g}x as mobile in its most mobile direction) oscillates at "
                f"{st.omega:.3g} rad/s (damping rate {st.damping_rate:.3g} 1/s), and an explicit "
                f"update is stable only while (omega h)^2 + 2 gamma h < 4: up to "
                f"{st.max_timestep_s * 1e3:.3g} ms for forces up to {st.top_N:g} N; use a "
                "smaller timestep or a heavier body"))
    if issues is None:
        warn_range_issues(found)
    else:
        issues.extend(found)
    return values


def plate_force(model: mujoco.MjModel, data: mujoco.MjData, plate_geom: int) -> float:
    """Sum of normal contact forces on the plate geom (N)."""
    total = 0.0
    for i in range(data.ncon):
        c = data.contact[i]
        if c.geom1 == plate_geom or c.geom2 == plate_geom:
            total += float(data.efc_force[c.efc_address])
    return total


def run_rig(model: mujoco.MjModel, time_s, displacement_mm, *, representation: str = "",
            settings: RigSettings = RigSettings()) -> Curve:
    """Drive the plate along ``displacement_mm(time_s)`` (linear in between) and record it: a
    simulated `Curve` (the plate's actual descent from first touch,
    the normal contact force on the plate; ``stats``: ``wall_s`` in ``mj_step`` alone,
    ``steps``, ``step_us``), labelled ``representation``."""
    t_cmd, d_cmd = paired_arrays(time_s, displacement_mm, ("time_s", "displacement_mm"))
    data = mujoco.MjData(model)
    dt = model.opt.timestep
    n = int(np.floor((t_cmd[-1] - t_cmd[0]) / dt + 1e-9))
    plate_geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "plate")
    bone_q = model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "load_cell")]
    z0 = float(model.body_pos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "plate"), 2])
    times = t_cmd[0] + dt * np.arange(n + 1)
    target_mm = np.interp(times, t_cmd, d_cmd)
    disp = np.empty(n + 1)
    force = np.empty(n + 1)
    disp[0], force[0] = target_mm[0], 0.0
    wall = 0.0
    for k in range(1, n + 1):
        plate_mm = target_mm[k] + 1e3 * data.qpos[bone_q]
        data.mocap_pos[0, 2] = z0 - 1e-3 * plate_mm
        t0 = time.perf_counter()
        mujoco.mj_step(model, data)
        wall += time.perf_counter() - t0
        disp[k] = plate_mm - 1e3 * data.qpos[bone_q]
        force[k] = plate_force(model, data, plate_geom)
    return Curve.simulated(times, disp, force, label=representation, wall_s=wall, steps=n)
