"""The v2 page's *Tuning record* and *Compute* sections: the hyperparameters each learner
ran on at each budget, and what the study cost, per learner and budget, read from the tuning
record's trials files and the run files (docs/BENCHMARKS.md, *Tuning record*, *Compute*).

Entry points: :func:`tuning_rows` and :func:`compute_rows` (each section's lines, from
:func:`report_v2.analyse_v2`'s analysis).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from sixaxis_avoid.benchmark import hyperparams as hpmod
from sixaxis_avoid.benchmark import stats
from sixaxis_avoid.benchmark.stats import fmt_steps

#: A (learner, budget) row before anything is added: ``tuned`` is 1 once a trials file of
#: its own is read; times in seconds.
ZERO = {"tuned": 0.0, "tune_wall": 0.0, "tune_cpu": 0.0, "wall": 0.0, "cpu": 0.0, "steps": 0.0}

#: The JAX part's goal: the whole study of the JAX learners, tuning included, in 2 hours of
#: wall time on the 2-core machine the project is developed on (seconds).
JAX_GOAL_S = 2 * 3600.0

#: The cores of the machine the goal is set on.
GOAL_CORES = 2


def tuning_env_steps(trials: dict[str, Any]) -> int:
    """Env steps a search trained: for every trial, task and seed, its curve's last
    checkpoint (on the goal task, counted over all targets)."""
    seeds = len(trials.get("seeds", []))
    return sum(
        int(curve["env_steps"][-1]) * seeds
        for t in trials.get("trials", [])
        for curve in t.get("curves", {}).values()
        if curve.get("env_steps")
    )


def _trials_file(path: str) -> Path | None:
    """A tuning record's trials file, by its path from the working directory or from the
    repository (as the hyperparameter file records it)."""
    for p in (Path(path), hpmod.HYPERPARAMS_DIR.parents[3] / path):
        if p.is_file():
            return p
    return None


def near_best(path: str) -> tuple[int, int] | None:
    """How decisive a search was, from its trials file (``path`` as the hyperparameter file
    records it): ``(near, of)``, the candidates whose objective lies within one run's full
    score of the best one's (``1 / (seeds x tasks)``, the best included) out of all that were
    scored. The search cannot tell those apart; None when the file or its counts are
    missing."""
    f = _trials_file(path)
    if f is None:
        return None
    data = json.loads(f.read_text())
    runs = len(data.get("seeds", [])) * len(data.get("tasks", []))
    objs = [t["objective"] for t in data.get("trials", []) if t.get("objective") is not None]
    if not runs or not objs:
        return None
    top = max(objs)
    return sum(o >= top - 1.0 / runs - 1e-12 for o in objs), len(objs)


def compute_rows(a: dict[str, Any]) -> list[str]:
    """What the study cost, per learner and budget: its tuning search's wall and CPU time
    (each trials file counted once, for the learner it tuned) and its runs' wall time and
    training CPU time (a JAX run's are its share of its vmapped group's), with the totals per
    family of learner."""
    data = hpmod.load(a["suite"].raw.get("hyperparams", a["suite"].name))
    rows: dict[tuple[str, int], dict[str, float]] = {}
    family: dict[str, str] = {}
    for r in a["runs"]:
        key = (r["spec"]["learner"], stats.budget_of_run(r))
        family[key[0]] = r["spec"]["family"]
        e = rows.setdefault(key, dict(ZERO))
        timing = r.get("timing", {})  # a run file without timing adds nothing
        e["wall"] += float(timing.get("run_wall_time_s", timing.get("wall_time_s", 0.0)))
        e["cpu"] += float(timing.get("cpu_time_s", 0.0))
        e["steps"] += float(r.get("result", {}).get("env_steps") or 0)
    seen: set[Path] = set()
    for lr, entry in data.get("learners", {}).items():
        for b, e in entry.get("by_budget", {}).items():
            f = _trials_file(e["trials"]) if e.get("trials") else None
            if f is None or f.resolve() in seen:
                continue
            t = json.loads(f.read_text())
            if t.get("learner", lr) != lr or "wall_time_s" not in t:
                continue
            seen.add(f.resolve())
            row = rows.setdefault((lr, int(b)), dict(ZERO))
            row["tuned"] = 1.0
            row["tune_wall"] += float(t["wall_time_s"])
            row["tune_cpu"] += float(t.get("cpu_time_s", 0.0))
            row["steps"] += tuning_env_steps(t)
    if not rows:
        return []

    def h(x: float) -> str:
        return f"{x / 3600:.2f}"

    out = [
        "## Compute",
        "",
        "Hours per learner and budget, from the trials files of the tuning record and the run "
        "files: tuning wall and CPU time, and the runs' wall time (one process per run; a JAX "
        "run's share of its vmapped group's) and training CPU time (evaluation excluded). The "
        "runs shared the machine with other work, so wall times are upper bounds. —: no "
        "search of its own (another learner's values, or nothing to tune).",
        "",
        "| learner | budget | tuning wall (h) | tuning CPU (h) | runs wall (h) | runs CPU (h) |",
        "|---|---|---|---|---|---|",
    ]
    totals: dict[str, list[float]] = {}
    for (lr, b), e in sorted(rows.items(), key=lambda kv: (kv[0][0], kv[0][1])):
        tune = f"{h(e['tune_wall'])} | {h(e['tune_cpu'])}" if e["tuned"] else "— | —"
        out.append(f"| {lr} | {fmt_steps(b)} | {tune} | {h(e['wall'])} | {h(e['cpu'])} |")
        t = totals.setdefault(family.get(lr, "?"), [0.0, 0.0, 0.0])
        t[0] += e["tune_wall"] + e["wall"]
        t[1] += e["tune_cpu"] + e["cpu"]
        t[2] += e["steps"]
    out += [
        "",
        "Per family, tuning and runs: "
        + "; ".join(
            f"{fam} {h(w)} h wall, {h(c)} h CPU" for fam, (w, c, _) in sorted(totals.items())
        )
        + ".",
        "",
    ]
    if "jax" in totals:
        w, c, steps = totals["jax"]
        todo = [
            f"{lr} at {', '.join(fmt_steps(b) for b in bs)}"
            for lr, bs in a.get("missing_budgets", {}).items()
            if family.get(lr) == "jax"
        ]
        met = w <= JAX_GOAL_S and not todo
        out += [
            f"**Goal for the JAX part** (its learners' tuning and runs at every budget, on this "
            f"machine): {h(JAX_GOAL_S)} h of wall time. "
            + ("Met" if met else "Not met")
            + f": {h(w)} h wall and {h(c)} core-hours so far ({w / JAX_GOAL_S:.1f}x the goal)"
            + (f", with {'; '.join(todo)} still to run" if todo else "")
            + ".",
            "",
        ]
        if c > 0 and steps > 0:
            floor = c / GOAL_CORES
            ratio = floor / JAX_GOAL_S
            out += [
                f"Why: the JAX learners trained {steps / 1e6:,.0f}M env steps so far (every "
                f"search trial's seeds, compiling included, and every run's first training; "
                f"Algorithm 2's re-plan rounds are in the runs' wall time but not here) in "
                f"{h(c)} core-hours: {steps / c:,.0f} env steps per core-second. With all "
                f"{GOAL_CORES} cores busy all the time that work alone takes {h(floor)} h "
                f"({ratio:.1f}x the goal), so no schedule meets the goal at this "
                f"rate: it needs the training itself {ratio:.1f}x faster per core"
                + (", before the budgets still to run" if todo else "")
                + ".",
                "",
            ]
    return out


def tuning_rows(a: dict[str, Any]) -> list[str]:
    """The tuning record per learner and budget (``by_budget`` of the hyperparameter file),
    beside the status the runs recorded."""
    hp_name = a["suite"].raw.get("hyperparams", a["suite"].name)
    data = hpmod.load(hp_name)
    learners = list(
        dict.fromkeys([*data.get("learners", {}), *[lr for lr in a.get("learners", [])]])
    )
    recorded: dict[tuple[str, int], set[str]] = {}
    for r in a["runs"]:
        key = (r["spec"]["learner"], stats.budget_of_run(r))
        recorded.setdefault(key, set()).add(r["spec"].get("hyperparams_status", "n/a"))
    out = [
        f"Hyperparameter file: `{hpmod.display_path(data['path'])}`"
        + ("" if Path(data["path"]).exists() else " (not written yet: no learner is tuned)")
        + ". A run at budget B takes the values tuned at B; without them it runs with the "
        "learner's defaults and is marked **untuned** (never values tuned at another budget). "
        "*Near the best*: the candidates whose objective lies within one run's full score of "
        "the best one's (1 / (seeds x tasks) of the search, the best included), out of all "
        "scored; the search cannot tell them apart, so on the study's tasks its choice among "
        "them may do better or worse than another of them.",
        "",
        "| learner | budget | status | trials | objective | near the best | status in the run "
        "files |",
        "|---|---|---|---|---|---|---|",
    ]
    best_only = a["suite"].best_only
    missing = a.get("missing_budgets", {})
    for lr in learners:
        by = data.get("learners", {}).get(lr, {}).get("by_budget", {})
        for b in a["axis"]:
            e = by.get(str(b))
            statuses = recorded.get((lr, b), set())
            if e is None and not statuses and b in best_only and b not in missing.get(lr, []):
                continue  # a budget for the best learners only, not due (*Statistics*)
            runs = ", ".join(sorted(statuses)) or "no runs"
            if e is None:
                # A learner without hyperparameters to tune (BFS) is "n/a", not "untuned".
                status = "n/a" if statuses == {"n/a"} else "**untuned**"
                out.append(f"| {lr} | {fmt_steps(b)} | {status} | — | — | — | {runs} |")
                continue
            obj = e.get("objective")
            obj_s = f"{obj:.3f}" if isinstance(obj, (int, float)) else str(obj or "—")
            trials = f"`{e['trials']}`" if e.get("trials") else "—"
            near = near_best(e["trials"]) if e.get("trials") else None
            near_s = f"{near[0]} of {near[1]}" if near else "—"
            out.append(
                f"| {lr} | {fmt_steps(b)} | {e.get('status', 'tuned')} | {trials} | {obj_s} "
                f"| {near_s} | {runs} |"
            )
    if not learners:
        out.append("| (none yet) | — | **untuned** | — | — | — | — |")
    return out
