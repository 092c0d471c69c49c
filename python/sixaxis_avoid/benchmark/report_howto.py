"""The v2 page's *How to run* section: the commands that produced the study, the report
command, and how to run a larger study on a Ray cluster (docs/BENCHMARKS.md, *How to run*),
its example being the runs the study lacks first.

Entry points: :func:`how_to_run` (the section's lines, from :func:`report_v2.analyse_v2`'s
analysis), :func:`report_command_v2` (the command that writes the page) and
:func:`cluster_runs` (the budget, learners and seeds of the cluster example).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from sixaxis_avoid.benchmark.stats import fmt_steps


def report_command_v2(a: dict[str, Any], out: Path) -> str:
    """The command that writes the page ``out`` from the study's results."""
    return (
        f"python -m sixaxis_avoid.benchmark report --suite {a['suite'].name} "
        f"--results {a['results_dir']} --out {out}"
    )


def cluster_runs(a: dict[str, Any]) -> tuple[int, list[str], int]:
    """The cluster example's budget, learners and seeds: the first budget of the axis that
    some ranked learner still lacks (``missing_budgets``), the learners that lack it and
    the seeds the ranking compares at the last budget every ranked learner ran; with none
    lacking, the best learners at the axis's last budget."""
    missing = a.get("missing_budgets") or {}
    common = a.get("common_budgets") or []
    seeds = len(a["per_budget"][common[-1]]["seeds"]) if common else len(a["suite"].seeds)
    if not missing:
        return a["axis"][-1], list(a.get("best") or a.get("ranked") or []), seeds
    budget = min(min(bs) for bs in missing.values())
    return budget, [lr for lr in a["ranked"] if budget in missing.get(lr, [])], seeds


def cluster_what(a: dict[str, Any], budget: int, learners: list[str], seeds: int) -> str:
    """What the cluster example's run command (:func:`cluster_runs`) runs, in words."""
    who = ", ".join(learners)
    if not a.get("missing_budgets"):
        return f"the best learners' ({who}) runs at {fmt_steps(budget)} env steps, {seeds} seeds"
    return (
        f"what the study lacks first: {who} at {fmt_steps(budget)} env steps ({seeds} seeds, "
        "as the ranking compares at the last budget every ranked learner ran), each once its "
        "search has put the values tuned there in the hyperparameter file (or its twin's "
        "values are borrowed)"
    )


def how_to_run(a: dict[str, Any], out: Path) -> list[str]:
    """The section: setup, every command the study's manifest recorded (or the default run
    command), the report command, then the Ray cluster paragraph."""
    suite = a["suite"].name
    commands = (a["manifest"] or {}).get("commands", []) or [
        f"python -m sixaxis_avoid.benchmark run --suite {suite} --out-dir {a['results_dir']}"
    ]
    budget, learners, seeds = cluster_runs(a)
    return [
        "## How to run",
        "",
        "```bash",
        "bash scripts/setup.sh && source .venv/bin/activate   # or: pip install -e '.[bench]'",
        *commands,
        report_command_v2(a, out),
        "```",
        "",
        "**On a Ray cluster**, for the budgets this machine cannot finish in a session "
        "(tested on two nodes started on loopback: tests/test_remote_ray.py); the run "
        f"command below is {cluster_what(a, budget, learners, seeds)}:",
        "",
        "```bash",
        "ray start --head --port=6379                 # on the head node",
        "ray start --address=HEAD:6379                # on every other node (same checkout and "
        "environment)",
        f"python -m sixaxis_avoid.benchmark run --suite {suite} --learners {','.join(learners)} "
        f"--seeds {seeds} --budgets {budget} --hyperparams python/sixaxis_avoid/benchmark/"
        f"hyperparams/v2.json --address HEAD:6379 --no-progress --out-dir {a['results_dir']}",
        "```",
        "",
        "Each SB3 or tabular run is a Ray task of one CPU; a JAX learner's seeds of one task and "
        "budget train in one vmapped call, one task of `--jax-cpus` CPUs (default 1). The run "
        "files are written where the driver runs, and the same command run again skips the runs "
        "already there; `touch OUT_DIR/STOP` stops a command without losing work (it hands out no"
        " more runs, its running runs finish, exit status 75). A command that was stopped left "
        "its wall time up to its last finished run in the directory's `study.json` (rewritten "
        "after each run), and the next one adds its own. A JAX search (`python -m "
        "sixaxis_avoid.benchmark.jax_tune`) takes `--address` too: each compiled group (a tuning "
        "task and a draw of the static knobs, 10 for this suite) is a Ray task of `--group-cpus` "
        "CPUs. It resumes from the groups it saved (`--parts`), so it can span sessions "
        "(with `--save-state`, from inside a group too: its training state is saved there "
        "every few minutes, on a machine that keeps it; with `--split-seeds`, a group not yet "
        "begun trains one seed at a time, each saved as it finishes), and the same command "
        "with `--status` prints how far it got; a "
        "parts directory under `docs/results/v2-pending` (its `study.json` is the search's "
        "manifest) is named in the headline as a set in progress until the search ends. It "
        "comes before a budget's runs: a run at a budget with no tuned entry uses "
        "the learner's defaults and is marked untuned (and an SB3 learner that borrows its JAX "
        "twin's values needs them borrowed first, `python -m sixaxis_avoid.benchmark.borrow`).",
        "",
        "SB3's PPO and DQN can also be tuned by a search of their own at a budget, with the "
        "JAX search's effort (its space and sampler, `--trials` draws x `--seeds` seeds on "
        "the tuning tasks, the final SPL as objective) plus the twin's values as one more "
        "candidate: `python -m sixaxis_avoid.benchmark.sb3_tune --learner ppo --suite "
        f"{suite} --budget 300000 --trials 32 --seeds 3 --out docs/results/v2-tuning/"
        "ppo-300000.json --record` (`--address` for a cluster). Its runs are benchmark runs "
        "without re-plans, kept beside the trials file (or in `--log-dir`), so a stopped "
        "search resumes; a log directory under `docs/results/v2-pending` is named in the "
        "headline as a set in progress until the search ends; `--record` puts the best "
        "values in place of the borrowed ones, and that budget's SB3 runs then run again on "
        "them.",
        "",
    ]
