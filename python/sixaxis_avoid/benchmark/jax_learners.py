"""rejax learners (PPO, DQN) on the JAX twin (``sixaxis_avoid.jax``), ``jax.vmap``-ed over
seeds and over hyperparameter candidates::

    taskset -c 0 python -m sixaxis_avoid.benchmark.jax_learners --algo ppo --task paper_simple \\
        --seeds 8 --budget 100000 --out results/jax_ppo_paper_simple.json
    taskset -c 0 python -m sixaxis_avoid.benchmark.jax_learners --algo dqn --seeds 8 \\
        --budget 30000 --sb3-steps 3000

Hyperparameters use Stable-Baselines3's names (``learning_rate``, ``lr_schedule``,
``net_arch``, ``n_envs``, ``n_steps``, ``batch_size``, ``n_epochs``, ``clip_range``,
``train_freq``, ``gradient_steps``, ``target_update_interval``, ...), so one values dict
configures the SB3 learner and its JAX twin; :func:`rejax_config` maps them onto rejax 0.1.3.
What maps exactly and what differs is in the "JAX learners" section of docs/PERFORMANCE.md.

One ``jax.jit`` call trains C candidates x S seeds (:func:`train_candidates`): the knobs
that rejax keeps as traced pytree leaves (:data:`TRACED`: learning rate and its schedule,
gamma, GAE lambda, clip and loss coefficients, gradient-norm cap, DQN's exploration schedule,
learning start and target-update interval, the env's episode cap) are vmapped; the others
fix array shapes or loop lengths (:data:`STATIC`: net, envs, rollout length, batch and
buffer sizes, epochs) and split the candidates into separately compiled groups.

The greedy policy (the most likely action of PPO's policy; DQN's arg-max Q) is scored on the
task's evaluation targets at every checkpoint, inside the jitted loop: it acts from the start
until the target or the step cap (the scenario's ``max_steps_per_episode``, which a
deterministic policy caught in a loop also reaches); ``success`` is reaching the target and
``spl`` is ``optimal / max(moves, optimal)`` on success (moves exclude bumps), as
``sixaxis_avoid.benchmark.learners.spl``. Checkpoints and the end of training fall on
whole training iterations (PPO: ``n_envs x n_steps`` env steps, DQN: ``n_envs``), the most
that fit in each checkpoint and in the budget (``learners.whole_iterations``); each one's
env-step count is recorded. Needs the ``jax-learners`` extra.

The values layer (defaults, the traced/static split, the checks, the mapping onto rejax)
is :mod:`sixaxis_avoid.benchmark.jax_values`, which needs no JAX; its names are re-exported
here.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from sixaxis_avoid._deps import require
from sixaxis_avoid.benchmark import jax_state
from sixaxis_avoid.benchmark._io import atomic_write_text
from sixaxis_avoid.benchmark.jax_groups import (  # re-exported: the groups' layout
    GroupJob,
    PlannedGroup,
    candidate_groups,
    group_part,
    merge_seed_outcomes,
    plan_groups,
    saved_group,
)
from sixaxis_avoid.benchmark.jax_rejax import counting_env, rejax_classes  # re-exported
from sixaxis_avoid.benchmark.jax_values import (  # re-exported: the learners' public names
    ACTIVATIONS,
    ALGOS,
    DEFAULTS,
    DQN_DEFAULTS,
    ENV_DEFAULTS,
    LR_SCHEDULES,
    PPO_DEFAULTS,
    STATIC,
    TRACED,
    JaxLearnerError,
    check_values,
    iteration_steps,
    rejax_config,
    static_key,
    traced_fields,
    updates_per_env_step,
)
from sixaxis_avoid.benchmark.learners import whole_iterations

__all__ = [
    "ACTIVATIONS", "ALGOS", "DEFAULTS", "DQN_DEFAULTS", "ENV_DEFAULTS", "LR_SCHEDULES",
    "PPO_DEFAULTS", "STATIC", "TRACED", "Compiled", "GroupJob", "JaxLearnerError",
    "candidate_groups", "candidate_rows", "check_values", "compiled_group", "counting_env",
    "group_part", "iteration_steps", "main", "merge_seed_outcomes", "parse_args",
    "parse_sets", "rejax_classes", "rejax_config", "run", "saved_group", "sb3_speed",
    "static_key", "traced_fields", "train_candidates", "train_group", "train_in_process",
    "updates_per_env_step",
]  # fmt: skip


class Compiled:
    """One compiled group: the base algorithm of a group's static values on one task, and
    the jitted function that trains C candidates x S seeds of it."""

    def __init__(
        self, algo: str, task: Any, values: dict[str, Any], budget: int, checkpoints: list[int]
    ) -> None:
        jax = require("jax", "rejax learners")
        jnp = jax.numpy
        from sixaxis_avoid.jax import make

        self.algo, self.task, self.values = algo, task, values
        twin, params = make(
            task.scenario,
            reward_scale=float(values["reward_scale"]),
            assist=bool(values["assist"]),
            max_episode_steps=int(values["max_episode_steps"]),
            random_target=task.is_goal,
        )
        self.twin, self.params = twin, params
        index = {tuple(int(v) for v in c): i for i, c in enumerate(np.asarray(params.target_cells))}
        self.targets = [index[tuple(int(v) for v in t)] for t in task.eval_targets]
        self.optimal = [int(o) for o in task.optimal_lengths]
        self.eval_cap = int(task.scenario.max_steps_per_episode)
        step = iteration_steps(algo, values)
        # Whole iterations at or under each checkpoint and the budget (learners.whole_iterations).
        iters = sorted({whole_iterations(int(c), step) // step for c in checkpoints if int(c) > 0})
        total = whole_iterations(int(budget), step) // step
        iters = [i for i in iters if i < total] + [total]
        self.iteration_steps = step
        self.checkpoint_iterations = iters
        self.env_steps = [i * step for i in iters]
        cfg = rejax_config(algo, values)
        cls = rejax_classes()[algo]
        env = counting_env(twin, params)
        base = cls.create(
            env=env,
            env_params=params,
            total_timesteps=total * step,
            eval_freq=total * step,
            lr_iterations=total,
            **cfg,
        )
        self.base = base
        segments = np.diff([0, *iters]).astype(np.int32)
        evaluate = self.evaluator()

        def algo_of(fields: dict[str, Any]) -> Any:
            f = dict(fields)
            mes = f.pop("max_episode_steps").astype(jnp.int32)
            return base.replace(env_params=base.env_params._replace(max_steps_in_episode=mes), **f)

        def advance(a: Any, ts: Any, n: Any) -> Any:
            return jax.lax.fori_loop(0, n, lambda _, t: a.train_iteration(t), ts)

        def finish(a: Any, ts: Any, ev: Any) -> Any:
            es = ts.env_state
            first = jnp.where(es.first_step >= 0, (es.first_step - 1) * a.num_envs, -1)
            first = jnp.where(
                first >= 0, first + jnp.arange(a.num_envs) + 1, jnp.iinfo(jnp.int32).max
            )
            j = jnp.argmin(first)
            out = {
                "success": ev[0],
                "spl": ev[1],
                "reached": ev[2],
                "moves": ev[3],
                "first_success_env_steps": jnp.where(
                    first[j] == jnp.iinfo(jnp.int32).max, -1, first[j]
                ),
                "first_success_episode": es.first_episode[j] * a.num_envs,
                "episodes": es.episodes.sum(),
            }
            return out, self.policy_params(ts)

        def train_one(fields: dict[str, Any], key: Any) -> Any:
            a = algo_of(fields)
            ts = a.init_state(key)

            def segment(ts: Any, n: Any) -> Any:
                ts = advance(a, ts, n)
                return ts, evaluate(a, ts)

            ts, ev = jax.lax.scan(segment, ts, jnp.asarray(segments))
            return finish(a, ts, ev)

        def batched(f: Any, inner: tuple[Any, ...], outer: tuple[Any, ...], **jit: Any) -> Any:
            return jax.jit(jax.vmap(jax.vmap(f, in_axes=inner), in_axes=outer), **jit)

        # The same training in pieces, for a group whose state is saved as it trains
        # (:meth:`run` with ``state``): the state after init, after n more iterations, the
        # evaluation at a checkpoint and the outcome. Each piece traces the same calls as
        # ``train_one``: the same training, whose numbers equal one call's up to float
        # rounding (compiled apart, the pieces round differently; tests/test_jax_learners.py).
        # A state crosses between pieces as its leaves (arrays): its static fields (the
        # optimiser's functions, which close over traced knobs) are rebuilt in each piece
        # from a fresh state's structure (its arrays are unused, and compiled away).
        leaves = jax.tree_util.tree_leaves

        def state_of(a: Any, ls: list[Any]) -> Any:
            fresh = a.init_state(jax.random.PRNGKey(0))
            return jax.tree_util.tree_unflatten(jax.tree_util.tree_structure(fresh), ls)

        def advance_piece(f: Any, ls: list[Any], n: Any) -> Any:
            a = algo_of(f)
            return leaves(advance(a, state_of(a, ls), n))

        def evaluate_piece(f: Any, ls: list[Any]) -> Any:
            a = algo_of(f)
            return evaluate(a, state_of(a, ls))

        def finish_piece(f: Any, ls: list[Any], ev: Any) -> Any:
            a = algo_of(f)
            return finish(a, state_of(a, ls), ev)

        self._pieces = {
            "init": batched(lambda f, k: leaves(algo_of(f).init_state(k)), (None, 0), (0, None)),
            "advance": batched(advance_piece, (None, 0, None), (0, 0, None), donate_argnums=(1,)),
            "evaluate": batched(evaluate_piece, (None, 0), (0, 0)),
            "finish": batched(finish_piece, (None, 0, 0), (0, 0, 0)),
        }
        self.segments = [int(n) for n in segments]
        self._piece_executables: dict[tuple[int, int], dict[str, Any]] = {}
        self._train = jax.jit(jax.vmap(jax.vmap(train_one, in_axes=(None, 0)), in_axes=(0, None)))
        self._executables: dict[tuple[int, int], Any] = {}

    def policy_params(self, ts: Any) -> Any:
        return ts.actor_ts.params if self.algo == "ppo" else ts.q_ts.params

    def greedy(self, algo: Any, params: Any, obs: Any) -> Any:
        """The greedy action of the policy ``params`` at ``obs``."""
        jnp = require("jax.numpy", "rejax learners")
        if self.algo == "ppo":
            dist = algo.actor.apply(params, obs[None], method="_action_dist")
            return jnp.argmax(dist.logits[0])
        return jnp.argmax(algo.agent.apply(params, obs[None])[0])

    def evaluator(self) -> Any:
        """``evaluate(algo, ts) -> (success, spl, reached, moves)`` of the greedy policy on
        the evaluation targets."""
        jax = require("jax", "rejax learners")
        jnp = jax.numpy
        twin, targets_a = self.twin, jnp.asarray(self.targets, jnp.int32)
        optimal_a = jnp.asarray(self.optimal, jnp.float32)
        cap = self.eval_cap

        def evaluate(algo: Any, ts: Any) -> Any:
            params = self.policy_params(ts)
            key = jax.random.PRNGKey(0)  # the greedy rollout draws nothing

            def one(t: Any) -> Any:
                p = algo.env_params._replace(reset_target=t, max_steps_in_episode=jnp.int32(cap))
                obs, st = twin.reset_env(key, p)

                def body(c: Any) -> Any:
                    obs, st, _, _, moves, n = c
                    a = self.greedy(algo, params, obs)
                    obs, st, _, d, info = twin.step_env(key, st, a, p)
                    moves = moves + jnp.logical_not(info["collided"]).astype(jnp.int32)
                    return obs, st, d, info["terminated"], moves, n + 1

                init = (obs, st, jnp.bool_(False), jnp.bool_(False), jnp.int32(0), jnp.int32(0))
                c = jax.lax.while_loop(lambda c: jnp.logical_and(~c[2], c[5] < cap), body, init)
                return c[3], c[4]

            reached, moves = jax.vmap(one)(targets_a)
            spl = jnp.where(reached, optimal_a / jnp.maximum(moves, optimal_a), 0.0)
            return reached.astype(jnp.float32).mean(), spl.mean(), reached, moves

        return evaluate

    def paths(self, params: Any) -> list[list[list[int]] | None]:
        """The greedy paths (cells, bumps excluded) of one trained policy from the start to
        each evaluation target; None where it does not reach the target within the cap."""
        jax = require("jax", "rejax learners")
        jnp = jax.numpy
        roll = self._roll if hasattr(self, "_roll") else self._make_roll()
        start = [int(v) for v in np.asarray(self.params.cells)[int(self.params.start_state)]]
        out: list[list[list[int]] | None] = []
        for t in self.targets:
            cells, moved, term = (np.asarray(x) for x in roll(params, jnp.int32(t)))
            if not term.any():
                out.append(None)
                continue
            end = int(np.argmax(term)) + 1
            out.append(
                [start] + [[int(v) for v in c] for c, m in zip(cells[:end], moved[:end]) if m]
            )
        return out

    def _make_roll(self) -> Any:
        """The jitted greedy rollout of :meth:`paths` (built once)."""
        jax = require("jax", "rejax learners")
        jnp = jax.numpy
        twin, base, cap = self.twin, self.base, self.eval_cap

        @jax.jit
        def roll(params: Any, t: Any) -> Any:
            p = self.params._replace(reset_target=t, max_steps_in_episode=jnp.int32(cap))
            key = jax.random.PRNGKey(0)
            obs, st = twin.reset_env(key, p)

            def body(c: Any, _: Any) -> Any:
                obs, st, done = c
                a = self.greedy(base, params, obs)
                obs2, st2, _, d, info = twin.step_env(key, st, a, p)
                moved = jnp.logical_and(~done, ~info["collided"])
                out = (info["cell"], moved, jnp.logical_and(~done, info["terminated"]))
                keep = jax.tree_util.tree_map(
                    lambda x, y: jnp.where(done, x, y), (obs, st), (obs2, st2)
                )
                return (keep[0], keep[1], jnp.logical_or(done, d)), out

            _, (cells, moved, term) = jax.lax.scan(body, (obs, st, jnp.bool_(False)), None, cap)
            return cells, moved, term

        self._roll = roll
        return roll

    def run(
        self,
        candidates: list[dict[str, Any]],
        seeds: list[int],
        state: str | Path | None = None,
        ident: str = "",
    ) -> dict[str, Any]:
        """Train every candidate (this group's static values) on every seed in one call.

        With ``state`` (a file path), the training runs in pieces of at most 1/
        :data:`jax_state.STATE_PIECES` of its iterations (:func:`jax_state.train_in_pieces`),
        and its state (every candidate's and seed's nets, optimiser, env and random key, and
        the evaluations so far) is saved there at most every :data:`jax_state.STATE_EVERY_S`
        seconds of training and at the checkpoints. A call that finds a state saved by the
        same training (``ident``, the candidates, seeds, checkpoints and pieces) goes on from
        it, so a group stopped midway loses at most those seconds; the file goes once the
        group is done. The outcome is the same whatever the stops, and equals that of one
        call (without ``state``) up to float rounding; ``train_wall_s`` and ``train_cpu_s``
        add up every call's training, and ``resumes`` counts the calls that went on from a
        saved state."""
        jax = require("jax", "rejax learners")
        jnp = jax.numpy
        fields = [traced_fields(self.algo, c) for c in candidates]
        batch = {k: jnp.asarray([f[k] for f in fields], jnp.float32) for k in fields[0]}
        keys = jax.vmap(jax.random.PRNGKey)(jnp.asarray(seeds))
        if state is not None:
            return self._run_in_pieces(candidates, seeds, batch, keys, Path(state), ident)
        t0 = time.perf_counter()
        shape = (len(candidates), len(seeds))
        if shape not in self._executables:  # compiled once per (candidates, seeds) shape
            self._executables[shape] = self._train.lower(batch, keys).compile()
        compiled = self._executables[shape]
        compile_s = time.perf_counter() - t0
        t0, c0 = time.perf_counter(), time.process_time()
        out, params = compiled(batch, keys)
        out = jax.tree_util.tree_map(np.asarray, jax.block_until_ready(out))
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        return self._outcome(out, params, len(candidates) * len(seeds), compile_s, wall, cpu, 0)

    def _outcome(
        self,
        out: Any,
        params: Any,
        runs: int,
        compile_s: float,
        wall: float,
        cpu: float,
        resumes: int,
    ) -> dict[str, Any]:
        return {
            "out": out,  # arrays (C, S, ...)
            "params": params,
            "compile_s": compile_s,
            "train_wall_s": wall,
            "train_cpu_s": cpu,
            "resumes": resumes,
            "env_steps": self.env_steps,
            "env_steps_per_s": runs * self.env_steps[-1] / wall,
        }

    def _run_in_pieces(
        self,
        candidates: list[dict[str, Any]],
        seeds: list[int],
        batch: dict[str, Any],
        keys: Any,
        state: Path,
        ident: str,
    ) -> dict[str, Any]:
        """:meth:`run` with ``state``: the pieces, saving and resuming the training state."""
        import hashlib

        jax = require("jax", "rejax learners")
        jnp = jax.numpy
        pieces = self._pieces
        chunk = max(1, -(-sum(self.segments) // jax_state.STATE_PIECES))
        mark = hashlib.sha256(
            json.dumps(
                [ident, candidates, list(seeds), self.segments, chunk, self.iteration_steps],
                sort_keys=True,
                default=str,
            ).encode()
        ).hexdigest()
        t0 = time.perf_counter()
        shape = (len(candidates), len(seeds))
        if shape not in self._piece_executables:  # compiled once per shape, as in one call
            ts = jax.eval_shape(pieces["init"], batch, keys)
            self._piece_executables[shape] = {
                "init": pieces["init"].lower(batch, keys).compile(),
                "advance": pieces["advance"].lower(batch, ts, jnp.int32(1)).compile(),
                "evaluate": pieces["evaluate"].lower(batch, ts).compile(),
            }
        ex = self._piece_executables[shape]
        ts = jax.block_until_ready(ex["init"](batch, keys))  # the state's leaves
        compile_s = time.perf_counter() - t0
        out, params, wall, cpu, resumes = jax_state.train_in_pieces(
            ex, pieces["finish"], batch, ts, self.segments, chunk, state, mark
        )
        runs = len(candidates) * len(seeds)
        return self._outcome(out, params, runs, compile_s, wall, cpu, resumes)


_GROUPS: dict[str, Compiled] = {}


def compiled_group(
    algo: str, task: Any, values: dict[str, Any], budget: int, checkpoints: list[int]
) -> Compiled:
    """The :class:`Compiled` group of ``values``' static knobs on ``task`` (built once per
    process: a second tuning or run group of the same shapes reuses its executable)."""
    key = json.dumps(
        [algo, task.id, task.kind, task.spec, static_key(algo, values), budget, checkpoints],
        sort_keys=True,
        default=str,
    )
    if key not in _GROUPS:
        _GROUPS[key] = Compiled(algo, task, values, budget, checkpoints)
    return _GROUPS[key]


def train_group(
    algo: str,
    task: Any,
    members: list[dict[str, Any]],
    seeds: list[int],
    budget: int,
    checkpoints: list[int],
    state: tuple[str, str] | None = None,
) -> dict[str, Any]:
    """Train one group (candidates of equal :data:`STATIC` values) x ``seeds`` on ``task``
    in one compiled call (or in pieces, with ``state``): the per-candidate curves
    (``success``, ``spl``: C lists of S lists, one value per checkpoint), the checkpoints'
    ``env_steps``, and the timing (seconds):
    ``compile_s``, ``train_wall_s``, ``train_cpu_s`` and the whole group's ``group_wall_s``
    and ``group_cpu_s``. Plain JSON values, so a Ray worker can return it.

    ``state``: ``(path, ident)``, where the training saves its state as it goes and goes on
    from a state saved there by the same group (:meth:`Compiled.run`); the earlier calls'
    training time counts in the group's, and ``resumes`` counts them."""
    t0, c0 = time.perf_counter(), time.process_time()
    comp = compiled_group(algo, task, members[0], budget, checkpoints)
    if state is None:
        r = comp.run(members, seeds)
    else:
        r = comp.run(members, seeds, state=state[0], ident=state[1])
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    # Training done by earlier calls on a saved state (its time is in r's train times).
    earlier_wall = max(0.0, r["train_wall_s"] - wall)
    earlier_cpu = max(0.0, r["train_cpu_s"] - cpu)
    return {
        "env_steps": [int(x) for x in r["env_steps"]],
        "success": r["out"]["success"].tolist(),
        "spl": r["out"]["spl"].tolist(),
        "compile_s": r["compile_s"],
        "train_wall_s": r["train_wall_s"],
        "train_cpu_s": r["train_cpu_s"],
        "resumes": int(r["resumes"]),
        "group_wall_s": wall + earlier_wall,
        "group_cpu_s": cpu + earlier_cpu,
    }


def candidate_rows(
    checked: list[dict[str, Any]],
    idx: list[int],
    g: int,
    outcome: dict[str, Any],
    resumed: bool,
    paths: list[Path | None],
) -> dict[int, dict[str, Any]]:
    """One :func:`train_candidates` entry per candidate of group ``g`` (indices ``idx``):
    ``resumed`` if its whole outcome was read back, ``resumed_wall_s`` the wall time of what
    was read back (a group split by seed may be read back in part), ``parts`` its files."""
    keys = ("compile_s", "train_wall_s", "train_cpu_s", "group_wall_s", "group_cpu_s")
    back = outcome.get("resumed_wall_s", outcome["group_wall_s"] if resumed else 0.0)
    return {
        i: {
            "values": checked[i],
            "group": g,
            "group_size": len(idx),
            "env_steps": outcome["env_steps"],
            "success": outcome["success"][j],
            "spl": outcome["spl"][j],
            "resumed": resumed,
            "resumed_wall_s": float(back),
            "state_resumes": int(outcome.get("resumes", 0)),
            "parts": [str(f) for f in paths if f is not None],
            **{k: outcome[k] for k in keys},
        }
        for j, i in enumerate(idx)
    }


def train_in_process(jobs: list[GroupJob]) -> Any:
    """:func:`train_candidates`' default ``dispatch``: the jobs one after another, here."""
    for k, job in enumerate(jobs):
        yield k, train_group(*job)


def train_candidates(
    algo: str,
    tasks: list[Any],
    candidates: list[dict[str, Any]],
    seeds: list[int],
    budget: int,
    checkpoints: list[int] | None = None,
    parts: Path | None = None,
    dispatch: Any = None,
    log: Any = None,
    save_state: bool = False,
    split_seeds: bool = False,
) -> dict[str, list[dict[str, Any]]]:
    """Train every candidate (a values dict) x every seed on each of ``tasks`` for
    ``budget`` env steps: one compiled, vmapped call per task and group of equal
    :data:`STATIC` values (:func:`train_group`). Returns, per task id, one entry per
    candidate, in order: its values, group, per-seed curves (``success``, ``spl``: lists of
    S lists, one value per checkpoint), ``env_steps`` of the checkpoints, the group's timing,
    whether the group was ``resumed`` and its ``part`` file (or None).

    ``dispatch(jobs)`` trains the jobs (:data:`GroupJob`) and yields ``(index, outcome)`` as
    each finishes, in any order: :func:`train_in_process` by default; a Ray dispatch spreads
    them over a cluster (:mod:`sixaxis_avoid.benchmark.jax_tune`).

    With ``parts`` (a directory), each group's outcome is saved there as it finishes, and a
    group whose saved outcome matches (same task, candidates, seeds, budget, checkpoints and
    versions of jax and rejax: :func:`group_part`) is read back instead of trained again, so a
    long search stopped midway resumes where it stopped. With ``save_state`` too, a group
    trains in pieces and saves its state there as it goes (:data:`jax_state.STATE_SUFFIX`,
    :meth:`Compiled.run`), so a stop loses minutes of it, not the whole group, on a machine
    (or shared file system) that keeps the file. Pieces give the same numbers whatever the
    stops, but not bit for bit those of one call (float rounding differs across the
    compiled pieces), so the mode is part of a group's identity (:func:`group_part`).

    With ``split_seeds`` (and ``parts``), a group not yet begun (no outcome or state saved)
    trains as one group per seed (:func:`plan_groups`), each saved as it finishes (with its
    group's identity, ``group_ident``, and its ``seed``); the entries are the same once
    every seed is in (:func:`merge_seed_outcomes`)."""
    checked = [check_values(algo, c) for c in candidates]
    checkpoints = checkpoints or [budget]
    rows: dict[str, dict[int, dict[str, Any]]] = {t.id: {} for t in tasks}
    jobs: list[GroupJob] = []
    where: list[PlannedGroup] = []
    # A split group's seeds so far: (task, group) -> seed index -> (outcome, read back, file)
    split: dict[tuple[str, int], dict[int, tuple[dict[str, Any], bool, Path | None]]] = {}

    def settle(p: PlannedGroup, out: dict[str, Any], resumed: bool) -> None:
        if p.split is None:
            rows[p.task.id].update(candidate_rows(checked, p.members, p.group, out, resumed,
                                                  [p.part]))  # fmt: skip
            return
        got = split.setdefault((p.task.id, p.group), {})
        got[p.split] = (out, resumed, p.part)
        if len(got) < len(seeds):
            return
        each = [got[k] for k in range(len(seeds))]
        merged = merge_seed_outcomes([o for o, _, _ in each])
        merged["resumed_wall_s"] = sum(o["group_wall_s"] for o, back, _ in each if back)
        rows[p.task.id].update(candidate_rows(checked, p.members, p.group, merged,
                                              all(b for _, b, _ in each),
                                              [f for _, _, f in each]))  # fmt: skip

    plan = plan_groups(algo, tasks, checked, seeds, budget, checkpoints, parts, save_state,
                       split_seeds)  # fmt: skip
    for p in plan:
        saved = saved_group(p.part, p.ident)
        if saved is not None:
            settle(p, saved, True)
        else:
            job = p.job if p.state is None else (*p.job, (str(p.state), p.ident))
            jobs.append(job)
            where.append(p)
    for k, outcome in (dispatch or train_in_process)(jobs):
        p = where[k]
        out = {"ident": p.ident, **outcome}
        if p.split is not None:
            out.update(group_ident=p.group_ident, seed=int(seeds[p.split]))
        if p.part is not None:
            atomic_write_text(p.part, json.dumps(out) + "\n")
        settle(p, out, False)
        if log:
            which = "" if p.split is None else f" seed {seeds[p.split]}"
            log(f"{p.task.id} group {p.group}{which}: {out['group_wall_s']:.0f} s")
    return {t: [r[i] for i in range(len(checked))] for t, r in rows.items()}


# ------------------------------------------------------------------------------------------
# CLI


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--algo", choices=ALGOS, default="ppo", help="rejax's PPO or DQN")
    p.add_argument("--suite", default="v1", help="suite whose task --task names")
    p.add_argument("--task", default="paper_simple")
    p.add_argument("--seeds", type=int, default=8, help="seeds 0..N-1, vmapped")
    p.add_argument("--seed-offset", type=int, default=0, help="first seed")
    p.add_argument("--budget", type=int, default=100_000, help="env steps per seed")
    p.add_argument("--evaluations", type=int, default=10, help="evenly spaced checkpoints")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=JSON",
        help="a hyperparameter (SB3's name), e.g. --set learning_rate=1e-3 --set "
        "net_arch=[64,64] --set lr_schedule='\"linear\"'; the others are the algorithm's "
        "defaults (jax_learners.PPO_DEFAULTS / DQN_DEFAULTS)",
    )
    p.add_argument(
        "--sb3-steps",
        type=int,
        default=0,
        help="also train SB3's PPO or DQN with the same values for this many env steps (one "
        "seed, one torch thread, the native SixAxisVecEnv) and record its env steps/s",
    )
    p.add_argument("--out", type=Path, default=None, help="JSON file (also printed)")
    return p.parse_args(argv)


def parse_sets(sets: list[str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for s in sets:
        name, eq, raw = s.partition("=")
        if not eq:
            raise JaxLearnerError(f"--set: {s!r} is not NAME=JSON")
        try:
            out[name] = json.loads(raw)
        except json.JSONDecodeError:
            out[name] = raw  # a bare string, e.g. lr_schedule=linear
    return out


def run(a: argparse.Namespace) -> dict[str, Any]:
    jax = require("jax", "rejax learners")
    from sixaxis_avoid.benchmark.tasks import load_suite

    values = check_values(a.algo, parse_sets(a.set))
    task = load_suite(a.suite).task(a.task)
    n = max(1, a.evaluations)
    checkpoints = [round(a.budget * (i + 1) / n) for i in range(n)]
    seeds = list(range(a.seed_offset, a.seed_offset + a.seeds))
    comp = Compiled(a.algo, task, values, a.budget, checkpoints)
    r = comp.run([values], seeds)
    success, spl = r["out"]["success"][0], r["out"]["spl"][0]  # (seeds, checkpoints)
    return {
        "algo": a.algo,
        "rejax_version": importlib.metadata.version("rejax"),
        "jax_version": jax.__version__,
        "task": a.task,
        "suite": a.suite,
        "seeds": seeds,
        "flags": {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(a).items()},
        "values": values,
        "rejax_config": json.loads(json.dumps(rejax_config(a.algo, values), default=list)),
        "compile_s": r["compile_s"],
        "train_wall_s": r["train_wall_s"],
        "train_cpu_s": r["train_cpu_s"],
        "env_steps_per_s": r["env_steps_per_s"],
        # On a loaded machine the process's CPU time is the fairer clock.
        "env_steps_per_cpu_s": len(seeds) * r["env_steps"][-1] / r["train_cpu_s"],
        "updates_per_env_step": updates_per_env_step(a.algo, values),
        "eval_env_steps": r["env_steps"],
        "success": success.tolist(),
        "spl": spl.tolist(),
        "final_success_mean": float(success[:, -1].mean()),
        "final_spl_mean": float(spl[:, -1].mean()),
        "seeds_reaching_target": int((success[:, -1] > 0).sum()),
        "seeds_reaching_target_any_eval": int((success.max(axis=1) > 0).sum()),
    }


def sb3_speed(a: argparse.Namespace, values: dict[str, Any]) -> dict[str, Any]:
    """SB3's PPO or DQN with the same values, timed: env steps/s on one torch thread."""
    torch = require("torch", "the SB3 comparison")
    sb3 = require("stable_baselines3", "the SB3 comparison")
    from sixaxis_avoid.benchmark.learners import linear_schedule
    from sixaxis_avoid.benchmark.tasks import load_suite
    from sixaxis_avoid.sb3 import SixAxisVecEnv

    task = load_suite(a.suite).task(a.task)
    torch.set_num_threads(1)
    kw: dict[str, Any] = {"reward_scale": values["reward_scale"], "assist": values["assist"]}
    if task.is_goal:
        kw["random_target"] = True
    n_envs = int(values["n_envs"]) if a.algo == "ppo" else 1
    venv = SixAxisVecEnv(
        n_envs, seed=a.seed_offset, scenario=task.scenario,
        max_episode_steps=int(values["max_episode_steps"]), **kw,
    )  # fmt: skip
    activation = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU}[values["activation"]]
    lr = values["learning_rate"]
    if values["lr_schedule"] == "linear":
        lr = linear_schedule(float(lr))
    common = {
        "learning_rate": lr, "gamma": values["gamma"], "max_grad_norm": values["max_grad_norm"],
        "batch_size": values["batch_size"], "seed": a.seed_offset, "device": "cpu", "verbose": 0,
        "policy_kwargs": {"net_arch": values["net_arch"], "activation_fn": activation},
    }  # fmt: skip
    if a.algo == "ppo":
        model = sb3.PPO(
            "MlpPolicy", venv, n_steps=values["n_steps"], n_epochs=values["n_epochs"],
            gae_lambda=values["gae_lambda"], clip_range=values["clip_range"],
            ent_coef=values["ent_coef"], vf_coef=values["vf_coef"], **common,
        )  # fmt: skip
    else:
        model = sb3.DQN(
            "MlpPolicy", venv, buffer_size=values["buffer_size"],
            learning_starts=values["learning_starts"], train_freq=values["train_freq"],
            gradient_steps=values["gradient_steps"],
            target_update_interval=values["target_update_interval"],
            exploration_fraction=values["exploration_fraction"],
            exploration_initial_eps=values["exploration_initial_eps"],
            exploration_final_eps=values["exploration_final_eps"], **common,
        )  # fmt: skip
    t0, c0 = time.perf_counter(), time.process_time()
    model.learn(a.sb3_steps)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    return {
        "algo": a.algo,
        "env_steps": a.sb3_steps,
        "wall_s": wall,
        "cpu_s": cpu,
        "env_steps_per_s": a.sb3_steps / wall,
        "env_steps_per_cpu_s": a.sb3_steps / cpu,
        "updates_per_env_step": updates_per_env_step(a.algo, values),
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    a = parse_args(argv)
    out = run(a)
    if a.sb3_steps > 0:
        out["sb3"] = sb3_speed(a, out["values"])
        out["speedup_vs_sb3"] = out["env_steps_per_s"] / out["sb3"]["env_steps_per_s"]
        out["speedup_vs_sb3_cpu"] = out["env_steps_per_cpu_s"] / out["sb3"]["env_steps_per_cpu_s"]
    text = json.dumps(out, indent=1)
    if a.out is not None:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text(text + "\n")
    print(text)
    return out


if __name__ == "__main__":
    main()
