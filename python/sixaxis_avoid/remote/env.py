"""The Gymnasium env over a server world of one lane (:class:`RemoteEnv`)."""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from sixaxis_avoid._checks import invalid
from sixaxis_avoid.remote._session import (
    _OBSERVATION,
    DEFAULT_CONNECT_TIMEOUT,
    DEFAULT_TIMEOUT,
    _address_of,
    _seed_settings,
    _Session,
    _settings,
    _space_of,
    _World,
)


class RemoteEnv(gym.Env):
    """``SixAxisAvoid-v0`` on an env server: a world of one lane.

    ``address`` is ``"host:port"``, ``"unix:PATH"`` or a ``Server`` of
    :func:`sixaxis_avoid.serve`; ``token`` the server's bearer token (needed when it was
    started with one); ``env_kwargs`` the in-process env's keywords (``scenario``,
    ``obs_type`` — ``"vector"``, ``"index"`` or ``"goal"`` for the goal env's ``Dict``
    observations — ``assist``, ``reward_scale``, ``random_target``, ``arm_aware``) plus
    ``max_episode_steps`` (default: the scenario's ``learning.max_steps_per_episode``, as
    the ``SixAxisAvoid-v0`` registration). They are checked here exactly as the in-process
    env checks them (same errors), then by the server.

    Spaces, rewards, termination, truncation (by the server at ``max_episode_steps``, where
    ``gym.make`` adds a ``TimeLimit``) and ``info["is_success"]`` are those of
    ``gym.make("SixAxisAvoid-v0", ...)``; so is the trajectory for the same
    ``reset(seed=...)`` and actions. ``info`` also holds ``collided``,
    ``distance_to_target``, ``cell`` and ``detour_penalty`` when the server sends them.

    ``timeout`` (seconds) bounds the wait for each answer and ``connect_timeout`` the
    connection: past them a ``TimeoutError`` names the server and the request. A dropped
    server raises ``ConnectionError`` at the next call; a bad value the server refuses
    raises :class:`~sixaxis_avoid.InvalidArgumentError`, any other refusal
    :class:`ServerError`. :meth:`close` leaves and destroys the world; the env is also a
    context manager.

    ``transport`` is ``"rust"`` (the default: the extension's client, the GIL released
    while it waits) or ``"grpc"`` (grpcio; the default when TLS ``credentials``, a
    ``grpc.ChannelCredentials``, are given); docs/SERVER.md "What a step costs".
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": []}

    def __init__(
        self,
        address: Any,
        *,
        token: str | None = None,
        timeout: float = DEFAULT_TIMEOUT,
        connect_timeout: float = DEFAULT_CONNECT_TIMEOUT,
        credentials: Any = None,
        transport: str | None = None,
        **env_kwargs: Any,
    ):
        self.address = _address_of(address)
        kw, settings = _settings(1, env_kwargs, "RemoteEnv")
        self.scenario = kw["scenario"]
        self.obs_type = kw["obs_type"]
        self.reward_scale = kw["reward_scale"]
        self.random_target = kw["random_target"]
        self.arm_aware = kw["arm_aware"]
        self.max_episode_steps = kw["max_episode_steps"]
        self.render_mode = None
        self.action_space = spaces.Discrete(6)
        self.observation_space = _space_of(self.obs_type, self.scenario)
        self._session = _Session(
            self.address,
            settings,
            token=token,
            credentials=credentials,
            transport=transport,
            timeout=timeout,
            connect_timeout=connect_timeout,
        )
        self._world = _World(self._session, slice(0, 1), self.obs_type)
        self._index = self.obs_type == "index"
        self._seeded = False

    def _obs(self, d: dict[str, np.ndarray]):
        obs = d[_OBSERVATION][0]
        if self._index:
            return int(obs)
        obs = obs.astype(np.float32, copy=False)
        if self.obs_type == "goal":
            return {
                "observation": obs,
                "achieved_goal": d["achieved_goal"][0].astype(np.float32, copy=False),
                "desired_goal": d["desired_goal"][0].astype(np.float32, copy=False),
            }
        return obs

    def _info(self, d: dict[str, np.ndarray]) -> dict[str, Any]:
        info: dict[str, Any] = {}
        for name in self._world.extras:
            v = d[name][0]
            info[name] = tuple(v.tolist()) if name == "cell" else v.item()
        info["is_success"] = bool(d["is_success"][0])
        return info

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        if seed is None and not self._seeded:
            # As the in-process env: the lane's generator from np_random's first draw.
            seed = int(self.np_random.integers(0, 2**31))
        self._seeded = True
        s = self._session
        s.send_reset(_seed_settings(seed))
        s.send_step(self._world, None)
        s.receive()
        d = self._world.decode(s.receive())
        return self._obs(d), self._info(d)

    def step(self, action):
        a = np.asarray(action)
        if a.dtype.kind not in "iu" or a.size != 1:
            raise invalid("action", action, "must be an integer in 0..6")
        d = self._world.decode(self._session.step(self._world, a.astype(np.int32)))
        return (
            self._obs(d),
            float(d["reward"][0]),
            bool(d["terminated"][0]),
            bool(d["truncated"][0]),
            self._info(d),
        )

    def close(self) -> None:
        """Leave and destroy the world; every later call raises ``ConnectionError``."""
        if getattr(self, "_session", None) is not None:
            self._session.close()

    def __del__(self):
        # No goodbye at garbage collection (it could wait on a hung server): ending the
        # stream frees the world on the server (docs/SERVER.md "Sessions and worlds").
        s = getattr(self, "_session", None)
        if s is not None:
            try:
                s._shutdown()
            except Exception:
                pass


# The vector env --------------------------------------------------------------------------------
