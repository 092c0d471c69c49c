"""Hyperparameters of the deep learners: the file ``benchmark run`` reads and ``benchmark
tune`` writes, and the search spaces of the tuning.

The file (``hyperparams/<name>.json`` in this package, or a path) holds, per learner, the
values and where they come from: ``"tuned"`` with the command, trial count and objective of
the Optuna study that chose them, or ``"defaults"`` (the learner's built-in values, pending a
tuning run; the report says so).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from sixaxis_avoid.benchmark._io import atomic_write_text

HYPERPARAMS_DIR = Path(__file__).resolve().parent / "hyperparams"

NET_ARCHS = {"64,64": [64, 64], "128,128": [128, 128], "256,256": [256, 256]}
EPISODE_CAPS = [100, 200, 500, 1000]
#: QR-DQN's nets (see :func:`suggest`: its search space is bounded in compute).
QRDQN_NET_ARCHS = ["64,64", "128,128"]


def hyperparams_path(name_or_path: str | Path) -> Path:
    p = Path(name_or_path)
    return p if p.suffix else HYPERPARAMS_DIR / f"{name_or_path}.json"


def display_path(path: str | Path) -> str:
    """How a page names a hyperparameter file: a file of this package by its path in the
    repository (``python/sixaxis_avoid/benchmark/hyperparams/v2.json``, whatever the working
    directory), any other file by its path relative to the working directory."""
    p = Path(path).resolve()
    if p.parent == HYPERPARAMS_DIR:
        source_tree = HYPERPARAMS_DIR.parents[2]
        inside = source_tree if source_tree.name == "python" else HYPERPARAMS_DIR.parents[1]
        return p.relative_to(inside.parent).as_posix()
    return os.path.relpath(p)


def load(name_or_path: str | Path) -> dict[str, Any]:
    """The hyperparameter file (a missing file reads as empty: every learner's defaults)."""
    p = hyperparams_path(name_or_path)
    if not p.exists():
        return {"learners": {}, "path": str(p)}
    try:
        data = json.loads(p.read_text())
    except json.JSONDecodeError as e:
        raise ValueError(f"hyperparameter file {p}: not JSON ({e})") from e
    if not isinstance(data.get("learners"), dict):
        raise ValueError(f"hyperparameter file {p}: field 'learners' must be an object")
    data["path"] = str(p)
    return data


def values_for(data: dict[str, Any], learner: str, defaults: dict[str, Any]) -> dict[str, Any]:
    """The learner's values: its defaults updated by the file's."""
    entry = data.get("learners", {}).get(learner, {})
    return {**defaults, **entry.get("values", {})}


def status_for(data: dict[str, Any], learner: str) -> str:
    """``tuned`` or ``defaults`` (pending a tuning run)."""
    entry = data.get("learners", {}).get(learner)
    return "tuned" if entry and entry.get("status") == "tuned" else "defaults"


def record_tuning(
    path: Path, learner: str, values: dict[str, Any], tuning: dict[str, Any]
) -> dict[str, Any]:
    """Write a learner's tuned values (other learners' entries stay)."""
    data = load(path)
    data.pop("path", None)
    if not data.get("note"):
        data["note"] = (
            "Chosen by `python -m sixaxis_avoid.benchmark tune`; each learner's entry records "
            "the command, trial count, objective and tasks of its study."
        )
    data["learners"][learner] = {"status": "tuned", "values": values, "tuning": tuning}
    statuses = {status_for(data, k) for k in data["learners"]}
    data["status"] = "tuned" if statuses == {"tuned"} else "partly tuned"
    atomic_write_text(path, json.dumps(data, indent=1) + "\n")
    return data


def suggest(trial: Any, learner: str) -> dict[str, Any]:
    """Optuna's draw of a learner's hyperparameters (env knobs included)."""
    c, f, i = trial.suggest_categorical, trial.suggest_float, trial.suggest_int
    # QR-DQN's space is bounded in compute (see its n_quantiles below).
    bounded = learner == "qrdqn"
    common = {
        "learning_rate": f("learning_rate", 1e-4, 3e-3, log=True),
        "gamma": c("gamma", [0.9, 0.95, 0.98, 0.99, 0.995]),
        "net_arch": NET_ARCHS[c("net_arch", QRDQN_NET_ARCHS if bounded else list(NET_ARCHS))],
        "max_episode_steps": c("max_episode_steps", EPISODE_CAPS),
    }
    if learner in ("dqn", "qrdqn"):
        # Gradient steps per env step (the replay ratio) at most 1/2, the defaults' ratio, so
        # no draw costs more than the defaults (the study has to fit the machine).
        gradient_steps = c("gradient_steps", [1, 2, 4])
        replay_ratio = c("replay_ratio", [0.0625, 0.125, 0.25, 0.5])
        hp = {
            **common,
            "batch_size": c("batch_size", [32, 64, 128] if bounded else [32, 64, 128, 256]),
            "buffer_size": c("buffer_size", [10_000, 50_000, 100_000]),
            "learning_starts": c("learning_starts", [0, 500, 1000, 5000]),
            "target_update_interval": c("target_update_interval", [100, 500, 1000, 5000]),
            "train_freq": round(gradient_steps / replay_ratio),
            "gradient_steps": gradient_steps,
            "exploration_fraction": f("exploration_fraction", 0.05, 0.5),
            "exploration_final_eps": f("exploration_final_eps", 0.01, 0.2),
        }
        if learner == "qrdqn":
            # Bounded in compute (nets to 128x128, batches to 128, 10 or 25 quantiles: the
            # rl-baselines3-zoo values for CartPole and MountainCar). A gradient step's
            # quantile loss is batch x N x N: the first study's draw in a wider space (256x256,
            # batch 256, 50 quantiles) cost 5x DQN's CPU time per env step, 4.0 of the x1
            # study's 5.3 core-hours. The costliest draw here takes 40% of that draw's time
            # (10 s against 26 s for 6k env steps of gen-medium-0 on one core).
            hp["n_quantiles"] = c("n_quantiles", [10, 25])
        return hp
    if learner == "ppo":
        return {
            **common,
            "n_envs": c("n_envs", [4, 8, 16]),
            "n_steps": c("n_steps", [64, 128, 256, 512, 1024]),
            "batch_size": c("batch_size", [32, 64, 128, 256]),
            "n_epochs": c("n_epochs", [3, 5, 10, 20]),
            "gae_lambda": c("gae_lambda", [0.8, 0.9, 0.95, 0.98, 1.0]),
            "ent_coef": f("ent_coef", 1e-4, 0.1, log=True),
            "clip_range": c("clip_range", [0.1, 0.2, 0.3]),
        }
    if learner == "a2c":
        return {
            **common,
            "n_envs": c("n_envs", [4, 8, 16]),
            "n_steps": i("n_steps", 5, 64, log=True),
            "gae_lambda": c("gae_lambda", [0.8, 0.9, 0.95, 0.98, 1.0]),
            "ent_coef": f("ent_coef", 1e-4, 0.1, log=True),
        }
    raise ValueError(f"tune: no search space for learner {learner!r} (dqn, qrdqn, ppo, a2c)")


TUNABLE = ("dqn", "qrdqn", "ppo", "a2c")
