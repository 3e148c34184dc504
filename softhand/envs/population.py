"""A population of handshake partners like the paper's 30 subjects, and the paper's experiment over it.

The paper's handshake experiment: one experimenter (190 x 88 mm hand, Table 1) shook hands with 30
male subjects; the sensors on the experimenter's hand recorded each region's force, and Fig. 4
marks the regions where it exceeded 2 N. Here each partner is drawn from published distributions:

================== ===================================================== =========================
quantity           distribution (truncated at +-2.5 SD)                  source
================== ===================================================== =========================
hand length        normal, 187.5 +- 11.37 mm                            paper Table 1 (subjects)
hand width         normal, 89.53 +- 6.80 mm, independent of the length   paper Table 1; independence
                                                                         is an assumption (Table 1
                                                                         gives no correlation)
grip per phalanx   normal, 2.5 +- 0.5 N                                  mean: Melnyk et al., IEEE
                                                                         AIM 2014 (data gloves);
                                                                         SD: assumption (20 %)
duration           normal, 3.63 +- 0.45 s (phases scale together)        Cabibihan et al., Front.
                                                                         Robot. AI 2022
shake phase        uniform in [0, 2 pi)                                  -
================== ===================================================== =========================

:func:`sample_partners` draws them from one seed (reproducible); :func:`run_partner` runs one
handshake for one partner (a module-level function, so it runs in worker processes);
:func:`population_summary` gives per region the share of partners over 2 N and the distribution
of the peak force, beside the paper's set.
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass

import numpy as np

from softhand.envs.partner import GRIP_FORCE_N, PARTNER_SD_RANGE
from softhand.paper import paper

__all__ = [
    "DURATION_S",
    "GRIP_SD_N",
    "Partner",
    "population_summary",
    "run_partner",
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
            duration_s=_truncated_normal(rng, *DURATION_S),
            shake_phase_rad=float(rng.uniform(0.0, 2 * np.pi))))
    return out


def run_partner(partner: Partner, settings: dict) -> dict:
    """One handshake with ``partner``; ``settings``: HandshakeEnv keywords (design, skins,
    representation, timestep_s, ...) and ``controller``. Returns what the population keeps:
    per region peak and mean force (N), the regions over 2 N, the force accounting, the grip
    tracking, how many warnings the run raised (its episode's summary of the contacts beyond their
    calibrated range, and any from building the scene) and the wall time (s). The warnings are
    counted, then passed on as they were (in a worker process, :func:`softhand.parallel.run_tasks`
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
