"""Runs of a study: one (learner, task, seed) run is one Ray task, one result file.

- :func:`plan_runs` lists a study's runs (their specs: everything a run depends on).
- :func:`execute_run` is one run, a pure function of its spec (any machine, same result).
- :func:`run_study` runs the unfinished ones on Ray (a local Ray on all cores by default, or
  the cluster at ``address``), writes each result file atomically as it arrives, skips runs
  whose file already holds a result for the same spec, and counts runs on a progress bar.
  A file named :data:`STOP_FILE` in the output directory asks it to stop: it hands out no
  more runs, lets the running ones finish and write their files, and returns
  ``stopped: True``.
"""

from __future__ import annotations

import datetime as dt
import functools
import hashlib
import json
import os
import platform
import re
import socket
import sys
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from sixaxis_avoid.benchmark import hyperparams as hpmod
from sixaxis_avoid.benchmark._io import atomic_write_text
from sixaxis_avoid.benchmark.algorithm2 import algorithm1_record, algorithm2_record
from sixaxis_avoid.benchmark.learners import RunContext, family_of, resolve
from sixaxis_avoid.benchmark.tasks import Suite, Task

SCHEMA = 1

#: The learner families whose hyperparameters are tuned (the others: the paper's values, or
#: no learning): their runs record "tuned" or "untuned".
TUNED = ("deep", "jax")

#: PyTorch CPU settings every run gets, so that a deep learner's floating-point results do
#: not depend on the machine's instruction set: MKL's conditional numerical reproducibility
#: (MKL_CBWR=COMPATIBLE) and ATen's AVX2 kernels (not AVX-512 where a CPU has it). Without
#: them a 30k-step PPO run took other decisions on an AVX-512 machine than on an AVX2 one
#: (tests/test_benchmark_numerics.py). They do not make an Intel and an AMD CPU agree: DQN
#: and A2C runs made on an Intel Xeon differed when re-run on an AMD EPYC. They must be in the
#: environment before torch is imported: :func:`pin_numerics` at package import, and Ray's
#: ``runtime_env`` for every worker.
NUMERICS_ENV = {"MKL_CBWR": "COMPATIBLE", "ATEN_CPU_CAPABILITY": "avx2"}


def pin_numerics() -> dict[str, str]:
    """Set :data:`NUMERICS_ENV` in this process's environment, keeping a value already set;
    returns the values in force."""
    for k, v in NUMERICS_ENV.items():
        os.environ.setdefault(k, v)
    return {k: os.environ[k] for k in NUMERICS_ENV}


def numerics() -> dict[str, Any]:
    """The arithmetic this process runs with: the pinned variables and the CPU kernels torch
    actually dispatches to (None when torch is not loaded)."""
    torch = sys.modules.get("torch")
    return {
        **{k: os.environ.get(k) for k in NUMERICS_ENV},
        "torch_cpu_capability": None if torch is None else torch.backends.cpu.get_cpu_capability(),
    }


# ------------------------------------------------------------------------------------------
# Specs


def budget_of(
    suite: Suite, family: str, task: Task, scale: float = 1.0, budget: int | None = None
) -> dict[str, Any]:
    """A run's budget: env steps (and the tabular learner's options that fit it).

    With a budget axis (suite v2), every learner gets ``budget`` env steps (default: the
    axis's largest), and a tabular ("native") run stops there with its epsilon falling over
    env steps (``max_env_steps``, ``epsilon_schedule="env_steps"``); the paper's learner
    (family "paper", the reproduction row) keeps its episode count. Without one (v1), the
    deep budget and the native episode cap."""
    b = {**suite.budgets, **task.spec.get("budgets", {})}
    axis = b.get("axis")
    if axis is not None:
        steps = max(1, round(int(budget if budget is not None else max(axis)) * scale))
        if family == "native":
            return {
                "env_steps": steps,
                "native": {"max_env_steps": steps, "epsilon_schedule": "env_steps"},
            }
        if family == "paper":
            return {
                "env_steps": steps,
                "native": {"episodes": int(b.get("native_episodes", 10_000))},
            }
        return {"env_steps": 0} if family == "reference" else {"env_steps": steps}
    deep = int(b["deep_goal"] if task.is_goal and "deep_goal" in b else b["deep"])
    deep = max(1, round(deep * scale))
    if family in ("native", "paper"):
        native = {"episodes": int(b.get("native_episodes", 10_000))}
        if family == "native" and b.get("native_steps") is not None:
            native["max_env_steps"] = int(b["native_steps"])
        return {"env_steps": deep, "native": native}
    if family == "reference":
        return {"env_steps": 0}
    return {"env_steps": deep}


def plan_runs(
    suite: Suite,
    learners: list[str],
    seeds: list[int] | None = None,
    tasks: list[Task] | None = None,
    hyperparams: str | Path = "v1",
    budget_scale: float = 1.0,
    overrides: dict[str, dict[str, Any]] | None = None,
    tag: str | None = None,
    budgets: list[int] | None = None,
) -> list[dict[str, Any]]:
    """The specs of a study's runs: learners x tasks x seeds (``tag`` prefixes their result
    files, e.g. a tuning trial's number); on a suite with a budget axis (``budgets.axis``),
    x budgets (``budgets``: a subset of the axis, default all of it but its ``best_only``
    tail, the budgets only the best learners run and only when asked for), each run's
    ``budget`` one of them, except the paper's learner (family "paper": its episode count
    does not depend on the budget), planned once, at the largest budget chosen."""
    axis = suite.budgets.get("axis")
    if budgets is not None and axis is None:
        raise ValueError(f"budgets {budgets}: suite {suite.name!r} has no budget axis")
    chosen: list[int | None] = [None]
    if axis is not None:
        every = [b for b in axis if b not in suite.best_only]
        chosen = [int(b) for b in (every if budgets is None else budgets)]
        for b in chosen:
            if b not in axis:
                raise ValueError(f"budgets: {b} is not on suite {suite.name!r}'s axis {axis}")
    specs = []
    last = max((b for b in chosen if b is not None), default=None)
    for axis_budget in chosen:
        specs += _plan_at(
            suite, learners, seeds, tasks, hyperparams, budget_scale, overrides, tag, axis_budget,
            last,
        )  # fmt: skip
    return specs


def _plan_at(
    suite: Suite,
    learners: list[str],
    seeds: list[int] | None,
    tasks: list[Task] | None,
    hyperparams: str | Path,
    budget_scale: float,
    overrides: dict[str, dict[str, Any]] | None,
    tag: str | None,
    axis_budget: int | None,
    last_budget: int | None = None,
) -> list[dict[str, Any]]:
    hp_file = hpmod.load(hyperparams)
    specs = []
    for learner in learners:
        cls = resolve(learner)
        family = family_of(cls)
        if family == "paper" and axis_budget is not None and axis_budget != last_budget:
            continue  # the paper's 10,000 episodes do not depend on the budget: run once
        values = hpmod.values_for(hp_file, learner, dict(getattr(cls, "defaults", {})))
        status = "n/a" if family not in TUNED else hpmod.status_for(hp_file, learner)
        if axis_budget is not None:
            # A run at budget B takes the values tuned at B (the file's ``by_budget``), never
            # those of another budget: without them it runs with defaults, "untuned".
            entry = hp_file.get("learners", {}).get(learner, {}).get("by_budget", {})
            at = entry.get(str(axis_budget))
            values = {**dict(getattr(cls, "defaults", {})), **((at or {}).get("values", {}))}
            if at is not None:
                status = str(at.get("status", "tuned"))
            elif family in (*TUNED, "native"):  # on a budget axis the tabular ones are tuned too
                status = "untuned"
        values.update(suite.raw.get("overrides", {}).get(learner, {}))
        values.update((overrides or {}).get(learner, {}))
        for task in tasks if tasks is not None else suite.tasks:
            budget = budget_of(suite, family, task, budget_scale, axis_budget)
            hp = {**values, **budget.get("native", {})}
            cap = suite.algorithm2.get(
                "native" if family == "paper" else family, suite.algorithm2["deep"]
            )
            for seed in seeds if seeds is not None else suite.seeds:
                specs.append(
                    {
                        "schema": SCHEMA,
                        "suite": suite.name,
                        "suite_version": suite.version,
                        "learner": learner,
                        "family": family,
                        "task": {"id": task.id, "kind": task.kind, **task.spec},
                        "seed": int(seed),
                        "budget": budget["env_steps"],
                        "checkpoints": suite.checkpoints(max(budget["env_steps"], 1))
                        if family != "reference"
                        else [],
                        "hyperparams": hp,
                        "hyperparams_status": status,
                        "max_replans": int(cap),
                        **({"tag": tag} if tag else {}),
                        # The axis budget this run belongs to (BFS's own budget is 0).
                        **({"budget_axis": axis_budget} if axis_budget is not None else {}),
                    }
                )
    return specs


def spec_hash(spec: dict[str, Any]) -> str:
    return hashlib.sha256(json.dumps(spec, sort_keys=True).encode()).hexdigest()[:16]


def run_key(spec: dict[str, Any]) -> str:
    raw = f"{spec['task']['id']}__{spec['learner']}__s{spec['seed']}"
    if spec.get("budget_axis"):  # a run of a suite's budget axis: one file per budget
        raw = f"{raw}__b{spec['budget_axis']}"
    if spec.get("tag"):
        raw = f"{spec['tag']}__{raw}"
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", raw)


def task_of(spec: dict[str, Any]) -> Task:
    t = dict(spec["task"])
    return Task(id=t.pop("id"), kind=t.pop("kind"), spec=t)


# ------------------------------------------------------------------------------------------
# One run


def execute_run(spec: dict[str, Any]) -> dict[str, Any]:
    """One (learner, task, seed) run: train, record the curve, score the greedy path, run
    Algorithms 1 and 2 on it. ``result`` depends on the spec alone; ``timing`` and ``host``
    on where it ran."""

    if spec.get("family") == "jax":  # trains its seeds vmapped: docs/PERFORMANCE.md
        return resolve(spec["learner"]).run_group([spec])[0]
    try:  # one thread per run: the same result on any machine, and no oversubscription
        import torch

        torch.set_num_threads(1)
    except ImportError:
        pass
    t0 = time.perf_counter()
    task = task_of(spec)
    cls = resolve(spec["learner"])
    learner = cls(spec["hyperparams"])
    ctx = RunContext(
        task, spec["seed"], spec["budget"], learner.hyperparams, spec["checkpoints"], learner
    )
    learner.learn(ctx)
    ctx.finish()
    final = ctx.points[-1]
    scores = [p["score"] for p in ctx.points]
    conv = None
    if final["score"] > 0:
        k = len(scores) - 1
        while k > 0 and scores[k - 1] == final["score"]:
            k -= 1
        conv = k
    optimal = task.optimal_lengths
    paths = final["paths"]
    result: dict[str, Any] = {
        "score": final["score"],
        "success": final["success"],
        "paths": paths,
        "path_lengths": [None if p is None else len(p) - 1 for p in paths],
        "optimal_lengths": optimal,
        "env_steps": int(ctx.env_steps),
        "episodes": int(ctx.episodes),
        "curve": [
            {"env_steps": p["env_steps"], "score": p["score"], "success": p["success"]}
            for p in ctx.points
        ],
        "first_success": None
        if ctx.first_success is None
        else {k: ctx.first_success[k] for k in ("env_steps", "episode")},
        "convergence": None if conv is None else {"env_steps": ctx.points[conv]["env_steps"]},
    }
    timing: dict[str, Any] = {
        "wall_time_s": final["wall_time_s"],
        "cpu_time_s": final["cpu_time_s"],
        "curve": [
            {"wall_time_s": p["wall_time_s"], "cpu_time_s": p["cpu_time_s"]} for p in ctx.points
        ],
        "first_success": None
        if ctx.first_success is None
        else {k: ctx.first_success[k] for k in ("wall_time_s", "cpu_time_s")},
        "convergence": None
        if conv is None
        else {k: ctx.points[conv][k] for k in ("wall_time_s", "cpu_time_s")},
    }
    if hasattr(learner, "converged_episode"):
        result["core_converged_episode"] = learner.converged_episode
    if hasattr(learner, "vec_env"):  # the SB3 learners' VecEnv class (SixAxisVecEnv)
        result["vec_env"] = learner.vec_env
    if not task.is_goal:
        path = paths[0]
        result["algorithm1"] = algorithm1_record(task.scenario, path)
        result["algorithm2"], timing["algorithm2"] = algorithm2_record(
            task.scenario,
            spec["seed"],
            learner.algorithm2_learner(ctx),
            spec["max_replans"],
            **learner.algorithm2_kwargs(),
        )
    timing["run_wall_time_s"] = time.perf_counter() - t0
    return run_record(spec, result, timing)


def run_record(
    spec: dict[str, Any],
    result: dict[str, Any],
    timing: dict[str, Any],
    extra_versions: dict[str, str] | None = None,
) -> dict[str, Any]:
    """A run file's content, the one layout every learner's runs are written in: the spec,
    its key and hash, the result, the timing and the host (``extra_versions``: the versions
    of packages this learner used besides the common ones)."""
    return {
        "schema": SCHEMA,
        "key": run_key(spec),
        "spec_hash": spec_hash(spec),
        "spec": spec,
        "result": result,
        "timing": timing,
        "host": {
            "hostname": socket.gethostname(),
            "pid": os.getpid(),
            "ray_node": ray_node(),
            # The CPU and versions the run had: a deep run's floating-point result can
            # depend on the CPU's vendor (docs: python/README.md, "Same result").
            "machine": machine(),
            "versions": {**versions(), **(extra_versions or {})},
            "numerics": numerics(),
        },
    }


def ray_node() -> str | None:
    """The Ray node this process runs on (None outside Ray)."""
    ray = sys.modules.get("ray")
    if ray is None or not ray.is_initialized():
        return None
    return ray.get_runtime_context().get_node_id()


# ------------------------------------------------------------------------------------------
# Result files


def run_path(out_dir: Path, spec: dict[str, Any]) -> Path:
    return Path(out_dir) / "runs" / f"{run_key(spec)}.json"


def finished(out_dir: Path, spec: dict[str, Any]) -> bool:
    """A result file for this very spec is there (a changed spec re-runs)."""
    p = run_path(out_dir, spec)
    try:
        return json.loads(p.read_text()).get("spec_hash") == spec_hash(spec)
    except (OSError, json.JSONDecodeError):
        return False


def load_record(out_dir: Path, spec: dict[str, Any]) -> dict[str, Any]:
    return json.loads(run_path(out_dir, spec).read_text())


def write_run(out_dir: Path, record: dict[str, Any]) -> Path:
    p = run_path(out_dir, record["spec"])
    atomic_write_text(p, json.dumps(record, indent=1) + "\n")
    return p


def load_runs(out_dir: Path) -> list[dict[str, Any]]:
    runs = []
    for p in sorted((Path(out_dir) / "runs").glob("*.json")):
        runs.append(json.loads(p.read_text()))
    return runs


# ------------------------------------------------------------------------------------------
# Ray


def init_ray(address: str | None, num_cpus: int | None) -> bool:
    """Connect to the cluster at ``address`` or start a local Ray (all cores unless
    ``num_cpus``); returns whether this call started it (and should shut it down)."""
    import ray

    if ray.is_initialized():
        return False
    path = os.pathsep.join(p for p in [os.getcwd(), os.environ.get("PYTHONPATH", "")] if p)
    kw: dict[str, Any] = {
        "log_to_driver": False,
        "runtime_env": {"env_vars": {"PYTHONPATH": path, **pin_numerics()}},
    }
    if address:
        ray.init(address=address, **kw)
    else:
        ray.init(
            num_cpus=num_cpus or os.cpu_count(),
            include_dashboard=False,
            object_store_memory=256 * 1024**2,
            **kw,
        )
    return True


def _progress(total: int, initial: int, enabled: bool) -> Any:
    from tqdm.auto import tqdm

    return tqdm(
        total=total, initial=initial, unit="run", disable=not enabled, file=sys.stderr, smoothing=0
    )


def seed_major(specs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The specs seed by seed (seeds in order of first appearance), otherwise in their order:
    the order runs are handed to Ray, so a study stopped early holds whole seeds, and the
    next seed's runs fill the cores while the last runs of a seed finish."""
    rank: dict[int, int] = {}
    for s in specs:
        rank.setdefault(s["seed"], len(rank))
    return sorted(specs, key=lambda s: rank[s["seed"]])


#: The file in a study's output directory that asks a running :func:`run_study` to stop
#: once its running runs have finished (``touch OUT_DIR/STOP``); it is removed when the
#: study returns, and a stale one is removed, with a message, when a study starts.
STOP_FILE = "STOP"

#: The exit status of a command that stopped on :data:`STOP_FILE` with runs left
#: (sysexits' EX_TEMPFAIL: the same command resumes them).
EXIT_STOPPED = 75

#: How often (s) a study waiting on its runs looks for :data:`STOP_FILE`.
STOP_POLL_S = 1.0


def stop_requested(out_dir: Path) -> bool:
    """Whether ``out_dir`` holds :data:`STOP_FILE`."""
    return (Path(out_dir) / STOP_FILE).exists()


def cluster_cpus() -> int:
    """The CPUs of the connected Ray cluster's live nodes (at least 1)."""
    import ray

    return max(1, int(ray.cluster_resources().get("CPU", 1)))


def manifest_counts(res: dict[str, Any], wall_time_s_before: float) -> dict[str, Any]:
    """A study manifest's counts from :func:`run_study`'s counts ``res`` (so far or final),
    with the wall time of the earlier calls into the same directory added: what `run`'s
    ``study.json`` and ``sb3_tune``'s log manifest both hold."""
    return {
        "runs": res["runs"],
        "ran_now": res["ran"],
        "skipped_now": res["skipped"],
        "wall_time_s_now": res["wall_time_s"],
        "wall_time_s_total": wall_time_s_before + res["wall_time_s"],
        "failures": res["failures"],
    }


def runs_left(res: dict[str, Any]) -> int:
    """The runs :func:`run_study` did not make (stopped, or failed)."""
    return res["runs"] - res["skipped"] - res["ran"]


def run_study(
    specs: list[dict[str, Any]],
    out_dir: Path,
    *,
    address: str | None = None,
    num_cpus: int | None = None,
    use_ray: bool = True,
    progress: bool = True,
    on_result: Callable[[dict[str, Any]], None] | None = None,
    on_progress: Callable[[dict[str, Any]], None] | None = None,
    jax_cpus: int = 1,
) -> dict[str, Any]:
    """Run the specs whose result file is missing, seed by seed (:func:`seed_major`);
    returns counts and failures (``runs``, ``skipped``, ``ran``, ``failures``,
    ``wall_time_s``, ``stopped``). ``on_result`` gets each record as its file is written;
    ``on_progress`` gets those counts so far after each finished or failed run.

    On Ray the runs are handed out as CPUs free up (at most the cluster's CPUs reserved at a
    time, re-read as nodes join or leave), so every run handed out is running. That is what
    makes a stop request (:data:`STOP_FILE` in ``out_dir``) lose no work: no run is handed
    out after it, the running ones finish and write their files, and the study returns
    ``stopped: True`` with the rest not run; the same call later runs only the rest. An
    interrupt (Ctrl-C) stops at once instead: the running runs are lost.

    A JAX learner's runs of one task and budget train together, their seeds vmapped in one
    call (``run_group`` of its class): on Ray each such group is one task that reserves
    ``jax_cpus`` CPUs (capped at the largest node's CPUs; 1 by default, since two groups on
    one CPU each trained more per hour than one group on two: docs/PERFORMANCE.md), beside
    the other learners' runs, one CPU each."""
    out_dir = Path(out_dir)
    if stop_requested(out_dir):
        (out_dir / STOP_FILE).unlink()
        print(f"{out_dir}: removed a stop request left by an earlier command", file=sys.stderr)
    todo = [s for s in seed_major(specs) if not finished(out_dir, s)]
    skipped = len(specs) - len(todo)
    bar = _progress(len(specs), skipped, progress)
    failures: list[tuple[str, str]] = []
    t0 = time.perf_counter()
    ran = 0
    stopped = False

    def counts() -> dict[str, Any]:
        return {
            "runs": len(specs),
            "skipped": skipped,
            "ran": ran,
            "failures": list(failures),
            "wall_time_s": time.perf_counter() - t0,
            "stopped": stopped,
        }

    def stop_now() -> bool:
        nonlocal stopped
        if not stopped and stop_requested(out_dir):
            stopped = True
            print(f"{out_dir}: stop requested; the running runs finish", file=sys.stderr)
        return stopped

    def done(record: dict[str, Any]) -> None:
        nonlocal ran
        write_run(out_dir, record)
        ran += 1
        if on_result:
            on_result(record)
        if on_progress:
            on_progress(counts())
        bar.update(1)

    started = False
    jax_specs = [s for s in todo if s.get("family") == "jax"]
    # The groups and their runs: jax_runs (all seeds of a learner, task and budget).
    groups = resolve(jax_specs[0]["learner"]).groups(jax_specs) if jax_specs else []
    rest = [s for s in todo if s.get("family") != "jax"]
    if not use_ray:
        for group in groups:
            if stop_now():
                break
            for record in run_jax_group(group):
                done(record)
        for s in rest:
            if stop_now():
                break
            done(execute_run(s))
    elif groups or rest:
        import ray

        started = init_ray(address, num_cpus)
        try:
            remote = ray.remote(num_cpus=1, max_retries=0)(execute_run)
            per_group = min(jax_cpus, max_node_cpus())
            remote_group = ray.remote(num_cpus=per_group, max_retries=0)(run_jax_group)
            # The long JAX groups first, then the single runs fill the CPUs they leave.
            # Each entry: (its task's launcher, its runs, the CPUs it reserves).
            queue = [(lambda g=g: remote_group.remote(g), g, per_group) for g in groups]
            queue += [(lambda s=s: remote.remote(s), [s], 1) for s in rest]
            queue.reverse()  # popped from the end
            pending: dict[Any, tuple[list[dict[str, Any]], int]] = {}
            while queue or pending:
                if queue and not stop_now():
                    room = cluster_cpus() - sum(c for _, c in pending.values())
                    # A task wider than the room still goes when nothing else runs.
                    while queue and (queue[-1][2] <= room or not pending):
                        launch, batch, cpus = queue.pop()
                        pending[launch()] = (batch, cpus)
                        room -= cpus
                if not pending:
                    break
                ready, _ = ray.wait(list(pending), num_returns=1, timeout=STOP_POLL_S)
                if not ready:
                    continue
                batch, _ = pending.pop(ready[0])
                try:
                    out = ray.get(ready[0])
                except ray.exceptions.RayError as e:
                    for spec in batch:
                        failures.append((run_key(spec), str(e).splitlines()[-1][:500]))
                        bar.update(1)
                    if on_progress:
                        on_progress(counts())
                    continue
                for record in out if isinstance(out, list) else [out]:
                    done(record)
        finally:
            if started:
                ray.shutdown()
    # The request is answered (or came after every run was handed out): never left behind,
    # where it could be committed with the study's files.
    (out_dir / STOP_FILE).unlink(missing_ok=True)
    bar.close()
    return counts()


def run_jax_group(group: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One JAX group's records (its learner's ``run_group``), in this process or a Ray
    worker's."""
    return resolve(group[0]["learner"]).run_group(group)


def max_node_cpus() -> int:
    """The most CPUs any live node of the connected Ray cluster has (at least 1)."""
    import ray

    cpus = [n["Resources"].get("CPU", 0) for n in ray.nodes() if n.get("Alive")]
    return max(1, int(max(cpus, default=1)))


# ------------------------------------------------------------------------------------------
# Study manifest


@functools.cache
def machine() -> str:
    """The CPU, core count and OS: the core's one description (``_core.machine``)."""
    from sixaxis_avoid import _core

    return _core.machine()


@functools.cache
def versions() -> dict[str, str]:
    import importlib.metadata as md

    import sixaxis_avoid

    out = {"python": platform.python_version(), "sixaxis_avoid": sixaxis_avoid.__version__}
    for pkg in ("numpy", "gymnasium", "stable_baselines3", "sb3_contrib", "torch", "ray"):
        try:
            out[pkg] = md.version(pkg.replace("_", "-"))
        except md.PackageNotFoundError:
            pass
    return out


def write_manifest(out_dir: Path, manifest: dict[str, Any]) -> None:
    manifest = {
        **manifest,
        "date": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "machine": machine(),
        "versions": versions(),
        "load_average": [round(x, 2) for x in os.getloadavg()],
    }
    atomic_write_text(Path(out_dir) / "study.json", json.dumps(manifest, indent=1) + "\n")


def mean_or_none(xs: list[float]) -> float | None:
    return float(np.mean(xs)) if xs else None
