"""The JAX twin as a ``gymnax.environments.environment.Environment``, for libraries that
check for gymnax's classes (rejax's ``isinstance(action_space, gymnax...Discrete)``).

Everything is delegated to :class:`~sixaxis_avoid.jax.SixAxisAvoidJax`; only the spaces are
gymnax's own. Needs gymnax (the ``jax-learners`` extra).
"""

from __future__ import annotations

from typing import Any

from sixaxis_avoid._deps import require
from sixaxis_avoid.jax.env import EnvParams, SixAxisAvoidJax

gymnax = require("gymnax", "The gymnax interface of the JAX twin")
_environment = require("gymnax.environments.environment", "The gymnax interface of the JAX twin")
_spaces = require("gymnax.environments.spaces", "The gymnax interface of the JAX twin")


class GymnaxEnv(_environment.Environment):
    """``twin`` with gymnax's base class (its ``step`` and ``reset``, which autoreset as the
    twin's do) and gymnax's ``Discrete(6)`` and ``Box(-1, 1, (13,))`` spaces;
    ``default_params`` is ``params``."""

    def __init__(self, twin: SixAxisAvoidJax, params: EnvParams):
        self.twin = twin
        self._params = params

    @property
    def default_params(self) -> EnvParams:
        return self._params

    def step_env(self, key: Any, state: Any, action: Any, params: EnvParams) -> Any:
        return self.twin.step_env(key, state, action, params)

    def reset_env(self, key: Any, params: EnvParams) -> Any:
        return self.twin.reset_env(key, params)

    def get_obs(self, state: Any, params: Any = None, key: Any = None) -> Any:
        return self.twin.get_obs(state, params if params is not None else self._params)

    @property
    def name(self) -> str:
        return self.twin.name

    @property
    def num_actions(self) -> int:
        return self.twin.num_actions

    def action_space(self, params: Any = None) -> Any:
        return _spaces.Discrete(self.twin.num_actions)

    def observation_space(self, params: Any = None) -> Any:
        import jax.numpy as jnp

        return _spaces.Box(-1.0, 1.0, (13,), jnp.float32)


def as_gymnax(twin: SixAxisAvoidJax, params: EnvParams) -> GymnaxEnv:
    """The twin as a gymnax ``Environment`` whose ``default_params`` are ``params``."""
    return GymnaxEnv(twin, params)
