"""SB3's PPO and DQN on their JAX twin's tuned values: the hyperparameter file's
``learners[ppo|dqn].by_budget[B]`` derived from ``learners[jax_ppo|jax_dqn].by_budget[B]``::

    python -m sixaxis_avoid.benchmark.borrow --learner ppo --budget 100000

The twin's values already use SB3's names (:mod:`sixaxis_avoid.benchmark.jax_values`).
The entry adds ``implementation: rejax`` (:mod:`sixaxis_avoid.benchmark.implementation`),
so SB3 trains the algorithm the twin's search tuned, and keeps the twin's tuning record
(command, trials file, objective), since that search chose the values. Two of the twin's
values are not SB3 learner settings and are checked instead of copied:

- ``activation``: SB3's MlpPolicy default for the algorithm (PPO tanh, DQN ReLU), which the
  SB3 learners use; any other value is an error;
- DQN's ``replay_sample``: SB3 draws its minibatches with replacement; the twin's draw is
  named in the entry's ``source`` when it differs.

The docs' "JAX against SB3" section of docs/BENCHMARKS.md shows that the two
implementations agree at these values.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path
from typing import Any

from sixaxis_avoid.benchmark._io import atomic_write_text
from sixaxis_avoid.benchmark.hyperparams import HYPERPARAMS_DIR, display_path
from sixaxis_avoid.benchmark.jax_values import JAX_LEARNER

#: The JAX twin of each SB3 learner.
TWIN = JAX_LEARNER
#: SB3's MlpPolicy activation per algorithm (the SB3 learners take no activation setting).
SB3_ACTIVATION = {"ppo": "tanh", "dqn": "relu"}
#: What ``implementation: rejax`` changes in SB3 (learners.PPO_IMPLEMENTATIONS /
#: DQN_IMPLEMENTATIONS).
IMPLEMENTATION = {
    "ppo": "LeCun-normal init, actor and critic gradients clipped each on its own, "
    "truncation as termination, value clipping at clip_range",
    "dqn": "half the squared TD error as the loss (SB3: Huber), LeCun-normal init, "
    "truncation as termination, train_freq envs stepped once between update phases, no "
    "hindsight replay on the goal task",
}


class BorrowError(ValueError):
    """A twin entry that cannot be borrowed (names the field and value)."""


def borrowed_status(twin: str) -> str:
    """The ``status`` of an SB3 entry borrowed from its JAX ``twin`` (and so the
    ``hyperparams_status`` of its runs): how a report tells runs on the twin's values from
    runs on values of SB3's own search (status ``tuned``)."""
    return f"{twin}'s tuned values and rejax's implementation (not tuned for SB3)"


def sb3_values(learner: str, values: dict[str, Any], where: str) -> tuple[dict[str, Any], str]:
    """A JAX learner's values (SB3's names) as the SB3 ``learner``'s settings: the
    ``activation`` is checked to be SB3's MlpPolicy default and dropped, and so is DQN's
    ``replay_sample`` (SB3 draws with replacement), which is returned beside the values
    ("" for PPO). ``where`` names the values in an error."""
    values = dict(values)
    activation = values.pop("activation", SB3_ACTIVATION[learner])
    if activation != SB3_ACTIVATION[learner]:
        raise BorrowError(
            f"{where}.activation: {activation!r} is not SB3's {learner.upper()} activation "
            f"{SB3_ACTIVATION[learner]!r}"
        )
    sample = values.pop("replay_sample", "without_replacement") if learner == "dqn" else ""
    return values, sample


def borrowed_entry(data: dict[str, Any], learner: str, budget: int) -> dict[str, Any]:
    """The SB3 ``learner``'s entry at ``budget`` from its twin's entry in ``data``."""
    if learner not in TWIN:
        raise BorrowError(f"learner: {learner!r} has no JAX twin ({', '.join(TWIN)})")
    twin = TWIN[learner]
    entry = data.get("learners", {}).get(twin, {}).get("by_budget", {}).get(str(int(budget)))
    if not entry or entry.get("status") != "tuned":
        raise BorrowError(
            f"learners.{twin}.by_budget.{int(budget)}: no tuned entry to borrow "
            f"(tune it first: python -m sixaxis_avoid.benchmark.jax_tune --algo {learner} ...)"
        )
    values, sample = sb3_values(
        learner, entry["values"], f"learners.{twin}.by_budget.{int(budget)}.values"
    )
    draw = ""
    if learner == "dqn":
        draw = (
            "; minibatches drawn with replacement, as both draw them"
            if sample == "with_replacement"
            else f"; the twin drew minibatches {sample.replace('_', ' ')}, SB3 with replacement"
        )
    values["implementation"] = "rejax"
    return {
        "values": values,
        "status": borrowed_status(twin),
        "source": f"{twin} by_budget {int(budget)}: the same algorithm tuned by its JAX twin "
        f"({entry.get('n_trials', '?')} trials x {len(entry.get('seeds', [])) or '?'} seeds x "
        f"{len(entry.get('tasks', [])) or '?'} tuning tasks); the values use SB3's names. "
        f"implementation 'rejax': {IMPLEMENTATION[learner]}, as rejax 0.1.3 does{draw} "
        "(docs/BENCHMARKS.md, 'JAX against SB3')",
        **{k: entry[k] for k in ("trials", "objective", "command", "date") if k in entry},
    }


def borrow(path: Path, learner: str, budget: int, command: str) -> dict[str, Any]:
    """Write the borrowed entry into the hyperparameter file at ``path`` (the rest stays)."""
    data = json.loads(path.read_text())
    entry = {**borrowed_entry(data, learner, budget), "derived_by": command}
    by_budget = data["learners"].setdefault(learner, {}).setdefault("by_budget", {})
    by_budget[str(int(budget))] = entry
    atomic_write_text(path, json.dumps(data, indent=1) + "\n")
    return entry


def main(argv: list[str] | None = None) -> dict[str, Any]:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--learner", choices=sorted(TWIN), required=True)
    p.add_argument("--budget", type=int, required=True, help="env steps")
    p.add_argument(
        "--hyperparams",
        type=Path,
        default=HYPERPARAMS_DIR / "v2.json",
        help="hyperparameter file read and written",
    )
    a = p.parse_args(argv if argv is not None else sys.argv[1:])
    args = ["--learner", a.learner, "--budget", str(a.budget)]
    command = "python -m sixaxis_avoid.benchmark.borrow " + shlex.join(
        [*args, "--hyperparams", display_path(a.hyperparams)]
    )
    entry = borrow(a.hyperparams, a.learner, a.budget, command)
    print(json.dumps(entry, indent=1))
    return entry


if __name__ == "__main__":
    main()
