"""The JAX learners' hyperparameter values, without JAX: the defaults (SB3's names), which
knobs are traced (vmapped over candidates in one compiled call) and which fix shapes (one
compiled group each), the checks, and how a values dict maps onto rejax's fields.

Entry points: :func:`check_values` (a values dict over the algorithm's defaults, checked;
:class:`JaxLearnerError` names the field and value), :func:`static_key` (the compiled group),
:func:`rejax_config` / :func:`traced_fields` (rejax's static keywords / traced fields) and
:func:`updates_per_env_step`. The learners themselves are in
:mod:`sixaxis_avoid.benchmark.jax_learners`, which re-exports these names; what maps exactly
onto rejax and what differs is in the "JAX learners" section of docs/PERFORMANCE.md.
"""

from __future__ import annotations

import json
from typing import Any

ALGOS = ("ppo", "dqn")

#: The benchmark learner of each algorithm on the JAX twin; the SB3 learner of the same
#: algorithm is named by the algorithm (``ppo``, ``dqn``). Declared once here: the tuner,
#: the borrowed SB3 entries and the report's JAX-against-SB3 section all read it.
JAX_LEARNER = {"ppo": "jax_ppo", "dqn": "jax_dqn"}

#: Env settings every JAX learner shares with the SB3 learners (``learners.ENV_DEFAULTS``).
ENV_DEFAULTS: dict[str, Any] = {"reward_scale": 1e-4, "assist": True}

#: PPO's values: suite v1's tuned SB3 PPO values (hyperparams/v1.json), SB3's tanh and
#: vf_coef 0.5 and max_grad_norm 0.5, a constant learning rate.
PPO_DEFAULTS: dict[str, Any] = {
    **ENV_DEFAULTS,
    "max_episode_steps": 1000,
    "learning_rate": 0.0025083101485988907,
    "lr_schedule": "constant",
    "gamma": 0.9,
    "net_arch": [128, 128],
    "activation": "tanh",
    "n_envs": 8,
    "n_steps": 64,
    "batch_size": 128,
    "n_epochs": 5,
    "gae_lambda": 0.9,
    "clip_range": 0.1,
    "ent_coef": 0.00011201827711749114,
    "vf_coef": 0.5,
    "max_grad_norm": 0.5,
}

#: DQN's values: suite v1's tuned SB3 DQN values (hyperparams/v1.json), SB3's ReLU, initial
#: exploration 1.0 and max_grad_norm 10, a constant learning rate. SB3 steps one env
#: ``train_freq`` times between update phases; rejax steps ``train_freq`` envs once (its
#: ``num_envs``), so the env steps between update phases and the updates per env step match.
DQN_DEFAULTS: dict[str, Any] = {
    **ENV_DEFAULTS,
    "max_episode_steps": 100,
    "learning_rate": 0.001235896055013618,
    "lr_schedule": "constant",
    "gamma": 0.99,
    "net_arch": [128, 128],
    "activation": "relu",
    "batch_size": 128,
    "buffer_size": 10_000,
    "learning_starts": 1000,
    "target_update_interval": 500,
    "train_freq": 8,
    "gradient_steps": 4,
    "exploration_fraction": 0.47873705518264326,
    "exploration_initial_eps": 1.0,
    "exploration_final_eps": 0.09495382193734919,
    "max_grad_norm": 10.0,
    # rejax's draw (without replacement); "with_replacement" is SB3's draw, O(batch_size)
    # where rejax's costs O(buffer_size) per minibatch (docs/PERFORMANCE.md, JAX learners).
    "replay_sample": "without_replacement",
}
REPLAY_SAMPLES = ("without_replacement", "with_replacement")

DEFAULTS = {"ppo": PPO_DEFAULTS, "dqn": DQN_DEFAULTS}

#: Values that are traced (vmapped over candidates in one compiled call).
TRACED: dict[str, tuple[str, ...]] = {
    "ppo": (
        "learning_rate", "lr_schedule", "gamma", "gae_lambda", "clip_range", "ent_coef",
        "vf_coef", "max_grad_norm", "max_episode_steps",
    ),
    "dqn": (
        "learning_rate", "lr_schedule", "gamma", "max_grad_norm", "exploration_fraction",
        "exploration_initial_eps", "exploration_final_eps", "learning_starts",
        "target_update_interval", "max_episode_steps",
    ),
}  # fmt: skip
#: Values that fix shapes, loop lengths or the env's tables: one compiled group each.
STATIC: dict[str, tuple[str, ...]] = {
    "ppo": (
        "reward_scale", "assist", "net_arch", "activation", "n_envs", "n_steps", "batch_size",
        "n_epochs",
    ),
    "dqn": (
        "reward_scale", "assist", "net_arch", "activation", "batch_size", "buffer_size",
        "train_freq", "gradient_steps", "replay_sample",
    ),
}  # fmt: skip
LR_SCHEDULES = {"constant": 0.0, "linear": 1.0}
ACTIVATIONS = ("tanh", "relu")


class JaxLearnerError(ValueError):
    """A hyperparameter value the JAX learners cannot use (names the field and value)."""


def check_values(algo: str, values: dict[str, Any]) -> dict[str, Any]:
    """``values`` over the algorithm's defaults, checked: unknown names and bad values raise
    :class:`JaxLearnerError` naming the field and the value."""
    if algo not in DEFAULTS:
        raise JaxLearnerError(f"algo: {algo!r} is not a JAX learner ({', '.join(ALGOS)})")
    out = {**DEFAULTS[algo], **values}
    unknown = sorted(set(out) - set(DEFAULTS[algo]))
    if unknown:
        raise JaxLearnerError(
            f"{algo}: unknown hyperparameter {unknown[0]!r} = {out[unknown[0]]!r} "
            f"(known: {', '.join(sorted(DEFAULTS[algo]))})"
        )
    if out["lr_schedule"] not in LR_SCHEDULES:
        raise JaxLearnerError(
            f"lr_schedule: {out['lr_schedule']!r} is not a schedule (use 'constant' or 'linear')"
        )
    if out["activation"] not in ACTIVATIONS:
        raise JaxLearnerError(f"activation: {out['activation']!r} is not one of {ACTIVATIONS}")
    net = out["net_arch"]
    if not (isinstance(net, (list, tuple)) and net and all(int(h) > 0 for h in net)):
        raise JaxLearnerError(f"net_arch: {net!r} is not a list of positive layer sizes")
    out["net_arch"] = [int(h) for h in net]
    positive = ["learning_rate", "max_grad_norm", "max_episode_steps", "batch_size"]
    positive += (
        ["n_envs", "n_steps", "n_epochs", "clip_range"]
        if algo == "ppo"
        else ["buffer_size", "train_freq", "gradient_steps", "target_update_interval"]
    )
    for k in positive:
        if not float(out[k]) > 0:
            raise JaxLearnerError(f"{k}: {out[k]!r} must be positive")
    for k in ["gamma"] + (["gae_lambda"] if algo == "ppo" else []):
        if not 0.0 <= float(out[k]) <= 1.0:
            raise JaxLearnerError(f"{k}: {out[k]!r} must be in [0, 1]")
    if algo == "ppo":
        rollout = int(out["n_envs"]) * int(out["n_steps"])
        if rollout % int(out["batch_size"]):
            raise JaxLearnerError(
                f"batch_size: {out['batch_size']!r} does not divide n_envs x n_steps = {rollout}"
            )
    else:
        for k in ("exploration_fraction", "exploration_initial_eps", "exploration_final_eps"):
            if not 0.0 <= float(out[k]) <= 1.0:
                raise JaxLearnerError(f"{k}: {out[k]!r} must be in [0, 1]")
        if out["replay_sample"] not in REPLAY_SAMPLES:
            raise JaxLearnerError(
                f"replay_sample: {out['replay_sample']!r} is not one of {REPLAY_SAMPLES}"
            )
        if int(out["learning_starts"]) < 0:
            raise JaxLearnerError(f"learning_starts: {out['learning_starts']!r} is negative")
    return out


def static_key(algo: str, values: dict[str, Any]) -> str:
    """The compiled group a candidate belongs to (its :data:`STATIC` values)."""
    return json.dumps({k: values[k] for k in STATIC[algo]}, sort_keys=True)


def iteration_steps(algo: str, values: dict[str, Any]) -> int:
    """Env steps of one training iteration (the checkpoint grain)."""
    if algo == "ppo":
        return int(values["n_envs"]) * int(values["n_steps"])
    return int(values["train_freq"])


def rejax_config(algo: str, values: dict[str, Any]) -> dict[str, Any]:
    """rejax's static keywords for ``values`` (the traced ones are set per candidate by
    :func:`traced_fields`)."""
    cfg: dict[str, Any] = {
        "agent_kwargs": {
            "hidden_layer_sizes": tuple(values["net_arch"]),
            "activation": values["activation"],
        },
        "skip_initial_evaluation": True,
    }
    if algo == "ppo":
        n = int(values["n_envs"]) * int(values["n_steps"])
        cfg.update(
            num_envs=int(values["n_envs"]),
            num_steps=int(values["n_steps"]),
            num_minibatches=n // int(values["batch_size"]),
            num_epochs=int(values["n_epochs"]),
        )
    else:
        cfg.update(
            num_envs=int(values["train_freq"]),
            num_epochs=int(values["gradient_steps"]),
            batch_size=int(values["batch_size"]),
            buffer_size=int(values["buffer_size"]),
            ddqn=False,  # SB3's DQN: the target net's max, not double DQN
            polyak=0.0,  # SB3's hard target update (rejax: polyak 0 copies the online net)
            replay_with_replacement=values["replay_sample"] == "with_replacement",
        )
    return cfg


def traced_fields(algo: str, values: dict[str, Any]) -> dict[str, float]:
    """The traced values of one candidate, as floats named by the rejax fields they set."""
    out = {
        "learning_rate": float(values["learning_rate"]),
        "lr_decay": LR_SCHEDULES[values["lr_schedule"]],
        "gamma": float(values["gamma"]),
        "max_grad_norm": float(values["max_grad_norm"]),
        "max_episode_steps": float(values["max_episode_steps"]),
    }
    if algo == "ppo":
        out.update(
            gae_lambda=float(values["gae_lambda"]),
            clip_eps=float(values["clip_range"]),
            ent_coef=float(values["ent_coef"]),
            vf_coef=float(values["vf_coef"]),
        )
    else:
        out.update(
            exploration_fraction=float(values["exploration_fraction"]),
            eps_start=float(values["exploration_initial_eps"]),
            eps_end=float(values["exploration_final_eps"]),
            fill_buffer=float(values["learning_starts"]),
            target_update_freq=float(values["target_update_interval"]),
        )
    return out


def updates_per_env_step(algo: str, values: dict[str, Any]) -> float:
    """Gradient steps per env step (the same for rejax and SB3 at the same values)."""
    if algo == "ppo":
        n = int(values["n_envs"]) * int(values["n_steps"])
        return int(values["n_epochs"]) * (n // int(values["batch_size"])) / n
    return int(values["gradient_steps"]) / int(values["train_freq"])
