"""The v2 page's *How to run* section: the commands that produced the study, the report
command, and how to run a larger study on a Ray cluster (docs/BENCHMARKS.md, *How to run*).

Entry points: :func:`how_to_run` (the section's lines, from :func:`report_v2.analyse_v2`'s
analysis) and :func:`report_command_v2` (the command that writes the page).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any


def report_command_v2(a: dict[str, Any], out: Path) -> str:
    """The command that writes the page ``out`` from the study's results."""
    return (
        f"python -m sixaxis_avoid.benchmark report --suite {a['suite'].name} "
        f"--results {a['results_dir']} --out {out}"
    )


def how_to_run(a: dict[str, Any], out: Path) -> list[str]:
    """The section: setup, every command the study's manifest recorded (or the default run
    command), the report command, then the Ray cluster paragraph."""
    suite = a["suite"].name
    commands = (a["manifest"] or {}).get("commands", []) or [
        f"python -m sixaxis_avoid.benchmark run --suite {suite} --out-dir {a['results_dir']}"
    ]
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
        "(tested on two nodes started on loopback: tests/test_remote_ray.py):",
        "",
        "```bash",
        "ray start --head --port=6379                 # on the head node",
        "ray start --address=HEAD:6379                # on every other node (same checkout and "
        "environment)",
        f"python -m sixaxis_avoid.benchmark run --suite {suite} --learners jax_ppo,ppo "
        "--seeds 5 --budgets 1000000 --hyperparams python/sixaxis_avoid/benchmark/hyperparams/"
        f"v2.json --address HEAD:6379 --no-progress --out-dir {a['results_dir']}",
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
        "every few minutes), and the same command with `--status` prints how far it got; a "
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
