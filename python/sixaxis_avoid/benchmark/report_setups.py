"""How the runs' hyperparameter setups differ, for the v2 page (docs/BENCHMARKS.md): which
implementation each SB3 learner runs (the headline's *Implementation* line), where a
learner's values change along the budget axis (*Score by budget*), and runs that a re-run on
other values replaced, against the runs that replaced them (the headline's *Replaced runs*).

Entry points: :func:`implementation_line`, :func:`tuning_changes` and
:func:`tuning_changes_line`, :func:`replaced_at` and :func:`replaced_line`. Each reads a v2
report's analysis (``report_v2.analyse_v2``) or a part of it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sixaxis_avoid.benchmark import stats
from sixaxis_avoid.benchmark.stats import fmt_ci, fmt_steps

#: What each implementation of an SB3 learner is, for the headline's *Implementation* line
#: (learner -> implementation -> note).
IMPLEMENTATION_NOTES = {
    "ppo": {
        "rejax": "`learners.PPO_IMPLEMENTATIONS`: SB3 PPO with rejax 0.1.3's initialisation, "
        "gradient clipping per network, truncation as termination and value clipping, the "
        "implementation jax_ppo's values were tuned on; with SB3's own they starve its actor: "
        "*JAX against SB3*, the ablation",
        "sb3": "SB3's own PPO, on the values SB3's own search chose at this budget "
        "(`sb3_tune`, *Tuning record*)",
    },
    "dqn": {
        "rejax": "`learners.DQN_IMPLEMENTATIONS`: SB3 DQN with rejax 0.1.3's squared TD-error "
        "loss, initialisation, truncation as termination, train_freq envs stepped once "
        "between update phases and plain replay (no HER) on the goal task, the implementation "
        "jax_dqn's values were tuned on; with SB3's Huber loss they fail: *JAX against SB3*",
        "sb3": "SB3's own DQN, on the values SB3's own search chose at this budget "
        "(`sb3_tune`, *Tuning record*)",
    },
}


def implementation_line(impl: dict[str, list[str]]) -> str:
    """The headline's *Implementation* line: each learner's implementations at the headline
    budget (learner -> sorted names), each with its note when it has one."""
    return (
        "**Implementation**: "
        + "; ".join(
            f"{lr} runs with `implementation: {x}`"
            + (f" ({note})" if (note := IMPLEMENTATION_NOTES.get(lr, {}).get(x)) else "")
            for lr, v in impl.items()
            for x in v
        )
        + "."
    )


def tuning_changes(a: dict[str, Any]) -> list[dict[str, Any]]:
    """Adjacent budgets of the axis at which a learner's runs differ in where their
    hyperparameters came from (``hyperparams_status``) or in their implementation: its
    plateau mark between them then compares runs on different values, not only on more env
    steps. One entry per learner and pair: ``learner``, ``budgets`` (the two, in env steps)
    and ``setups`` (each budget's status and implementation, as sorted lists)."""
    out = []
    bs = a["budgets"]
    for lr in a["learners"]:
        for x, y in zip(bs, bs[1:]):
            gx = a["per_budget"][x]["learners"].get(lr)
            gy = a["per_budget"][y]["learners"].get(lr)
            if gx is None or gy is None:
                continue
            sx = (gx["status"], gx.get("implementation", []))
            sy = (gy["status"], gy.get("implementation", []))
            if sx != sy:
                out.append({"learner": lr, "budgets": [x, y], "setups": [sx, sy]})
    return out


def tuning_changes_line(changes: list[dict[str, Any]]) -> str:
    """The *Score by budget* line naming :func:`tuning_changes` ('' when there are none)."""
    if not changes:
        return ""

    def setup(st: tuple[list[str], list[str]]) -> str:
        status, impl = st
        return "; ".join(status) + (f"; implementation {', '.join(impl)}" if impl else "")

    return (
        "**Hyperparameters change along the axis** here, so these marks compare runs on "
        "different values, not only on more env steps: "
        + "; ".join(
            f"{c['learner']} from {fmt_steps(c['budgets'][0])} ({setup(c['setups'][0])}) to "
            f"{fmt_steps(c['budgets'][1])} ({setup(c['setups'][1])})"
            for c in changes
        )
        + "."
    )


def replaced_at(a: dict[str, Any], b: int, reps: int = 2000) -> list[dict[str, Any]]:
    """Each learner whose runs at budget ``b`` (env steps) replaced earlier ones on other
    hyperparameters (``a["replaced"]``, kept beside the study): the earlier runs' status,
    mean final SPL with its 95% stratified-bootstrap interval and success count, against
    the study's runs on the same (task, seed) pairs: how many score higher on each side,
    and the difference of the means (study minus earlier)."""
    out = []
    study = {
        (r["spec"]["learner"], r["spec"]["task"]["id"], r["spec"]["seed"]): r
        for r in a["runs"]
        if stats.budget_of_run(r) == b
    }
    for rs in a.get("replaced", []):
        old = [r for r in rs["runs"] if stats.budget_of_run(r) == b]
        pairs = [
            (r, study[k])
            for r in old
            if (k := (r["spec"]["learner"], r["spec"]["task"]["id"], r["spec"]["seed"])) in study
        ]
        if not pairs:
            continue
        lr = old[0]["spec"]["learner"]
        tasks = [t for t in a["tasks"] if any(r["spec"]["task"]["id"] == t for r, _ in pairs)]
        scores, seeds = stats.score_matrices([r for r, _ in pairs], [lr], tasks)
        if not seeds:
            continue
        mean, ci = stats.mean_ci(scores[lr], reps=reps)
        now = float(np.mean([n["result"]["score"] for _, n in pairs]))
        before = float(np.mean([r["result"]["score"] for r, _ in pairs]))
        out.append(
            {
                "learner": lr,
                "dir": rs["dir"],
                "status": sorted({r["spec"].get("hyperparams_status", "n/a") for r, _ in pairs}),
                "runs": len(pairs),
                "mean": mean,
                "mean_ci": ci,
                "success": stats.success_count([r for r, _ in pairs]),
                "higher_before": sum(r["result"]["score"] > n["result"]["score"] for r, n in pairs),
                "higher_now": sum(n["result"]["score"] > r["result"]["score"] for r, n in pairs),
                "diff": now - before,
            }
        )
    return out


def replaced_line(rows: list[dict[str, Any]], b: int) -> str:
    """The headline's *Replaced runs* line (:func:`replaced_at`; '' without any)."""
    if not rows:
        return ""
    return (
        "**Replaced runs**: "
        + "; ".join(
            f"{r['learner']}'s {r['runs']} runs at {fmt_steps(b)} on {', '.join(r['status'])}, "
            f"which its runs above replaced (`{r['dir']}`), scored a mean SPL of "
            f"{fmt_ci(r['mean'], r['mean_ci'])} with {r['success'][0]}/{r['success'][1]} "
            f"targets reached: the runs above score {r['diff']:+.3f} against them on the same "
            f"tasks and seeds (higher in {r['higher_now']} of the {r['runs']} pairs, lower in "
            f"{r['higher_before']}, equal in the rest)"
            for r in rows
        )
        + "."
    )
