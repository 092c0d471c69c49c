"""docs/BENCHMARKS.md and its figures, regenerated from a study's result files.

``python -m sixaxis_avoid.benchmark report --results results/bench/v1`` reads
``study.json`` and ``runs/*.json`` and writes the Markdown report and three figures: IQM
learning curves with 95% bands, performance profiles with bands, and IQM / mean / optimality
gap with 95% confidence intervals.
"""

from __future__ import annotations

import json
import math
import os
import re
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from sixaxis_avoid.benchmark import hyperparams as hpmod
from sixaxis_avoid.benchmark import stats
from sixaxis_avoid.benchmark._io import atomic_savefig, atomic_write_text
from sixaxis_avoid.benchmark.learners import BUILTIN, PLUGINS, resolve
from sixaxis_avoid.benchmark.longer import (
    analyse_longer,
    change_label,
    figure_name,
    fmt_ci,
    is_variant,
    longer_figure,
    longer_section,
    n_seeds,
    run_hours,
)
from sixaxis_avoid.benchmark.runner import load_runs, task_of
from sixaxis_avoid.benchmark.stats import fmt_steps

COLORS = {
    "q_assist": "tab:blue",
    "q_plain": "tab:orange",
    "bfs": "black",
    "dqn": "tab:green",
    "qrdqn": "tab:olive",
    "ppo": "tab:red",
    "a2c": "tab:purple",
}


def fmt(v: Any, spec: str = ".2f") -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "—"
    return format(v, spec) if isinstance(v, float) else str(v)


def fmt_time(v: Any) -> str:
    if v is None:
        return "—"
    v = float(v)
    if v < 1e-3:
        return f"{v * 1e6:.0f} µs"
    if v < 1:
        return f"{v * 1e3:.1f} ms"
    return f"{v:.1f} s"


def title(learner: str) -> str:
    cls = BUILTIN.get(learner) or (resolve(learner) if learner in PLUGINS else None)
    return cls.title if cls else f"user learner `{learner}`"


def analyse(results: Path, reps: int = stats.REPS) -> dict[str, Any]:
    """Everything the report shows, computed from the result files."""
    manifest = json.loads((Path(results) / "study.json").read_text())
    runs = load_runs(results)
    learners = [lr for lr in manifest["learners"] if any(r["spec"]["learner"] == lr for r in runs)]
    tasks = [t for t in manifest["tasks"] if any(r["spec"]["task"]["id"] == t for r in runs)]
    runs = [
        r for r in runs if r["spec"]["learner"] in learners and r["spec"]["task"]["id"] in tasks
    ]
    scores, seeds = stats.score_matrices(runs, learners, tasks)
    if not seeds:
        raise ValueError(f"{results}: no seed has a result for every (learner, task)")
    reference = tuple(
        lr
        for lr in learners
        if any(r["spec"]["learner"] == lr and r["spec"]["family"] == "reference" for r in runs)
    )
    agg = stats.aggregates(scores, reps=reps, poi_exclude=reference)
    hi = max(max(p["env_steps"] for p in r["result"]["curve"]) for r in runs)
    grid = np.unique(np.geomspace(1, max(hi, 2), 40).round().astype(np.int64))
    curves = stats.iqm_curves(runs, learners, tasks, seeds, grid, reps=max(reps // 4, 100))
    task_objs = {
        t: task_of(next(r["spec"] for r in runs if r["spec"]["task"]["id"] == t)) for t in tasks
    }
    groups: dict[str, list[str]] = {}
    for t in tasks:
        groups.setdefault(task_objs[t].group, []).append(t)
    mine = {lr: [r for r in runs if r["spec"]["learner"] == lr] for lr in learners}
    per = {lr: stats.per_learner(mine[lr]) for lr in learners}
    per_group = {
        g: {
            lr: stats.per_learner([r for r in mine[lr] if r["spec"]["task"]["id"] in ts])
            for lr in learners
        }
        for g, ts in groups.items()
    }
    per_task = {
        t: {
            lr: stats.per_learner([r for r in mine[lr] if r["spec"]["task"]["id"] == t])
            for lr in learners
        }
        for t in tasks
    }
    return {
        "manifest": manifest,
        "runs": runs,
        "learners": learners,
        "tasks": tasks,
        "task_objs": task_objs,
        "seeds": seeds,
        "agg": agg,
        "grid": grid.tolist(),
        "curves": curves,
        "groups": groups,
        "per": per,
        "per_group": per_group,
        "per_task": per_task,
        "reps": reps,
    }


# ------------------------------------------------------------------------------------------
# Figures


def iqm_figure_title(a: dict[str, Any]) -> str:
    """The IQM bars' title; names the learners with one seed, drawn as a point without a bar."""
    one_seed = [lr for lr in a["learners"] if a["agg"]["learners"][lr].get("seeds", 2) < 2]
    return "Final score (SPL) with 95% stratified-bootstrap CIs" + (
        f"; {', '.join(one_seed)}: 1 seed, point only" if one_seed else ""
    )


def figures(a: dict[str, Any], out_dir: Path) -> dict[str, Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out: dict[str, Path] = {}
    learners = a["learners"]
    n_runs = len(a["seeds"]) * len(a["tasks"])

    fig, ax = plt.subplots(figsize=(8, 4.5))
    grid = np.asarray(a["grid"])
    for lr in learners:
        c = a["curves"][lr]
        color = COLORS.get(lr)
        keep = grid <= max(c["max_env_steps"], 1)
        ax.plot(grid[keep], np.asarray(c["iqm"])[keep], color=color, label=lr)
        ax.fill_between(
            grid[keep],
            np.asarray(c["lo"])[keep],
            np.asarray(c["hi"])[keep],
            color=color,
            alpha=0.15,
            linewidth=0,
        )
    ax.set_xscale("log")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("environment steps")
    ax.set_ylabel("IQM score (SPL of the greedy path)")
    ax.set_title(f"Learning curves: IQM over {n_runs} runs per learner, 95% CI band")
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    out["curves"] = out_dir / "bench_curves.png"
    atomic_savefig(fig, out["curves"])
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7, 4.5))
    taus = np.asarray(a["agg"]["taus"])
    for lr in learners:
        s = a["agg"]["learners"][lr]
        color = COLORS.get(lr)
        ax.plot(taus, s["profile"], color=color, label=lr)
        ax.fill_between(taus, *s["profile_ci"], color=color, alpha=0.15, linewidth=0)
    ax.set_xlabel(r"score threshold $\tau$")
    ax.set_ylabel(r"fraction of runs with score > $\tau$")
    ax.set_title("Performance profiles (95% CI band)")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    out["profiles"] = out_dir / "bench_profiles.png"
    atomic_savefig(fig, out["profiles"])
    plt.close(fig)

    fig, axes = plt.subplots(1, 3, figsize=(12, 0.5 * len(learners) + 1.5), sharey=True)
    ys = np.arange(len(learners))
    for ax, key, label in zip(
        axes, ("iqm", "mean", "optimality_gap"), ("IQM", "mean", "optimality gap")
    ):
        for y, lr in zip(ys, learners):
            s = a["agg"]["learners"][lr]
            lo, hi = s[f"{key}_ci"]
            if s.get("seeds", 2) >= 2:  # one seed: nothing to resample, a point only
                ax.barh(y, hi - lo, left=lo, height=0.6, color=COLORS.get(lr, "gray"), alpha=0.6)
            ax.plot([s[key]] * 2, [y - 0.3, y + 0.3], color="black", linewidth=1.5)
        ax.set_xlabel(label)
        ax.set_xlim(-0.02, 1.02)
        ax.grid(True, axis="x", alpha=0.3)
    axes[0].set_yticks(ys)
    axes[0].set_yticklabels(learners)
    fig.suptitle(iqm_figure_title(a))
    fig.tight_layout()
    out["iqm"] = out_dir / "bench_iqm.png"
    atomic_savefig(fig, out["iqm"])
    plt.close(fig)
    return out


# ------------------------------------------------------------------------------------------
# Markdown


def hyperparam_section(a: dict[str, Any]) -> list[str]:
    specs = {}
    for r in a["runs"]:
        specs.setdefault(r["spec"]["learner"], r["spec"])
    deep = [lr for lr in a["learners"] if specs[lr]["family"] == "deep"]
    if not deep:
        return []
    suite_hp = a["manifest"]["suite"].get("hyperparams", "v1")
    data = hpmod.load(suite_hp)
    pending = [lr for lr in deep if specs[lr]["hyperparams_status"] != "tuned"]
    out = ["## Hyperparameters of the deep learners", ""]
    if pending:
        out += [
            f"**Not tuned: {', '.join(pending)} ran with defaults, pending a tuning run** "
            "(`python -m sixaxis_avoid.benchmark tune`; see *How to run*). Their results "
            "are those of untuned baselines and say little about what the algorithm can do.",
            "",
        ]
    for lr in deep:
        entry = data.get("learners", {}).get(lr, {})
        tuning = entry.get("tuning")
        src = (
            f"tuned: `{tuning['command']}`, {tuning['trials']} trials, best objective "
            f"{tuning['best_value']:.3f} on {', '.join(tuning['tasks'])}"
            if tuning and specs[lr]["hyperparams_status"] == "tuned"
            else "defaults (see `sixaxis_avoid/benchmark/learners.py`), pending a tuning run"
        )
        values = ", ".join(f"`{k}`={v}" for k, v in sorted(specs[lr]["hyperparams"].items()))
        out += [f"- **{lr}** — {src}. Values: {values}.", ""]
    return out


def plateau(a: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Per learner of ``a``, whether its curves had flattened (see :func:`stats.plateau`)."""
    return stats.plateau(a["runs"], a["learners"])


def plateau_section(a: dict[str, Any]) -> list[str]:
    rows = plateau(a)
    return [
        "## Did the curves plateau?",
        "",
        "Mean final-path score over a learner's runs at a quarter, half and all of each run's "
        "env steps, and the fraction of runs whose score still changed in the second half of "
        "their budget. A learner whose score still rises from half to full budget, or changes "
        "late in many runs, has not plateaued: its figures are a lower bound on what it can do "
        "with more samples (the cluster command under *How to run* scales every budget; "
        "*Longer budgets*, where present, measures it). *best*: the mean of each run's best "
        "checkpoint score; *ended below best*: runs that found a better path than the one "
        "they ended with.",
        "",
        "| learner | runs | score at 1/4 | at 1/2 | at end | runs still changing after 1/2 "
        "| best | ended below best |",
        "|---|---|---|---|---|---|---|---|",
        *[
            f"| {lr} | {v['runs']} | {v['quarter']:.3f} | {v['half']:.3f} | {v['end']:.3f} | "
            f"{v['changed_late']:.2f} | {v['best']:.3f} | {v['fell_from_best']:.2f} |"
            for lr, v in rows.items()
        ],
        "",
    ]


def longer_headline(a: dict[str, Any]) -> list[str]:
    """One line per *Longer budgets* section: each learner's IQM at x1 and there."""
    out = []
    for lo in a.get("longer", []):
        if not lo["learners"]:
            continue
        parts = []
        variant = is_variant(lo)
        for lr, v in lo["learners"].items():
            g = v["agg"]["learners"]
            # A variant's changes are listed in its section (often too many for a headline).
            change = "" if variant else change_label(v).replace("`", "")
            parts.append(
                f"**{lr}**{' (' + change + ')' if change else ''} IQM {g['x1']['iqm']:.2f} → "
                f"{fmt_ci(g['long'], 'iqm')} on its {n_seeds(len(v['seeds']))}"
            )
        where = (
            "At the same budgets with other hyperparameters (*Same budgets, other "
            "hyperparameters* below)"
            if variant
            else f"With every deep budget x{lo['scale']:g} (*Longer budgets* below)"
        )
        out += [f"{where}: " + "; ".join(parts) + ".", ""]
    return out


def study_commands(manifest: dict[str, Any]) -> list[str]:
    """Every ``run`` command that filled a study's directory, in the order they ran."""
    return list(manifest.get("commands", [manifest["command"]]))


def provenance(manifest: dict[str, Any]) -> str:
    """Where and when a study ran: its one command, or the last of the several that filled
    its directory (runs of earlier commands may have run on other machines)."""
    n = len(study_commands(manifest))
    where = f"{manifest['date']} on {manifest['machine']}"
    total = manifest.get("wall_time_s_total")
    if n == 1:
        took = "" if total is None else f" in {total / 60:.0f} min of wall time"
        return f"Run {where}{took}"
    took = "" if total is None else f"; the commands took {total / 60:.0f} min of wall time in all"
    return (
        f"Filled by {n} `run` commands into one directory (*How to run*; a command skips the "
        f"runs already there), the last ended {where}{took}"
    )


def run_machines(runs: list[dict[str, Any]]) -> str:
    """Which machines a study's runs ran on (each run file's ``host.machine``): a deep run's
    floating-point result can depend on the CPU's vendor, so a study whose deep runs came
    from several machines says so."""
    kinds = Counter(r.get("host", {}).get("machine") for r in runs)
    unknown = kinds.pop(None, 0)
    if not kinds:
        return ""
    if len(kinds) == 1 and not unknown:
        return f"Every run ran on {next(iter(kinds))}."
    listed = "; ".join(f"{k}: {n}" for k, n in kinds.items())
    if unknown:
        listed += f"; not recorded (older result files): {unknown}"
    return (
        f"Runs per machine: {listed}. A deep learner's result for a seed can differ between "
        "CPU vendors (python/README.md), so compare its runs from one machine."
    )


def report_command(a: dict[str, Any]) -> str:
    """The ``report`` command that writes this page from its result directories."""
    suite = a["manifest"]["suite"]["name"]
    return (
        "python -m sixaxis_avoid.benchmark report --results "
        + a.get("results_dir", f"results/bench/{suite}")
        + "".join(f" --longer {lo['dir']}" for lo in a.get("longer", []))
        + (f" --out {a['out']}" if a.get("out") else "")
    )


def run_commands(a: dict[str, Any]) -> list[str]:
    """The commands that made this study: the tuning runs recorded in the hyperparameter
    file, the study's own commands, and a cluster-sized variant of them."""
    data = hpmod.load(a["manifest"]["suite"].get("hyperparams", "v1"))
    tune_cmds: list[str] = []
    for entry in data.get("learners", {}).values():
        cmd = (entry.get("tuning") or {}).get("command")
        if cmd and cmd not in tune_cmds:
            tune_cmds.append(cmd)
    suite = a["manifest"]["suite"]["name"]
    return [
        "```bash",
        "bash scripts/setup.sh && source .venv/bin/activate   # or: pip install -e '.[bench]'",
        *(tune_cmds or [f"python -m sixaxis_avoid.benchmark tune --suite {suite}"]),
        *study_commands(a["manifest"]),
        *[c for lo in a.get("longer", []) for c in lo["manifest"].get("commands", [])],
        report_command(a),
        "# a cluster-sized run: join a Ray cluster, 20 seeds, every deep budget x10",
        f"python -m sixaxis_avoid.benchmark run --suite {suite} --address auto --seeds 20 "
        "--budget-scale 10 --out-dir results/bench/cluster",
        "```",
    ]


def table(rows: dict[str, dict[str, Any]], label: str) -> list[str]:
    head = [
        label,
        "learner",
        "runs",
        "success",
        "mean score",
        "env steps (median)",
        "1st success: steps / wall / CPU",
        "convergence: steps / wall / CPU",
        "Alg. 1 passes",
        "Alg. 2 success (runs)",
        "re-plans",
    ]
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for key, per in rows.items():
        for lr, s in per.items():
            if not s["runs"]:
                continue
            out.append(
                "| "
                + " | ".join(
                    [
                        key,
                        lr,
                        str(s["runs"]),
                        fmt(s["success_rate"]),
                        fmt(s["score_mean"], ".3f"),
                        fmt_steps(s["env_steps_median"]),
                        f"{fmt_steps(s['first_success_steps'])} / "
                        f"{fmt_time(s['first_success_wall_s'])} / "
                        f"{fmt_time(s['first_success_cpu_s'])} ({fmt(s['first_success_rate'])})",
                        f"{fmt_steps(s['convergence_steps'])} / "
                        f"{fmt_time(s['convergence_wall_s'])} / "
                        f"{fmt_time(s['convergence_cpu_s'])} ({fmt(s['convergence_rate'])})",
                        fmt(s["algorithm1_pass_rate"]),
                        f"{fmt(s['algorithm2_success_rate'])} ({s['algorithm2_runs']})",
                        fmt(s["replans_mean"], ".1f"),
                    ]
                )
                + " |"
            )
    return out


def markdown(
    a: dict[str, Any],
    figs: dict[str, Path],
    out_path: Path,
    longer: list[dict[str, Any]] | None = None,
) -> str:
    m = a["manifest"]
    suite = m["suite"]
    agg = a["agg"]
    learners = a["learners"]
    rel = {k: os.path.relpath(v, out_path.parent) for k, v in figs.items()}

    def metric(lr: str, key: str) -> str:
        s = agg["learners"][lr]
        return stats.interval_text(s[key], s[f"{key}_ci"], s.get("seeds", 2), digits=3)

    ranked = sorted(
        learners, key=lambda lr: (-agg["learners"][lr]["iqm"], -agg["learners"][lr]["mean"])
    )
    tasks_lines = []
    for t in a["tasks"]:
        d = a["task_objs"][t].describe()
        tasks_lines.append(
            f"| {t} | {d['group']} | {'x'.join(map(str, d['grid']))} | {d['obstacles']} | "
            f"{len(d['targets'])} | {', '.join(map(str, d['optimal_lengths']))} |"
        )
    poi = agg["poi"]
    poi_learners = [x for x in learners if any(k.startswith(f"{x},") for k in poi)]
    poi_rows = []
    for x in poi_learners:
        cells = []
        for y in poi_learners:
            p = poi.get(f"{x},{y}")
            cells.append(
                "—" if p is None else stats.interval_text(p["p"], p["ci"], len(a["seeds"]))
            )
        poi_rows.append(f"| **{x}** | " + " | ".join(cells) + " |")
    L = [
        "# Learner benchmark",
        "",
        "Generated by `python -m sixaxis_avoid.benchmark report` from the result files of the "
        "study below (do not edit by hand; re-run the commands under *How to run*):",
        "",
        "```bash",
        report_command(a),
        "```",
        "",
        *(
            [
                f"This is the history page of suite {suite['name']}; the current benchmark is "
                f"[{Path(a['current']).name}]({os.path.relpath(a['current'], out_path.parent)}).",
                "",
            ]
            if a.get("current")
            else []
        ),
        f"Suite **{suite['name']}** version {suite['version']}: {suite.get('description', '')} "
        f"{len(a['tasks'])} tasks x {len(a['seeds'])} seeds x {len(learners)} learners = "
        f"{len(a['runs'])} runs, each a Ray task ({m['ray']}). {provenance(m)}; the runs took "
        f"{run_hours(a['runs']):.1f} core-hours (each run's own wall time, summed); load "
        f"average at the end {m['load_average']}. Versions: "
        + ", ".join(f"{k} {v}" for k, v in m["versions"].items())
        + "."
        + "".join(f" {s}" for s in [run_machines(a["runs"])] if s),
        "",
        "## Headline",
        "",
        "Ranked by IQM of the final score (95% stratified-bootstrap CI; overlapping intervals "
        "are not a ranking):",
        "",
        *[
            f"{i + 1}. **{lr}** ({title(lr)}): IQM {metric(lr, 'iqm')}, success "
            f"{fmt(a['per'][lr]['success_rate'])}, median "
            f"{fmt_steps(a['per'][lr]['env_steps_median'])} env steps."
            for i, lr in enumerate(ranked)
        ],
        "",
        *longer_headline(a),
        "Learners use different numbers of env steps (the column above): the tabular learners "
        "the paper's episode count, the deep learners the suite's budget, BFS none (it reads "
        "the grid). Compare sample efficiency on the learning curves (score against env "
        "steps), and check *Did the curves plateau?* before reading a final score as what a "
        "learner can reach.",
        "",
        *hyperparam_section(a),
        "## Aggregate scores (rliable)",
        "",
        "Score of a run: SPL of its final greedy path (BFS optimum over the path's length if it "
        "reaches the target, else 0), averaged over the task's evaluation targets. Intervals: 95% "
        f"stratified bootstrap over runs ({a['reps']} replications, seeded).",
        "",
        # A marked section (scripts/docsections.py): README.md shows a copy of it.
        "<!-- benchmark-aggregate:begin -->",
        "| learner | IQM | mean | optimality gap |",
        "|---|---|---|---|",
        *[
            f"| {lr} | {metric(lr, 'iqm')} | {metric(lr, 'mean')} | "
            f"{metric(lr, 'optimality_gap')} |"
            for lr in learners
        ],
        "<!-- benchmark-aggregate:end -->",
        "",
        f"![IQM, mean and optimality gap]({rel['iqm']})",
        "",
        f"![Performance profiles]({rel['profiles']})",
        "",
        f"![Learning curves]({rel['curves']})",
        "",
        "### Probability of improvement",
        "",
        "P(row > column): the probability that a run of the row learner scores higher than a run "
        "of the column learner on a task drawn at random (ties count half), 95% CI. The "
        "reference (BFS) is left out.",
        "",
        "| | " + " | ".join(poi_learners) + " |",
        "|---|" + "---|" * len(poi_learners),
        *poi_rows,
        "",
        *plateau_section(a),
        *[
            x
            for i, lo in enumerate(longer or [])
            for x in longer_section(lo, rel.get(f"longer{i}"))
        ],
        "## Per learner (all tasks)",
        "",
        *table({"all": a["per"]}, "tasks"),
        "",
        "## Per group",
        "",
        *table(a["per_group"], "group"),
        "",
        "## Per task",
        "",
        *table(a["per_task"], "task"),
        "",
        "## Tasks",
        "",
        "| task | group | grid | obstacles | targets | BFS optimum (moves) |",
        "|---|---|---|---|---|---|",
        *tasks_lines,
        "",
        f"Budgets: {json.dumps(suite['budgets'])}; Algorithm 2 re-plan caps per family: "
        f"{json.dumps(suite.get('algorithm2', {}))}.",
        "",
        "## What the columns mean",
        "",
        "- **success**: fraction of evaluation targets the final greedy path reaches, averaged "
        "over runs. Tabular Q-learning: the eq. 8 greedy rollout (fails on a collision or a "
        "revisit). Deep learners: the deterministic policy from the start until the target, a "
        "loop (a repeated cell and collision flag) or the step cap; bumps leave the terminal in "
        "place and are not moves.",
        "- **env steps**: env steps the learner used. Tabular Q-learning: the paper's episode "
        "count (10000 unless the suite says otherwise); on goal tasks re-learned per target and "
        "summed. Deep learners: the suite's budget (v1's run files: rounded up to a whole "
        "rollout by PPO/A2C; runs made since the budget became a cap stop at the last whole "
        "rollout within it).",
        "- **1st success**: env steps and training time (wall / CPU, greedy evaluations "
        "excluded) until the first training episode that reached a target; median over the runs "
        "that had one (their fraction in brackets).",
        "- **convergence**: the first checkpoint from which the greedy score stays at its final "
        "value, for runs whose final score is above 0 (their fraction in brackets); checkpoints "
        "are the suite's geometric grid of env steps.",
        "- **Alg. 1 passes**: the whole arm follows the first learned path (Algorithm 1 from "
        "beta_0). **Alg. 2 success**: the paper's re-planning loop, run by the core's "
        "`sixaxis_avoid.plan(learner=...)` for every learner (deep learners retrain from scratch "
        "per re-plan, within the suite's cap); the number of runs where it ran in brackets.",
        "",
        "## How to run",
        "",
        *run_commands(a),
        "",
        "A restarted `run` skips the runs whose result file is there (for the same spec).",
        "",
    ]
    return "\n".join(L)


def longer_figures(longer: list[dict[str, Any]], figures_dir: Path) -> dict[str, Path]:
    """One figure per *Longer budgets* section that ran a learner, named by its scale and
    what it changed (``longer_x10_ppo_lr_schedule_linear.png``), keyed ``longer{i}``."""
    figs: dict[str, Path] = {}
    names: set[str] = set()
    for i, lo in enumerate(longer):
        if lo["learners"]:
            name = figure_name(lo)
            name = name if name not in names else f"{name}_{i + 1}"
            names.add(name)
            figs[f"longer{i}"] = longer_figure(lo, figures_dir / f"{name}.png", COLORS)
    return figs


_SECTION = re.compile(r"<!-- ([\w.-]+):begin -->\n.*?<!-- \1:end -->", re.S)


def keep_other_sections(out: Path, text: str, exclude: set[str] | None = None) -> str:
    """``text`` with the marked sections of the old ``out`` that other scripts own (markers
    as in scripts/docsections.py, e.g. ``jax-twin``) appended, so a regeneration keeps them
    (but those in ``exclude``: sections that moved to another page)."""
    if not out.exists():
        return text
    mine = {m.group(1) for m in _SECTION.finditer(text)} | set(exclude or ())
    kept = [m.group(0) for m in _SECTION.finditer(out.read_text()) if m.group(1) not in mine]
    return text.rstrip("\n") + "".join(f"\n\n{k}" for k in kept) + "\n"


def write_report(
    results: Path,
    out: Path,
    figures_dir: Path | None = None,
    reps: int = stats.REPS,
    longer: Path | list[Path] | None = None,
    current: Path | None = None,
    out_label: str | None = None,
) -> dict[str, Any]:
    """Write the report ``out`` and its figures from the study in ``results``; with
    ``longer``, a second study of the same suite at a larger ``--budget-scale`` is set beside
    it (section *Longer budgets*). ``current``: the page of the current benchmark, when this
    one is a history page (it links it); ``out_label``: the ``--out`` its command names."""
    results, out = Path(results), Path(out)
    figures_dir = Path(figures_dir) if figures_dir else out.parent / "figures" / "bench"
    a = analyse(results, reps)
    a["results_dir"] = str(results)
    if current is not None:
        a["current"] = str(current)
    if out_label:
        a["out"] = out_label
    figs = figures(a, figures_dir)
    dirs = [longer] if isinstance(longer, (str, Path)) else list(longer or [])
    a["longer"] = [analyse_longer(a, Path(d), reps) for d in dirs]
    figs.update(longer_figures(a["longer"], figures_dir))
    atomic_write_text(out, keep_other_sections(out, markdown(a, figs, out, a["longer"])))
    summary = {
        "learners": a["learners"],
        "tasks": a["tasks"],
        "seeds": a["seeds"],
        "aggregates": a["agg"],
        "per_learner": a["per"],
        "per_group": a["per_group"],
    }
    summary["longer"] = longer_summary(a["longer"])
    atomic_write_text(figures_dir / "bench_summary.json", json.dumps(summary, indent=1) + "\n")
    return a


def longer_summary(longer: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The figures of each *Longer budgets* section, for the JSON beside the report."""
    return [
        {
            lr: {k: v[k] for k in ("seeds", "scale", "changed", "status", "budget_env_steps",
                                   "poi_long_over_x1", "plateau_x1", "plateau_long", "per_task",
                                   "core_hours")}
            | {"aggregates": {x: {k: y[k] for k in ("iqm", "iqm_ci", "mean", "mean_ci")}
                              for x, y in v["agg"]["learners"].items()}}
            for lr, v in lo["learners"].items()
        }
        for lo in longer
    ]  # fmt: skip


def longer_markdown(a: dict[str, Any], figs: dict[str, Path], out_path: Path) -> str:
    """The page ``report --longer-only`` writes: the *Longer budgets* sections alone, for a
    reported study that holds just the learners compared (their x1 runs)."""
    m = a["manifest"]
    suite = m["suite"]
    rel = {k: os.path.relpath(v, out_path.parent) for k, v in figs.items()}
    learners = ", ".join(a["learners"])
    sections = [
        x for i, lo in enumerate(a["longer"]) for x in longer_section(lo, rel.get(f"longer{i}"))
    ]
    # The suite's deep learners that no section here compares (no x1 runs given for them).
    tuned = hpmod.load(suite.get("hyperparams", "v1")).get("learners", {})
    compared = {lr for lo in a["longer"] for lr in lo["learners"]}
    absent = [lr for lr in tuned if lr not in compared]
    L = [
        "# Learner benchmark: longer budgets",
        "",
        "Generated by `python -m sixaxis_avoid.benchmark report --longer-only` from the result "
        "files of the studies below (do not edit by hand; re-run the commands under *How to "
        "run*).",
        "",
        f"Suite **{suite['name']}** version {suite['version']}. Each section runs some deep "
        "learners with every deep budget of the suite multiplied, with the hyperparameters "
        "tuned at x1, and sets each beside its own x1 runs on the same tasks and seeds: does "
        "its score still rise with more env steps, and where does its curve flatten? The x1 "
        f"runs are {len(a['runs'])} runs of {learners} in `{a['results_dir']}`. "
        f"{provenance(m)}; versions: "
        + ", ".join(f"{k} {v}" for k, v in m["versions"].items())
        + ". Score of a run: SPL of its final greedy path (BFS optimum over the path's length "
        "if it reaches the target, else 0), averaged over the task's evaluation targets.",
        "",
        "## Headline",
        "",
        *longer_headline(a),
        *(
            [f"Not run with a longer budget here: {', '.join(absent)} (see *How to run*).", ""]
            if absent
            else []
        ),
        *sections,
        "## How to run",
        "",
        "```bash",
        "bash scripts/setup.sh && source .venv/bin/activate   # or: pip install -e '.[bench]'",
        *study_commands(m),
        *[c for lo in a["longer"] for c in lo["manifest"].get("commands", [])],
        "python -m sixaxis_avoid.benchmark report --longer-only --results "
        + a["results_dir"]
        + "".join(f" --longer {lo['dir']}" for lo in a["longer"])
        + f" --out {out_path}",
        "```",
        "",
        "A restarted `run` skips the runs whose result file is there (for the same spec), so a "
        "command with more `--seeds` adds only the seeds not yet run.",
        "",
    ]
    return "\n".join(L)


def write_longer_report(
    results: Path,
    longer: list[Path],
    out: Path,
    figures_dir: Path | None = None,
    reps: int = stats.REPS,
) -> dict[str, Any]:
    """Write only the *Longer budgets* sections to ``out``: each study in ``longer`` beside
    the x1 runs in ``results`` of the same learners (which need not hold the whole suite)."""
    results, out = Path(results), Path(out)
    if not longer:
        raise ValueError("--longer-only needs at least one --longer DIR")
    figures_dir = Path(figures_dir) if figures_dir else out.parent / "figures" / "bench"
    a = analyse(results, reps)
    a["results_dir"] = str(results)
    a["longer"] = [analyse_longer(a, Path(d), reps) for d in longer]
    figs = longer_figures(a["longer"], figures_dir)
    atomic_write_text(out, longer_markdown(a, figs, out))
    summary = longer_summary(a["longer"])
    atomic_write_text(figures_dir / "longer_summary.json", json.dumps(summary, indent=1) + "\n")
    return a
