"""Longer budgets: the same suite with every deep budget scaled, for some learners and seeds.

The reported study is sized for one small machine; its plateau table shows whether the deep
learners' curves had flattened by the end of their budget. This module reads a second study
of the same suite run with ``--budget-scale K`` (its own results directory) and sets each of
its learners beside itself in the reported study, on the same tasks and seeds:

- final score at x1 and at xK: IQM and mean with 95% stratified-bootstrap CIs, and the
  probability that a run at xK beats a run at x1 (rliable);
- the best checkpoint score (did the learner find the path at some point and then lose it?);
- the plateau table at xK, per-task mean scores at both budgets, and a figure of both
  learning curves.

Entry points: :func:`analyse_longer` (numbers), :func:`longer_figure` and
:func:`longer_section` (what ``report --longer DIR`` adds to docs/BENCHMARKS.md).
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path
from typing import Any

import numpy as np

from sixaxis_avoid.benchmark import stats
from sixaxis_avoid.benchmark._io import atomic_savefig
from sixaxis_avoid.benchmark.runner import load_runs

_UNSET = object()


def change_label(v: dict[str, Any]) -> str:
    """What a learner's longer runs changed beyond the budget, short: its untuned defaults
    (against tuned values at x1), or the changed hyperparameters."""
    if v.get("status") == "defaults" and v.get("status_x1") == "tuned":
        return "untuned defaults"
    return ", ".join(f"`{k}`={json.dumps(x)}" for k, x in v["changed"].items())


def run_hours(runs: list[dict[str, Any]]) -> float:
    """Hours of one core the runs took: each run's wall time (training, evaluations and
    Algorithm 2), summed; unlike the driver's wall time it survives restarts."""
    return sum(r["timing"].get("run_wall_time_s", r["timing"]["wall_time_s"]) for r in runs) / 3600


def is_variant(lo: dict[str, Any]) -> bool:
    """A study at the x1 budgets that changed hyperparameters: a variant, not a longer run."""
    return lo["scale"] == 1 and bool(section_changes(lo))


def section_changes(lo: dict[str, Any]) -> str:
    """What a longer study changed beyond the budget, learner by learner ('' if nothing)."""
    return "; ".join(
        f"{lr}: {change_label(v)}" for lr, v in lo["learners"].items() if change_label(v)
    )


def figure_name(lo: dict[str, Any]) -> str:
    """A file name for a longer study's figure: its scale and what it changed."""
    changes = section_changes(lo)
    slug = re.sub(r"[^a-z0-9]+", "_", changes.lower()).strip("_")
    if len(slug) > 60:  # many changed values: a short name, told apart by a digest
        slug = slug[:40].rstrip("_") + "_" + hashlib.sha256(changes.encode()).hexdigest()[:8]
    return f"longer_x{lo['scale']:g}" + (f"_{slug}" if slug else "")


def n_seeds(n: int) -> str:
    """'1 seed', '3 seeds'."""
    return f"{n} seed" if n == 1 else f"{n} seeds"


def _key(r: dict[str, Any]) -> tuple[str, str, int]:
    return r["spec"]["learner"], r["spec"]["task"]["id"], r["spec"]["seed"]


def best_score(r: dict[str, Any]) -> float:
    """A run's best checkpoint score (its final evaluation included)."""
    return max([p["score"] for p in r["result"]["curve"]] + [r["result"]["score"]])


def analyse_longer(a: dict[str, Any], long_dir: Path, reps: int = stats.REPS) -> dict[str, Any]:
    """Compare the runs in ``long_dir`` with the reported study ``a`` (from
    :func:`report.analyse`), learner by learner, on the (task, seed) pairs both have for
    every task of ``a``."""
    long_dir = Path(long_dir)
    tasks = a["tasks"]
    runs = [r for r in load_runs(long_dir) if r["spec"]["task"]["id"] in tasks]
    if not runs:
        raise ValueError(f"--longer {long_dir}: no result files for the study's tasks")
    # The manifest is written when a `run` command ends; a study still running has none yet.
    manifest_path = long_dir / "study.json"
    manifest = json.loads(manifest_path.read_text()) if manifest_path.exists() else {}
    named = manifest.get("learners", []) + [_key(r)[0] for r in runs]
    learners = [lr for lr in dict.fromkeys(named) if any(_key(r)[0] == lr for r in runs)]
    base = {_key(r): r for r in a["runs"]}
    # Every seed among the reported study's runs; below, each learner keeps those it has on
    # every task (not only the seeds complete for all learners: one may have more seeds).
    base_seeds = sorted({k[2] for k in base})
    out: dict[str, Any] = {
        "dir": str(long_dir),
        "manifest": manifest,
        "learners": {},
        "tasks": tasks,
    }
    for lr in learners:
        mine = {_key(r): r for r in runs if r["spec"]["learner"] == lr}
        seeds = [
            s for s in base_seeds if all((lr, t, s) in mine and (lr, t, s) in base for t in tasks)
        ]
        if not seeds:
            continue
        long_runs = [mine[(lr, t, s)] for t in tasks for s in seeds]
        short_runs = [base[(lr, t, s)] for t in tasks for s in seeds]

        def matrix(by: dict[tuple[str, str, int], dict[str, Any]], f: Any) -> np.ndarray:
            return np.array([[f(by[(lr, t, s)]) for t in tasks] for s in seeds])  # noqa: B023

        final = {
            "x1": matrix(base, lambda r: r["result"]["score"]),
            "long": matrix(mine, lambda r: r["result"]["score"]),
            "best": matrix(mine, best_score),
        }
        agg = stats.aggregates(final, reps=reps, poi_exclude=("best",))
        scale = float(np.median([r["spec"]["budget"] / base[_key(r)]["spec"]["budget"]
                                 for r in long_runs]))  # fmt: skip
        budgets = sorted({(r["spec"]["task"]["id"], r["spec"]["budget"]) for r in long_runs})
        hi = max(r["result"]["curve"][-1]["env_steps"] for r in long_runs)
        grid = np.unique(np.geomspace(1, max(hi, 2), 40).round().astype(np.int64))
        curves = {}
        for label, rs in (("x1", short_runs), ("long", long_runs)):
            curves[label] = stats.iqm_curves(
                rs, [lr], tasks, seeds, grid, reps=max(reps // 4, 100)
            )[lr]
        hp_long, hp_x1 = long_runs[0]["spec"]["hyperparams"], short_runs[0]["spec"]["hyperparams"]
        out["learners"][lr] = {
            "seeds": seeds,
            # Hyperparameters that differ from the reported study's (beyond the budget).
            # (a key only the reported study set reads "default": the library's own value).
            "changed": {
                k: hp_long.get(k, "default")
                for k in sorted(set(hp_long) | set(hp_x1))
                if hp_long.get(k, _UNSET) != hp_x1.get(k, _UNSET)
            },
            "status": long_runs[0]["spec"].get("hyperparams_status"),
            "status_x1": short_runs[0]["spec"].get("hyperparams_status"),
            "scale": scale,
            "budget_env_steps": sorted({b for _, b in budgets}),
            "agg": agg,
            "poi_long_over_x1": agg["poi"]["long,x1"],
            "per_x1": stats.per_learner(short_runs),
            "per_long": stats.per_learner(long_runs),
            "plateau_x1": stats.plateau(short_runs, [lr])[lr],
            "plateau_long": stats.plateau(long_runs, [lr])[lr],
            "per_task": {
                t: {
                    "x1": float(final["x1"][:, j].mean()),
                    "long": float(final["long"][:, j].mean()),
                    "best": float(final["best"][:, j].mean()),
                }
                for j, t in enumerate(tasks)
            },
            "grid": grid.tolist(),
            "curves": curves,
            "core_hours": run_hours(long_runs),
            "core_hours_x1_runs": run_hours(short_runs),
        }
    # Deep learners of the reported study left out, with what they would cost at the scale
    # most learners here ran at (their own summed run time at x1, times the scale).
    scales = [v["scale"] for v in out["learners"].values()]
    out["scale"] = float(np.median(scales)) if scales else None
    out["not_run"] = {}
    for lr in a["learners"]:
        rs = [r for r in a["runs"] if r["spec"]["learner"] == lr]
        if lr in out["learners"] or not rs or rs[0]["spec"]["family"] != "deep":
            continue
        hours = sum(r["timing"].get("run_wall_time_s", r["timing"]["wall_time_s"]) for r in rs)
        out["not_run"][lr] = {
            "runs": len(rs),
            "core_hours_x1": hours / 3600,
            "core_hours_estimate": hours / 3600 * (out["scale"] or 1.0),
        }
    return out


def longer_figure(lo: dict[str, Any], path: Path, colors: dict[str, str]) -> Path:
    """IQM learning curves at x1 (dashed) and at the longer budget (solid), one panel per
    learner, 95% CI bands."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(lo["learners"])
    fig, axes = plt.subplots(1, max(len(names), 1), figsize=(4.2 * max(len(names), 1), 3.8),
                             sharey=True, squeeze=False)  # fmt: skip
    for ax, lr in zip(axes[0], names):
        v = lo["learners"][lr]
        grid = np.asarray(v["grid"])
        color = colors.get(lr, "gray")
        for label, style, name in (("x1", "--", "x1"), ("long", "-", f"x{v['scale']:g}")):
            c = v["curves"][label]
            keep = grid <= max(c["max_env_steps"], 1)
            ax.plot(grid[keep], np.asarray(c["iqm"])[keep], style, color=color, label=name)
            ax.fill_between(grid[keep], np.asarray(c["lo"])[keep], np.asarray(c["hi"])[keep],
                            color=color, alpha=0.12, linewidth=0)  # fmt: skip
        ax.set_xscale("log")
        ax.set_ylim(-0.02, 1.02)
        ax.set_title(f"{lr}: {n_seeds(len(v['seeds']))} x {len(lo['tasks'])} tasks")
        ax.set_xlabel("environment steps")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    axes[0][0].set_ylabel("IQM score (SPL of the greedy path)")
    fig.tight_layout()
    atomic_savefig(fig, path)
    plt.close(fig)
    return path


def fmt_ci(s: dict[str, Any], key: str) -> str:
    """An aggregate with its 95% CI (none with one seed per task)."""
    return stats.interval_text(s[key], s[f"{key}_ci"], s.get("seeds", 2))


def longer_section(lo: dict[str, Any], figure_rel: str | None) -> list[str]:
    """The Markdown section ``report --longer`` adds."""
    m = lo["manifest"]
    if not lo["learners"]:
        return []
    scale = lo["scale"]
    changed = section_changes(lo)
    variant = is_variant(lo)
    word = "variant" if variant else "longer"
    here_text = "in the variant" if variant else "with the longer budget"
    if variant:
        L = [
            f"## Same budgets, other hyperparameters ({changed})",
            "",
            "The same suite at the same budgets with other hyperparameters for the learners "
            "below, set beside the same learners, tasks and seeds of the x1 study.",
        ]
    else:
        L = [
            f"## Longer budgets (x{scale:g}{', ' + changed if changed else ''})",
            "",
            f"The same suite with every deep budget multiplied by {scale:g} (hyperparameters "
            f"as tuned at x1{', but ' + changed if changed else ', unchanged'}), for the "
            "learners and seeds below, set beside the same learners, tasks and seeds of the x1 "
            "study.",
        ]
    L[-1] += (
        " Score: the final greedy path's SPL, as above; *best checkpoint* is the best score a "
        "run's greedy path had at any checkpoint (it found that path, whether or not it kept "
        f"it). P({word} > x1): the probability that a run here scores higher than one of the "
        "x1 study on a random task (ties half), 95% CI. Core-hours: each run's own wall time, "
        "summed, for the x1 runs and these."
    )
    L += [
        "",
        f"| learner | seeds | env steps per run | IQM x1 | IQM {word} | mean x1 | mean {word} "
        f"| P({word} > x1) | success x1 → {word} | best checkpoint (mean) "
        f"| core-hours x1 → {word} |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for lr, v in lo["learners"].items():
        g = v["agg"]["learners"]
        p = v["poi_long_over_x1"]
        poi = stats.interval_text(p["p"], p["ci"], len(v["seeds"]))
        L.append(
            f"| {lr} | {len(v['seeds'])} | {' / '.join(f'{b:,}' for b in v['budget_env_steps'])} "
            f"| {fmt_ci(g['x1'], 'iqm')} | {fmt_ci(g['long'], 'iqm')} | {fmt_ci(g['x1'], 'mean')} "
            f"| {fmt_ci(g['long'], 'mean')} | {poi} "
            f"| {v['per_x1']['success_rate']:.2f} → {v['per_long']['success_rate']:.2f} "
            f"| {g['best']['mean']:.2f} | {v['core_hours_x1_runs']:.2f} → {v['core_hours']:.2f} |"
        )
    for lr, v in lo["learners"].items():
        if change_label(v) == "untuned defaults":
            L += [
                "",
                f"{lr}'s values here against the tuned ones (`default`: the library's own): "
                + ", ".join(f"`{k}`={json.dumps(x)}" for k, x in v["changed"].items())
                + ".",
            ]
    L += [
        "",
        f"Did the {word} curves plateau? Mean score at a quarter, half and all of each run's "
        "env steps; runs whose score changed after half; mean best checkpoint; runs that ended "
        "below their best:",
        "",
        "| learner | budget | score at 1/4 | at 1/2 | at end | changing after 1/2 | best "
        "| ended below best |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for lr, v in lo["learners"].items():
        here = "variant" if variant else f"x{v['scale']:g}"
        for label, key in (("x1", "plateau_x1"), (here, "plateau_long")):
            q = v[key]
            L.append(
                f"| {lr} | {label} | {q['quarter']:.3f} | {q['half']:.3f} | {q['end']:.3f} | "
                f"{q['changed_late']:.2f} | {q['best']:.3f} | {q['fell_from_best']:.2f} |"
            )
    L += [
        "",
        f"Mean final score per task (x1 → {word}; best checkpoint in brackets):",
        "",
        "| task | " + " | ".join(lo["learners"]) + " |",
        "|---|" + "---|" * len(lo["learners"]),
    ]
    for t in lo["tasks"]:
        cells = []
        for v in lo["learners"].values():
            c = v["per_task"][t]
            cells.append(f"{c['x1']:.2f} → {c['long']:.2f} ({c['best']:.2f})")
        L.append(f"| {t} | " + " | ".join(cells) + " |")
    L.append("")
    if figure_rel:
        L += [
            f"![Learning curves at x1 and {here_text}]({figure_rel})",
            "",
        ]
    if lo["not_run"]:
        L.append(
            f"Not run {here_text} (the cost at this scale, estimated from their own run time "
            "at x1): "
            + "; ".join(
                f"{lr}: {v['runs']} runs, {v['core_hours_x1']:.1f} core-hours at x1, about "
                f"{v['core_hours_estimate']:.0f} at x{scale:g}"
                for lr, v in lo["not_run"].items()
            )
            + "."
        )
        L.append("")
    L += [
        "Commands (in the order they filled the study's directory; a finished run is skipped, "
        "so a command with `--seeds N` adds the seeds not yet there):",
        "",
        "```bash",
        *m.get("commands", [m["command"]] if "command" in m else ["(still running)"]),
        "```",
        "",
    ]
    return L
