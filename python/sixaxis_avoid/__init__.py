"""SixAxisAvoid: a six-axis arm that learns to reach a target through clutter.

Importing the package registers the Gymnasium ids ``SixAxisAvoid-v0``,
``SixAxisAvoidArm-v0`` (arm-aware) and ``SixAxisAvoidGoal-v0`` (goal-conditioned, for
hindsight experience replay), and the joint-space ``SixAxisAvoidJoint-v0`` and
``SixAxisAvoidJointGoal-v0`` (docs/JOINT.md), each with a native Rust-batched vector env::

    import gymnasium as gym
    import sixaxis_avoid

    env = gym.make("SixAxisAvoid-v0")
    envs = gym.make_vec("SixAxisAvoid-v0", num_envs=1024)
    goal_env = gym.make("SixAxisAvoidGoal-v0", random_target=True)

The core (grid world, Q-learning, kinematics) is Rust, in the extension ``sixaxis_avoid._core``.
Every error of bad input is a :class:`SixAxisError`, itself a ``ValueError``; a caught Rust
panic is :class:`InternalError`, a ``RuntimeError``.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from sixaxis_avoid._core import (
    Arm,
    InternalError,
    InvalidArgumentError,
    PlanResult,
    PosePlanner,
    QTableMismatchError,
    Scenario,
    ScenarioError,
    ScenarioNotFoundError,
    ScenarioParseError,
    Server,
    SixAxisError,
    SixAxisIOError,
    TrainResult,
    __version__,
    cells_reachable,
    clear_pose_at,
    export_scenario,
    generate_scenario,
    greedy_path_of,
    load_q,
    options,
    plan,
    serve,
    shortest_path,
    train,
    unreachable_cells,
)
from sixaxis_avoid._ids import (
    ARM_ENV_ID,
    ENV_ID,
    GOAL_ENV_ID,
    JOINT_ENV_ID,
    JOINT_GOAL_ENV_ID,
)

#: Step cap of the registrations: the default scenario's ``learning.max_steps_per_episode``.
MAX_EPISODE_STEPS = Scenario().max_steps_per_episode


#: Step cap of the joint-space registrations (the core's default ``max_episode_steps``,
#: from its one table of the joint env's keywords).
JOINT_MAX_EPISODE_STEPS: int = next(
    o["default"] for o in options("joint") if o["key"] == "max_episode_steps"
)

#: The registrations: id -> (env class, native vector env class, default keywords, step cap).
_REGISTRATIONS = {
    ENV_ID: ("env:SixAxisAvoidEnv", "vector:SixAxisAvoidVectorEnv", {}, MAX_EPISODE_STEPS),
    ARM_ENV_ID: (
        "env:SixAxisAvoidEnv",
        "vector:SixAxisAvoidVectorEnv",
        {"arm_aware": True},
        MAX_EPISODE_STEPS,
    ),
    GOAL_ENV_ID: (
        "env:SixAxisAvoidGoalEnv",
        "vector:SixAxisAvoidGoalVectorEnv",
        {},
        MAX_EPISODE_STEPS,
    ),
    JOINT_ENV_ID: (
        "joint:SixAxisAvoidJointEnv",
        "joint:SixAxisAvoidJointVectorEnv",
        {},
        JOINT_MAX_EPISODE_STEPS,
    ),
    JOINT_GOAL_ENV_ID: (
        "joint:SixAxisAvoidJointGoalEnv",
        "joint:SixAxisAvoidJointGoalVectorEnv",
        {},
        JOINT_MAX_EPISODE_STEPS,
    ),
}


def _register() -> None:
    for env_id, (env_cls, vec_cls, kwargs, cap) in _REGISTRATIONS.items():
        if env_id in gym.registry:
            continue
        gym.register(
            id=env_id,
            entry_point=f"sixaxis_avoid.{env_cls}",
            vector_entry_point=f"sixaxis_avoid.{vec_cls}",
            max_episode_steps=cap,
            kwargs=kwargs,
        )


_register()


def verify_plan(plan: Any, scenario: Any = None, **kwargs: Any):
    """Replay a plan in MuJoCo (see :func:`sixaxis_avoid.verify.verify_plan`; needs the
    ``mujoco`` extra)."""
    from sixaxis_avoid.verify import verify_plan as _verify

    return _verify(plan, scenario, **kwargs)


def make(env_id: str = ENV_ID, scenario: Any = None, **kwargs: Any) -> gym.Env:
    """``gym.make`` with ``max_episode_steps`` taken from the scenario's
    ``learning.max_steps_per_episode`` (unless given)."""
    s = scenario if isinstance(scenario, Scenario) else Scenario(scenario)
    kwargs.setdefault("max_episode_steps", s.max_steps_per_episode)
    return gym.make(env_id, scenario=s, **kwargs)


__all__ = [
    "ARM_ENV_ID",
    "ENV_ID",
    "GOAL_ENV_ID",
    "JOINT_ENV_ID",
    "JOINT_GOAL_ENV_ID",
    "JOINT_MAX_EPISODE_STEPS",
    "MAX_EPISODE_STEPS",
    "Arm",
    "InternalError",
    "InvalidArgumentError",
    "PlanResult",
    "PosePlanner",
    "QTableMismatchError",
    "Scenario",
    "ScenarioError",
    "ScenarioNotFoundError",
    "ScenarioParseError",
    "Server",
    "SixAxisError",
    "SixAxisIOError",
    "TrainResult",
    "__version__",
    "cells_reachable",
    "clear_pose_at",
    "export_scenario",
    "generate_scenario",
    "greedy_path_of",
    "load_q",
    "make",
    "options",
    "plan",
    "serve",
    "shortest_path",
    "train",
    "unreachable_cells",
    "verify_plan",
]
