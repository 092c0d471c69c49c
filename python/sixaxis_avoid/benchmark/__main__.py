"""``python -m sixaxis_avoid.benchmark {run,tune,tune-native,report,list}``: the learner benchmark.

python -m sixaxis_avoid.benchmark list                          # suites, learners, tasks
python -m sixaxis_avoid.benchmark run --suite quick             # CI-sized, a minute or two
python -m sixaxis_avoid.benchmark run --suite v1                # the reported study
python -m sixaxis_avoid.benchmark run --suite v1 --address auto # on a Ray cluster
python -m sixaxis_avoid.benchmark tune --suite v1 --trials 30   # Optuna, tuning tasks only
python -m sixaxis_avoid.benchmark tune-native --budget 100000 --trials 32 --seeds 3  # tabular
python -m sixaxis_avoid.benchmark run --suite v1 --learners ppo --budget-scale 10 \
    --set ppo.lr_schedule=linear --out-dir results/bench/v1-x10-lin  # longer, one change
python -m sixaxis_avoid.benchmark run --suite v2 --budgets 30000,100000   # part of the axis
python -m sixaxis_avoid.benchmark report --results docs/results/v2   # docs/BENCHMARKS.md (v2)
python -m sixaxis_avoid.benchmark report --results docs/results/v1 --longer docs/results/v1-x10 \
    --longer docs/results/v1-x4 --longer docs/results/v1-x10-lin   # docs/BENCHMARKS-v1.md
python -m sixaxis_avoid.benchmark report --longer-only --results X1 --longer DIR   # sections alone
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from sixaxis_avoid.benchmark import learners as lmod
from sixaxis_avoid.benchmark import runner
from sixaxis_avoid.benchmark.cli import command_line, parse_seeds, split
from sixaxis_avoid.benchmark.tasks import SuiteError, available, load_suite

DEFAULT_LEARNERS = "q_assist,q_plain,bfs,dqn,qrdqn,ppo,a2c"


def parse_sets(items: list[str]) -> dict[str, dict[str, Any]]:
    """``--set LEARNER.KEY=VALUE`` flags as per-learner overrides."""
    out: dict[str, dict[str, Any]] = {}
    for item in items:
        target, eq, raw = item.partition("=")
        learner, dot, key = target.partition(".")
        if not (eq and dot and learner and key):
            raise SystemExit(f"--set: {item!r}: expected LEARNER.KEY=VALUE")
        try:
            value = json.loads(raw)
        except json.JSONDecodeError:
            value = raw
        out.setdefault(learner, {})[key] = value
    return out


def union(first: list[str], then: list[str]) -> list[str]:
    """``first`` followed by the items of ``then`` not in it, order kept."""
    return list(dict.fromkeys([*first, *then]))


def add_ray_args(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("Ray")
    g.add_argument("--address", help="join this Ray cluster (e.g. auto, ray://host:10001)")
    g.add_argument("--num-cpus", type=int, help="local Ray: cores to use (default: all)")
    g.add_argument(
        "--no-ray", action="store_true", help="run in this process, one run after another"
    )
    g.add_argument("--no-progress", action="store_true", help="no progress bar")


def parse_args(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m sixaxis_avoid.benchmark", description=__doc__)
    sub = p.add_subparsers(dest="cmd", required=True)

    r = sub.add_parser("run", help="run a study (skips runs already done)")
    r.add_argument("--suite", default="v1", help=f"name ({', '.join(available())}) or path")
    r.add_argument("--learners", default=DEFAULT_LEARNERS, help="comma list; module:Class too")
    r.add_argument("--tasks", help="comma list of task ids (default: the suite's)")
    r.add_argument(
        "--seeds",
        help="a count N (0..N-1) or a comma list; one seed k: 'k,' (default: the suite's)",
    )
    r.add_argument("--hyperparams", help="hyperparameter file (default: the suite's)")
    r.add_argument(
        "--budget-scale", type=float, default=1.0, help="multiply the deep learners' budgets"
    )
    r.add_argument(
        "--budgets",
        help="comma list of env-step budgets of the suite's axis (suite v2; default: all "
        "but the best_only ones, which only the best learners run: name them)",
    )
    r.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="LEARNER.KEY=VALUE",
        help="override a hyperparameter (VALUE as JSON, else a string), e.g. "
        "ppo.lr_schedule=linear; repeatable",
    )
    r.add_argument("--out-dir", type=Path, help="default results/bench/SUITE")
    add_ray_args(r)
    r.add_argument(
        "--jax-cpus",
        type=int,
        default=1,
        help="Ray: CPUs each JAX group reserves (a JAX learner's seeds of one task and budget, "
        "vmapped in one call; capped at the largest node's CPUs)",
    )

    t = sub.add_parser("tune", help="Optuna study per deep learner on the tuning tasks")
    t.add_argument("--suite", default="v1")
    t.add_argument("--learners", default=",".join(("dqn", "qrdqn", "ppo", "a2c")))
    t.add_argument("--trials", type=int, default=10, help="trials per learner")
    t.add_argument("--seeds", help="default: the suite's tuning seeds")
    t.add_argument("--budget-scale", type=float, default=1.0)
    t.add_argument("--parallel-trials", type=int, default=2, help="trials run at once")
    t.add_argument("--sampler-seed", type=int, default=0)
    t.add_argument("--storage", help="Optuna storage URL (e.g. sqlite:///tune.db) to resume")
    t.add_argument("--out", type=Path, help="hyperparameter file (default: the suite's)")
    t.add_argument("--log-dir", type=Path, help="trial results (default results/tune/SUITE)")
    add_ray_args(t)

    tn = sub.add_parser(
        "tune-native", help="random search for the tabular learners at one env-step budget"
    )
    tn.add_argument("--suite", default="v1", help="its tuning tasks are searched on")
    tn.add_argument("--learners", default="q_assist", help="comma list of q_assist, q_plain")
    tn.add_argument("--budget", type=int, required=True, help="env steps per run")
    tn.add_argument("--trials", type=int, default=32)
    tn.add_argument(
        "--seeds",
        help="a count N (N seeds from the suite's first tuning seed; default 3) or a list",
    )
    tn.add_argument("--sampler-seed", type=int, default=0)
    tn.add_argument(
        "--out",
        type=Path,
        help="trials export (default docs/results/v2-tuning/LEARNER-BUDGET.json)",
    )
    tn.add_argument(
        "--record", type=Path, help="hyperparameter file whose by_budget entry gets the best values"
    )
    tn.add_argument("--no-progress", action="store_true")

    rep = sub.add_parser("report", help="docs/BENCHMARKS.md and figures from result files")
    rep.add_argument("--results", type=Path, default=Path("results/bench/v1"))
    rep.add_argument(
        "--suite",
        help="the study's suite (default: its study.json's); a suite with a budget axis (v2) "
        "gets the v2 page, which also works before any run (it says the results are pending)",
    )
    rep.add_argument(
        "--out",
        type=Path,
        help="default docs/BENCHMARKS.md for a suite with a budget axis (v2), "
        "docs/BENCHMARKS-v1.md for v1 (the history page), docs/BENCHMARKS_LONGER.md with "
        "--longer-only",
    )
    rep.add_argument(
        "--history",
        type=Path,
        default=Path("docs/BENCHMARKS-v1.md"),
        help="v2 page: the history page it links (default docs/BENCHMARKS-v1.md)",
    )
    rep.add_argument("--figures-dir", type=Path, help="default: OUT's folder / figures/bench")
    rep.add_argument("--reps", type=int, default=2000, help="bootstrap replications")
    rep.add_argument(
        "--longer",
        type=Path,
        action="append",
        help="results of the same suite at a larger --budget-scale, set beside the study "
        "(repeatable: one section each)",
    )
    rep.add_argument(
        "--longer-only",
        action="store_true",
        help="write only the --longer sections, beside the x1 runs in --results (which may "
        "hold just the learners compared)",
    )

    ls = sub.add_parser("list", help="suites, learners and a suite's tasks")
    ls.add_argument("--suite", default="v1")
    ls.add_argument("--json", action="store_true")
    args = p.parse_args(argv)
    for name in ("budget_scale",):
        if getattr(args, name, 1.0) <= 0:
            p.error(f"--{name.replace('_', '-')} must be > 0")
    for name in ("trials", "parallel_trials", "num_cpus", "reps", "jax_cpus"):
        v = getattr(args, name, None)
        if v is not None and v < 1:
            p.error(f"--{name.replace('_', '-')} must be >= 1")
    return args


def cmd_run(args: argparse.Namespace, argv: list[str]) -> int:
    suite = load_suite(args.suite)
    tasks = None if args.tasks is None else [suite.task(t) for t in split(args.tasks)]
    learners = split(args.learners)
    for name in learners:
        lmod.resolve(name)
    sets = parse_sets(args.set)
    for name in sets:
        if name not in learners:
            raise SystemExit(f"--set {name}.…: {name!r} is not one of --learners {learners}")
    budgets = None
    if args.budgets is not None:
        try:
            budgets = [int(b) for b in split(args.budgets)]
        except ValueError:
            raise SystemExit(
                f"--budgets: {args.budgets!r}: expected env steps, e.g. 30000,100000"
            ) from None
    try:
        specs = runner.plan_runs(
            suite,
            learners,
            seeds=parse_seeds(args.seeds),
            tasks=tasks,
            hyperparams=args.hyperparams or suite.raw.get("hyperparams", "v1"),
            budget_scale=args.budget_scale,
            overrides=sets,
            budgets=budgets,
        )
    except ValueError as e:
        if budgets is None and "axis" not in str(e):
            raise
        raise SystemExit(f"--budgets: {e}") from e
    out = args.out_dir or Path("results") / "bench" / suite.name
    print(f"{len(specs)} runs ({len(learners)} learners) -> {out}", file=sys.stderr)
    manifest_path = out / "study.json"
    previous: dict[str, Any] = {}
    if manifest_path.exists():
        previous = json.loads(manifest_path.read_text())
    if previous.get("finished") is False:
        # An earlier command into this directory was stopped: its manifest (written after
        # each of its runs) counts its wall time up to its last finished run.
        print(f"{out}: resuming a command that was stopped", file=sys.stderr)
    # A study directory can be filled by several commands (more seeds, another learner, a
    # restart): the manifest keeps every command and the union of what they asked for.
    command = command_line(argv)
    commands = list(previous.get("commands", [previous["command"]] if previous else []))
    if not commands or commands[-1] != command:
        commands.append(command)

    def write_manifest(res: dict[str, Any], finished: bool) -> None:
        runner.write_manifest(
            out,
            {
                "command": command,
                "commands": commands,
                "suite": suite.raw,
                "learners": union(previous.get("learners", []), learners),
                "tasks": union(previous.get("tasks", []), [t.id for t in (tasks or suite.tasks)]),
                "seeds": sorted(set(previous.get("seeds", [])) | {s["seed"] for s in specs}),
                **runner.manifest_counts(res, previous.get("wall_time_s_total", 0.0)),
                "ray": "in-process" if args.no_ray else (args.address or "local"),
                "finished": finished,
            },
        )

    # After each finished run the manifest is rewritten (finished: false), so a command that
    # is stopped (a session's time limit, a lost machine) leaves its wall time so far on
    # record, and the next command into the directory adds to it.
    res = runner.run_study(
        specs,
        out,
        address=args.address,
        num_cpus=args.num_cpus,
        use_ray=not args.no_ray,
        progress=not args.no_progress,
        jax_cpus=args.jax_cpus,
        on_progress=lambda so_far: write_manifest(so_far, False),
    )
    write_manifest(res, not res["stopped"])
    print(
        f"{res['ran']} ran, {res['skipped']} already done, {len(res['failures'])} failed, "
        f"{res['wall_time_s']:.1f} s",
        file=sys.stderr,
    )
    for key, err in res["failures"]:
        print(f"FAILED {key}: {err}", file=sys.stderr)
    if res["failures"]:
        return 1
    if res["stopped"]:
        left = runner.runs_left(res)
        print(f"stopped on request: {left} runs left; the same command runs them", file=sys.stderr)
        return runner.EXIT_STOPPED
    return 0


def cmd_list(args: argparse.Namespace) -> int:
    suite = load_suite(args.suite)
    data = {
        "suites": available(),
        "learners": {k: v.title for k, v in lmod.BUILTIN.items()},
        "suite": suite.name,
        "seeds": suite.seeds,
        "budgets": suite.budgets,
        "tasks": [t.describe() for t in suite.tasks],
        "tuning_tasks": [t.describe() for t in suite.tuning_tasks],
    }
    if args.json:
        print(json.dumps(data, indent=1))
        return 0
    print(f"suites: {', '.join(data['suites'])}")
    print("learners: " + "; ".join(f"{k} ({v})" for k, v in data["learners"].items()))
    print(f"suite {suite.name} v{suite.version}: seeds {suite.seeds}, budgets {suite.budgets}")
    for label, rows in (("task", data["tasks"]), ("tuning task", data["tuning_tasks"])):
        for d in rows:
            print(
                f"  {label} {d['id']:<22} {d['group']:<18} grid {'x'.join(map(str, d['grid']))}"
                f" ({d['states']} states, {d['cell_mm']:g} mm), {d['obstacles']} obstacles, "
                f"{d['blocked']} blocked cells, optimum {d['optimal_lengths']} moves"
            )
    return 0


def has_budget_axis(args: argparse.Namespace) -> bool:
    """The report's suite (``--suite``, else the study's ``study.json``) has a budget axis."""
    if args.suite:
        return "axis" in load_suite(args.suite).budgets
    manifest = Path(args.results) / "study.json"
    if not manifest.exists():
        return False  # the v1 report names the missing file
    return "axis" in json.loads(manifest.read_text()).get("suite", {}).get("budgets", {})


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parse_args(argv)
    try:
        if args.cmd == "run":
            return cmd_run(args, argv)
        if args.cmd == "list":
            return cmd_list(args)
        if args.cmd == "tune":
            from sixaxis_avoid.benchmark.tune import cmd_tune

            return cmd_tune(args, argv)
        if args.cmd == "tune-native":
            from sixaxis_avoid.benchmark.tune import cmd_tune_native

            return cmd_tune_native(args, argv)
        if args.cmd == "report":
            from sixaxis_avoid.benchmark.report import write_longer_report, write_report
            from sixaxis_avoid.benchmark.report_v2 import write_report_v2

            try:
                if not args.longer_only and has_budget_axis(args):
                    args.out = args.out or Path("docs/BENCHMARKS.md")
                    write_report_v2(
                        args.results,
                        args.out,
                        args.figures_dir,
                        reps=args.reps,
                        suite=args.suite,
                        history=args.history if args.history.exists() else None,
                    )
                elif args.longer_only:
                    args.out = args.out or Path("docs/BENCHMARKS_LONGER.md")
                    write_longer_report(
                        args.results, args.longer or [], args.out, args.figures_dir, args.reps
                    )
                else:
                    # v1 is the history page: its command names its --out, and it links the
                    # current page (docs/BENCHMARKS.md) when it is not that page itself.
                    args.out = args.out or Path("docs/BENCHMARKS-v1.md")
                    current = args.out.parent / "BENCHMARKS.md"
                    write_report(
                        args.results,
                        args.out,
                        args.figures_dir,
                        reps=args.reps,
                        longer=args.longer,
                        current=current if args.out.name != current.name else None,
                        out_label=str(args.out),
                    )
            except (ValueError, FileNotFoundError) as e:  # a results directory it cannot use
                print(f"error: {e}", file=sys.stderr)
                return 2
            print(f"wrote {args.out}", file=sys.stderr)
            return 0
    except (SuiteError, lmod.LearnerError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 2


if __name__ == "__main__":
    sys.exit(main())
