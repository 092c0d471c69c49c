"""Statistics of a study, with rliable (Agarwal et al., NeurIPS 2021).

Per learner, over the reported tasks and seeds: the final score's IQM, mean and optimality
gap with 95% stratified-bootstrap confidence intervals, the performance profile (fraction of
runs scoring above tau) with bands, the probability of improvement of each learner over each
other, and IQM learning curves over env steps with bands; plus success rate and the env steps
and seconds (wall and CPU) to the first success and to convergence.

The score of a run is SPL, success weighted by path length: the BFS optimum over the greedy
path's length if the path reaches the target, else 0 (1 = optimal), averaged over the task's
evaluation targets (goal tasks have several).
"""

from __future__ import annotations

import zlib
from typing import Any, Callable

import numpy as np

#: Bootstrap replications (rliable's performance-profile default).
REPS = 2000
TAUS = np.linspace(0.0, 1.0, 41)


#: What an interval reads as when there is one run per task: a stratified bootstrap then has
#: nothing to resample, and its "interval" is the point itself.
NO_CI = "(1 seed: no CI)"


def fmt_steps(v: Any) -> str:
    """Env steps for a table: ``30k``, ``1.00M``, ``512``; ``—`` for None."""
    if v is None:
        return "—"
    v = float(v)
    if v >= 1e6:
        return f"{v / 1e6:.2f}M"
    if v >= 1e4:
        return f"{v / 1e3:.0f}k"
    return f"{v:.0f}"


def fmt_ci(point: float, ci: list[float], digits: int = 3) -> str:
    """``0.800 [0.733, 0.867]``; a zero-width interval (every resample the same: all runs
    scored alike) reads ``1.000 (all equal)``, not as certainty."""
    if ci[1] - ci[0] < 10.0 ** (-digits - 2):
        return f"{point:.{digits}f} (all equal)"
    return f"{point:.{digits}f} [{ci[0]:.{digits}f}, {ci[1]:.{digits}f}]"


def interval_text(point: float, lo_hi: list[float], seeds: int = 2, digits: int = 2) -> str:
    """``0.60 [0.42, 0.89]``, or ``0.60 (1 seed: no CI)`` with one run per task."""
    if seeds < 2:
        return f"{point:.{digits}f} {NO_CI}"
    return f"{point:.{digits}f} [{lo_hi[0]:.{digits}f}, {lo_hi[1]:.{digits}f}]"


def rliable_library() -> Any:
    """``rliable.library`` (its stratified bootstraps need arch < 8, which needs pandas < 3:
    the ``bench`` extra pins both). rliable draws its resampling indices from NumPy's global
    generator: :func:`seeded` seeds it, so the intervals are reproducible."""
    from rliable import library

    return library


def seeded(seed: int = 0) -> None:
    np.random.seed(seed)  # noqa: NPY002 (rliable resamples with the global generator)


def key_seed(seed: int, key: str) -> int:
    """The bootstrap seed of one learner (or pair of learners) ``key`` in a study seeded
    with ``seed``: a stream of its own, so adding a learner's runs to a study leaves every
    other learner's intervals as they were."""
    return (int(seed) * 1_000_003 + zlib.crc32(key.encode())) % 2**32


def per_key(
    estimate: Callable[[dict[str, Any]], tuple[dict[str, Any], dict[str, Any]]],
    data: dict[str, Any],
    seed: int,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """rliable's ``(point, interval)`` dicts of ``estimate`` over ``data``, one key at a time,
    each with the global generator seeded by :func:`key_seed` (rliable draws a key's
    resamples after the previous key's, so one call over every key would tie them)."""
    point: dict[str, Any] = {}
    ci: dict[str, Any] = {}
    for k, v in data.items():
        seeded(key_seed(seed, k))
        p, c = estimate({k: v})
        point.update(p)
        ci.update(c)
    return point, ci


def score_matrices(
    runs: list[dict[str, Any]], learners: list[str], tasks: list[str]
) -> tuple[dict[str, np.ndarray], list[int]]:
    """Per learner, final scores as (seeds, tasks); only seeds every (learner, task) has."""
    by = {(r["spec"]["learner"], r["spec"]["task"]["id"], r["spec"]["seed"]): r for r in runs}
    seeds = sorted({k[2] for k in by})
    common = [s for s in seeds if all((lr, t, s) in by for lr in learners for t in tasks)]
    out = {
        lr: np.array([[by[(lr, t, s)]["result"]["score"] for t in tasks] for s in common])
        for lr in learners
    }
    return out, common


def curve_on(grid: np.ndarray, curve: list[dict[str, Any]], key: str = "score") -> np.ndarray:
    """A run's curve as a step function on ``grid`` (the last value carried forward; 0 before
    the first point)."""
    xs = np.array([p["env_steps"] for p in curve])
    ys = np.array([p[key] for p in curve])
    idx = np.searchsorted(xs, grid, side="right") - 1
    return np.where(idx >= 0, ys[np.clip(idx, 0, None)], 0.0)


def aggregates(
    scores: dict[str, np.ndarray],
    seed: int = 0,
    reps: int = REPS,
    poi_exclude: tuple[str, ...] = (),
) -> dict[str, Any]:
    """IQM, mean and optimality gap with 95% CIs; performance profiles; probability of
    improvement for every ordered pair of learners (but those in ``poi_exclude``)."""
    from rliable import metrics

    rly = rliable_library()

    def agg(x: np.ndarray) -> np.ndarray:
        return np.array(
            [
                metrics.aggregate_iqm(x),
                metrics.aggregate_mean(x),
                metrics.aggregate_optimality_gap(x),
            ]
        )

    point, ci = per_key(lambda d: rly.get_interval_estimates(d, agg, reps=reps), scores, seed)
    profiles, profile_cis = per_key(
        lambda d: rly.create_performance_profile(d, TAUS, reps=reps), scores, seed
    )
    names = [k for k in scores if k not in poi_exclude]
    # P(Y > X) = 1 - P(X > Y): one bootstrap per unordered pair.
    pairs = {
        f"{a},{b}": (scores[a], scores[b]) for i, a in enumerate(names) for b in names[i + 1 :]
    }
    poi_point: dict[str, Any] = {}
    poi_ci: dict[str, Any] = {}
    if pairs:
        poi_point, poi_ci = per_key(
            lambda d: rly.get_interval_estimates(d, metrics.probability_of_improvement, reps=reps),
            pairs,
            seed,
        )
    out: dict[str, Any] = {"learners": {}, "taus": TAUS.tolist(), "poi": {}}
    for k in scores:
        out["learners"][k] = {
            # Runs per task (with one, `interval_text` prints no interval).
            "seeds": int(np.shape(scores[k])[0]),
            "iqm": float(point[k][0]),
            "iqm_ci": [float(ci[k][0][0]), float(ci[k][1][0])],
            "mean": float(point[k][1]),
            "mean_ci": [float(ci[k][0][1]), float(ci[k][1][1])],
            "optimality_gap": float(point[k][2]),
            "optimality_gap_ci": [float(ci[k][0][2]), float(ci[k][1][2])],
            "profile": profiles[k].tolist(),
            "profile_ci": [profile_cis[k][0].tolist(), profile_cis[k][1].tolist()],
        }
    for pair in pairs:
        p = float(np.asarray(poi_point[pair]).ravel()[0])
        lo, hi = float(np.ravel(poi_ci[pair][0])[0]), float(np.ravel(poi_ci[pair][1])[0])
        a, b = pair.split(",")
        out["poi"][pair] = {"p": p, "ci": [lo, hi]}
        out["poi"][f"{b},{a}"] = {"p": 1.0 - p, "ci": [1.0 - hi, 1.0 - lo]}
    return out


def iqm_curves(
    runs: list[dict[str, Any]], learners: list[str], tasks: list[str], seeds: list[int],
    grid: np.ndarray, seed: int = 0, reps: int = REPS // 4,
) -> dict[str, Any]:  # fmt: skip
    """IQM of the score over (seeds, tasks) at each env step of ``grid``, with 95% CIs."""
    import scipy.stats

    rly = rliable_library()
    by = {(r["spec"]["learner"], r["spec"]["task"]["id"], r["spec"]["seed"]): r for r in runs}
    data = {
        lr: np.array(
            [[curve_on(grid, by[(lr, t, s)]["result"]["curve"]) for t in tasks] for s in seeds]
        )
        for lr in learners
    }

    def iqm_at(x: np.ndarray) -> np.ndarray:
        # rliable's aggregate_iqm at every grid point at once (the same trimmed mean).
        return scipy.stats.trim_mean(x.reshape(-1, x.shape[-1]), proportiontocut=0.25, axis=0)

    point, ci = per_key(lambda d: rly.get_interval_estimates(d, iqm_at, reps=reps), data, seed)
    return {
        lr: {
            "iqm": point[lr].tolist(),
            "lo": ci[lr][0].tolist(),
            "hi": ci[lr][1].tolist(),
            # The curve is defined up to the longest run (later values are carried forward).
            "max_env_steps": max(
                by[(lr, t, s)]["result"]["curve"][-1]["env_steps"] for t in tasks for s in seeds
            ),
        }
        for lr in learners
    }


def median_or_none(xs: list[float]) -> float | None:
    return float(np.median(xs)) if xs else None


def milestone(runs: list[dict[str, Any]], key: str, prefix: str) -> dict[str, float | None]:
    """Medians of env steps, wall and CPU seconds to a milestone (first success,
    convergence) over the runs that reached it."""
    return {
        f"{prefix}_steps": median_or_none([r["result"][key]["env_steps"] for r in runs]),
        f"{prefix}_wall_s": median_or_none([r["timing"][key]["wall_time_s"] for r in runs]),
        f"{prefix}_cpu_s": median_or_none([r["timing"][key]["cpu_time_s"] for r in runs]),
    }


def per_learner(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Plain figures over a set of runs: success rate, score, and the medians (over the runs
    that got there) of env steps and seconds to the first success and to convergence."""
    n = len(runs)
    firsts = [r for r in runs if r["result"]["first_success"] is not None]
    convs = [r for r in runs if r["result"]["convergence"] is not None]
    alg2 = [r["result"]["algorithm2"] for r in runs if r["result"].get("algorithm2")]
    alg2_ok = alg2
    alg1 = [r["result"].get("algorithm1") for r in runs if "algorithm1" in r["result"]]
    return {
        "runs": n,
        "success_rate": float(np.mean([r["result"]["success"] for r in runs])) if n else None,
        "score_mean": float(np.mean([r["result"]["score"] for r in runs])) if n else None,
        "env_steps_median": median_or_none([r["result"]["env_steps"] for r in runs]),
        "wall_time_s_median": median_or_none([r["timing"]["wall_time_s"] for r in runs]),
        "cpu_time_s_median": median_or_none([r["timing"]["cpu_time_s"] for r in runs]),
        "first_success_rate": len(firsts) / n if n else None,
        **milestone(firsts, "first_success", "first_success"),
        "convergence_rate": len(convs) / n if n else None,
        **milestone(convs, "convergence", "convergence"),
        "algorithm1_pass_rate": float(np.mean([bool(a and a["complete"]) for a in alg1]))
        if alg1
        else None,
        "algorithm2_runs": len(alg2_ok),
        "algorithm2_success_rate": float(np.mean([a["success"] for a in alg2_ok]))
        if alg2_ok
        else None,
        "replans_mean": float(np.mean([a["replans"] for a in alg2_ok])) if alg2_ok else None,
    }


def plateau(runs: list[dict[str, Any]], learners: list[str]) -> dict[str, dict[str, Any]]:
    """Per learner, whether the curves had flattened by the end of the budget: the mean score
    at a quarter, half and all of each run's env steps; the fraction of runs whose score
    still changed in the second half of their budget; the mean of each run's best checkpoint
    score and the fraction of runs that ended below their best (found a path, then lost it)."""
    out: dict[str, dict[str, Any]] = {}
    for lr in learners:
        at: list[np.ndarray] = []
        for r in runs:
            if r["spec"]["learner"] != lr or not r["result"]["curve"]:
                continue
            end = max(p["env_steps"] for p in r["result"]["curve"])
            q, h, e = curve_on(np.array([end / 4, end / 2, end]), r["result"]["curve"])
            # Still changing: a checkpoint after end/2 differs from the score at end/2.
            late = [p["score"] for p in r["result"]["curve"] if p["env_steps"] > end / 2]
            changed = any(abs(v - h) > 1e-12 for v in late)
            best = max(p["score"] for p in r["result"]["curve"])
            at.append(np.array([q, h, e, float(changed), best, float(e < best - 1e-12)]))
        if at:
            m = np.mean(at, axis=0)
            out[lr] = {
                "runs": len(at),
                "quarter": float(m[0]),
                "half": float(m[1]),
                "end": float(m[2]),
                "changed_late": float(m[3]),
                "best": float(m[4]),
                "fell_from_best": float(m[5]),
            }
    return out


# ------------------------------------------------------------------------------------------
# Benchmark v2: statistics that fit near-binary outcomes (docs/BENCHMARKS.md, "Statistics")

#: IQM is shown only when fewer than this fraction of the scores are exactly 0 or 1: with
#: more, the middle half of the sorted scores is mostly zeros and ones and the IQM is a
#: stretched copy of the mean (about clip((mean - 0.25) / 0.5, 0, 1)), not a robust centre.
IQM_DEGENERATE_FRACTION = 0.75

#: The SPL a run must reach for "env steps to SPL >= 0.95".
SPL_REACHED = 0.95

#: z of a two-sided 95% interval.
Z95 = 1.959963984540054


def wilson(successes: int, trials: int, z: float = Z95) -> dict[str, float]:
    """Wilson score interval of a binomial proportion (95% by default): the success rate
    ``successes / trials`` with bounds that stay inside [0, 1] and do not collapse to a
    point at 0 or 1 (as the normal approximation does)."""
    if trials < 1 or not 0 <= successes <= trials:
        raise ValueError(f"wilson: successes {successes} of trials {trials}")
    p = successes / trials
    z2 = z * z
    centre = (p + z2 / (2 * trials)) / (1 + z2 / trials)
    half = z / (1 + z2 / trials) * np.sqrt(p * (1 - p) / trials + z2 / (4 * trials * trials))
    return {
        "rate": p,
        "lo": 0.0 if successes == 0 else max(0.0, float(centre - half)),
        "hi": 1.0 if successes == trials else min(1.0, float(centre + half)),
        "successes": int(successes),
        "trials": int(trials),
    }


def success_count(runs: list[dict[str, Any]]) -> tuple[int, int]:
    """Successes out of trials over runs: each run counts one trial per evaluation target
    (its ``result.success`` is the fraction of its targets reached)."""
    k = n = 0
    for r in runs:
        m = len(r["result"]["optimal_lengths"])
        k += round(float(r["result"]["success"]) * m)
        n += m
    return k, n


def degenerate_fraction(x: np.ndarray) -> float:
    """The fraction of the scores that are exactly 0 or 1."""
    x = np.asarray(x, dtype=float).ravel()
    return float(np.mean((x == 0.0) | (x == 1.0))) if x.size else 1.0


def iqm_shown(x: np.ndarray) -> bool:
    """IQM is meaningful for these scores (see :data:`IQM_DEGENERATE_FRACTION`)."""
    return degenerate_fraction(x) < IQM_DEGENERATE_FRACTION


def budget_of_run(r: dict[str, Any]) -> int:
    """The budget of the axis a run belongs to (``spec.budget_axis``; else its budget)."""
    return int(r["spec"].get("budget_axis") or r["spec"]["budget"])


def steps_to(curve: list[dict[str, Any]], level: float = SPL_REACHED) -> int | None:
    """Env steps of the first checkpoint whose score is >= ``level`` (None: never)."""
    for p in curve:
        if p["score"] >= level - 1e-12:
            return int(p["env_steps"])
    return None


def kaplan_meier(times: np.ndarray, observed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The Kaplan-Meier survival curve: event times and S just after each (a run
    "survives" until it reaches the level; censored runs never did within their budget)."""
    times = np.asarray(times, dtype=float)
    observed = np.asarray(observed, dtype=bool)
    ts = np.unique(times[observed])
    s, out = 1.0, []
    for t in ts:
        at_risk = np.sum(times >= t)
        events = np.sum((times == t) & observed)
        s *= 1.0 - events / at_risk
        out.append(s)
    return ts, np.array(out)


def km_median(times: np.ndarray, observed: np.ndarray) -> float | None:
    """The Kaplan-Meier median: the first event time where S <= 1/2 (None: half the runs or
    more never reached the level within their budget, the median is beyond it)."""
    ts, s = kaplan_meier(times, observed)
    hit = np.flatnonzero(s <= 0.5 + 1e-12)
    return float(ts[hit[0]]) if hit.size else None


def steps_to_level(
    runs: list[dict[str, Any]], level: float = SPL_REACHED, seed: int = 0, reps: int = REPS
) -> dict[str, Any]:
    """Env steps to SPL >= ``level`` over runs, censored at each run's budget: the
    Kaplan-Meier median with a 95% interval from a bootstrap of the runs stratified by task
    (percentiles; a bound is None where the resampled median lies beyond the budget), and the
    fraction of runs that reached it."""
    times, observed, strata = [], [], []
    for r in runs:
        t = steps_to(r["result"]["curve"], level)
        observed.append(t is not None)
        times.append(t if t is not None else r["result"]["env_steps"] or r["spec"]["budget"])
        strata.append(r["spec"]["task"]["id"])
    times_a, obs_a = np.array(times, dtype=float), np.array(observed, dtype=bool)
    if not len(times_a):
        return {"runs": 0, "reached": 0, "median": None, "ci": [None, None]}
    rng = np.random.default_rng(seed)
    groups = [np.flatnonzero(np.array(strata) == g) for g in dict.fromkeys(strata)]
    meds = []
    for _ in range(reps):
        idx = np.concatenate([rng.choice(g, size=len(g), replace=True) for g in groups])
        m = km_median(times_a[idx], obs_a[idx])
        meds.append(np.inf if m is None else m)
    lo, hi = np.percentile(meds, [2.5, 97.5], method="lower")
    return {
        "runs": len(times_a),
        "reached": int(obs_a.sum()),
        "median": km_median(times_a, obs_a),
        "ci": [None if np.isinf(lo) else float(lo), None if np.isinf(hi) else float(hi)],
    }


def mean_ci(scores: np.ndarray, seed: int = 0, reps: int = REPS) -> tuple[float, list[float]]:
    """Mean of (runs, tasks) scores with its 95% stratified-bootstrap interval (rliable;
    tasks as strata)."""
    from rliable import metrics

    rly = rliable_library()
    seeded(seed)
    point, ci = rly.get_interval_estimates(
        {"x": np.asarray(scores, dtype=float)},
        lambda x: np.array([metrics.aggregate_mean(x)]),
        reps=reps,
    )
    return float(point["x"][0]), [float(ci["x"][0][0]), float(ci["x"][1][0])]


def plateaued(here: dict[str, Any], there: dict[str, Any]) -> bool:
    """A learner's mean SPL at the next budget (``there["mean"]``) lies inside its 95%
    interval at this one (``here["mean_ci"]``): the plateau test of docs/BENCHMARKS.md."""
    lo, hi = here["mean_ci"]
    return bool(lo - 1e-12 <= there["mean"] <= hi + 1e-12)


def headline_budget(
    by_budget: dict[int, dict[str, dict[str, Any]]], best: list[str]
) -> dict[str, Any]:
    """The headline budget of an axis: the smallest budget at which every learner of
    ``best`` has plateaued, i.e. its mean SPL at the next budget of the axis lies inside its
    95% interval at this one. ``by_budget[B][learner]`` holds ``mean`` and ``mean_ci``. With
    no such budget, the largest (``plateaued`` False: the plateau is not shown)."""
    budgets = sorted(by_budget)
    checks = []
    for b, nxt in zip(budgets, budgets[1:]):
        rows = {}
        for lr in best:
            here, there = by_budget[b].get(lr), by_budget[nxt].get(lr)
            if here is None or there is None:
                rows[lr] = None
                continue
            rows[lr] = plateaued(here, there)
        checks.append({"budget": b, "next": nxt, "within": rows})
        if rows and all(v is True for v in rows.values()):
            return {"budget": b, "plateaued": True, "checks": checks, "best": list(best)}
    return {"budget": budgets[-1], "plateaued": False, "checks": checks, "best": list(best)}


def best_learners(rows: dict[str, dict[str, Any]]) -> list[str]:
    """The learners whose mean SPL interval overlaps that of the top learner (by mean):
    those the data cannot tell from the best."""
    if not rows:
        return []
    top = max(rows, key=lambda lr: rows[lr]["mean"])
    lo_top = rows[top]["mean_ci"][0]
    return [lr for lr in rows if rows[lr]["mean_ci"][1] >= lo_top - 1e-12]
