"""The Gymnasium vector env over server worlds (:class:`RemoteVectorEnv`)."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from sixaxis_avoid import _core
from sixaxis_avoid._checks import invalid
from sixaxis_avoid.env import (
    check_keywords,
)
from sixaxis_avoid.remote._session import (
    _GOALS,
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
from sixaxis_avoid.vector import discrete_actions_of, reset_mask_of, seed_list_of


def _split(num_envs: int, parts: int) -> list[slice]:
    """``num_envs`` lanes in ``parts`` contiguous runs, the first ones a lane longer."""
    base, extra = divmod(num_envs, parts)
    out, start = [], 0
    for k in range(parts):
        n = base + (1 if k < extra else 0)
        out.append(slice(start, start + n))
        start += n
    return out


class RemoteVectorEnv(VectorEnv):
    """The native vector env (``gym.make_vec("SixAxisAvoid-v0", num_envs=N)``) with its lanes
    on one or several env servers.

    ``address_or_addresses`` is one address (as :class:`RemoteEnv`) or a sequence of them;
    the ``num_envs`` lanes are split over the addresses in contiguous runs (the first
    addresses get one lane more when it does not divide), each run one world of the
    server, so one Step request carries all its lanes. :meth:`step` writes the request to
    every server before it reads any answer: the servers step at the same time.
    ``env_kwargs`` are the in-process keywords, checked as the native vector env checks
    them (same errors), then by each server; ``obs_type`` may be ``"goal"`` for the goal
    vector env's batched ``Dict`` observations.

    Gymnasium 1.x next-step autoreset, as the native vector env: the step after a lane's
    episode ends resets that lane, ignores its action and returns reward 0, not terminated,
    not truncated. ``reset(seed=s)`` seeds lane ``i`` with ``s + i`` (a list of seeds must
    be consecutive within each address's run); for the same seed and actions the
    observations, rewards and flags equal the native vector env's to the bit.
    ``reset(options={"reset_mask": mask})`` resets only the lanes where ``mask`` is true.
    ``info`` holds ``is_success`` (and ``collided``, ``distance_to_target``, ``cell``,
    ``detour_penalty`` when the server sends them), each with its ``_key`` mask.

    ``lanes_per_world`` (default: all of an address's lanes) splits each address's run
    into worlds of at most that many lanes (each world its own session, all stepped at
    once); a server resets either every lane of a world or, with ``lanes_per_world=1``,
    exactly the lanes asked for.

    ``token``, ``timeout``, ``connect_timeout``, ``credentials`` and ``transport`` as
    :class:`RemoteEnv`;
    a failure of any server fails the step (no lane is silently dropped). :meth:`close`
    leaves and destroys every world.
    """

    metadata: ClassVar[dict[str, Any]] = {
        "autoreset_mode": AutoresetMode.NEXT_STEP,
        "render_modes": [],
    }

    def __init__(
        self,
        address_or_addresses: Any,
        num_envs: int = 1,
        *,
        token: str | None = None,
        timeout: float = DEFAULT_TIMEOUT,
        connect_timeout: float = DEFAULT_CONNECT_TIMEOUT,
        credentials: Any = None,
        transport: str | None = None,
        copy: bool = True,
        lanes_per_world: int | None = None,
        **env_kwargs: Any,
    ):
        if isinstance(address_or_addresses, (str, bytes)) or hasattr(
            address_or_addresses, "address"
        ):
            addresses = [_address_of(address_or_addresses)]
        else:
            addresses = [_address_of(a) for a in address_or_addresses]
            if not addresses:
                raise invalid("address_or_addresses", address_or_addresses, "names no server")
        num_envs = check_keywords(num_envs=num_envs)["num_envs"]
        if len(addresses) > num_envs:
            raise invalid(
                "address_or_addresses",
                address_or_addresses,
                f"has more servers ({len(addresses)}) than lanes (num_envs={num_envs})",
            )
        self.copy = check_keywords(copy=copy)["copy"]
        if lanes_per_world is not None:
            lanes_per_world = check_keywords(num_envs=lanes_per_world)["num_envs"]
        self.lanes_per_world = lanes_per_world
        kw, _ = _settings(num_envs, env_kwargs, "RemoteVectorEnv")
        self.addresses = addresses
        self.num_envs = num_envs
        self.scenario = kw["scenario"]
        self.obs_type = kw["obs_type"]
        self.reward_scale = kw["reward_scale"]
        self.random_target = kw["random_target"]
        self.arm_aware = kw["arm_aware"]
        self.max_episode_steps = kw["max_episode_steps"]
        self.render_mode = None
        self.single_observation_space = _space_of(self.obs_type, self.scenario)
        self.single_action_space = spaces.Discrete(6)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)

        runs: list[tuple[str, slice]] = []
        for address, run in zip(addresses, _split(num_envs, len(addresses))):
            n = run.stop - run.start
            parts = 1 if lanes_per_world is None else -(-n // lanes_per_world)
            runs += [
                (address, slice(run.start + s.start, run.start + s.stop)) for s in _split(n, parts)
            ]
        self._worlds: list[_World] = []
        try:
            for address, lanes in runs:
                _, settings = _settings(lanes.stop - lanes.start, env_kwargs, "RemoteVectorEnv")
                session = _Session(
                    address,
                    settings,
                    token=token,
                    credentials=credentials,
                    transport=transport,
                    timeout=timeout,
                    connect_timeout=connect_timeout,
                )
                self._worlds.append(_World(session, lanes, self.obs_type))
        except BaseException:
            self.close()
            raise
        self._extras = self._worlds[0].extras
        n = num_envs
        obs_dtype = np.int64 if self.obs_type == "index" else np.float32
        obs_shape = (n,) if self.obs_type == "index" else (n, _core.VECTOR_OBS_DIM)
        self._obs = np.zeros(obs_shape, dtype=obs_dtype)
        self._goals = {g: np.zeros((n, 3), dtype=np.float32) for g in _GOALS}
        self._rewards = np.zeros(n, dtype=np.float64)
        self._terminated = np.zeros(n, dtype=bool)
        self._truncated = np.zeros(n, dtype=bool)
        self._success = np.zeros(n, dtype=bool)
        self._extra_bufs: dict[str, np.ndarray] = {}
        self._mask = np.ones(n, dtype=bool)
        # 1-lane worlds end episodes the dm_env way (docs/SERVER.md "Episodes"): the client
        # does the next-step autoreset for them.
        self._ended = np.zeros(n, dtype=bool)
        self._seeded = False
        self._closed = False

    # Gymnasium API ----------------------------------------------------------------------
    def _world_seeds(self, seed: Any) -> list[int | None]:
        n = self.num_envs
        if seed is None:
            if self._seeded:
                return [None] * len(self._worlds)
            # As the native vector env: random generators on the first reset.
            base = int(np.random.SeedSequence().generate_state(1)[0] >> 1)
            return [base + w.lanes.start for w in self._worlds]
        if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            return [int(seed) + w.lanes.start for w in self._worlds]
        seeds = seed_list_of(seed, n)
        out: list[int | None] = []
        for w in self._worlds:
            run = seeds[w.lanes]
            if all(s is None for s in run):
                out.append(None)
                continue
            first = run[0]
            if any(s is None for s in run) or any(
                int(s) != int(first) + k for k, s in enumerate(run)
            ):
                raise invalid(
                    "seed",
                    seed,
                    "a remote world seeds its lanes s, s+1, ...: the seeds of lanes "
                    f"{w.lanes.start}..{w.lanes.stop - 1} must be consecutive integers",
                )
            out.append(int(first))
        return out

    def reset(self, *, seed: Any = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed if isinstance(seed, (int, np.integer)) else None)
        self._check_open()
        mask = reset_mask_of(options, self.num_envs)
        seeds = self._world_seeds(seed) if mask is None else [None] * len(self._worlds)
        self._seeded = True
        sent = []
        for w, s in zip(self._worlds, seeds):
            if mask is None or mask[w.lanes].all():
                w.session.send_reset(_seed_settings(s))
            elif not mask[w.lanes].any():
                continue
            else:
                self._reset_lanes(w, mask[w.lanes])
            w.session.send_step(w, None)
            sent.append(w)
        for w in sent:
            if mask is None or mask[w.lanes].all():
                w.session.receive()
        decoded = [(w, w.decode(w.session.receive())) for w in sent]
        for w, d in decoded:
            self._store(w, d, mask)
            rows = (
                w.lanes if mask is None else np.arange(w.lanes.start, w.lanes.stop)[mask[w.lanes]]
            )
            self._rewards[rows] = 0.0
            self._terminated[rows] = False
            self._truncated[rows] = False
            self._success[rows] = False
            self._ended[rows] = False
        return self._observations(), self._info()

    @staticmethod
    def _reset_lanes(w: _World, lanes: np.ndarray) -> None:
        """Reset some lanes of a multi-lane world: a Reset with ``reset_mask`` (docs/SERVER.md
        "Episodes"; a server that resets only whole worlds refuses it)."""
        try:
            w.session.send_reset({"reset_mask": lanes})
            w.session.receive()
        except _core.InvalidArgumentError as e:
            raise invalid(
                "options['reset_mask']",
                lanes.tolist(),
                f"the server at {w.session.address} resets every lane of a world ({e}); "
                "make the env with lanes_per_world=1 to reset single lanes",
            ) from None

    def actions_array(self, actions) -> np.ndarray:
        """``actions`` as the int32 array of shape ``(num_envs,)`` sent to the servers."""
        a = discrete_actions_of(actions, self.num_envs)
        # Checked here too, so a bad action fails before any server is written to.
        if a.size and (a.min() < 0 or a.max() > 5):
            raise invalid("actions", actions, "must be integers in 0..6")
        return a.astype(np.int32, copy=False)

    def step(self, actions):
        self._check_open()
        a = self.actions_array(actions)
        restart = []
        for w in self._worlds:
            if w.n == 1 and self._ended[w.lanes.start]:
                # The dm_env world ended its episode: the autoreset step starts the next one.
                w.session.send_reset({})
                w.session.send_step(w, None)
                restart.append(w)
            else:
                w.session.send_step(w, a[w.lanes])
        for w in restart:
            w.session.receive()
        for w in self._worlds:
            d = w.decode(w.session.receive())
            self._store(w, d, None)
            lanes = w.lanes
            if w in restart:
                self._rewards[lanes] = 0.0
                self._terminated[lanes] = False
                self._truncated[lanes] = False
                self._success[lanes] = False
                self._ended[lanes] = False
            else:
                self._rewards[lanes] = d["reward"]
                self._terminated[lanes] = d["terminated"]
                self._truncated[lanes] = d["truncated"]
                self._success[lanes] = d["is_success"]
                if w.n == 1:
                    self._ended[lanes] = d["terminated"] | d["truncated"]
        return (
            self._observations(),
            self._result(self._rewards),
            self._result(self._terminated),
            self._result(self._truncated),
            self._info(),
        )

    def _store(self, w: _World, d: dict[str, np.ndarray], mask: np.ndarray | None) -> None:
        """Write a world's observations (all its lanes, or those of ``mask``) into the
        buffers."""
        rows: Any = w.lanes
        sel: Any = slice(None)
        if mask is not None and not mask[w.lanes].all():
            sel = mask[w.lanes]
            rows = np.arange(w.lanes.start, w.lanes.stop)[sel]
        self._obs[rows] = d[_OBSERVATION][sel]
        if self.obs_type == "goal":
            for g in _GOALS:
                self._goals[g][rows] = d[g][sel]
        for name in self._extras:
            buf = self._extra_bufs.get(name)
            if buf is None:
                v = d[name]
                buf = np.zeros((self.num_envs, *v.shape[1:]), dtype=v.dtype)
                self._extra_bufs[name] = buf
            buf[rows] = d[name][sel]

    def _result(self, arr: np.ndarray) -> np.ndarray:
        return arr.copy() if self.copy else arr

    def _observations(self):
        obs = self._result(self._obs)
        if self.obs_type == "goal":
            return {
                "observation": obs,
                **{g: self._result(self._goals[g]) for g in _GOALS},
            }
        return obs

    def _info(self) -> dict[str, Any]:
        m = self._mask
        info: dict[str, Any] = {}
        for name, buf in self._extra_bufs.items():
            info[name] = self._result(buf)
            info["_" + name] = m
        info["is_success"] = self._success.copy()
        info["_is_success"] = m
        return info

    def __enter__(self) -> RemoteVectorEnv:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def _check_open(self) -> None:
        if self._closed:
            raise invalid("env", self, "is closed")

    def render(self):
        return None

    def close_extras(self, **kwargs: Any) -> None:
        for w in getattr(self, "_worlds", []):
            w.session.close()
        self._closed = True

    @property
    def cells(self) -> np.ndarray:
        """Each lane's terminal cell, ``(N, 3)`` int32 (when the server sends ``cell``)."""
        if "cell" not in self._extra_bufs:
            raise AttributeError("cells: the server sends no per-lane `cell` observation")
        return self._extra_bufs["cell"].copy()

    @property
    def num_states(self) -> int:
        return int(np.prod(self.scenario.shape))


# Stable-Baselines3 -------------------------------------------------------------------------------
