"""docs/BENCHMARKS.md for a suite with a budget axis (suite v2), from its result files.

``python -m sixaxis_avoid.benchmark report --results docs/results/v2`` reads ``study.json``
and ``runs/*.json`` (one run per learner, task, seed and budget of the axis) and writes one
page: the headline at the headline budget (the smallest budget of the axis at which the best
learners have plateaued, shown with the score of every learner at every budget), success
rates with Wilson intervals, SPL with stratified-bootstrap intervals, IQM where it is not
degenerate, per-task tables, all learners' curves on one env-steps axis, performance
profiles, probability of improvement, env steps to SPL >= 0.95 (censored at the budget), the
tuning record per learner and budget, and a link to the history (v1's page). Without result
files yet, the page says so and shows the suite, the tuning record and the commands.

The statistics are in :mod:`sixaxis_avoid.benchmark.stats` (section "Benchmark v2").
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from sixaxis_avoid.benchmark import stats
from sixaxis_avoid.benchmark._io import atomic_savefig, atomic_write_text
from sixaxis_avoid.benchmark.report_compute import compute_rows, tuning_rows
from sixaxis_avoid.benchmark.report_howto import how_to_run, report_command_v2
from sixaxis_avoid.benchmark.report_pending import (
    in_progress_sentence,
    replaced_sets,
    sets_in_progress,
)
from sixaxis_avoid.benchmark.report_setups import (
    implementation_line,
    replaced_at,
    replaced_line,
    tuning_changes,
    tuning_changes_line,
)
from sixaxis_avoid.benchmark.runner import load_runs
from sixaxis_avoid.benchmark.stats import fmt_ci, fmt_steps
from sixaxis_avoid.benchmark.tasks import Suite, load_suite
from sixaxis_avoid.benchmark.twins import twin_agreement, twin_rows

#: Learners reported as the paper's reproduction, outside the ranking (docs/BENCHMARKS.md).
REPRODUCTION = ("q_paper",)

#: The README's copy of the headline (scripts/docsections.py).
HEADLINE_SECTION = "benchmark-headline"


def fmt_wilson(w: dict[str, Any]) -> str:
    return f"{w['rate']:.3f} [{w['lo']:.3f}, {w['hi']:.3f}] ({w['successes']}/{w['trials']})"


def fmt_steps_to(s: dict[str, Any], budget: int) -> str:
    """``42k [30k, 61k] (27/30 reached)``; a median or bound beyond the budget reads
    ``> budget``."""
    if not s["runs"]:
        return "—"

    def one(v: float | None) -> str:
        return f"> {fmt_steps(budget)}" if v is None else fmt_steps(v)

    lo, hi = s["ci"]
    return f"{one(s['median'])} [{one(lo)}, {one(hi)}] ({s['reached']}/{s['runs']} reached)"


# ------------------------------------------------------------------------------------------
# Analysis


def analyse_v2(
    results: Path, suite: Suite | str | None = None, reps: int = stats.REPS
) -> dict[str, Any]:
    """Everything the v2 page shows, from the result files in ``results`` (none: pending)."""
    results = Path(results)
    manifest_path = results / "study.json"
    manifest = json.loads(manifest_path.read_text()) if manifest_path.exists() else None
    if suite is None:
        if manifest is None:
            raise ValueError(f"{results}: no study.json; give the suite (--suite)")
        suite = manifest["suite"]["name"]
    suite = load_suite(suite) if not isinstance(suite, Suite) else suite
    if "axis" not in suite.budgets:
        raise ValueError(f"suite {suite.name!r} has no budget axis: use the v1 report")
    runs = load_runs(results) if (results / "runs").is_dir() else []
    runs = [r for r in runs if r["spec"]["suite"] == suite.name]
    a: dict[str, Any] = {
        "suite": suite,
        "manifest": manifest,
        "results_dir": str(results),
        "runs": runs,
        "reps": reps,
        "axis": [int(b) for b in suite.budgets["axis"]],
    }
    if not runs:
        a["pending"] = True
        return a
    a["pending"] = False
    order = list((manifest or {}).get("learners", []))
    learners = list(dict.fromkeys([*order, *(r["spec"]["learner"] for r in runs)]))
    learners = [lr for lr in learners if any(r["spec"]["learner"] == lr for r in runs)]
    suite_ids = [t.id for t in suite.tasks]
    present = {r["spec"]["task"]["id"] for r in runs}
    tasks = [t for t in suite_ids if t in present]
    family = {r["spec"]["learner"]: r["spec"]["family"] for r in runs}
    reference = [lr for lr in learners if family[lr] == "reference"]
    reproduction = [lr for lr in learners if lr in REPRODUCTION]
    ranked = [lr for lr in learners if lr not in reference and lr not in reproduction]
    budgets = sorted({stats.budget_of_run(r) for r in runs})
    per_budget: dict[int, dict[str, Any]] = {}
    for b in budgets:
        at = [r for r in runs if stats.budget_of_run(r) == b]
        have = {(r["spec"]["learner"], r["spec"]["task"]["id"]) for r in at}
        complete = [lr for lr in learners if all((lr, t) in have for t in tasks)]
        entry: dict[str, Any] = {"learners": {}, "complete": complete, "seeds": []}
        if complete:
            scores, seeds = stats.score_matrices(at, complete, tasks)
            entry["seeds"] = seeds
            if seeds:
                agg = stats.aggregates(
                    scores, reps=reps, poi_exclude=tuple(reference + reproduction)
                )
                entry["agg"] = agg
                for lr in complete:
                    mine = [
                        r for r in at if r["spec"]["learner"] == lr and r["spec"]["seed"] in seeds
                    ]
                    g = agg["learners"][lr]
                    k, n = stats.success_count(mine)
                    entry["learners"][lr] = {
                        "runs": len(mine),
                        "mean": g["mean"],
                        "mean_ci": g["mean_ci"],
                        "iqm": g["iqm"],
                        "iqm_ci": g["iqm_ci"],
                        "degenerate": stats.degenerate_fraction(scores[lr]),
                        "iqm_shown": stats.iqm_shown(scores[lr]),
                        "success": stats.wilson(k, n),
                        "steps_to": stats.steps_to_level(mine, reps=max(reps // 4, 100))
                        if family[lr] != "reference"
                        else None,
                        "status": sorted(
                            {r["spec"].get("hyperparams_status", "n/a") for r in mine}
                        ),
                        # A learner run as another implementation (SB3 PPO as rejax's).
                        "implementation": sorted(
                            {
                                str(r["spec"]["hyperparams"]["implementation"])
                                for r in mine
                                if r["spec"].get("hyperparams", {}).get("implementation")
                            }
                        ),
                        "per_task": {
                            t: {
                                "mean": float(np.mean(scores[lr][:, j])),
                                "success": stats.success_count(
                                    [r for r in mine if r["spec"]["task"]["id"] == t]
                                ),
                            }
                            for j, t in enumerate(tasks)
                        },
                    }
        per_budget[b] = entry
    # Runs that used more env steps than the budget they are reported at (a learner that
    # does not stop at its budget): the page lists them, a same-budget study has none.
    over: list[dict[str, Any]] = []
    for lr in learners:
        if family[lr] == "reference":
            continue
        for b in budgets:
            used = [
                int(r["result"]["env_steps"])
                for r in runs
                if r["spec"]["learner"] == lr and stats.budget_of_run(r) == b
            ]
            n_over = sum(u > b for u in used)
            if n_over:
                over.append({"learner": lr, "budget": b, "runs": n_over, "of": len(used),
                             "max_env_steps": max(used)})  # fmt: skip
    means = {b: per_budget[b]["learners"] for b in budgets}
    # A ranking compares learners at one budget, so the headline sits at a budget where
    # every ranked learner ran on every task: the plateau is looked for among those.
    common = [b for b in budgets if all(lr in per_budget[b]["complete"] for lr in ranked)]
    scope = common or budgets
    last = scope[-1]
    best = stats.best_learners({lr: v for lr, v in means[last].items() if lr in ranked})
    # The suite's best_only budgets (the axis's tail) are for the best learners at the budget
    # before them alone: the others are not missing there, and nobody is while that budget
    # is not one every ranked learner ran (its best learners are not known yet).
    best_only = suite.best_only
    axis = a["axis"]
    missing = {
        lr: [
            b
            for b in axis
            if (b not in per_budget or lr not in per_budget[b]["complete"])
            and (b not in best_only or (lr in best and axis[axis.index(b) - 1] == last))
        ]
        for lr in ranked
    }
    missing = {lr: bs for lr, bs in missing.items() if bs}
    # The plateau is the best learners' own: at the last budget every ranked learner ran, it
    # is checked against the next budget of the axis at which every best learner ran (the
    # others need not have). The headline never moves past that last common budget.
    after = [b for b in budgets if b > last and all(lr in per_budget[b]["complete"] for lr in best)]
    head = (
        stats.headline_budget({b: means[b] for b in [*scope, *after[:1]]}, best) if best else None
    )
    if head and not head["plateaued"]:
        head["budget"] = last
    a.update(
        {
            "learners": learners,
            "ranked": ranked,
            "reference": reference,
            "reproduction": reproduction,
            "tasks": tasks,
            "budgets": budgets,
            "per_budget": per_budget,
            "best": best,
            "headline": head,
            "common_budgets": common,
            "missing_budgets": missing,
            "over_budget": over,
            "in_progress": sets_in_progress(results),
            "replaced": replaced_sets(results),
        }
    )
    a["twins"] = twin_agreement(a, reps=reps)
    return a


# ------------------------------------------------------------------------------------------
# Figures


def figures_v2(a: dict[str, Any], out_dir: Path) -> dict[str, Path]:
    """Two figures: every learner's mean curve (its runs at the largest budget) and its final
    score at each budget of the axis on one env-steps axis; performance profiles at the
    headline budget."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from sixaxis_avoid.benchmark.report import COLORS

    out: dict[str, Path] = {}
    learners = [lr for lr in a["learners"] if lr not in a["reference"]]
    fig, ax = plt.subplots(figsize=(8, 4.5))
    top = max(a["budgets"])
    grid = np.unique(np.geomspace(max(1, top // 1000), top, 60).round())
    for i, lr in enumerate(learners):
        color = COLORS.get(lr, f"C{i % 10}")
        mine = [r for r in a["runs"] if r["spec"]["learner"] == lr]
        if not mine:
            continue
        b_max = max(stats.budget_of_run(r) for r in mine)
        longest = [r for r in mine if stats.budget_of_run(r) == b_max and r["result"]["curve"]]
        if longest:
            g = grid[grid <= b_max]
            ys = np.mean([stats.curve_on(g, r["result"]["curve"]) for r in longest], axis=0)
            ax.plot(g, ys, color=color, label=f"{lr} (curve at {fmt_steps(b_max)})")
        pts = [(b, e["learners"][lr]) for b, e in a["per_budget"].items() if lr in e["learners"]]
        if pts:
            xs = [b for b, _ in pts]
            ys = [v["mean"] for _, v in pts]
            err = np.array(
                [[v["mean"] - v["mean_ci"][0], v["mean_ci"][1] - v["mean"]] for _, v in pts]
            )
            ax.errorbar(xs, ys, yerr=err.T, fmt="o", color=color, capsize=3, markersize=4)
    if a["headline"]:
        ax.axvline(a["headline"]["budget"], color="gray", linestyle=":", linewidth=1)
    ax.set_xscale("log")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("environment steps")
    ax.set_ylabel("mean SPL")
    ax.set_title(
        "Lines: mean SPL along the runs at each learner's largest budget\n"
        "points: final mean SPL at each budget of the axis (95% CI); dotted: headline budget",
        fontsize=9,
    )
    ax.legend(fontsize=7, loc="upper left")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    out["curves"] = out_dir / "bench_v2_curves.png"
    atomic_savefig(fig, out["curves"])
    plt.close(fig)

    b = a["headline"]["budget"] if a["headline"] else max(a["budgets"])
    agg = a["per_budget"][b].get("agg")
    if agg:
        fig, ax = plt.subplots(figsize=(7, 4.5))
        taus = np.asarray(agg["taus"])
        for i, lr in enumerate(agg["learners"]):
            s = agg["learners"][lr]
            color = COLORS.get(lr, f"C{i % 10}")
            ax.plot(taus, s["profile"], color=color, label=lr)
            ax.fill_between(taus, *s["profile_ci"], color=color, alpha=0.15, linewidth=0)
        ax.set_xlabel(r"SPL threshold $\tau$")
        ax.set_ylabel(r"fraction of runs with SPL > $\tau$")
        ax.set_title(f"Performance profiles at {fmt_steps(b)} env steps (95% CI band)")
        ax.legend(fontsize=8)
        ax.grid(True, alpha=0.3)
        fig.tight_layout()
        out["profiles"] = out_dir / "bench_v2_profiles.png"
        atomic_savefig(fig, out["profiles"])
        plt.close(fig)
    return out


# ------------------------------------------------------------------------------------------
# Markdown


def tasks_rows(suite: Suite) -> list[str]:
    out = [
        "| task | group | grid | states | cell (mm) | blocked cells | targets | "
        "BFS optimum (moves) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for t in suite.tasks:
        d = t.describe()
        out.append(
            f"| {t.id} | {d['group']} | {'x'.join(map(str, d['grid']))} | {d['states']} | "
            f"{d['cell_mm']:g} | {d['blocked']} | {len(d['targets'])} | "
            f"{', '.join(map(str, d['optimal_lengths']))} |"
        )
    return out


STATISTICS = [
    "## Statistics",
    "",
    "- **Budget**: a run uses at most its budget of env steps. A learner that trains in "
    "whole iterations (PPO: rollouts of n_envs x n_steps; DQN: steps of its n_envs envs) "
    "stops after the most whole iterations that fit in the budget, and scores each "
    "checkpoint after the most that fit in it; the tabular learners stop at the budget "
    "exactly. A run that used more is listed under *Over budget* and its row is not a "
    "same-budget comparison.",
    "- **Score of a run**: SPL of its final greedy path (BFS optimum over the path's length if "
    "it reaches the target, else 0), averaged over the task's evaluation targets.",
    "- **Success rate**: targets reached out of runs x evaluation targets, with the Wilson "
    "95% score interval (it stays inside [0, 1] and does not shrink to a point when every "
    "run succeeds or fails).",
    "- **SPL**: the mean over tasks and seeds, with a 95% stratified-bootstrap interval "
    f"(rliable, {stats.REPS:,} resamples; tasks are the strata, seeds are resampled within "
    "each task; each learner, and each pair of learners, resamples from a seeded stream of "
    "its own, so adding one learner's runs moves no other interval). *all equal*: "
    "every run scored the same, so the bootstrap has nothing to resample and gives no "
    "interval; read the success rate's Wilson interval instead.",
    f"- **IQM** is shown only where fewer than {stats.IQM_DEGENERATE_FRACTION:.0%} of the "
    "scores are exactly 0 or 1; with more, the middle half of the scores is mostly zeros and "
    "ones and the IQM is a stretched copy of the mean (the column then gives that fraction).",
    f"- **Env steps to SPL ≥ {stats.SPL_REACHED}**: the first checkpoint of a run's curve at "
    "or above it; a run that never gets there is censored at its budget. The median is the "
    "Kaplan-Meier median (the first time the fraction not yet there falls to 1/2; `> B` "
    "when half the runs or more never got there within B), the interval the 2.5 and 97.5 "
    "percentiles of that median over a bootstrap of the runs stratified by task.",
    "- **Headline budget**: the best learners are those whose SPL interval at the largest "
    "budget overlaps the top learner's. The headline budget is the smallest budget of the "
    "axis at which each of them has plateaued: its mean SPL at the next budget lies inside "
    "its interval at this one. When not every learner ran every budget, the ranking stops "
    "at the largest budget all of them ran, and the plateau there is checked against the "
    "next budget at which every best learner ran. Without such a budget the headline sits "
    "at the largest budget (all of them ran) and says the plateau is not shown. The budgets "
    "the suite marks for the best learners only (`budgets.best_only`, the axis's tail) are "
    "run by the best learners at the budget before them and by no other: they show the "
    "plateau there, and the ranking never reaches them.",
    "- **Performance profile**: the fraction of runs with SPL above τ, 95% band; "
    "**probability of improvement**: P(a run of the row learner scores higher than a run "
    "of the column learner on a task drawn at random), ties counting half (rliable).",
    "",
]


def plateau_detail(a: dict[str, Any], b: int) -> str:
    """Where the plateau at ``b`` stands for each best learner: its mean SPL at the next
    budget it ran, inside or outside its interval at ``b`` (outside: the task that moved
    most), and those that ran no budget after ``b``. Empty when none of them did."""
    best = (a.get("headline") or {}).get("best", [])
    parts, not_run, later = [], [], set()
    for lr in best:
        here = a["per_budget"][b]["learners"].get(lr)
        nb = next((x for x in a["budgets"] if x > b and lr in a["per_budget"][x]["learners"]), None)
        if here is None or nb is None:
            not_run.append(lr)
            continue
        later.add(nb)
        there = a["per_budget"][nb]["learners"][lr]
        inside = stats.plateaued(here, there)
        text = (
            f"{lr}'s mean at {fmt_steps(nb)}, {there['mean']:.3f}, lies "
            f"{'inside' if inside else 'outside'} its interval here, "
            f"{fmt_ci(here['mean'], here['mean_ci'])}"
        )
        if not inside:
            moved = {
                t: there["per_task"][t]["mean"] - v["mean"]
                for t, v in here["per_task"].items()
                if t in there["per_task"]
            }
            t = max(moved, key=lambda k: abs(moved[k]))
            text += (
                f", most of all on {t} ({here['per_task'][t]['mean']:.3f} here, "
                f"{there['per_task'][t]['mean']:.3f} there)"
            )
        parts.append(text)
    if not parts:
        return ""
    if not_run:
        who = " and ".join([", ".join(not_run[:-1]), not_run[-1]] if len(not_run) > 1 else not_run)
        nxt = ", ".join(fmt_steps(x) for x in sorted(later))
        parts.append(f"{who} {'has' if len(not_run) == 1 else 'have'} not run {nxt} yet")
    return f"At {fmt_steps(b)}: " + "; ".join(parts) + "."


def headline_table(a: dict[str, Any], b: int) -> list[str]:
    e = a["per_budget"][b]["learners"]
    rows = sorted((lr for lr in e if lr in a["ranked"]), key=lambda lr: -e[lr]["mean"])
    rows += [lr for lr in e if lr not in a["ranked"]]
    out = [
        f"| learner | success (Wilson 95%) | SPL [95% CI] | IQM | env steps to SPL ≥ "
        f"{stats.SPL_REACHED} | hyperparameters |",
        "|---|---|---|---|---|---|",
    ]
    for lr in rows:
        v = e[lr]
        iqm = (
            fmt_ci(v["iqm"], v["iqm_ci"])
            if v["iqm_shown"]
            else f"— ({v['degenerate']:.0%} of scores 0 or 1)"
        )
        label = (
            lr
            if lr in a["ranked"]
            else f"{lr} ({'reference' if lr in a['reference'] else 'reproduction'}, not ranked)"
        )
        steps = "—" if v["steps_to"] is None else fmt_steps_to(v["steps_to"], b)
        out.append(
            f"| {label} | {fmt_wilson(v['success'])} | {fmt_ci(v['mean'], v['mean_ci'])} | "
            f"{iqm} | {steps} | {', '.join(v['status'])} |"
        )
    return out


def runs_line(runs: list[dict[str, Any]], n_learners: int, n_tasks: int, n_budgets: int) -> str:
    """What the study's runs are: a product of learners, tasks, seeds and budgets when they
    fill one, else the learner-budget pairs run and the seeds per task at each (a learner can
    miss a budget, and the deep learners run fewer seeds than the others)."""
    seeds: dict[tuple[str, int], set[int]] = {}
    for r in runs:
        spec = r["spec"]
        seeds.setdefault((spec["learner"], stats.budget_of_run(r)), set()).add(spec["seed"])
    n_seeds = len({s for ss in seeds.values() for s in ss})
    full = len(seeds) == n_learners * n_budgets and all(len(ss) == n_seeds for ss in seeds.values())
    if full and len(runs) == n_learners * n_tasks * n_seeds * n_budgets:
        return (
            f"{len(runs)} runs: {n_learners} learners x {n_tasks} tasks x {n_seeds} seeds x "
            f"{n_budgets} budgets"
        )
    by_count: dict[int, int] = {}
    for ss in seeds.values():
        by_count[len(ss)] = by_count.get(len(ss), 0) + 1
    counts = sorted(by_count.items(), reverse=True)
    per = ", ".join(
        f"{k} seeds per task at {v}" if i == 0 else f"{k} at {v}" for i, (k, v) in enumerate(counts)
    )
    return (
        f"{len(runs)} runs: {n_learners} learners, {n_tasks} tasks, {n_budgets} budgets; "
        f"{len(seeds)} of the {n_learners * n_budgets} learner-budget pairs run (*Score by "
        f"budget*), {per}"
    )


def markdown_v2(a: dict[str, Any], figs: dict[str, Path], out: Path, history: Path | None) -> str:
    suite = a["suite"]
    rel = {k: os.path.relpath(v, out.parent) for k, v in figs.items()}
    hist = os.path.relpath(history, out.parent) if history else None
    best_only = suite.best_only
    axis = ", ".join(fmt_steps(b) for b in a["axis"]) + (
        f" ({', '.join(fmt_steps(b) for b in best_only)} for the best learners only, *Statistics*)"
        if best_only
        else ""
    )
    L = [
        "# Learner benchmark",
        "",
        "Generated by `python -m sixaxis_avoid.benchmark report` from the result files of the "
        "study below (do not edit by hand; re-run the commands under *How to run*):",
        "",
        "```bash",
        report_command_v2(a, out),
        "```",
        "",
        f"Suite **{suite.name}** version {suite.version}: {suite.raw.get('description', '')} "
        f"Budget axis (env steps): {axis}; {len(suite.tasks)} tasks, "
        f"{len(suite.seeds)} seeds.",
        "",
    ]
    if hist:
        L += [f"History: the v1 study and its page, [{Path(hist).name}]({hist}).", ""]
    if a["pending"]:
        L += [
            "## Headline",
            "",
            f"<!-- {HEADLINE_SECTION}:begin -->",
            # Plain paths, no links: README.md shows a copy of this section.
            f"No results of suite {suite.name} yet: `{a['results_dir']}` holds no run files "
            "(the commands are under *How to run* in docs/BENCHMARKS.md)."
            + (f" The v1 study is in {out.parent / Path(hist).name}." if hist else ""),
            f"<!-- {HEADLINE_SECTION}:end -->",
            "",
        ]
    else:
        from sixaxis_avoid.benchmark.report import provenance, run_machines

        m = a["manifest"]
        head = a["headline"]
        b = head["budget"] if head else max(a["budgets"])
        L += [
            runs_line(a["runs"], len(a["learners"]), len(a["tasks"]), len(a["budgets"]))
            + (f". {provenance(m)}." if m and "date" in m else ".")
            + "".join(f" {s}" for s in [run_machines(a["runs"])] if s),
            "",
            f"## Headline ({fmt_steps(b)} env steps)",
            "",
        ]
        if head and head["plateaued"]:
            nxt = next(c["next"] for c in head["checks"] if c["budget"] == b)
            only = (
                f" Not every learner ran at {fmt_steps(nxt)}; the plateau is the best "
                "learners' own, so only they need to have."
                if nxt not in a["common_budgets"] and a["common_budgets"]
                else ""
            )
            L.append(
                f"At {fmt_steps(b)} env steps the best learners ({', '.join(head['best'])}) "
                f"have plateaued: each one's mean SPL at the next budget ({fmt_steps(nxt)}) "
                "lies inside its 95% interval here (*Score by budget*)."
                + only
                + " Ranked by mean SPL; overlapping intervals are not a ranking."
            )
        else:
            where = (
                "the largest budget"
                if b == a["axis"][-1] or not a["common_budgets"]
                else "the largest budget at which every ranked learner ran"
            )
            L.append(
                "**The plateau is not shown**: at no budget "
                + ("of the axis" if where == "the largest budget" else "that every ranked "
                   "learner ran")
                + f" did every best learner ({', '.join(head['best']) if head else 'none'}) "
                f"stay within its interval at the next budget, so the headline sits at {where}, "
                f"{fmt_steps(b)}, and its figures are lower bounds."
                + (f" {detail}" if (detail := plateau_detail(a, b)) else "")
            )  # fmt: skip
        if a["missing_budgets"]:
            L += [
                "",
                "**Not every learner ran at every budget of the axis**, so a learner's row at "
                "a budget it did not run is empty and the ranking stops at the budgets all of "
                "them ran ("
                + (", ".join(fmt_steps(x) for x in a["common_budgets"]) or "none")
                + "). Not run yet: "
                + "; ".join(
                    f"{lr} at {', '.join(fmt_steps(x) for x in bs)}"
                    for lr, bs in a["missing_budgets"].items()
                )
                + ". Each is a tuning command and a run command per budget: those recorded "
                "for the budgets run (*Tuning record*, *How to run*) with the budget changed.",
            ]
        if a["in_progress"]:
            # Its own paragraph: a set may be under way once every learner ran every budget
            # too (a search of SB3's own, a re-run on new values).
            L += ["", in_progress_sentence(a["in_progress"])]
        L += [
            "",
            f"<!-- {HEADLINE_SECTION}:begin -->",
            *headline_table(a, b),
            f"<!-- {HEADLINE_SECTION}:end -->",
            "",
        ]
        impl = {
            lr: g["implementation"]
            for lr, g in a["per_budget"][b]["learners"].items()
            if g.get("implementation")
        }
        if impl:
            L += [implementation_line(impl), ""]
        if line := replaced_line(replaced_at(a, b, reps=a["reps"]), b):
            L += [line, ""]
        if a["over_budget"]:
            L += [
                "**Over budget**: these runs used more env steps than the budget they are "
                "reported at, so their row is not a same-budget comparison: "
                + "; ".join(
                    f"{o['learner']} at {fmt_steps(o['budget'])}: {o['runs']} of {o['of']} "
                    f"runs, up to {fmt_steps(o['max_env_steps'])}"
                    for o in a["over_budget"]
                )
                + ".",
                "",
            ]
        L += [
            "## Score by budget",
            "",
            "Mean SPL [95% stratified-bootstrap CI] of each learner at each budget of the axis "
            "(runs at a budget use the hyperparameters tuned at it). ✓: the next budget's "
            "mean lies inside this interval (plateaued); ✗: it does not.",
            "",
            "| learner | " + " | ".join(fmt_steps(x) for x in a["budgets"]) + " |",
            "|---|" + "---|" * len(a["budgets"]),
        ]
        for lr in a["learners"]:
            cells = []
            for i, x in enumerate(a["budgets"]):
                v = a["per_budget"][x]["learners"].get(lr)
                if v is None:
                    cells.append("—")
                    continue
                mark = ""
                if i + 1 < len(a["budgets"]):
                    nxt = a["per_budget"][a["budgets"][i + 1]]["learners"].get(lr)
                    if nxt is not None:
                        mark = " ✓" if stats.plateaued(v, nxt) else " ✗"
                cells.append(fmt_ci(v["mean"], v["mean_ci"]) + mark)
            L.append(f"| {lr} | " + " | ".join(cells) + " |")
        if line := tuning_changes_line(tuning_changes(a)):
            L += ["", line]
        L += [
            "",
            f"![Curves of every learner on one env-steps axis]({rel['curves']})",
            "",
        ]
        if "profiles" in rel:
            L += [f"![Performance profiles]({rel['profiles']})", ""]
        agg = a["per_budget"][b].get("agg", {})
        poi = agg.get("poi", {})
        names = [x for x in agg.get("learners", {}) if any(k.startswith(f"{x},") for k in poi)]
        if names:
            L += [
                f"### Probability of improvement ({fmt_steps(b)} env steps)",
                "",
                "P(row > column), 95% CI; the reference and the reproduction rows are left out.",
                "",
                "| | " + " | ".join(names) + " |",
                "|---|" + "---|" * len(names),
                *[
                    f"| **{x}** | "
                    + " | ".join(
                        "—" if x == y else fmt_ci(poi[f"{x},{y}"]["p"], poi[f"{x},{y}"]["ci"], 2)
                        for y in names
                    )
                    + " |"
                    for x in names
                ],
                "",
            ]
        L += [
            f"## Per task ({fmt_steps(b)} env steps)",
            "",
            "Mean SPL over seeds (targets reached / runs x targets).",
            "",
            "| task | " + " | ".join(a["per_budget"][b]["learners"]) + " |",
            "|---|" + "---|" * len(a["per_budget"][b]["learners"]),
        ]
        for t in a["tasks"]:
            cells = []
            for v in a["per_budget"][b]["learners"].values():
                k, n = v["per_task"][t]["success"]
                cells.append(f"{v['per_task'][t]['mean']:.3f} ({k}/{n})")
            L.append(f"| {t} | " + " | ".join(cells) + " |")
        groups: dict[str, list[str]] = {}
        for t in a["tasks"]:
            groups.setdefault(suite.task(t).group, []).append(t)
        L += [
            "",
            f"### Per group ({fmt_steps(b)} env steps)",
            "",
            "Mean SPL over the group's tasks and seeds; success with its Wilson 95% interval.",
            "",
            "| group | tasks | " + " | ".join(a["per_budget"][b]["learners"]) + " |",
            "|---|---|" + "---|" * len(a["per_budget"][b]["learners"]),
        ]
        for g, ts in groups.items():
            cells = []
            for v in a["per_budget"][b]["learners"].values():
                k = sum(v["per_task"][t]["success"][0] for t in ts)
                n = sum(v["per_task"][t]["success"][1] for t in ts)
                mean = float(np.mean([v["per_task"][t]["mean"] for t in ts]))
                cells.append(f"{mean:.3f}, " + fmt_wilson(stats.wilson(k, n)))
            L.append(f"| {g} | {len(ts)} | " + " | ".join(cells) + " |")
        L += [
            "",
            f"## Env steps to SPL ≥ {stats.SPL_REACHED}",
            "",
            "Kaplan-Meier median [95% CI], censored at the budget (*Statistics*).",
            "",
            "| learner | " + " | ".join(fmt_steps(x) for x in a["budgets"]) + " |",
            "|---|" + "---|" * len(a["budgets"]),
        ]
        for lr in a["learners"]:
            if lr in a["reference"]:
                continue
            cells = []
            for x in a["budgets"]:
                v = a["per_budget"][x]["learners"].get(lr)
                cells.append(
                    "—" if v is None or v["steps_to"] is None else fmt_steps_to(v["steps_to"], x)
                )
            L.append(f"| {lr} | " + " | ".join(cells) + " |")
        L.append("")
    L += [
        *twin_rows(a.get("twins", [])),
        "## Tuning record",
        "",
        *tuning_rows(a),
        "",
        *compute_rows(a),
        "## Tasks",
        "",
        "Finer grids are the same physical world re-gridded (`cell_mm`, `Scenario.regrid`, "
        "docs/SCENARIOS.md): more states and longer paths, where tabular learning gets hard. "
        "No two tasks are the same world for a learner (checked when the suite loads).",
        "",
        *tasks_rows(suite),
        "",
        "The Stable-Baselines3 learners train on the native `sixaxis_avoid.sb3.SixAxisVecEnv` "
        "(all of a run's envs stepped in one Rust call) on every kind of task above: fixed "
        "targets, the goal task's random targets and goal observations, re-gridded worlds, "
        "and the worlds of Algorithm 2's re-plan rounds. It is step for step the same as the "
        "`DummyVecEnv` of single envs that suite v1's runs used, and a run gives the same "
        "result on either (tests/test_sb3_vecenv.py, tests/test_benchmark_units.py), so no "
        "task keeps the old path; an SB3 run file names its VecEnv (`result.vec_env`). "
        "Training speed on each: docs/PERFORMANCE.md, *JAX learners*.",
        "",
        *STATISTICS,
        *how_to_run(a, out),
    ]  # fmt: skip
    if hist:
        L += [
            "## History",
            "",
            f"- [{Path(hist).name}]({hist}): suite v1 (the paper's scenarios, one generated "
            "world per level, deep budgets of 30k env steps against the tabular learners' "
            "10,000 episodes), its longer-budget sections and its own commands.",
            "",
        ]
    return "\n".join(L)


def write_report_v2(
    results: Path,
    out: Path,
    figures_dir: Path | None = None,
    reps: int = stats.REPS,
    suite: str | None = None,
    history: Path | None = None,
) -> dict[str, Any]:
    """Write the v2 page ``out`` (figures in ``figures_dir``, default ``figures/bench-v2``
    beside it) from the runs in ``results``; ``history``: the v1 page it links."""
    from sixaxis_avoid.benchmark.report import keep_other_sections

    out = Path(out)
    figures_dir = Path(figures_dir) if figures_dir else out.parent / "figures" / "bench-v2"
    a = analyse_v2(results, suite, reps)
    figs = {} if a["pending"] else figures_v2(a, figures_dir)
    text = markdown_v2(a, figs, out, history)
    # The history page's marked sections stay there (one page per section).
    theirs = set()
    if history and Path(history).exists():
        from sixaxis_avoid.benchmark.report import _SECTION

        theirs = {m.group(1) for m in _SECTION.finditer(Path(history).read_text())}
    atomic_write_text(out, keep_other_sections(out, text, exclude=theirs))
    if not a["pending"]:
        summary = {
            "budgets": a["budgets"],
            "headline": a["headline"],
            "per_budget": {
                str(b): {lr: {k: v[k] for k in ("mean", "mean_ci", "success", "iqm_shown",
                                                "degenerate", "steps_to")}
                         for lr, v in e["learners"].items()}
                for b, e in a["per_budget"].items()
            },
        }  # fmt: skip
        atomic_write_text(
            figures_dir / "bench_v2_summary.json", json.dumps(summary, indent=1) + "\n"
        )
    return a
