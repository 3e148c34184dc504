"""The multi-objective search: optuna over the design space, a 2D screen, then a 3D check.

Sampler: optuna's ``TPESampler(multivariate=True, constant_liar=True)`` by default. Multivariate
TPE models the variables jointly (the pocket's height, span and roof act together on the roof's
bending), needs no population, and so learns from the first few dozen FE runs, the budget of an FE
screen; the constant liar keeps the designs of one batch (run at once on workers) apart. The
alternative, NSGA-II (``NSGAIISampler``), evolves a population (default 50) and needs several
generations; `compare_samplers` measures both on one budget by the hypervolume of the front
(``reports/design-search-samplers.md``).

Storage: an optuna ``JournalStorage`` on a file journal in the output folder
(``journal.log``), appended after every trial, so that ``--resume`` continues the same study
after Ctrl-C (the trials that were running then are marked failed, ``interrupted``, and do not
count). Trials run in batches through `softhand.parallel.run_tasks` (this process, local worker
processes, or a Dask cluster), asked and told by this process only, which alone writes the
journal.

Each trial's variables are fractions of the dependent ranges (`DesignSpace.candidate`) and two
categorical materials; its values are the two objectives (`softhand.design.evaluate`); a design
the FE cannot carry to the force (no equilibrium) is a failed trial with the reason kept.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from softhand.design.evaluate import (
    OBJECTIVES,
    SCREEN_CONTACT_POINTS,
    Evaluation,
    evaluate,
    screen_settings,
)
from softhand.design.space import VARIABLES, Candidate, DesignSpace
from softhand.fem.library import library
from softhand.parallel import run_tasks

__all__ = ["SAMPLERS", "SearchOutcome", "compare_samplers", "hypervolume", "make_sampler",
           "open_study", "pareto_evaluations", "run_search", "study_contact_points"]

SAMPLERS = ("tpe", "nsga2")
STUDY = "design-search"
JOURNAL = "journal.log"


def make_sampler(name: str, seed: int | None):
    """``tpe`` (default, module docstring) or ``nsga2``."""
    import optuna

    if name == "tpe":
        return optuna.samplers.TPESampler(multivariate=True, constant_liar=True, seed=seed,
                                          n_startup_trials=10)
    if name == "nsga2":
        return optuna.samplers.NSGAIISampler(seed=seed, population_size=20)
    raise ValueError(f"sampler = {name!r}: allowed {', '.join(SAMPLERS)}")


#: The FE's contact points per face direction of a study made before they could be chosen
_CONTACT_POINTS_BEFORE = 4


def _config(space: DesignSpace, mesh: str, max_force_N: float,
            contact_points: int = _CONTACT_POINTS_BEFORE) -> dict[str, Any]:
    return {"bounds": {k: list(v) for k, v in space.bounds.items()},
            "materials": list(space.materials), "mesh": mesh, "max_force_N": max_force_N,
            "contact_points": contact_points, "objectives": list(OBJECTIVES)}


def open_study(out: str | Path, space: DesignSpace, *, sampler: str = "tpe",
               seed: int | None = 0, resume: bool = False, mesh: str = "default",
               max_force_N: float = 2.0, contact_points: int | None = None):
    """The study in ``out/journal.log``: new, or (``resume``) the one there.

    ``contact_points`` (`screen_settings`): None is `SCREEN_CONTACT_POINTS` for a new study and
    the journal's own number for a resumed one (4 for a journal from before the choice).

    Raises:
        ValueError: a journal exists without ``resume``; ``resume`` without a journal; or a
            journal of another space, mesh, force or number of contact points (naming the
            difference).
    """
    import optuna
    from optuna.storages import JournalStorage
    from optuna.storages.journal import JournalFileBackend

    path = Path(out) / JOURNAL
    if path.exists() and not resume:
        raise ValueError(f"{path} holds a study already: add --resume to continue it, or choose "
                         "another --out")
    if resume and not path.exists():
        raise ValueError(f"--resume: {path} does not exist (nothing to resume); run without "
                         "--resume to start a study there")
    Path(out).mkdir(parents=True, exist_ok=True)
    storage = JournalStorage(JournalFileBackend(str(path)))
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(study_name=STUDY, storage=storage, load_if_exists=resume,
                                directions=["minimize"] * len(OBJECTIVES),
                                sampler=make_sampler(sampler, seed))
    if resume and seed is not None:  # a fresh stream: the seed's first draws were made already
        study.sampler = make_sampler(sampler, seed + len(study.get_trials(deepcopy=False)))
    old = study.user_attrs.get("config")
    if old is not None and "contact_points" not in old:  # a study from before the choice
        old = {**old, "contact_points": _CONTACT_POINTS_BEFORE}
    if contact_points is None:
        contact_points = SCREEN_CONTACT_POINTS if old is None else old["contact_points"]
    config = _config(space, mesh, max_force_N, contact_points)
    if old is None:
        study.set_user_attr("config", config)
        study.set_user_attr("sampler", sampler)
    elif old != config:
        diff = [f"{k} {old.get(k)!r} (the journal) vs {config[k]!r} (this run)"
                for k in config if old.get(k) != config[k]]
        raise ValueError(f"--resume: {path} is a study of other settings ({'; '.join(diff)})")
    return study


def study_contact_points(study) -> int:
    """The contact points per face direction the study's runs use (`open_study`)."""
    return int(study.user_attrs["config"].get("contact_points", _CONTACT_POINTS_BEFORE))


def _counted(study) -> int:
    """Finished trials: complete, or failed by the FE (not interrupted)."""
    from optuna.trial import TrialState

    stale = set(study.user_attrs.get("interrupted_trials", []))
    return sum(1 for t in study.get_trials(deepcopy=False)
               if t.state == TrialState.COMPLETE
               or (t.state == TrialState.FAIL and t.number not in stale
                   and t.user_attrs.get("error") != "interrupted"))


def _close_stale(study) -> None:
    """Trials left running by an interrupted run: failed, and listed in the study's
    ``interrupted_trials`` (they do not count)."""
    from optuna.trial import TrialState

    running = [t.number for t in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,))]
    if not running:
        return
    for number in running:
        study.tell(number, state=TrialState.FAIL)
    study.set_user_attr("interrupted_trials",
                        sorted({*study.user_attrs.get("interrupted_trials", []), *running}))


def _ask(study, space: DesignSpace) -> tuple[Any, Candidate]:
    trial = study.ask()
    fractions = {name: trial.suggest_float(name, 0.0, 1.0) for name in VARIABLES}
    inner = trial.suggest_categorical("inner", list(space.materials))
    outer = trial.suggest_categorical("outer", list(space.materials))
    cand = space.candidate(fractions, inner, outer)
    trial.set_user_attr("candidate", cand.to_dict())
    return trial, cand


@dataclass(frozen=True)
class SearchOutcome:
    """What a search run did.

    Attributes:
        study: the optuna study (its journal holds every trial).
        done_before: trials finished before this run (a resume).
        ran: trials this run finished (complete or failed).
        failed: this run's failed trials and why.
        interrupted: Ctrl-C stopped it.
        wall_s: this run's wall time.
    """

    study: Any
    done_before: int
    ran: int
    failed: dict[int, str] = field(default_factory=dict)
    interrupted: bool = False
    wall_s: float = 0.0


def run_search(space: DesignSpace, *, trials: int, out: str | Path, seed: int | None = 0,
               sampler: str = "tpe", resume: bool = False, mesh: str = "default",
               max_force_N: float = 2.0, threads: int | None = 1, cluster: str | None = None,
               progress: Callable[[int, int], None] | None = None,
               contact_points: int | None = None) -> SearchOutcome:
    """Run (or continue) the 2D screen until ``trials`` trials have finished.

    Args:
        trials: total finished trials wanted in the study (a resume counts those in the journal).
        contact_points: the FE's contact points per face direction in every run
            (`screen_settings`): 2 (`SCREEN_CONTACT_POINTS`), or 4, the FE's default and the
            shipped search's (about half as fast); None: 2 for a new study, the journal's own
            for a resumed one.
        threads: local worker processes (1: this process, one trial at a time; N: batches of
            4 N trials, the sampler asked for all of a batch before it runs); not with
            ``cluster``.
        cluster: a Dask scheduler's address: batches of 8 on its workers.
        progress: called with (finished trials, ``trials``) once the study is open and after
            each trial.

    Raises:
        ValueError: ``trials`` < 1, a material without an elongation at break (durability needs
            it), or a study that `open_study` refuses.
    """
    import time

    if isinstance(trials, bool) or not isinstance(trials, int) or trials < 1:
        raise ValueError(f"trials = {trials!r}: allowed an integer >= 1")
    no_break = [m for m in space.materials if library()[m].elongation_at_break_pct is None]
    if no_break:
        allowed = ", ".join(n for n, m in library().items() if m.elongation_at_break_pct)
        raise ValueError(f"materials: {', '.join(no_break)} has no elongation at break in the "
                         f"library (durability cannot be scored); allowed: {allowed}")
    t0 = time.perf_counter()
    study = open_study(out, space, sampler=sampler, seed=seed, resume=resume, mesh=mesh,
                       max_force_N=max_force_N, contact_points=contact_points)
    _close_stale(study)
    before = _counted(study)
    if progress:
        progress(before, trials)
    settings = screen_settings(mode="2d", mesh=mesh, max_force_N=max_force_N,
                               contact_points=study_contact_points(study))
    workers = 1 if cluster is not None else max(1, threads or 1)
    # local workers start with each batch (parallel.run_tasks): batches of 4 per worker amortise
    # that; the cluster's workers stay up, 8 at a time keep them busy
    batch_size = 8 if cluster is not None else (1 if workers == 1 else 4 * workers)
    failed: dict[int, str] = {}
    ran, interrupted = 0, False
    try:  # the loop's test too: a Ctrl-C right after a trial's progress lands there
        while before + ran < trials and not interrupted:
            n = min(batch_size, trials - before - ran)
            asked = dict(_ask(study, space) for _ in range(n))
            by_number = {t.number: (t, c) for t, c in asked.items()}
            tasks = [(num, (c, settings)) for num, (_, c) in by_number.items()]
            outcome = run_tasks(evaluate, tasks, threads=None if cluster else min(n, workers),
                                cluster=cluster)
            for num, (trial, _) in by_number.items():
                if num in outcome.results:
                    ev: Evaluation = outcome.results[num]
                    trial.set_user_attr("evaluation", ev.to_dict())
                    if any(v is None for v in ev.objectives):
                        why = "2 N not reached" if ev.lifelike_distance_pct is None else "no usage"
                        trial.set_user_attr("error", why)
                        study.tell(trial, state=_fail())
                        failed[num] = why
                    else:
                        study.tell(trial, list(ev.objectives))
                elif num in outcome.errors:
                    why = " ".join(str(outcome.errors[num]).split())[:300]
                    trial.set_user_attr("error", why)
                    study.tell(trial, state=_fail())
                    failed[num] = why
                else:
                    trial.set_user_attr("error", "interrupted")
                    study.tell(trial, state=_fail())
                    continue
                ran += 1
                if progress:
                    progress(before + ran, trials)
            interrupted = outcome.interrupted
    except KeyboardInterrupt:  # between two FE runs (asking, telling): stop here too;
        interrupted = True     # a trial asked and not told is closed on --resume
    return SearchOutcome(study=study, done_before=before, ran=ran, failed=failed,
                         interrupted=interrupted, wall_s=time.perf_counter() - t0)


def _fail():
    from optuna.trial import TrialState

    return TrialState.FAIL


def completed(study) -> list[dict[str, Any]]:
    """Every complete trial's evaluation (dict), with its trial number."""
    from optuna.trial import TrialState

    return [{"trial": t.number, **t.user_attrs["evaluation"]}
            for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))]


def pareto_evaluations(study) -> list[dict[str, Any]]:
    """The Pareto set (optuna's ``best_trials``), sorted by lifelike distance."""
    rows = [{"trial": t.number, **t.user_attrs["evaluation"]} for t in study.best_trials]
    return sorted(rows, key=lambda r: r["lifelike_distance_pct"])


def candidate_of(row: dict[str, Any]) -> Candidate:
    c = row["candidate"]
    return Candidate(**{k: c[k] for k in VARIABLES}, inner=c["inner"], outer=c["outer"])


def hypervolume(points: np.ndarray, reference: tuple[float, float]) -> float:
    """Area dominated by 2-objective ``points`` (minimised) up to ``reference``."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    pts = pts[np.all(pts < np.asarray(reference), axis=1)]
    if not len(pts):
        return 0.0
    pts = pts[np.argsort(pts[:, 0])]
    area, best_y = 0.0, reference[1]
    for x, y in pts:
        if y < best_y:
            area += (reference[0] - x) * (best_y - y)
            best_y = y
    return float(area)


def compare_samplers(space: DesignSpace, *, trials: int, seeds: tuple[int, ...], out: str | Path,
                     mesh: str = "default", reference: tuple[float, float] = (60.0, 0.2),
                     progress: Callable[[str], None] | None = None,
                     contact_points: int = SCREEN_CONTACT_POINTS) -> dict[str, Any]:
    """Run each sampler for ``trials`` trials per seed; the hypervolume of each front.

    Returns:
        ``{"trials", "seeds", "reference", "samplers": {name: {"hypervolume": [per seed],
        "mean", "best_lifelike_pct": [per seed], "wall_s"}}}``.
    """
    import time

    result: dict[str, Any] = {"trials": trials, "seeds": list(seeds), "mesh": mesh,
                              "reference": list(reference), "objectives": list(OBJECTIVES),
                              "contact_points": contact_points,
                              "space": asdict(space), "samplers": {}}
    for name in SAMPLERS:
        row: dict[str, Any] = {"hypervolume": [], "best_lifelike_pct": [], "wall_s": []}
        for seed in seeds:
            t0 = time.perf_counter()
            folder = Path(out) / f"{name}-seed{seed}"
            s = run_search(space, trials=trials, out=folder, seed=seed, sampler=name, mesh=mesh,
                           resume=(folder / JOURNAL).exists(), contact_points=contact_points)
            pts = np.array([t.values for t in s.study.best_trials])
            row["hypervolume"].append(hypervolume(pts, reference))
            row["best_lifelike_pct"].append(float(pts[:, 0].min()) if len(pts) else None)
            row["wall_s"].append(time.perf_counter() - t0)
            if progress:
                progress(f"{name} seed {seed}: hypervolume {row['hypervolume'][-1]:.3f}")
        row["mean"] = float(np.mean(row["hypervolume"]))
        result["samplers"][name] = row
    return result


def dump(data: Any) -> str:
    return json.dumps(data, indent=1, default=float)
