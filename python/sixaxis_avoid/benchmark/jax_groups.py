"""The compiled groups of a JAX search or run, laid out without training anything: which
candidates share a compiled program (:func:`candidate_groups`), where each group's outcome
and training state are saved and the identity a saved outcome must carry
(:func:`group_part`, :func:`plan_groups`, :class:`PlannedGroup`), and reading a saved
outcome back (:func:`saved_group`). :func:`jax_learners.train_candidates` trains what
:func:`plan_groups` lays out; ``jax_tune --status`` reads a search's progress from it. Needs
no JAX.

A group not yet begun can be split by seed (``split_seeds``): one compiled group of the
same candidates per seed, each with its own outcome and state file, merged back into the
group's outcome (:func:`merge_seed_outcomes`) once every seed is saved. At 3 seeds a split
seed cost about 0.45 of the whole group (jax_dqn's second draw at 3M env steps, see
docs/PERFORMANCE.md), so it fits a sitting on a fresh machine that keeps no state between
sittings. Its seed's random stream is the same as in the whole
group, its float rounding may not be (another vmapped shape), so a split seed is a group of
its own identity.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import json
from pathlib import Path
from typing import Any

from sixaxis_avoid.benchmark import jax_state
from sixaxis_avoid.benchmark.jax_values import check_values, static_key

#: One group to train: ``(algo, task, members, seeds, budget, checkpoints[, state])``, the
#: arguments of :func:`jax_learners.train_group`.
GroupJob = tuple[Any, ...]


def candidate_groups(algo: str, candidates: list[dict[str, Any]]) -> list[list[int]]:
    """The candidates' indices split by their :data:`jax_values.STATIC` values (one compiled program
    each), in order of first appearance."""
    groups: dict[str, list[int]] = {}
    for i, c in enumerate(candidates):
        groups.setdefault(static_key(algo, check_values(algo, c)), []).append(i)
    return list(groups.values())


def group_part(parts: Path, job: GroupJob, pieces: bool = False) -> tuple[Path, str]:
    """Where :func:`jax_learners.train_candidates` saves one group's outcome (``job``: the
    arguments of :func:`jax_learners.train_group`), and the identity (a sha256) a saved
    outcome must carry to be read back: the algorithm, the task (id, kind, spec), the
    group's checked values, the seeds, the budget (env steps), the checkpoints, the versions
    of jax and rejax, and with ``pieces`` the pieces' size (a group trained in pieces with
    a saved state)."""
    import hashlib

    algo, task, members, seeds, budget, checkpoints = job[:6]
    versions = {}
    for pkg in ("jax", "rejax"):
        try:
            versions[pkg] = importlib.metadata.version(pkg)
        except importlib.metadata.PackageNotFoundError:
            versions[pkg] = None
    blob = json.dumps(
        [algo, task.id, task.kind, task.spec, members, list(seeds), int(budget),
         [int(c) for c in checkpoints], versions]
        + ([{"pieces": jax_state.STATE_PIECES}] if pieces else []),
        sort_keys=True,
        default=str,
    )  # fmt: skip
    ident = hashlib.sha256(blob.encode()).hexdigest()
    return parts / f"{task.id}--{ident[:16]}.json", ident


def saved_group(path: Path | None, ident: str | None) -> dict[str, Any] | None:
    """The outcome saved at ``path`` if it carries ``ident`` (:func:`group_part`), else None."""
    if path is None or not path.exists():
        return None
    saved = json.loads(path.read_text())
    return saved if saved.get("ident") == ident else None


@dataclasses.dataclass(frozen=True)
class PlannedGroup:
    """One compiled group of a search or a run (:func:`plan_groups`): its ``task``, its index
    ``group`` among the task's groups, the candidates' indices (``members``), the arguments
    of :func:`jax_learners.train_group` (``job``), the file of its outcome (``part``) and the
    identity that file must carry (``ident``), both None without ``parts``, and the file of its
    training state (``state``, absolute: a Ray worker's cwd differs) when it trains in
    pieces, else None. A group split by seed is planned as one entry per seed: ``split`` is
    that seed's index in the search's seeds (None: the whole group) and ``group_ident`` the
    whole group's identity, which the seed's saved outcome carries too."""

    task: Any
    group: int
    members: list[int]
    job: GroupJob
    part: Path | None
    ident: str | None
    state: Path | None
    split: int | None = None
    group_ident: str | None = None


def plan_groups(
    algo: str,
    tasks: list[Any],
    checked: list[dict[str, Any]],
    seeds: list[int],
    budget: int,
    checkpoints: list[int],
    parts: Path | None = None,
    save_state: bool = False,
    split_seeds: bool = False,
) -> list[PlannedGroup]:
    """The compiled groups that :func:`jax_learners.train_candidates` trains for these arguments
    (``checked``: the candidates' checked values), task by task, each group in order of
    :func:`candidate_groups`; nothing is trained. ``jax_tune --status`` reads a search's
    progress from it.

    With ``split_seeds`` (and ``parts``), a group with neither its whole outcome nor a
    whole training state saved in ``parts`` is planned as one group per seed, in the seeds'
    order (those files' presence is the one thing read): a group saved whole, or part way,
    goes on whole."""
    out = []
    pieces = save_state and parts is not None
    groups = candidate_groups(algo, checked)
    for task in tasks:
        for g, idx in enumerate(groups):
            members = [checked[i] for i in idx]
            whole = _planned(task, g, idx, (algo, task, members, seeds, budget, checkpoints),
                             parts, pieces)  # fmt: skip
            begun = whole.state is not None and whole.state.exists()
            if not split_seeds or parts is None or begun or saved_group(whole.part, whole.ident):
                out.append(whole)
                continue
            for k, seed in enumerate(seeds):
                one = (algo, task, members, [seed], budget, checkpoints)
                p = _planned(task, g, idx, one, parts, pieces)
                out.append(dataclasses.replace(p, split=k, group_ident=whole.ident))
    return out


def _planned(
    task: Any, g: int, idx: list[int], job: GroupJob, parts: Path | None, pieces: bool
) -> PlannedGroup:
    path, ident = (None, None) if parts is None else group_part(Path(parts), job, pieces)
    state = None
    if pieces and path is not None:
        state = path.resolve().with_suffix(jax_state.STATE_SUFFIX)
    return PlannedGroup(task, g, idx, job, path, ident, state)


#: The outcome fields of :func:`jax_learners.train_group` that add up over a split group's
#: seeds (seconds, and the calls that went on from a saved state).
ADDED = ("compile_s", "train_wall_s", "train_cpu_s", "group_wall_s", "group_cpu_s", "resumes")


def merge_seed_outcomes(outcomes: list[dict[str, Any]]) -> dict[str, Any]:
    """One group's outcome from its seeds' (a group split by seed, in the seeds' order):
    each candidate's ``success`` and ``spl`` rows (one per seed) side by side, the
    checkpoints' ``env_steps`` (the same for all), and the times and resumes added up
    (:data:`ADDED`): the layout of a whole group's outcome."""
    first = outcomes[0]
    if any(o["env_steps"] != first["env_steps"] for o in outcomes):
        raise ValueError("env_steps: the seeds of a split group differ in their checkpoints")
    merged: dict[str, Any] = {"env_steps": first["env_steps"]}
    for key in ("success", "spl"):
        merged[key] = [[row for o in outcomes for row in o[key][j]] for j in range(len(first[key]))]
    for key in ADDED:
        merged[key] = sum(o.get(key, 0) for o in outcomes)
    return merged


def saved_groups_count(parts: Path, n_seeds: int) -> int:
    """How many compiled groups are saved in ``parts``: each whole group's outcome, and each
    group split by seed (:func:`plan_groups`) with all its ``n_seeds`` seeds saved (a split
    seed's outcome carries its group's identity, ``group_ident``)."""
    whole, split = 0, {}
    for f in parts.glob("*--*.json"):
        g = json.loads(f.read_text()).get("group_ident")
        if g is None:
            whole += 1
        else:
            split[g] = split.get(g, 0) + 1
    return whole + sum(n >= n_seeds for n in split.values())
