"""A population of handshake partners like the paper's 30 subjects, and the paper's experiment over it.

The paper's handshake experiment: one experimenter (190 x 88 mm hand, Table 1) shook hands with 30
male subjects; the sensors on the experimenter's hand recorded each region's force, and Fig. 4
marks the regions where it exceeded 2 N. Here each partner is drawn from published
distributions; each quantity, its distribution (normal ones truncated at +-2.5 SD) and its source:

- hand length: normal, 187.5 +- 11.37 mm; paper Table 1 (subjects)
- hand width: normal, 89.53 +- 6.80 mm, independent of the length; paper Table 1 (independence is
  an assumption: Table 1 gives no correlation)
- grip per phalanx: normal, 2.5 +- 0.5 N; mean: Melnyk et al., IEEE AIM 2014 (data gloves; their
  "average strength of the grip", read as per phalanx: an assumption,
  softhand.envs.partner.GRIP_FORCE_N); SD: an assumption (20 %)
- duration: normal, 3.63 +- 0.45 s, Cabibihan et al., Front. Robot. AI 2022, as a factor on the
  timeline's phases (softhand.envs.partner.Timeline: 4.15 s, its closing and opening phases
  added to the published 3.63 s): the partner's duration is 4.15 s x (drawn / 3.63), and the
  phases scale together
- shake phase: uniform in [0, 2 pi)

`sample_partners` draws them from one seed (reproducible); `run_partner` runs one
handshake for one partner (a module-level function, so it runs in worker processes);
`run_population` runs many partners' handshakes together on the vector env (one world per
partner, stepped by mujoco.batch, the controllers for all worlds at once) with the results of
`run_partner` for each (equal to 1e-9 N; tests/test_population.py);
`population_summary` gives per region the share of partners over 2 N and the distribution
of the peak force, beside the paper's set.
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass

import numpy as np

from softhand.envs.partner import GRIP_FORCE_N, PARTNER_SD_RANGE, Timeline
from softhand.paper import paper

__all__ = [
    "DURATION_S",
    "GRIP_SD_N",
    "Partner",
    "population_summary",
    "run_partner",
    "run_population",
    "sample_partners",
]

#: Standard deviation of the grip per phalanx across partners (N). assumption: 20 % of the mean;
#: no published spread of handshake grip force was found.
GRIP_SD_N = 0.2 * GRIP_FORCE_N
#: Handshake duration, mean and SD (s): Cabibihan et al., Front. Robot. AI 2022.
DURATION_S = (3.63, 0.45)


@dataclass(frozen=True)
class Partner:
    """One sampled handshake partner.

    Attributes:
        index: position in the population (0-based).
        seed: the episode's seed (its sensor noise).
        hand_length_mm, hand_width_mm: the partner's hand (mm).
        grip_N: its grip per touching phalanx (N).
        duration_s: the handshake's duration (s).
        shake_phase_rad: the shake's phase (rad).
    """

    index: int
    seed: int
    hand_length_mm: float
    hand_width_mm: float
    grip_N: float
    duration_s: float
    shake_phase_rad: float

    def to_dict(self) -> dict:
        return asdict(self)


def _truncated_normal(rng: np.random.Generator, mean: float, sd: float) -> float:
    while True:
        x = rng.normal(mean, sd)
        if abs(x - mean) <= PARTNER_SD_RANGE * sd:
            return float(x)


def sample_partners(n: int, seed: int = 0) -> list[Partner]:
    """``n`` partners drawn from the module's distributions with ``seed``.

    Raises:
        ValueError: ``n`` not an integer >= 1 or ``seed`` not an integer >= 0.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n = {n!r}: allowed an integer >= 1")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed = {seed!r}: allowed an integer >= 0")
    subjects = paper()["anthropometry"]
    (lm, ls), (wm, ws) = subjects["subjects_hand_length_mm"], subjects["subjects_hand_width_mm"]
    rng = np.random.default_rng(seed)
    out = []
    for i in range(int(n)):
        out.append(Partner(
            index=i, seed=int(rng.integers(2**31)),
            hand_length_mm=_truncated_normal(rng, lm, ls),
            hand_width_mm=_truncated_normal(rng, wm, ws),
            grip_N=_truncated_normal(rng, GRIP_FORCE_N, GRIP_SD_N),
            duration_s=_truncated_normal(rng, *DURATION_S) * Timeline().total_s / DURATION_S[0],
            shake_phase_rad=float(rng.uniform(0.0, 2 * np.pi))))
    return out


def run_partner(partner: Partner, settings: dict) -> dict:
    """One handshake with ``partner``; ``settings``: HandshakeEnv keywords (design, skins,
    representation, timestep_s, ...) and ``controller``. Returns what the population keeps:
    per region peak and mean force (N), the regions over 2 N, the force accounting, the grip
    tracking, how many warnings the run raised (its episode's summary of the contacts beyond their
    calibrated range, and any from building the scene) and the wall time (s). The warnings are
    counted, then passed on as they were (in a worker process, `softhand.parallel.run_tasks`
    brings them back to the main process)."""
    import time

    from softhand.envs.handshake import HandshakeEnv
    from softhand.envs.run import run_handshake

    settings = dict(settings)
    controller = settings.pop("controller", "neutral")
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:  # counted for the results
        warnings.simplefilter("always")
        env = HandshakeEnv(partner_size=(partner.hand_length_mm, partner.hand_width_mm),
                           randomize=False, **settings)
        run = run_handshake(env=env, controller=controller, seed=partner.seed, options={
            "grip_N": partner.grip_N, "duration_s": partner.duration_s,
            "shake_phase_rad": partner.shake_phase_rad})
    for w in caught:  # and passed on, where they were raised
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    table = run.table()
    return {"partner": partner.to_dict(),
            "peak_N": {r: v["peak_N"] for r, v in table.items()},
            "mean_N": {r: v["mean_N"] for r, v in table.items()},
            "over_2N": run.over_2n,
            "force_accounting": run.force_accounting(),
            "grip": run.grip_tracking(),
            "warnings": len(caught),
            "wall_s": time.perf_counter() - t0}


def run_population(partners: list[Partner], settings: dict, *, nthread: int = 1
                   ) -> tuple[list[dict], dict[int, str]]:
    """The handshakes of ``partners`` on one vector env (softhand.envs.vector), one world each:
    what `run_partner` returns for each partner, in one batch. ``settings`` as for
    run_partner; ``nthread``: threads of each mujoco.batch Batch (1, the default, in a worker
    process of softhand.parallel, which holds one core; the cores this process may use, alone).

    Each world is built as run_partner builds its env (its construction's warnings counted for
    it), runs one episode (AutoresetMode.DISABLED: a world that ended stands still) and records
    every env step as run_handshake does: forces, phase, the partner's grip, and the force
    accounting of the world's contacts (ContactAreas on the world's MjData from the batch).
    ``wall_s`` of each result is its share of the batch's wall time, building included.

    Returns:
        The results of the partners whose handshake ran to its end, in order, and per partner
        index that diverged the `DivergenceError` text.
    """
    import time

    from softhand.envs.controllers import make_controller
    from softhand.envs.handshake import HandshakeEnv
    from softhand.envs.physics import DivergenceError, mujoco_warnings_kept
    from softhand.envs.run import ContactAreas, HandshakeRun, law_labels, pair_laws
    from softhand.envs.vector import AutoresetMode, HandshakeVectorEnv

    settings = dict(settings)
    controller = settings.pop("controller", "neutral")
    t0 = time.perf_counter()
    envs, caught = [], []
    for p in partners:
        with warnings.catch_warnings(record=True) as built:  # counted per partner
            warnings.simplefilter("always")
            envs.append(HandshakeEnv(partner_size=(p.hand_length_mm, p.hand_width_mm),
                                     randomize=False, **settings))
        caught.append(list(built))
    vec = HandshakeVectorEnv(envs=envs, nthread=nthread, autoreset_mode=AutoresetMode.DISABLED)
    n = len(partners)
    areas = []
    for e in envs:
        m = e.model
        areas.append(ContactAreas(m, [m.geom(g).id for g in e.region_geoms], pair_laws(e),
                                  [m.site(f"pro_touch_{r}").id for r in e.region_names]))
    frames: list[dict[str, list]] = [{k: [] for k in ("t", "f", "s", "ph", "g", "a", "acc")}
                                     for _ in range(n)]
    ended = np.zeros(n, bool)
    errors: dict[int, str] = {}
    ctrl = make_controller(controller)
    ending: list[list] = [[] for _ in range(n)]  # each world's warnings at its episode's end
    with warnings.catch_warnings(record=True) as during:
        warnings.simplefilter("always")
        obs, info = vec.reset(seed=[p.seed for p in partners], options={
            "grip_N": [p.grip_N for p in partners],
            "duration_s": [p.duration_s for p in partners],
            "shake_phase_rad": [p.shake_phase_rad for p in partners]})
        while not ended.all():
            del during[:]
            with mujoco_warnings_kept():  # a divergence is reported below, not printed
                obs, _, term, trunc, info = vec.step(ctrl.actions(obs, info, vec.region_names))
            # a world whose episode ended with contacts beyond range warned once, in world order
            warned = [w for w in np.flatnonzero((term | trunc) & ~ended)
                      if info["beyond_range_summary"][w]["contact_steps"]
                      or info["beyond_range_summary"][w]["bone_steps"]]
            for w, record in zip(warned, list(during), strict=False):
                ending[w].append(record)
            now = vec.physics.time
            for w in np.flatnonzero(~ended):
                if term[w]:
                    e = envs[w]
                    errors[partners[w].index] = str(DivergenceError(
                        vec.physics.divergence[w], skins=e.skins,
                        representations=e.representations,
                        timestep_s=float(e.model.opt.timestep)))
                    continue
                fr = frames[w]
                fr["t"].append(float(now[w]))
                fr["f"].append(info["region_forces_N"][w])
                fr["s"].append(info["sensor_readings_N"][w])
                fr["ph"].append(info["phase"][w])
                fr["g"].append((info["partner_grip_measured_N"][w], info["partner_grip_N"][w]))
                area, _, _ = areas[w](vec.physics.data(int(w)))
                fr["a"].append(area)
                fr["acc"].append(areas[w].accounting.copy())
            ended |= term | trunc
    share = (time.perf_counter() - t0) / n
    results = []
    for w, (p, e) in enumerate(zip(partners, envs, strict=True)):
        for x in (*caught[w], *ending[w]):  # passed on, where they were raised
            warnings.warn_explicit(x.message, x.category, x.filename, x.lineno)
        if p.index in errors:
            continue
        fr = frames[w]
        run = HandshakeRun(e.region_names, dict(e.skins), np.array(fr["t"]), np.zeros((0, 0)),
                           np.zeros((0, 3)), np.zeros((0, 4)), np.array(fr["f"]), [],
                           fr["ph"], share, 0, e.model, np.array(fr["a"]),
                           accounting=np.array(fr["acc"]), sensor_reading_N=np.array(fr["s"]),
                           partner_grip_N=np.array(fr["g"]), law_labels=tuple(law_labels(e)),
                           contact_laws=e.contact_laws, geometry_N=dict(areas[w].geometry))
        table = run.table()
        results.append({"partner": p.to_dict(),
                        "peak_N": {r: v["peak_N"] for r, v in table.items()},
                        "mean_N": {r: v["mean_N"] for r, v in table.items()},
                        "over_2N": run.over_2n,
                        "force_accounting": run.force_accounting(),
                        "grip": run.grip_tracking(),
                        "warnings": len(caught[w]) + len(ending[w]),
                        "wall_s": share})
    vec.close()
    return results, errors


def population_summary(results: list[dict]) -> dict[str, dict]:
    """Per region over the partners: the share over 2 N (%), the median and the 10th / 90th
    percentiles of the peak force (N), and whether the paper's Fig. 4 has it over 2 N."""
    if not results:
        return {}
    ref = set(paper()["handshake"]["over_2N"])
    regions = list(results[0]["peak_N"])
    out = {}
    for r in regions:
        peaks = np.array([res["peak_N"][r] for res in results])
        out[r] = {"over_2N_pct": float(100 * np.mean(peaks > 2.0)),
                  "median_peak_N": float(np.median(peaks)),
                  "p10_peak_N": float(np.percentile(peaks, 10)),
                  "p90_peak_N": float(np.percentile(peaks, 90)),
                  "paper_over_2N": r in ref}
    return out
