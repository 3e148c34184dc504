"""The ``flex`` level of detail of a phalanx skin: a 3D MuJoCo flex pad pressed by a rigid plate.

The pad is the FE phalanx (16 mm wide, 9 mm high, 10 mm long, half-ellipse section) as a
structured tetrahedral flex: a hexahedral grid in (length, u, v) mapped onto the half ellipse by
``x = u sqrt(1 - v^2/2)``, ``z = v sqrt(1 - u^2/2)`` (flat base, no degenerate cells), six
tetrahedra per hexahedron (conforming Kuhn split). Base nodes are pinned to the world (the bone);
every other node is a body with three slide joints and its lumped mass. A plate on a vertical
slide joint, driven by a stiff position servo, starts touching the apex and presses down.
Elasticity is MuJoCo's Saint Venant-Kirchhoff flex with Rayleigh damping (or the experimental
Stable Neo-Hookean, ``material="snh"``); both need the ``discrete`` integrator, the only one that
integrates flex elasticity implicitly in position. Gravity is off, as in the FE model.

Force: the sum of the normal forces (``mujoco.mj_contactForce``) of the plate-flex contacts,
frictionless (``condim=1``) like the FE plate; it equals the constraint force on the plate joint.
MuJoCo makes one contact per surface tetrahedron (its deepest point), so a contact row resolved in
one step chatters as that point hops between vertices; ``solref = (2 * timestep, 1)`` with
impedance 0.9999 is smooth and penetrates ~0.015 mm at 2 N (3 % of the solid-pu travel, absorbed by
the fit; it grows with the timestep). Displacement is the plate travel from first touch, read from
its joint, so the servo lag (10 um at 2 N) is not in it. Units: SI in MuJoCo; curves in mm and N.

SVK is linear in E: doubling E gives 1.92-1.97x the force at 0.05-0.2 mm (not 2: the contact
compliance does not scale). Its only nonlinearities are the growing contact patch and large
rotations, so stiffening FE curves (hyperfoam, pocket closure) fit only approximately, and it
softens in strong compression (E = 0.7 MPa: 15 N at 3.5 mm, 10 N at 4 mm). SNH stiffens instead
(20 N at 2.6 mm); neither gives NaN at 0.5-2 ms or to 60 % of the height.

Cost: the default mesh (2 x 12 x 3 cells = 432 tetrahedra, 117 free nodes, 352 dofs) makes a
step cost a few hundred times the same plate's step on a rigid box (`flex_cost_ratio`; a
coarser mesh costs less). A fit (``fit_flex``) moves Young's modulus only (Poisson's ratio 0.3,
starting from 0.5 MPa), a few simulations of the ramp. The cost and each skin's fitted error are
measured by ``softhand bench calibration`` (``reports/bench-calibration.md``), and on the hand by
``softhand bench flex`` (``reports/bench-flex.md``).

pocket2-sil: a homogeneous pad cannot be soft to 2 mm and stiffen sharply as the pocket closes; the
SVK fit is too stiff at 1-2 mm and too soft once the pocket has closed. Fitting poisson too
changed the solid-pu RMS by < 0.1 point.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import mujoco
import numpy as np
from scipy.optimize import least_squares

from softhand.laws.fit import Curve, FitStatus, fit_status

__all__ = ["CONTACT_BIT", "ContactPatch", "FlexFit", "FlexPadParams", "add_flex_pad", "add_plate",
           "build_flex_rig", "contact_patch", "fit_flex", "flex_cost_ratio", "plate_force",
           "set_flex_options", "simulate_flex_indentation"]

_PLATE_GEOM = "plate"
_PLATE_JOINT = "plate_z"
_PAD = "pad"
_PLATE_HALF_MM = (12.0, 7.0, 1.0)  # covers the 16 x 10 mm pad (the FE indenter is 20 x 10 mm)
_SERVO_HZ = 500.0  # plate servo natural frequency: kp = m (2 pi f)^2, critically damped
_SOLIMP = (0.9999, 0.9999, 1e-4, 0.5, 2.0)  # maximal impedance: contact penetration of micrometres
_MATERIALS = {"svk": 0, "snh": 1}  # mjsFlex.elastic3d
_CONTACT_STEPS = 2.0  # contact solref time constant in timesteps; 1 chatters (one point per tet)
#: contype/conaffinity bit shared by the pad and its plate only (a hand's geoms use bits 1, 2)
CONTACT_BIT = 4


def _check(name: str, value: float, lo: float, hi: float) -> None:
    try:
        ok = lo <= float(value) <= hi  # False for NaN
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"{name}={value!r} is outside the allowed range [{lo}, {hi}]")


@dataclass(frozen=True)
class FlexPadParams:
    """Material, damping and mesh of the flex pad.

    Attributes:
        young_Pa: Young's modulus of the SVK flex, Pa, in [1e3, 1e9].
        poisson: Poisson's ratio, in [0, 0.49] (linear tetrahedra lock as it nears 0.5).
        damping: Rayleigh damping of the flex elasticity, s, in [0, 0.1]. Default 0.002: adds 1 %
            to the force at 0.1 mm at 0.5 mm/s (0.01 s: 4 %). 0 works (MuJoCo warns, wrongly).
        n_length: cells along the finger, in [1, 12]. Default 2 (1: same solid-pu fit within 1 %).
        n_width: cells across the width, even (a node on the apex), in [2, 24]. Default 12 (the
            solid-pu RMS error is 1.8 / 1.3 / 1.0 % of 2 N with 8 / 10 / 12).
        n_height: cells from the base to the top, in [1, 12]. Default 3.
        width_mm: pad width, in [1, 100]. Default 16 (paper).
        height_mm: pad height above the bone, in [1, 100]. Default 9 (paper).
        length_mm: pad length, in [1, 100]. Default 10 (paper).
        density_kg_m3: mass density, in [100, 1e4]. Default 1100 (silicone, PU).
        material: ``"svk"`` (default; Saint Venant-Kirchhoff) or ``"snh"`` (experimental Stable
            Neo-Hookean, ``mjsFlex.elastic3d = 1``, not in MJCF), which stiffens in compression.
    """

    young_Pa: float = 1.0e6
    poisson: float = 0.3
    damping: float = 0.002
    n_length: int = 2
    n_width: int = 12
    n_height: int = 3
    width_mm: float = 16.0
    height_mm: float = 9.0
    length_mm: float = 10.0
    density_kg_m3: float = 1100.0
    material: str = "svk"

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Raise ValueError, quoting the value and its allowed range, for a bad field."""
        for name, lo, hi in (("young_Pa", 1e3, 1e9), ("poisson", 0.0, 0.49), ("damping", 0.0, 0.1),
                             ("width_mm", 1.0, 100.0), ("height_mm", 1.0, 100.0),
                             ("length_mm", 1.0, 100.0), ("density_kg_m3", 100.0, 1e4)):
            _check(name, getattr(self, name), lo, hi)
        for name, hi in (("n_length", 12), ("n_width", 24), ("n_height", 12)):
            value = getattr(self, name)
            if not isinstance(value, (int, np.integer)):
                raise ValueError(f"{name}={value!r} must be an integer in [1, {hi}]")
            _check(name, value, 2 if name == "n_width" else 1, hi)
        if self.n_width % 2:
            raise ValueError(f"n_width={self.n_width!r} must be even (allowed: 2, 4, ..., 24)")
        if self.material not in _MATERIALS:
            raise ValueError(f"material={self.material!r} is not one of {sorted(_MATERIALS)}")


@dataclass(frozen=True)
class FlexFit:
    """Result of `fit_flex`.

    Attributes:
        params: fitted pad parameters.
        rms_error_pct_of_2N: ``100 * RMS(F_sim - F_target) / 2 N`` over the target points.
        max_error_pct_of_2N: ``100 * max|F_sim - F_target| / 2 N``.
        n_simulations: number of ramp simulations run.
        wall_s: wall time of the fit, s.
        force_sim_N: fitted model's force at the target displacements.
        success: whether the optimiser reported convergence.
        step_us: mean wall time of one ``mj_step`` over the fit's simulations, microseconds.
    """

    params: FlexPadParams
    rms_error_pct_of_2N: float
    max_error_pct_of_2N: float
    n_simulations: int
    wall_s: float
    force_sim_N: np.ndarray = field(repr=False)
    success: bool
    step_us: float


def _pad_mesh(p: FlexPadParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Nodes (m), tetrahedra, pinned-node mask and lumped node masses (kg) of the pad."""
    nl, nw, nh = p.n_length, p.n_width, p.n_height
    y, u, v = np.meshgrid(np.linspace(-0.5, 0.5, nl + 1), np.linspace(-1.0, 1.0, nw + 1),
                          np.linspace(0.0, 1.0, nh + 1), indexing="ij")
    x = u * np.sqrt(1.0 - v**2 / 2.0)
    z = v * np.sqrt(1.0 - u**2 / 2.0)
    nodes = np.stack([x * p.width_mm / 2, y * p.length_mm, z * p.height_mm], -1).reshape(-1, 3)
    idx = np.arange(nodes.shape[0]).reshape(nl + 1, nw + 1, nh + 1)
    i, j, k = (a.ravel() for a in np.meshgrid(np.arange(nl), np.arange(nw), np.arange(nh),
                                              indexing="ij"))
    tets = []
    for order in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
        c = [np.zeros_like(i), np.zeros_like(i), np.zeros_like(i)]
        path = [idx[i, j, k]]
        for axis in order:  # walk from corner (0,0,0) to (1,1,1), one axis at a time
            c[axis] = c[axis] + 1
            path.append(idx[i + c[0], j + c[1], k + c[2]])
        tets.append(np.stack(path, -1))
    nodes, tets = nodes * 1e-3, np.concatenate(tets)
    e = nodes[tets[:, 1:]] - nodes[tets[:, :1]]
    signed = np.einsum("ij,ij->i", e[:, 0], np.cross(e[:, 1], e[:, 2]))
    # half the Kuhn tetrahedra come out left-handed: swap two corners so that every one has a
    # positive volume (MuJoCo's convention; the force is the same to the bit)
    flip = signed < 0
    tets[flip, 1], tets[flip, 2] = tets[flip, 2].copy(), tets[flip, 1].copy()
    vol = np.abs(signed) / 6.0
    mass = np.zeros(nodes.shape[0])  # lumped: a quarter of each tetrahedron to each corner
    np.add.at(mass, tets.ravel(), np.repeat(p.density_kg_m3 * vol / 4.0, 4))
    return nodes, tets, np.isin(np.arange(nodes.shape[0]), idx[:, :, 0]), mass


def add_plate(spec: mujoco.MjSpec, *, pos, quat=(1.0, 0.0, 0.0, 0.0), plate_mass_kg: float,
              timestep: float) -> None:
    """A plate body at ``pos`` / ``quat`` (world) whose bottom face is its frame's xy plane,
    sliding along its z (joint ``plate_z``; negative qpos presses), driven by a servo."""
    hx, hy, hz = (s * 1e-3 for s in _PLATE_HALF_MM)
    body = spec.worldbody.add_body(name="plate", pos=list(pos), quat=list(quat))
    body.add_joint(name=_PLATE_JOINT, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0.0, 0.0, 1.0])
    body.add_geom(name=_PLATE_GEOM, type=mujoco.mjtGeom.mjGEOM_BOX, size=[hx, hy, hz],
                  pos=[0.0, 0.0, hz], mass=plate_mass_kg, condim=1, contype=CONTACT_BIT,
                  conaffinity=CONTACT_BIT, solref=[_CONTACT_STEPS * timestep, 1.0],
                  solimp=list(_SOLIMP), rgba=[0.55, 0.6, 0.7, 0.5])
    act = spec.add_actuator(name="plate_servo", target=_PLATE_JOINT,
                            trntype=mujoco.mjtTrn.mjTRN_JOINT)
    act.set_to_position(kp=plate_mass_kg * (2 * np.pi * _SERVO_HZ) ** 2, dampratio=1.0)


def set_flex_options(spec: mujoco.MjSpec, timestep: float) -> None:
    """The options a flex pad needs: the ``discrete`` integrator (the only one that integrates
    flex elasticity, implicitly in position), Newton with tolerance 1e-6 (the manual's
    Deformables advice; the M + h^2 K solve may need > 100 iterations), and MuJoCo's default
    convex-collision tolerance of 1 um: each pad element meets the plate through the convex
    collider, whose error enters the penetration (the contact penetrates ~15 um at 2 N); the
    hand's 0.1 mm (`softhand.hands.skeleton.new_spec`) made the pad 60 % stiffer at
    0.4 mm."""
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_DISCRETE
    spec.option.ccd_tolerance = 1e-6
    spec.option.timestep = timestep
    spec.option.solver = mujoco.mjtSolver.mjSOL_NEWTON
    spec.option.tolerance = 1e-6
    spec.option.iterations = 400


def _base_spec(timestep: float) -> mujoco.MjSpec:
    spec = mujoco.MjSpec()
    spec.modelname = "softhand_flex_pad"
    set_flex_options(spec, timestep)
    spec.option.gravity = [0.0, 0.0, 0.0]
    return spec


def add_flex_pad(spec: mujoco.MjSpec, parent: mujoco.MjsBody, params: FlexPadParams, *,
                 timestep: float, pos=(0.0, 0.0, 0.0), rot=None, name: str = _PAD) -> None:
    """Add the pad as flex ``name`` on ``parent`` (the bone: its base nodes are pinned there).

    The pad frame (x across the width, y along the length, z up from the base, origin at the
    base centre) sits at ``pos`` (m) with rotation matrix ``rot`` (3x3, pad axes as columns)
    in ``parent``'s frame. Every other node is a child body of ``parent`` with three slide
    joints along ``parent``'s axes and its lumped mass, so the pad rides an articulated body.
    The flex collides only with geoms that share `CONTACT_BIT` (the plate's).
    """
    params.validate()
    nodes, tets, pinned, mass = _pad_mesh(params)
    rot = np.eye(3) if rot is None else np.asarray(rot, dtype=float)
    nodes = np.asarray(pos, dtype=float) + nodes @ rot.T
    vertbody, vert = [], []
    for n, (p, pin) in enumerate(zip(nodes, pinned, strict=True)):
        if pin:  # the bone: vertex fixed in the parent's frame
            vertbody.append(parent.name)
            vert.extend(p.tolist())
            continue
        # point mass; slide joints only, so rotation never enters (MuJoCo's floor: 1e-15)
        inertia = max(mass[n] * 1e-8, 1e-12)
        body = parent.add_body(name=f"{name}_{n}", pos=p.tolist(), mass=mass[n],
                               inertia=[inertia] * 3, explicitinertial=True)
        for axis in np.eye(3):
            body.add_joint(type=mujoco.mjtJoint.mjJNT_SLIDE, axis=axis.tolist())
        vertbody.append(body.name)
        vert.extend([0.0, 0.0, 0.0])
    flex = spec.add_flex()
    for key, value in {
        "name": name, "dim": 3, "radius": 0.0, "vertbody": vertbody, "vert": vert,
        "elem": tets.ravel().tolist(), "young": params.young_Pa, "poisson": params.poisson,
        "damping": params.damping, "elastic3d": _MATERIALS[params.material],
        "selfcollide": mujoco.mjtFlexSelf.mjFLEXSELF_NONE, "condim": 1,
        "contype": CONTACT_BIT, "conaffinity": CONTACT_BIT,
        "solref": [_CONTACT_STEPS * timestep, 1.0], "solimp": list(_SOLIMP),
        "rgba": [0.9, 0.7, 0.6, 1.0], "flatskin": True,  # smooth normals render it black
    }.items():
        setattr(flex, key, value)


def build_flex_rig(params: FlexPadParams, *, plate_mass_kg: float = 0.02,
                   timestep: float = 1e-3) -> mujoco.MjModel:
    """Compile the flex pad under a servo-driven rigid plate.

    Args:
        params: pad material and mesh.
        plate_mass_kg: plate mass, kg, in [1e-4, 10]; the servo gain scales with it
            (``kp = m (2 pi 500 Hz)^2``, critically damped), so the plate tracks the ramp.
        timestep: simulation step, s, in [1e-5, 5e-3].

    Returns:
        The model: flex ``"pad"`` (dim 3), plate body ``"plate"`` with slide joint ``"plate_z"``
        (qpos = displacement, negative downward) and position actuator ``"plate_servo"``. The
        plate bottom starts at the pad apex. Read the force with `plate_force`.
    """
    params.validate()
    _check("plate_mass_kg", plate_mass_kg, 1e-4, 10.0)
    _check("timestep", timestep, 1e-5, 5e-3)
    spec = _base_spec(timestep)
    add_flex_pad(spec, spec.worldbody, params, timestep=timestep)
    add_plate(spec, pos=[0.0, 0.0, params.height_mm * 1e-3], plate_mass_kg=plate_mass_kg,
               timestep=timestep)
    return spec.compile()


def plate_force(model: mujoco.MjModel, data: mujoco.MjData) -> tuple[float, float]:
    """Sum of normal forces of the plate's contacts (N) and their deepest penetration (m)."""
    gid, f6, total, pen = model.geom(_PLATE_GEOM).id, np.zeros(6), 0.0, 0.0
    for c in range(data.ncon):
        if gid in data.contact[c].geom:
            mujoco.mj_contactForce(model, data, c, f6)
            total, pen = total + f6[0], max(pen, -data.contact[c].dist)
    return total, pen


@dataclass(frozen=True)
class ContactPatch:
    """Where and how hard the plate presses the pad, at one instant.

    Attributes:
        force_N: sum of the plate's normal contact forces.
        area_mm2: contact area, upper bound: each pad surface vertex within ``tol_mm`` of the
            plate's face (or inside it) adds a third of the deformed area of every surface
            triangle it belongs to (its tributary area), so the patch's rim counts whole.
        inner_area_mm2: contact area, lower bound: the surface triangles whose three vertices
            all touch. The two differ by the rim's cells: the mesh's resolution.
        points_mm: (n, 2) in-contact vertices in the plate's frame (x across the pad's width,
            y along its length, from the plate's centre).
        pressure_kPa: (n,) each contact's normal force, given to the nearest in-contact vertex,
            over that vertex's tributary area; ``sum(pressure * area) = force``.
        tributary_mm2: (n,) each vertex's tributary area.
    """

    force_N: float
    area_mm2: float
    inner_area_mm2: float
    points_mm: np.ndarray = field(repr=False)
    pressure_kPa: np.ndarray = field(repr=False)
    tributary_mm2: np.ndarray = field(repr=False)


def contact_patch(model: mujoco.MjModel, data: mujoco.MjData, *, pad: str = _PAD,
                  tol_mm: float = 0.02) -> ContactPatch:
    """The plate's contact patch on flex ``pad`` (after ``mj_step`` or ``mj_forward``).

    ``tol_mm`` (default 0.02 mm): how close to the plate a vertex counts as touching; the
    contact itself penetrates about 0.015 mm at 2 N (module docstring), so 0.02 mm takes in
    every loaded vertex and almost no unloaded one.
    """
    f = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_FLEX, pad)
    if f < 0:
        raise ValueError(f"flex {pad!r} is not in the model")
    gid = model.geom(_PLATE_GEOM).id
    adr, num = model.flex_vertadr[f], model.flex_vertnum[f]
    xpos = data.flexvert_xpos[adr:adr + num]
    frame = data.geom_xmat[gid].reshape(3, 3)
    face = data.geom_xpos[gid] - frame[:, 2] * model.geom_size[gid, 2]
    local = (xpos - face) @ frame  # plate frame: z < 0 below its pressing face (the pad side)
    sadr, snum = model.flex_shelldataadr[f], model.flex_shellnum[f]
    tri = model.flex_shell[sadr:sadr + 3 * snum].reshape(-1, 3)
    e1, e2 = xpos[tri[:, 1]] - xpos[tri[:, 0]], xpos[tri[:, 2]] - xpos[tri[:, 0]]
    tri_area = 0.5 * np.linalg.norm(np.cross(e1, e2), axis=1) * 1e6
    tributary = np.zeros(num)
    np.add.at(tributary, tri.ravel(), np.repeat(tri_area / 3.0, 3))
    touching = np.flatnonzero((local[:, 2] * 1e3 >= -tol_mm) & (tributary > 0))
    force = np.zeros(touching.size)
    n = data.ncon
    con = data.contact
    mine = ((con.geom[:n] == gid).any(axis=1) & (con.flex[:n] == f).any(axis=1)
            & (con.efc_address[:n] >= 0))
    # the pad's contacts are frictionless (condim 1): each is one row, its normal force
    normal = data.efc_force[con.efc_address[:n][mine]]
    total = float(normal.sum())
    if touching.size and normal.size:
        gap = con.pos[:n][mine][:, None, :] - xpos[touching][None, :, :]
        np.add.at(force, np.argmin(np.einsum("cvk,cvk->cv", gap, gap), axis=1), normal)
    area = tributary[touching]
    whole = np.isin(tri, touching).all(axis=1)
    return ContactPatch(force_N=float(total), area_mm2=float(area.sum()),
                        inner_area_mm2=float(tri_area[whole].sum()),
                        points_mm=local[touching, :2] * 1e3,
                        pressure_kPa=np.divide(force, area, out=np.zeros_like(force),
                                               where=area > 0) * 1e3,
                        tributary_mm2=area)


def _run_ramp(model: mujoco.MjModel, *, speed_mm_s: float, depth_mm: float,
              max_force_N: float | None) -> Curve:
    data = mujoco.MjData(model)
    h = model.opt.timestep
    qadr = model.joint(_PLATE_JOINT).qposadr[0]
    n = int(np.ceil(depth_mm / speed_mm_s / h))
    t, delta, force = np.zeros(n), np.zeros(n), np.zeros(n)
    pen_max, steps, t_step, t0 = 0.0, 0, 0.0, time.perf_counter()
    for s in range(n):
        data.ctrl[0] = -min(speed_mm_s * (s + 1) * h, depth_mm) * 1e-3
        t1 = time.perf_counter()
        mujoco.mj_step(model, data)
        t_step += time.perf_counter() - t1
        steps += 1
        f, pen = plate_force(model, data)
        t[s], delta[s], force[s] = data.time, -data.qpos[qadr] * 1e3, f
        pen_max = max(pen_max, pen)
        bad = data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
        if bad or not np.isfinite(data.qpos).all():
            raise FloatingPointError(f"flex ramp diverged at step {s} (t = {data.time:.4f} s, "
                                     f"timestep {h}, delta {delta[s - 1] if s else 0:.3f} mm)")
        if max_force_N is not None and f >= max_force_N:
            break
    return Curve.simulated(t[:steps], delta[:steps], force[:steps], label="flex",
                           wall_s=time.perf_counter() - t0, steps=steps, step_wall_s=t_step,
                           max_penetration_mm=pen_max * 1e3,
                           n_warnings=int(sum(w.number for w in data.warning)))


def simulate_flex_indentation(params: FlexPadParams, *, speed_mm_s: float = 0.5,
                              depth_mm: float, timestep: float = 1e-3,
                              plate_mass_kg: float = 0.02,
                              max_force_N: float | None = None) -> Curve:
    """Press the plate into the pad at constant speed and record force against displacement.

    Args:
        params: pad material and mesh.
        speed_mm_s: commanded plate speed, mm/s, in [0.01, 100].
        depth_mm: commanded final plate travel from first touch, mm, in (0, 0.6 * height].
        timestep: simulation step, s.
        plate_mass_kg: plate mass, kg.
        max_force_N: stop early once the plate force reaches this (N); None runs the full ramp.

    Returns:
        A simulated `Curve`, one sample per step (``displacement_mm``:
        the measured plate travel; ``stats``: ``wall_s``, ``steps``, ``step_wall_s`` in
        ``mj_step`` alone, ``max_penetration_mm``, ``n_warnings``).

    Raises:
        FloatingPointError: the simulation produced a bad (NaN or huge) acceleration.
    """
    _check("speed_mm_s", speed_mm_s, 0.01, 100.0)
    _check("depth_mm", depth_mm, 1e-6, 0.6 * params.height_mm + 1e-9)
    model = build_flex_rig(params, plate_mass_kg=plate_mass_kg, timestep=timestep)
    return _run_ramp(model, speed_mm_s=speed_mm_s, depth_mm=depth_mm, max_force_N=max_force_N)


def fit_flex(delta_mm, force_N, *, speed_mm_s: float = 0.5, seed: int = 0,
             base: FlexPadParams | None = None, young_guess_Pa: float | None = None,
             fit_poisson: bool = False, timestep: float = 1e-3, max_sims: int = 40) -> FlexFit:
    """Fit Young's modulus (and optionally Poisson's ratio) to a force-displacement ramp.

    ``scipy.optimize.least_squares`` (trust region; forward differences with a 2 % step, far above
    the simulation noise) on ``(F_sim(delta_i) - F_i) / 2 N`` in ``young / young_guess`` (the force
    is linear in it) and ``poisson`` in [0, 0.49]. Each residual is one ramp simulation to
    ``max(delta) + 0.05 mm``, cached.

    Args:
        delta_mm: target displacements, mm (increasing, starting at or near 0).
        force_N: target forces, N.
        speed_mm_s: ramp speed, mm/s (0.5 in the FE).
        seed: seeds a log-uniform jitter of the young guess in [1/1.5, 1.5] (restarts); 0: none.
        base: mesh, damping and starting Poisson's ratio (default ``FlexPadParams()``).
        young_guess_Pa: initial Young's modulus; default ``base.young_Pa``.
        fit_poisson: also fit Poisson's ratio.
        timestep: simulation step, s.
        max_sims: cap on the number of ramp simulations (function evaluations).

    Returns:
        The fit, with its RMS and maximum error in % of 2 N over the target points.
    """
    t0 = time.perf_counter()
    d_t, f_t = np.asarray(delta_mm, dtype=float), np.asarray(force_N, dtype=float)
    if d_t.ndim != 1 or d_t.shape != f_t.shape or d_t.size < 2:
        raise ValueError(f"delta_mm and force_N must be 1D of equal length >= 2, got "
                         f"{d_t.shape} and {f_t.shape}")
    if np.any(np.diff(d_t) < 0) or d_t[0] < 0:
        raise ValueError("delta_mm must be non-negative and non-decreasing")
    base = FlexPadParams() if base is None else base
    e0 = base.young_Pa if young_guess_Pa is None else float(young_guess_Pa)
    if seed:
        e0 *= float(np.exp(np.random.default_rng(seed).uniform(-np.log(1.5), np.log(1.5))))
    _check("young_guess_Pa", e0, 1e3, 1e9)
    depth = float(d_t.max()) + 0.05
    cache: dict[tuple[float, ...], np.ndarray] = {}
    step_s: list[float] = []

    def params_of(x: np.ndarray) -> FlexPadParams:
        young = float(np.clip(x[0] * e0, 1e3, 1e9))
        return replace(base, young_Pa=young, poisson=float(x[1]) if fit_poisson else base.poisson)

    def residual(x: np.ndarray) -> np.ndarray:
        key = tuple(np.round(x, 12))
        if key not in cache:
            curve = simulate_flex_indentation(params_of(x), speed_mm_s=speed_mm_s,
                                              depth_mm=depth, timestep=timestep)
            cache[key] = curve.force_at(d_t)
            step_s.append(curve.stats["step_wall_s"] / curve.stats["steps"])
        return (cache[key] - f_t) / 2.0

    # young is unbounded (clipped in params_of): a bound makes the trust region crawl towards it
    x0 = np.array([1.0, base.poisson] if fit_poisson else [1.0])
    lo = [-np.inf, 0.0] if fit_poisson else [-np.inf]
    hi = [np.inf, 0.49] if fit_poisson else [np.inf]
    sol = least_squares(residual, x0, bounds=(lo, hi), diff_step=0.02, x_scale=1.0,
                        max_nfev=max(1, max_sims // (len(x0) + 1)), xtol=1e-3, ftol=1e-4)
    res = residual(sol.x)
    err = 100.0 * res  # residuals are in units of 2 N
    return FlexFit(params=params_of(sol.x), rms_error_pct_of_2N=float(np.sqrt(np.mean(err**2))),
                   max_error_pct_of_2N=float(np.abs(err).max()), n_simulations=len(cache),
                   wall_s=time.perf_counter() - t0, force_sim_N=res * 2.0 + f_t,
                   success=fit_status(sol, "flex Young's modulus") is FitStatus.CONVERGED,
                   step_us=1e6 * float(np.mean(step_s)))


def flex_cost_ratio(params: FlexPadParams | None = None, *, timestep: float = 1e-3,
                    depth_mm: float = 0.3, speed_mm_s: float = 5.0) -> tuple[float, float, float]:
    """Wall time per step of the flex rig over a rigid plate pressing a rigid box, same timestep.

    Same plate, servo, ramp and ``discrete`` integrator; the rigid pad is a fixed box of the pad's
    bounding size. Only ``mj_step`` is timed. Returns ``(ratio, flex_s_step, rigid_s_step)``.
    """
    params = FlexPadParams() if params is None else params
    flex = _run_ramp(build_flex_rig(params, timestep=timestep), speed_mm_s=speed_mm_s,
                     depth_mm=depth_mm, max_force_N=None)
    spec = _base_spec(timestep)
    half = [params.width_mm / 2e3, params.length_mm / 2e3, params.height_mm / 2e3]
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=half, pos=[0, 0, half[2]],
                            condim=1, solref=[_CONTACT_STEPS * timestep, 1.0],
                            solimp=list(_SOLIMP))
    add_plate(spec, pos=[0.0, 0.0, 2 * half[2]], plate_mass_kg=0.02, timestep=timestep)
    rigid = _run_ramp(spec.compile(), speed_mm_s=speed_mm_s, depth_mm=depth_mm, max_force_N=None)
    a, b = (c.stats["step_wall_s"] / c.stats["steps"] for c in (flex, rigid))
    return a / b, a, b
