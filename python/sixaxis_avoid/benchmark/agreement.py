"""JAX learners against SB3 with identical hyperparameters: do the two implementations agree?

    taskset -c 0 python -m sixaxis_avoid.benchmark.agreement --algo ppo \\
        --tasks paper_simple,gen-easy-0,gen-medium-0 --seeds 5 --budget 30000 \\
        --out docs/results/agreement/ppo-30000.json

For each task, rejax's PPO or DQN on the JAX twin (``sixaxis_avoid.benchmark.jax_learners``,
all seeds in one vmapped call) and the benchmark's own SB3 learner of the same name
(``sixaxis_avoid.benchmark.learners.PPO`` / ``DQN`` on ``SixAxisAvoid-v0``, one seed after
the other, one torch thread) train with the same values (SB3's names on both sides: the
``jax_learners`` defaults, changed with ``--set``) for the same env steps, and both score
their greedy policy on the task's evaluation targets at the env steps where the JAX run's
checkpoints fell. The score is the benchmark's (SPL of the greedy path, 0 if it misses the
target).

Agreement, per task (docs/BENCHMARKS.md, *JAX against SB3*): the 95% percentile-bootstrap
intervals over seeds of the two implementations' final scores overlap, and so do those of
their area under the curve (the mean score over the evaluation points); a two-sided
permutation test of the final scores is recorded too. With 5 seeds and near-binary outcomes
these intervals are wide: agreement says the two are not told apart at this sample size,
disagreement that they differ. Every knob is a flag; the JSON output keeps each seed's curve.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from sixaxis_avoid.benchmark._io import atomic_write_text

#: Bootstrap replications and the seed of the resampling.
REPS = 2000


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--algo", choices=("ppo", "dqn"), default="ppo")
    p.add_argument("--suite", default="v1")
    p.add_argument("--tasks", default="paper_simple,gen-easy-0,gen-medium-0")
    p.add_argument("--seeds", type=int, default=5, help="seeds 0..N-1 for both")
    p.add_argument("--budget", type=int, default=30_000, help="env steps per seed")
    p.add_argument("--evaluations", type=int, default=12, help="evenly spaced checkpoints")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=JSON",
        help="a hyperparameter (SB3's name) for both sides, as jax_learners' --set",
    )
    p.add_argument(
        "--sb3-implementation",
        choices=("sb3", "rejax"),
        default="sb3",
        help="the SB3 learner's implementation preset (learners.PPO_IMPLEMENTATIONS / "
        "DQN_IMPLEMENTATIONS): SB3's own, or rejax's, which the JAX side runs",
    )
    p.add_argument("--skip-sb3", action="store_true", help="JAX side only (a smoke run)")
    p.add_argument("--out", type=Path, default=None, help="JSON file")
    p.add_argument(
        "--from-json",
        type=Path,
        action="append",
        default=[],
        help="do not train: read this result file (repeatable) and write --markdown",
    )
    p.add_argument(
        "--ablation",
        type=Path,
        action="append",
        default=[],
        help="with --from-json: an ablation file of scripts/implementation_ablation.py "
        "(repeatable), shown after the table",
    )
    p.add_argument(
        "--markdown",
        type=Path,
        default=None,
        help="write the section 'jax-sb3-agreement' of this page (e.g. docs/BENCHMARKS.md)",
    )
    return p.parse_args(argv)


def jax_args(a: argparse.Namespace, task: str) -> argparse.Namespace:
    from sixaxis_avoid.benchmark import jax_learners

    return jax_learners.parse_args(
        [
            "--algo", a.algo, "--suite", a.suite, "--task", task, "--seeds", str(a.seeds),
            "--budget", str(a.budget), "--evaluations", str(a.evaluations),
            *[f"--set={x}" for x in a.set],
        ]
    )  # fmt: skip


#: The activation of SB3's policies, which the benchmark's SB3 learners do not change.
SB3_ACTIVATION = {"ppo": "tanh", "dqn": "relu"}


def sb3_values(algo: str, values: dict[str, Any], implementation: str = "sb3") -> dict[str, Any]:
    """The SB3 learner's hyperparameters: the JAX run's values (already SB3's names) without
    the activation, which must be SB3's own, and with the ``implementation`` preset unless it
    is SB3's own (``"sb3"``)."""
    out = dict(values)
    if implementation != "sb3":
        out["implementation"] = implementation
    act = out.pop("activation", SB3_ACTIVATION[algo])
    if act != SB3_ACTIVATION[algo]:
        raise ValueError(f"activation: {act!r}; SB3's {algo} learner uses {SB3_ACTIVATION[algo]}")
    return out


def sb3_curve(
    algo: str, task: Any, seed: int, values: dict[str, Any], budget: int, points: list[int]
):
    """One SB3 run's scores at ``points`` (env steps) and its wall time."""
    from sixaxis_avoid.benchmark.learners import RunContext, resolve

    learner = resolve(algo)(values)
    ctx = RunContext(task, seed, budget, learner.hyperparams, points, learner)
    t0 = time.perf_counter()
    learner.learn(ctx)
    ctx.finish()
    wall = time.perf_counter() - t0
    return [(p["env_steps"], p["score"]) for p in ctx.points], wall


def on_points(curve: list[tuple[int, float]], points: list[int]) -> list[float]:
    """The score recorded at each point: a checkpoint fires at the first env step at or past
    its point (SB3 steps ``n_envs`` env steps at a time), so the first record at or past it."""
    out = []
    for q in points:
        at = [s for e, s in curve if e >= q]
        if not at:
            raise RuntimeError(f"no SB3 evaluation at or after env step {q}")
        out.append(at[0])
    return out


def bootstrap_ci(x: np.ndarray, rng: np.random.Generator) -> list[float]:
    idx = rng.integers(0, len(x), size=(REPS, len(x)))
    means = x[idx].mean(axis=1)
    return [float(np.quantile(means, 0.025)), float(np.quantile(means, 0.975))]


def permutation_p(a: np.ndarray, b: np.ndarray, rng: np.random.Generator) -> float:
    """Two-sided permutation test of the difference of means (exact when small)."""
    from itertools import combinations

    pooled = np.concatenate([a, b])
    obs = abs(a.mean() - b.mean())
    n = len(pooled)
    if n <= 16:
        splits = list(combinations(range(n), len(a)))
        hits = 0
        for s in splits:
            mask = np.zeros(n, bool)
            mask[list(s)] = True
            hits += abs(pooled[mask].mean() - pooled[~mask].mean()) >= obs - 1e-12
        return hits / len(splits)
    hits = 0
    for _ in range(REPS):
        perm = rng.permutation(pooled)
        hits += abs(perm[: len(a)].mean() - perm[len(a) :].mean()) >= obs - 1e-12
    return (hits + 1) / (REPS + 1)


def summarise(jax_s: np.ndarray, sb3_s: np.ndarray, seed: int = 0) -> dict[str, Any]:
    """Scores are (seeds, points). Final score and area under the curve, per side, with
    intervals; whether they overlap."""
    rng = np.random.default_rng(seed)
    out: dict[str, Any] = {}
    for name, f in (("final", lambda s: s[:, -1]), ("auc", lambda s: s.mean(axis=1))):
        ja, sa_ = f(jax_s), f(sb3_s)
        jc, sc = bootstrap_ci(ja, rng), bootstrap_ci(sa_, rng)
        out[name] = {
            "jax": {"mean": float(ja.mean()), "ci": jc},
            "sb3": {"mean": float(sa_.mean()), "ci": sc},
            "overlap": bool(jc[0] <= sc[1] and sc[0] <= jc[1]),
        }
    out["final"]["permutation_p"] = permutation_p(jax_s[:, -1], sb3_s[:, -1], rng)
    out["agree"] = bool(out["final"]["overlap"] and out["auc"]["overlap"])
    return out


#: Where rejax's learners (0.1.3, as ``jax_learners.rejax_classes`` adjusts them: gradient
#: clipping by global norm, PPO's Adam eps 1e-5, DQN's hard target copy and net size) still
#: differ from SB3's (2.x) with the same values, read in their sources; the section lists them
#: so that a disagreement can be traced.
DIFFERENCES = {
    "ppo": (
        "value loss: rejax clips the value prediction to ±clip_range around the rollout's "
        "value (CleanRL's form: the larger of the clipped and unclipped losses, times 0.5); "
        "SB3 does not clip it (`clip_range_vf=None`), and with `clip_range_vf` takes the "
        "clipped prediction's loss alone (what `implementation: rejax` uses)",
        "optimiser: rejax has one Adam per network (actor, critic), each clipped to "
        "max_grad_norm on its own; SB3 one Adam over the summed loss, clipped once "
        "(`implementation: rejax`: one Adam, its actor and critic parameter groups clipped "
        "each on its own)",
    ),
    "dqn": (
        "loss: squared error in rejax; Huber (smooth L1) in SB3",
        "data: rejax steps `train_freq` envs side by side once per update phase, SB3 one env "
        "`train_freq` times (the same env steps and updates per env step, but `train_freq` "
        "episodes under way at once instead of one)",
    ),
    "both": (
        "initialisation: flax's default (LeCun normal) in rejax; SB3's orthogonal",
        "truncation: rejax treats a truncated episode as terminal (no bootstrap); SB3 "
        "bootstraps from the value of the last observation (PPO) or keeps the transition "
        "non-terminal (DQN)",
    ),
}


def ablation_markdown(ab: dict[str, Any], path: str) -> list[str]:
    """An ablation of ``scripts/implementation_ablation.py``: the SB3 learner (PPO or DQN,
    ``ab["algo"]``) with one implementation factor at a time changed toward rejax's, against
    the JAX learner's runs on the same tasks and seeds; for PPO, the gradient norms of
    ``scripts/ppo_gradnorms.py`` that show why, for DQN the loss's reading."""
    algo = ab.get("algo", "ppo")
    jname, up = f"jax_{algo}", algo.upper()
    j = ab[jname]
    rows = ab["variants"]
    lines = [
        "",
        f"### Why SB3 {up} failed with {jname}'s values: an ablation ({int(ab['budget']):,} "
        "env steps)",
        "",
        f"{ab['question']} SB3 {up} (the benchmark's `{algo}` learner, through the benchmark's "
        f"runner) with {jname}'s tuned values, first with SB3's implementation, then with "
        "factors changed toward rejax 0.1.3's, then all; tasks "
        f"{', '.join(ab['tasks'])}, seeds {', '.join(str(s) for s in ab['seeds'])}; mean final "
        f"SPL and runs that reached the target. File: `{path}` (each variant's command and "
        "values).",
        "",
        "| variant | what changed | mean SPL | reached |",
        "|---|---|---|---|",
        f"| {jname} | rejax on the JAX twin (the committed v2 runs) | {j['mean_spl']:.3f} "
        f"| {j['successes']}/{j['runs']} |",
    ]
    for name, r in rows.items():
        lines.append(
            f"| {name} | {r['what']} | {r['mean_spl']:.3f} | {r['successes']}/{r['runs']} |"
        )
    if algo == "dqn" and {"squared", "huber", "sb3"} <= set(rows):
        sq, hu, sb = rows["squared"], rows["huber"], rows["sb3"]
        lines += [
            "",
            f"**Cause.** The loss: with rejax's half squared TD error alone, SB3 DQN reaches "
            f"the target in {sq['successes']}/{sq['runs']} runs; with every other setting of "
            f"rejax's but SB3's Huber loss, in {hu['successes']}/{hu['runs']} (SB3 as it is: "
            f"{sb['successes']}/{sb['runs']}). The benchmark's rewards, scaled by 1e-4, still "
            "reach about -24 a step, so TD errors often pass 1, where Huber's gradient stops "
            "growing and the squared error's does not (`tests/test_benchmark_units.py` shows "
            "it on a replay sample). The values were tuned with rejax's loss; the benchmark's "
            "`dqn` learner now runs them with `implementation: rejax` "
            "(`learners.DQN_IMPLEMENTATIONS`), and the v2 dqn runs above are those.",
        ]
    g = ab.get("gradnorms", {})
    if "sb3" in g:
        b0 = g["sb3"]["median"]["first third"]
        lines += [
            "",
            f"**Cause.** Gradient norms per minibatch update (`scripts/ppo_gradnorms.py`, "
            f"{g['sb3']['task']} seed {g['sb3']['seed']}, median over the first third of the "
            f"updates): with SB3's implementation the critic's gradient norm is "
            f"{b0['critic_norm']:.0f} against the actor's {b0['actor_norm']:.2f}, so SB3's one "
            f"clip of their joint norm to max_grad_norm scales both by "
            f"{b0['clip_factor']:.4f}, and the actor's clipped gradient (RMS "
            f"{b0['actor_rms_after_clip']:.1e} per weight) falls below Adam's eps (1e-5): "
            "Adam's step m / (sqrt(v) + eps) shrinks with it, and the policy hardly moves in "
            "30k env steps. rejax clips each network on its own"
            + (
                f" (`gradclip` alone: {rows['gradclip']['successes']}/"
                f"{rows['gradclip']['runs']} reached)."
                if "gradclip" in rows
                else "."
            ),
        ]
        others = []
        for name, what in (("init", "LeCun init"), ("vfclip", "value clipping")):
            if name in g:
                m = g[name]["median"]["last third"]
                others.append(
                    f"{what} (`{name}`, {rows[name]['successes']}/{rows[name]['runs']} "
                    f"reached): critic norm {m['critic_norm']:.0f}, clip factor "
                    f"{m['clip_factor']:.4f}, actor RMS {m['actor_rms_after_clip']:.1e} over the "
                    "last third of the updates"
                )
        if others:
            lines[-1] += (
                " The other two factors that close it do so through the same clip: "
                + "; ".join(others)
                + "."
            )
        lines[-1] += (
            " The values were tuned on rejax's implementation; with SB3's they starve the "
            "actor. The benchmark's `ppo` learner now runs them with `implementation: rejax` "
            "(set in the hyperparameter file's ppo entry; `learners.PPO_IMPLEMENTATIONS`: LeCun "
            "init, actor and critic clipped each on its own, truncation as termination, value "
            "clipping at clip_range), and the v2 ppo runs above are those."
        )
    lines += ["", "```bash", *(r["command"] for r in rows.values())]
    lines += [*ab.get("gradnorms_commands", []), "```"]
    if ab.get("command_note"):
        lines += ["", f"RUNS: a directory outside the checkout. Note: {ab['command_note']}."]
    return lines


def markdown(
    results: list[dict[str, Any]], ablations: list[tuple[dict[str, Any], str]] = ()
) -> str:
    """The section: per algorithm and task, both implementations' final score and area under
    the curve with intervals, and whether they agree."""
    lines = [
        "## JAX against SB3: do the two implementations agree?",
        "",
        "Generated by `python -m sixaxis_avoid.benchmark.agreement` (module docstring: the "
        "protocol); commands below. rejax on the JAX twin and the benchmark's SB3 learner "
        "train with the same values for the same env steps and are scored the same way "
        "(greedy SPL on the task's evaluation targets) at the same env-step points. "
        "*Agree*: the 95% bootstrap intervals over seeds overlap for the final score and for "
        "the area under the curve (AUC, the mean score over the points).",
        "",
        "| algo | task | env steps | seeds | final JAX | final SB3 | AUC JAX | AUC SB3 "
        "| permutation p | agree |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    commands: list[str] = []
    notes: list[str] = []
    parted: list[str] = []
    for r in results:
        f = r["flags"]
        commands.append(
            "python -m sixaxis_avoid.benchmark.agreement "
            + " ".join(
                f"--{k.replace('_', '-')} {f[k]}"
                for k in ("algo", "suite", "tasks", "seeds", "budget", "evaluations")
            )
            + "".join(f" --set={x}" for x in f["set"])
            + (
                f" --sb3-implementation {impl}"
                if (impl := f.get("sb3_implementation", "sb3")) != "sb3"
                else ""
            )
            + (f" --out {f['out']}" if f.get("out") else "")
        )
        for tid, e in r["tasks"].items():
            if "agreement" not in e:
                continue
            g = e["agreement"]

            def cell(x: dict[str, Any]) -> str:
                return f"{x['mean']:.2f} [{x['ci'][0]:.2f}, {x['ci'][1]:.2f}]"

            algo = f["algo"] + (" (rejax impl.)" if impl != "sb3" else "")
            lines.append(
                f"| {algo} | {tid} | {int(f['budget']):,} "
                f"| {len(e['jax']['spl'])} | {cell(g['final']['jax'])} "
                f"| {cell(g['final']['sb3'])} | {cell(g['auc']['jax'])} "
                f"| {cell(g['auc']['sb3'])} | {g['final']['permutation_p']:.2f} "
                f"| {'yes' if g['agree'] else '**no**'} |"
            )
            if not g["agree"]:
                which = [
                    f"{name} {'JAX' if g[k]['jax']['mean'] > g[k]['sb3']['mean'] else 'SB3'} above"
                    for k, name in (("final", "final score"), ("auc", "AUC"))
                    if not g[k]["overlap"]
                ]
                parted.append(f"{f['algo']} on {tid} ({', '.join(which)})")
        speeds = [
            (e["jax"]["env_steps_per_s"], e["sb3"]["env_steps_per_s"])
            for e in r["tasks"].values()
            if "sb3" in e
        ]
        if speeds:
            notes.append(
                f"{f['algo']}: JAX {np.mean([s[0] for s in speeds]):,.0f} env steps/s (all "
                f"seeds in one vmapped call, compile excluded) against SB3 "
                f"{np.mean([s[1] for s in speeds]):,.0f} (one seed at a time, one torch "
                f"thread), on {r.get('machine', '?')}, mean over the tasks"
                + (
                    f"; load average at the end {r['load_average'][0]:.1f} (other work "
                    "shared the cores: lower bounds)."
                    if r.get("load_average")
                    else "."
                )
            )
    lines += [""] + [f"{n}\n" for n in notes]
    if parted:
        lines.append(
            "**Where they part:** "
            + "; ".join(parted)
            + ". The intervals that do not overlap are listed; the differences below are where "
            "to look, and an ablation that removes them one at a time is what would explain the "
            "gap."
        )
    for ab, path in ablations:
        lines += ablation_markdown(ab, path)
    algos = sorted({r["flags"]["algo"] for r in results})
    lines += ["", "Where rejax and SB3 differ with the same values (read in their sources):", ""]
    for algo in [*algos, "both"]:
        lines += [
            f"- {'' if algo == 'both' else algo.upper() + ', '}{d}." for d in DIFFERENCES[algo]
        ]
    if ablations:
        commands.append(
            "python -m sixaxis_avoid.benchmark.agreement "
            + " ".join(f"--from-json {r['flags']['out']}" for r in results if r["flags"].get("out"))
            + "".join(f" --ablation {path}" for _, path in ablations)
            + " --markdown docs/BENCHMARKS.md  # this section"
        )
    lines += ["", "```bash", *commands, "```"]
    return "\n".join(lines)


def write_section(page: Path, text: str, name: str = "jax-sb3-agreement") -> None:
    """Replace (or append) section ``name`` of ``page``, atomically."""
    begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
    body = page.read_text() if page.exists() else ""
    section = f"{begin}\n{text.strip()}\n{end}"
    if begin in body and end in body:
        body = body[: body.index(begin)] + section + body[body.index(end) + len(end) :]
    else:
        body = body.rstrip("\n") + ("\n\n" if body.strip() else "") + section + "\n"
    atomic_write_text(page, body)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    from sixaxis_avoid.benchmark import jax_learners
    from sixaxis_avoid.benchmark.runner import machine, pin_numerics
    from sixaxis_avoid.benchmark.tasks import load_suite

    pin_numerics()
    a = parse_args(argv)
    if a.from_json:
        results = [json.loads(p.read_text()) for p in a.from_json]
        ablations = [(json.loads(p.read_text()), str(p)) for p in a.ablation]
        if a.markdown is not None:
            write_section(a.markdown, markdown(results, ablations))
        return {"results": len(results)}
    suite = load_suite(a.suite)
    flags = {k: (None if v is None else str(v)) if k in ("out", "markdown") else v
             for k, v in vars(a).items() if k != "from_json"}  # fmt: skip
    out: dict[str, Any] = {"flags": flags, "tasks": {}}
    out["machine"] = machine()
    for tid in a.tasks.split(","):
        task = suite.task(tid)
        j = jax_args(a, tid)
        jr = jax_learners.run(j)
        points = [int(e) for e in jr["eval_env_steps"]]
        jax_s = np.asarray(jr["spl"], dtype=np.float64)
        entry: dict[str, Any] = {
            "eval_env_steps": points,
            "jax": {
                "spl": jax_s.tolist(),
                "train_wall_s": jr["train_wall_s"],
                "compile_s": jr["compile_s"],
                "env_steps_per_s": jr["env_steps_per_s"],
                "env_steps_per_cpu_s": jr["env_steps_per_cpu_s"],
                "values": jr["values"],
                "rejax_config": jr["rejax_config"],
            },
        }
        if not a.skip_sb3:
            values = sb3_values(a.algo, jr["values"], a.sb3_implementation)
            rows, walls = [], []
            for seed in jr["seeds"]:
                curve, wall = sb3_curve(a.algo, task, seed, values, a.budget, points)
                rows.append(on_points(curve, points))
                walls.append(wall)
            sb3_s = np.asarray(rows, dtype=np.float64)
            entry["sb3"] = {
                "spl": sb3_s.tolist(),
                "values": values,
                "train_wall_s": float(sum(walls)),
                "env_steps_per_s": len(walls) * a.budget / sum(walls),
            }
            entry["agreement"] = summarise(jax_s, sb3_s)
        out["tasks"][tid] = entry
        print(json.dumps({tid: entry.get("agreement")}), flush=True)
    out["load_average"] = list(os.getloadavg())  # speeds under load are lower bounds
    text = json.dumps(out, indent=1)
    if a.out is not None:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(a.out, text + "\n")
    if a.markdown is not None:
        write_section(a.markdown, markdown([out]))
    return out


if __name__ == "__main__":
    main()
