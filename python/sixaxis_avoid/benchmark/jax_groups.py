"""The compiled groups of a JAX search or run, laid out without training anything: which
candidates share a compiled program (:func:`candidate_groups`), where each group's outcome
and training state are saved and the identity a saved outcome must carry
(:func:`group_part`, :func:`plan_groups`, :class:`PlannedGroup`), and reading a saved
outcome back (:func:`saved_group`). :func:`jax_learners.train_candidates` trains what
:func:`plan_groups` lays out; ``jax_tune --status`` reads a search's progress from it. Needs
no JAX.
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
    pieces, else None."""

    task: Any
    group: int
    members: list[int]
    job: GroupJob
    part: Path | None
    ident: str | None
    state: Path | None


def plan_groups(
    algo: str,
    tasks: list[Any],
    checked: list[dict[str, Any]],
    seeds: list[int],
    budget: int,
    checkpoints: list[int],
    parts: Path | None = None,
    save_state: bool = False,
) -> list[PlannedGroup]:
    """The compiled groups that :func:`jax_learners.train_candidates` trains for these arguments
    (``checked``: the candidates' checked values), task by task, each group in order of
    :func:`candidate_groups`; nothing is trained or read. ``jax_tune --status`` reads a
    search's progress from it."""
    out = []
    pieces = save_state and parts is not None
    groups = candidate_groups(algo, checked)
    for task in tasks:
        for g, idx in enumerate(groups):
            job = (algo, task, [checked[i] for i in idx], seeds, budget, checkpoints)
            path, ident = (None, None) if parts is None else group_part(Path(parts), job, pieces)
            state = None
            if pieces and path is not None:
                state = path.resolve().with_suffix(jax_state.STATE_SUFFIX)
            out.append(PlannedGroup(task, g, idx, job, path, ident, state))
    return out
