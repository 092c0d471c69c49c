"""Gymnasium envs over a SixAxisAvoid env server (dm_env_rpc over gRPC; docs/SERVER.md).

:class:`RemoteEnv` is ``SixAxisAvoid-v0`` played on a server, :class:`RemoteVectorEnv` the
native vector env (``sixaxis_avoid.vector``) with its lanes on one or several servers; both
give the in-process envs' spaces, rewards, episode ends and, for the same seed and actions,
the same trajectories::

    import sixaxis_avoid
    from sixaxis_avoid.remote import RemoteEnv, RemoteVectorEnv

    with sixaxis_avoid.serve() as server:  # or `sixaxis serve` anywhere
        env = RemoteEnv(server.address, reward_scale=1e-4)
        envs = RemoteVectorEnv([server.address], num_envs=256, reward_scale=1e-4)

One server world holds all the lanes an address is given, so one Step request carries them
all; with several addresses the requests are written to every server before any answer is
read, so the servers step concurrently. :func:`start_ray_servers` starts one server per
node of a Ray cluster and returns their addresses. :class:`RemoteSB3VecEnv` is the
Stable-Baselines3 ``VecEnv`` (:class:`sixaxis_avoid.sb3.SixAxisVecEnv`) over a remote
vector env.

The protocol messages, tensors and errors are handled by the ``dm-env-rpc`` package (its
``connection``-level message packing, ``tensor_utils`` and ``error``); this module adds the
stream with timeouts, the Gymnasium semantics and the lane bookkeeping.
"""

from __future__ import annotations

import queue
import secrets
import threading
import time
import weakref
from collections import deque
from collections.abc import Iterable, Sequence
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.error import DependencyNotInstalled
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from sixaxis_avoid import _core
from sixaxis_avoid._checks import invalid
from sixaxis_avoid.env import (
    as_scenario,
    check_keywords,
    check_random_target,
    observation_space_of,
)

try:
    import grpc
    from dm_env_rpc.v1 import (
        dm_env_rpc_pb2,
        dm_env_rpc_pb2_grpc,
        error,
        message_utils,
        tensor_utils,
    )
except ImportError as e:  # pragma: no cover - exercised only without the packages
    raise DependencyNotInstalled(
        "sixaxis_avoid.remote needs dm-env-rpc (and its grpcio), which is not installed: "
        'pip install "sixaxis-avoid[server]"'
    ) from e

__all__ = [
    "RayServers",
    "RemoteEnv",
    "RemoteVectorEnv",
    "ServerError",
    "start_ray_servers",
]

#: Observation names of the protocol (docs/SERVER.md "Uids and specs"); uids come from the specs.
_OBSERVATION = "observation"
_GOALS = ("achieved_goal", "desired_goal")
_STEP_NAMES = ("reward", "terminated", "truncated", "is_success")
#: Per-lane info a server may add; taken when its specs name them (docs/SERVER.md).
_INFO_EXTRAS = ("collided", "distance_to_target", "cell", "detour_penalty")

_INVALID_ARGUMENT = grpc.StatusCode.INVALID_ARGUMENT.value[0]

#: Tensor payloads held as bytes (dm_env_rpc's packers read them with np.frombuffer).
_BYTE_PAYLOADS = ("int8s", "uint8s")

#: Seconds to wait for one answer of the server, and for the connection.
DEFAULT_TIMEOUT = 30.0
DEFAULT_CONNECT_TIMEOUT = 10.0


class ServerError(RuntimeError):
    """The server answered a request with an error Status other than a bad argument (those
    are :class:`~sixaxis_avoid.InvalidArgumentError`, as in process). ``code`` is the
    ``google.rpc`` code, ``message`` the server's words."""

    def __init__(self, address: str, what: str, code: int | None, message: str):
        if code is None:  # an answer that breaks the protocol (docs/SERVER.md)
            text = f"the env server at {address} answered {what} against the protocol: {message}"
        else:
            text = f"the env server at {address} refused {what}: {_code_name(code)}: {message}"
        super().__init__(text)
        self.address, self.code, self.message = address, code, message


def _code_name(code: int) -> str:
    for c in grpc.StatusCode:
        if c.value[0] == code:
            return c.name
    return f"code {code}"


# The watchdog -------------------------------------------------------------------------------
# One daemon thread for every session of the process: it cancels a stream whose answer is
# overdue, which makes the waiting read fail at once (a gRPC stream's reads take no timeout).
_sessions: weakref.WeakSet[_Session] = weakref.WeakSet()
_watchdog_lock = threading.Lock()
_watchdog: threading.Thread | None = None
_WATCH_PERIOD = 0.05


def _watch() -> None:
    while True:
        time.sleep(_WATCH_PERIOD)
        now = time.monotonic()
        for s in list(_sessions):
            d = s._deadline
            if d is not None and now > d:
                s._expire()


def _start_watchdog() -> None:
    global _watchdog
    with _watchdog_lock:
        if _watchdog is None:
            _watchdog = threading.Thread(target=_watch, name="sixaxis-remote-watchdog", daemon=True)
            _watchdog.start()


def _address_of(address: Any) -> str:
    """An address string from a string or an object with ``.address`` (a ``Server``)."""
    a = getattr(address, "address", address)
    if not isinstance(a, str) or not a:
        raise invalid("address", address, 'must be "host:port", "unix:PATH" or a Server')
    return a


class _Session:
    """One gRPC stream to one server, joined to one world it created.

    Requests are written without waiting (:meth:`send`) and answers read in order
    (:meth:`receive`), so several sessions can have a request in flight at once. Any
    failure of the stream (a timeout, a dropped server, a refused token) closes the
    session: every later request raises the same error, nothing is retried silently.
    """

    def __init__(
        self,
        address: str,
        settings: dict[str, Any],
        *,
        token: str | None,
        credentials: Any,
        timeout: float,
        connect_timeout: float,
    ):
        self.address = address
        self.timeout = timeout
        self._deadline: float | None = None
        self._expired = False
        self._down = False
        self._failure: BaseException | None = None
        self._pending: deque[tuple[str, str]] = deque()
        self.world_name: str | None = None
        self.joined = False
        options = [("grpc.max_send_message_length", -1), ("grpc.max_receive_message_length", -1)]
        if credentials is None:
            self._channel = grpc.insecure_channel(address, options=options)
        else:
            self._channel = grpc.secure_channel(address, credentials, options=options)
        try:
            grpc.channel_ready_future(self._channel).result(timeout=connect_timeout)
        except grpc.FutureTimeoutError:
            self._channel.close()
            raise TimeoutError(
                f"no env server answered at {address} within connect_timeout={connect_timeout} s"
            ) from None
        metadata = [("authorization", f"Bearer {token}")] if token is not None else None
        self._requests: queue.SimpleQueue = queue.SimpleQueue()
        stub = dm_env_rpc_pb2_grpc.EnvironmentStub(self._channel)
        self._call = stub.Process(iter(self._requests.get, None), metadata=metadata)
        _sessions.add(self)
        _start_watchdog()
        try:
            packed = {k: tensor_utils.pack_tensor(v) for k, v in settings.items()}
            created = self.call(dm_env_rpc_pb2.CreateWorldRequest(settings=packed), "CreateWorld")
            self.world_name = created.world_name
            joined = self.call(
                dm_env_rpc_pb2.JoinWorldRequest(world_name=self.world_name), "JoinWorld"
            )
            self.joined = True
            self.specs = joined.specs
        except BaseException:
            self.close()
            raise

    # Requests ------------------------------------------------------------------------------
    def send(self, request: Any, what: str) -> None:
        """Write ``request`` (a dm_env_rpc request message) without waiting for its answer."""
        if self._failure is not None:
            raise self._failure
        env_request, field = message_utils.pack_environment_request(request)
        if self._deadline is None:
            self._deadline = time.monotonic() + self.timeout
        self._pending.append((field, what))
        self._requests.put(env_request)

    def receive(self) -> Any:
        """The answer to the oldest request sent and not yet received."""
        if self._failure is not None:
            raise self._failure
        field, what = self._pending.popleft()
        try:
            response = next(self._call)
        except StopIteration:
            raise self._fail(
                ConnectionError(
                    f"the env server at {self.address} ended the session during {what}; "
                    "the world is gone: make a new env"
                )
            ) from None
        except grpc.RpcError as e:
            raise self._fail(self._stream_error(e, what)) from None
        finally:
            if not self._pending:
                self._deadline = None
            elif self._deadline is not None:
                self._deadline = time.monotonic() + self.timeout
        try:
            return message_utils.unpack_environment_response(response, field)
        except error.DmEnvRpcError as e:
            raise self._status_error(e.code, e.message, what) from None

    def call(self, request: Any, what: str) -> Any:
        self.send(request, what)
        return self.receive()

    def _status_error(self, code: int, message: str, what: str) -> Exception:
        if code == _INVALID_ARGUMENT:
            # The server checks with the core's table, in the in-process env's words.
            err = _core.InvalidArgumentError(message)
            return err
        return ServerError(self.address, what, code, message)

    def _stream_error(self, e: grpc.RpcError, what: str) -> Exception:
        code = e.code() if hasattr(e, "code") else None
        details = e.details() if hasattr(e, "details") else str(e)
        if self._expired:
            return TimeoutError(
                f"the env server at {self.address} did not answer {what} within "
                f"timeout={self.timeout} s; the session is closed: make a new env"
            )
        if code in (grpc.StatusCode.UNAUTHENTICATED, grpc.StatusCode.PERMISSION_DENIED):
            return PermissionError(
                f"the env server at {self.address} refused the session ({code.name}: "
                f"{details}); pass the server's token=..."
            )
        name = code.name if code is not None else "error"
        return ConnectionError(
            f"the env server at {self.address} ended the session during {what} "
            f"({name}: {details}); the world is gone: make a new env"
        )

    def _fail(self, err: BaseException) -> BaseException:
        self._failure = err
        self._deadline = None
        self._pending.clear()
        self._shutdown()
        return err

    def _expire(self) -> None:
        self._expired = True
        self._deadline = None
        self._call.cancel()

    # Closing ---------------------------------------------------------------------------------
    @property
    def failed(self) -> bool:
        return self._failure is not None

    def close(self) -> None:
        """LeaveWorld and DestroyWorld (when the stream still works), then close the stream."""
        if self._failure is None and self.world_name is not None:
            try:
                while self._pending:
                    self.receive()
                if self.joined:
                    self.call(dm_env_rpc_pb2.LeaveWorldRequest(), "LeaveWorld")
                    self.joined = False
                self.call(
                    dm_env_rpc_pb2.DestroyWorldRequest(world_name=self.world_name), "DestroyWorld"
                )
            except (ConnectionError, TimeoutError, ServerError, PermissionError):
                pass
            self.world_name = None
        if self._failure is None:
            self._failure = ConnectionError(f"the session with {self.address} is closed")
        self._shutdown()

    def _shutdown(self) -> None:
        if self._down:
            return
        self._down = True
        _sessions.discard(self)
        self._requests.put(None)
        self._call.cancel()
        self._channel.close()


# World settings --------------------------------------------------------------------------------
#: The in-process env keywords a remote env takes (docs/SERVER.md "CreateWorld settings").
_ENV_KEYWORDS = (
    "scenario",
    "obs_type",
    "assist",
    "reward_scale",
    "random_target",
    "arm_aware",
    "max_episode_steps",
    "render_mode",
)


def _settings(
    num_envs: int, env_kwargs: dict[str, Any], owner: str
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The checked env keywords (as the in-process envs check them) and the CreateWorld
    settings of a world of ``num_envs`` lanes (docs/SERVER.md "CreateWorld settings")."""
    unknown = sorted(set(env_kwargs) - set(_ENV_KEYWORDS))
    if unknown:
        raise TypeError(
            f"{owner}.__init__() got an unexpected keyword argument {unknown[0]!r} (the env "
            "keywords: " + ", ".join(_ENV_KEYWORDS) + ")"
        )
    scenario = env_kwargs.get("scenario")
    obs_type = env_kwargs.get("obs_type", "vector")
    render_mode = env_kwargs.get("render_mode")
    if render_mode is not None:
        raise invalid("render_mode", render_mode, "the remote envs do not render (None only)")
    # "goal" is the goal env's observation (SixAxisAvoidGoal-v0); the rest as the core checks.
    kw = check_keywords(
        **({} if obs_type == "goal" else {"obs_type": obs_type}),
        assist=env_kwargs.get("assist"),
        reward_scale=env_kwargs.get("reward_scale", 1.0),
        random_target=env_kwargs.get("random_target", False),
        arm_aware=env_kwargs.get("arm_aware", False),
        max_episode_steps=env_kwargs.get("max_episode_steps"),
    )
    kw["obs_type"] = obs_type
    check_random_target(obs_type, kw["random_target"])
    s = as_scenario(scenario)
    if kw["max_episode_steps"] is None:
        kw["max_episode_steps"] = s.max_steps_per_episode
    kw["scenario"] = s
    settings: dict[str, Any] = {
        "num_envs": np.int64(num_envs),
        "obs_type": kw["obs_type"],
        "reward_scale": np.float64(kw["reward_scale"]),
        "random_target": bool(kw["random_target"]),
        "arm_aware": bool(kw["arm_aware"]),
        "max_episode_steps": np.int64(kw["max_episode_steps"]),
    }
    if isinstance(scenario, str) and scenario in _core.Scenario.builtin_names():
        settings["scenario"] = scenario
    elif scenario is not None:
        # A path or dict is read here; the server gets the scenario itself.
        settings["scenario"] = s.to_json()
    if kw["assist"] is not None:
        settings["assist"] = bool(kw["assist"])
    return kw, settings


def _space_of(obs_type: str, scenario: _core.Scenario) -> spaces.Space:
    num_states = int(np.prod(scenario.shape))
    return observation_space_of(obs_type, num_states)


class _World:
    """A world of ``n`` lanes on one session: its uids, the Step request and the decoding of
    an answer into arrays of ``n`` rows."""

    def __init__(self, session: _Session, lanes: slice, obs_type: str):
        self.session = session
        self.lanes = lanes
        self.n = lanes.stop - lanes.start
        self.obs_type = obs_type
        specs = session.specs
        obs_uids = {spec.name: uid for uid, spec in specs.observations.items()}
        act_uids = {spec.name: uid for uid, spec in specs.actions.items()}
        names = [_OBSERVATION, *(_GOALS if obs_type == "goal" else ()), *_STEP_NAMES]
        missing = [n for n in names if n not in obs_uids]
        if missing or "action" not in act_uids:
            raise ServerError(
                session.address,
                "JoinWorld",
                None,
                "its specs lack " + ", ".join(missing or ["action"]) + " (docs/SERVER.md)",
            )
        self.extras = [n for n in _INFO_EXTRAS if n in obs_uids]
        self.names = names[: 1 + (2 if obs_type == "goal" else 0)]  # the observation part
        self.requested = [obs_uids[n] for n in (*names, *self.extras)]
        self.uid_names = {obs_uids[n]: n for n in (*names, *self.extras)}
        # Per uid: its name, dm_env_rpc's packer of its dtype and the shape with a lane axis
        # (a 1-lane world's tensors have none).
        self._unpack = {}
        for uid, name in self.uid_names.items():
            spec = specs.observations[uid]
            dtype = tensor_utils.data_type_to_np_type(spec.dtype)
            shape = tuple(spec.shape) if self.n > 1 else (1, *spec.shape)
            self._unpack[uid] = (name, tensor_utils.get_packer(dtype), shape)
        self.action_uid = act_uids["action"]
        self.action_dtype = tensor_utils.data_type_to_np_type(specs.actions[self.action_uid].dtype)

    def step_request(self, actions: np.ndarray | None) -> Any:
        req = dm_env_rpc_pb2.StepRequest(requested_observations=self.requested)
        if actions is not None:
            a = actions if self.n > 1 else actions.reshape(())
            req.actions[self.action_uid].CopyFrom(tensor_utils.pack_tensor(a, self.action_dtype))
        return req

    def decode(self, response: Any) -> dict[str, np.ndarray]:
        """Each requested observation as an array with a leading axis of ``n`` lanes."""
        out: dict[str, np.ndarray] = {}
        unpack = self._unpack
        for uid, tensor in response.observations.items():
            entry = unpack.get(uid)
            if entry is None:
                continue
            name, packer, shape = entry
            if packer.name in _BYTE_PAYLOADS:
                flat = packer.unpack(tensor)
            else:
                # np.array reads the repeated field as a buffer, ~300x np.fromiter (which
                # packer.unpack uses) on upb protobuf at N = 4096 (docs/PERFORMANCE.md "Server").
                flat = np.array(getattr(tensor, packer.name).array, packer.np_type)
            try:
                out[name] = flat.reshape(shape)
            except ValueError:
                raise ServerError(
                    self.session.address,
                    "Step",
                    None,
                    f"its {name!r} has {flat.size} {packer.name} values, its spec says "
                    f"shape {list(shape)}",
                ) from None
        if len(out) != len(unpack):
            for name in self.uid_names.values():
                if name in out:
                    continue
                raise ServerError(
                    self.session.address, "Step", None, f"its answer lacks the observation {name!r}"
                )
        return out


def _seed_settings(seed: int | None) -> dict[str, Any]:
    return {} if seed is None else {"seed": tensor_utils.pack_tensor(np.int64(seed))}


# The single env --------------------------------------------------------------------------------
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
        s.send(dm_env_rpc_pb2.ResetRequest(settings=_seed_settings(seed)), "Reset")
        s.send(self._world.step_request(None), "Step")
        s.receive()
        d = self._world.decode(s.receive())
        return self._obs(d), self._info(d)

    def step(self, action):
        a = np.asarray(action)
        if a.dtype.kind not in "iu" or a.size != 1:
            raise invalid("action", action, "must be an integer in 0..6")
        d = self._world.decode(
            self._session.call(self._world.step_request(a.astype(np.int32)), "Step")
        )
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

    ``token``, ``timeout``, ``connect_timeout`` and ``credentials`` as :class:`RemoteEnv`;
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
        seeds = list(seed)
        if len(seeds) != n:
            raise invalid("seed", seed, f"a list of seeds must have one per env ({n})")
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
        mask = None
        if options and "reset_mask" in options:
            mask = np.asarray(options["reset_mask"])
            if mask.dtype != np.bool_ or mask.shape != (self.num_envs,):
                raise invalid(
                    "options['reset_mask']",
                    options["reset_mask"],
                    f"must be a bool array of shape ({self.num_envs},)",
                )
        seeds = self._world_seeds(seed) if mask is None else [None] * len(self._worlds)
        self._seeded = True
        sent = []
        for w, s in zip(self._worlds, seeds):
            if mask is None or mask[w.lanes].all():
                w.session.send(dm_env_rpc_pb2.ResetRequest(settings=_seed_settings(s)), "Reset")
            elif not mask[w.lanes].any():
                continue
            else:
                self._reset_lanes(w, mask[w.lanes])
            w.session.send(w.step_request(None), "Step")
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
        """Reset some lanes of a multi-lane world (a Reset with ``reset_mask``, for a server
        that takes it)."""
        settings = {"reset_mask": tensor_utils.pack_tensor(lanes)}
        try:
            w.session.call(dm_env_rpc_pb2.ResetRequest(settings=settings), "Reset")
        except _core.InvalidArgumentError as e:
            raise invalid(
                "options['reset_mask']",
                lanes.tolist(),
                f"the server at {w.session.address} resets every lane of a world ({e}); "
                "make the env with lanes_per_world=1 to reset single lanes",
            ) from None

    def actions_array(self, actions) -> np.ndarray:
        """``actions`` as the int32 array of shape ``(num_envs,)`` sent to the servers."""
        a = np.asarray(actions)
        if a.dtype.kind not in "iu":
            raise invalid("actions", actions, "must be integers in 0..6")
        if a.shape != (self.num_envs,):
            a = a.reshape(-1) if a.size == self.num_envs else a
            if a.shape != (self.num_envs,):
                raise invalid("actions", actions, f"must have shape ({self.num_envs},)")
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
                w.session.send(dm_env_rpc_pb2.ResetRequest(), "Reset")
                w.session.send(w.step_request(None), "Step")
                restart.append(w)
            else:
                w.session.send(w.step_request(a[w.lanes]), "Step")
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
_sb3_class: type | None = None


def _remote_sb3_vec_env() -> type:
    """:class:`sixaxis_avoid.sb3.SixAxisVecEnv` driving a :class:`RemoteVectorEnv` (made on
    first use: SB3 is an optional extra)."""
    global _sb3_class
    if _sb3_class is not None:
        return _sb3_class
    from sixaxis_avoid import sb3

    class RemoteSB3VecEnv(sb3.SixAxisVecEnv):
        """SB3's ``VecEnv`` over env servers: :class:`sixaxis_avoid.sb3.SixAxisVecEnv`'s
        semantics (reset at once, ``terminal_observation``, ``TimeLimit.truncated``) and code,
        with a :class:`RemoteVectorEnv` in place of the native vector env.

        ``RemoteSB3VecEnv(addresses, n_envs, seed=None, token=None, **env_kwargs)``; the
        keywords are :class:`RemoteVectorEnv`'s; ``lanes_per_world`` defaults to 1 here, as
        SB3 resets each lane when its episode ends and a server resets whole worlds
        (docs/SERVER.md "Episodes"); all the worlds are stepped at once.
        """

        def __init__(
            self, address_or_addresses: Any, n_envs: int, seed: int | None = None, **kwargs: Any
        ):
            self.env_id = "remote"
            # SB3 resets a lane as soon as its episode ends: one world per lane.
            kwargs.setdefault("lanes_per_world", 1)
            self.venv = RemoteVectorEnv(address_or_addresses, n_envs, copy=False, **kwargs)
            v = self.venv
            self.render_mode = None
            self.render_arm = False
            self._render_size = 512
            self._user_attrs = [{} for _ in range(v.num_envs)]
            self._renderers = {}
            self._paths = None
            sb3.VecEnv.__init__(self, v.num_envs, v.single_observation_space, v.single_action_space)
            self.metadata = {"render_modes": [], "render_fps": 8}
            self._index = v.obs_type == "index"
            self._actions = None
            if seed is not None:
                self.seed(seed)

        @staticmethod
        def _infos(info: dict[str, Any], idx: Sequence[int] | None = None) -> list[dict]:
            # The keys the server sends (is_success always), per env, as SixAxisVecEnv's.
            sel = slice(None) if idx is None else list(idx)
            cols = {k: v[sel].tolist() for k, v in info.items() if not k.startswith("_")}
            n = len(cols["is_success"])
            rows = [
                {k: (tuple(v[i]) if k == "cell" else v[i]) for k, v in cols.items()}
                for i in range(n)
            ]
            return rows

    _sb3_class = RemoteSB3VecEnv
    return _sb3_class


def __getattr__(name: str) -> Any:
    if name == "RemoteSB3VecEnv":
        return _remote_sb3_vec_env()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# Ray ------------------------------------------------------------------------------------------
_LOOPBACK = ("127.", "localhost", "::1", "[::1]")
#: Servers started by start_ray_servers and not stopped (their actors live while held).
_ray_servers: list[RayServers] = []


class RayServers(list):
    """The addresses of the servers :func:`start_ray_servers` started (a ``list[str]``),
    with ``token`` (pass it to the remote envs), ``node_ids`` (the Ray node of each
    address), ``actors`` and :meth:`stop`. The servers live until :meth:`stop` (or the end
    of the Ray driver); it is also a context manager."""

    def __init__(
        self, addresses: Iterable[str], token: str | None, node_ids: list[str], actors: list[Any]
    ):
        super().__init__(addresses)
        self.token = token
        self.node_ids = node_ids
        self.actors = actors

    def stop(self) -> None:
        """Stop every server and end its actor."""
        import ray

        actors, self.actors = self.actors, []
        if actors:
            ray.get([a.stop.remote() for a in actors])
            for a in actors:
                ray.kill(a)
        if self in _ray_servers:
            _ray_servers.remove(self)

    def __enter__(self) -> RayServers:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.stop()

    def __eq__(self, other: object) -> bool:
        return self is other

    __hash__ = object.__hash__


class _ServerHolder:
    """The body of the Ray actor: one ``sixaxis_avoid.serve()`` server on its node."""

    def __init__(self, host: str, token: str | None, serve_kwargs: dict[str, Any]):
        self.server = _core.serve(f"{host}:0", token=token, **serve_kwargs)

    def address(self) -> str:
        return self.server.address

    def node_id(self) -> str:
        import ray

        return ray.get_runtime_context().get_node_id()

    def stop(self) -> None:
        self.server.stop()


def start_ray_servers(
    num_per_node: int = 1,
    *,
    token: str | None = None,
    actor_options: dict[str, Any] | None = None,
    **serve_kwargs: Any,
) -> RayServers:
    """Start ``num_per_node`` env servers on every alive node of the connected Ray cluster
    (``ray.init(...)`` first; the package must be installed on every node) and return their
    addresses, reachable from the driver: each server binds its node's IP address on a free
    port.

    Each server is ``sixaxis_avoid.serve(...)`` held by a Ray actor pinned to its node
    (``NodeAffinitySchedulingStrategy``, not soft); ``serve_kwargs`` go to ``serve``,
    ``actor_options`` to the actor (default ``num_cpus=0``: the server's threads are not
    Ray tasks). A server on a non-loopback address needs a token: without ``token`` one is
    generated (``secrets.token_urlsafe``) and returned as ``.token`` of the result::

        servers = start_ray_servers()
        envs = RemoteVectorEnv(servers, num_envs=64, token=servers.token)
        ...
        servers.stop()
    """
    try:
        import ray
        from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy
    except ImportError as e:
        raise DependencyNotInstalled(
            "start_ray_servers needs ray, which is not installed: pip install ray"
        ) from e
    if (
        isinstance(num_per_node, bool)
        or not isinstance(num_per_node, (int, np.integer))
        or (num_per_node < 1)
    ):
        raise invalid("num_per_node", num_per_node, "must be an integer >= 1")
    if not ray.is_initialized():
        raise invalid("ray", None, "start_ray_servers needs ray.init(...) first")
    nodes = [n for n in ray.nodes() if n.get("Alive")]
    if token is None and any(not n["NodeManagerAddress"].startswith(_LOOPBACK) for n in nodes):
        token = secrets.token_urlsafe(32)
    options = {"num_cpus": 0, **(actor_options or {})}
    holder = ray.remote(_ServerHolder)
    actors, node_ids = [], []
    for node in nodes:
        for _ in range(int(num_per_node)):
            actor = holder.options(
                scheduling_strategy=NodeAffinitySchedulingStrategy(node["NodeID"], soft=False),
                **options,
            ).remote(node["NodeManagerAddress"], token, serve_kwargs)
            actors.append(actor)
            node_ids.append(node["NodeID"])
    try:
        addresses = ray.get([a.address.remote() for a in actors])
    except BaseException:
        for a in actors:
            ray.kill(a)
        raise
    servers = RayServers(addresses, token, node_ids, actors)
    _ray_servers.append(servers)
    return servers
