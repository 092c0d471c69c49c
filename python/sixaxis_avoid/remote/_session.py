"""The stream to an env server (dm_env_rpc over gRPC; docs/SERVER.md): the session with
its timeouts, world settings, and the protocol's names. Shared by the remote envs of this
package.

Two transports (docs/SERVER.md "What a step costs"): ``"rust"`` (the default), the
extension's :class:`sixaxis_avoid._core.DmEnvClient` (tonic, the GIL released while it
waits), and ``"grpc"``, grpcio with dm-env-rpc's message packing (used for TLS
``credentials``, which the Rust client does not take)."""

from __future__ import annotations

import queue
import socket
import threading
import time
import weakref
from collections import deque
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.error import DependencyNotInstalled

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


#: Observation names of the protocol (docs/SERVER.md "Uids and specs"); uids come from the specs.
_OBSERVATION = "observation"
_GOALS = ("achieved_goal", "desired_goal")
_STEP_NAMES = ("reward", "terminated", "truncated", "is_success")
#: Per-lane info a server may add; taken when its specs name them (docs/SERVER.md).
_INFO_EXTRAS = ("collided", "distance_to_target", "cell", "detour_penalty")

_INVALID_ARGUMENT = grpc.StatusCode.INVALID_ARGUMENT.value[0]

#: Tensor payloads held as bytes (dm_env_rpc's packers read them with np.frombuffer).
_BYTE_PAYLOADS = ("int8s", "uint8s")

#: The transports (docs/SERVER.md "What a step costs").
TRANSPORTS = ("rust", "grpc")

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
_sessions: weakref.WeakSet[_GrpcSession] = weakref.WeakSet()
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


def _transport_of(transport: Any, credentials: Any) -> str:
    """The checked transport: ``None`` is ``"rust"``, or ``"grpc"`` with TLS credentials."""
    if transport is None:
        return "grpc" if credentials is not None or not hasattr(_core, "DmEnvClient") else "rust"
    if transport not in TRANSPORTS:
        raise invalid("transport", transport, 'must be "rust", "grpc" or None (the default)')
    if transport == "rust" and credentials is not None:
        raise invalid(
            "transport",
            transport,
            'the Rust client speaks plain TCP and Unix sockets: TLS credentials need "grpc"',
        )
    return transport


def _last_attempt(channel: Any) -> str:
    """gRPC's account of why a channel never became ready (nothing listening, a TLS
    handshake refused, a socket closed by a server that wants TLS), "" when it gives none:
    a call that does not wait for the channel fails at once with it."""
    probe = channel.unary_unary(
        "/grpc.health.v1.Health/Check",
        request_serializer=lambda b: b,
        response_deserializer=lambda b: b,
    )
    try:
        probe(b"", timeout=0.5)
    except grpc.RpcError as e:
        return e.details() if hasattr(e, "details") else ""
    return ""


def _answers_in_tls(address: str) -> bool:
    """Whether the server at ``address`` (``host:port``, ``unix:PATH``) answers the HTTP/2
    client preface with a TLS record (a server started with ``--tls-cert``/``--tls-key``
    sends an alert: content type 21, version 3.x); False if nothing answers within half a
    second. As the Rust client's probe (rust/python/src/client/transport.rs)."""
    try:
        if address.startswith("unix:"):
            path = address[len("unix:") :]
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            sock.settimeout(0.5)
            sock.connect(path[2:] if path.startswith("//") else path)
        else:
            host, _, port = address.rpartition(":")
            sock = socket.create_connection((host.strip("[]"), int(port)), timeout=0.5)
        with sock:
            sock.sendall(b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n")
            head = sock.recv(2)
    except (OSError, ValueError):
        return False
    # TLS record types 20-23, then the major version 3; an HTTP/2 server's SETTINGS begins 0.
    return len(head) == 2 and 20 <= head[0] <= 23 and head[1] == 3


class _Spec:
    """One tensor spec of a world: ``name``, ``dtype`` (the protocol's DataType number) and
    ``shape``, whichever transport read it."""

    __slots__ = ("dtype", "name", "shape")

    def __init__(self, name: str, dtype: int, shape: Any):
        self.name, self.dtype, self.shape = name, int(dtype), tuple(int(d) for d in shape)


class _Specs:
    """A world's specs: ``actions`` and ``observations``, uid -> :class:`_Spec`."""

    def __init__(self, actions: dict[int, _Spec], observations: dict[int, _Spec]):
        self.actions, self.observations = actions, observations

    @classmethod
    def of_proto(cls, specs: Any) -> _Specs:
        def part(m):
            return {int(uid): _Spec(s.name, s.dtype, s.shape) for uid, s in m.items()}

        return cls(part(specs.actions), part(specs.observations))

    @classmethod
    def of_rust(cls, specs: dict[str, dict[int, tuple]]) -> _Specs:
        def part(m):
            return {int(uid): _Spec(*t) for uid, t in m.items()}

        return cls(part(specs["actions"]), part(specs["observations"]))


def _Session(
    address: str,
    settings: dict[str, Any],
    *,
    token: str | None,
    credentials: Any,
    timeout: float,
    connect_timeout: float,
    transport: str | None = None,
) -> _GrpcSession | _RustSession:
    """One stream to one server, joined to one world it created with ``settings``, over
    ``transport`` (:data:`TRANSPORTS`; None: ``"rust"``, or ``"grpc"`` with TLS
    ``credentials``)."""
    kind = _transport_of(transport, credentials)
    cls = _RustSession if kind == "rust" else _GrpcSession
    return cls(
        address,
        settings,
        token=token,
        credentials=credentials,
        timeout=timeout,
        connect_timeout=connect_timeout,
    )


class _BaseSession:
    """What both transports' sessions hold: the server's ``address``, the answer
    ``timeout``, the world (``world_name``, ``joined``) and the answers awaited in order
    (``_pending``); the round trip :meth:`call`, and :meth:`close` (LeaveWorld and
    DestroyWorld while the stream works, then the transport's :meth:`_shutdown`).

    A subclass gives ``send``, ``receive``, ``failed``, ``_leave_world``,
    ``_destroy_world`` and ``_shutdown``."""

    transport: str

    def __init__(self, address: str, timeout: float):
        self.address = address
        self.timeout = timeout
        self.world_name: str | None = None
        self.joined = False
        self._pending: deque[Any] = deque()

    def call(self, request: Any, what: str) -> Any:
        self.send(request, what)
        return self.receive()

    def close(self) -> None:
        """LeaveWorld and DestroyWorld (when the stream still works), then close the stream."""
        if not self.failed and self.world_name is not None:
            try:
                while self._pending:
                    self.receive()
                if self.joined:
                    self._leave_world()
                    self.joined = False
                self._destroy_world(self.world_name)
            except (ConnectionError, TimeoutError, ServerError, PermissionError):
                pass
            self.world_name = None
        self._shutdown()


class _GrpcSession(_BaseSession):
    """One gRPC stream (grpcio) to one server, joined to one world it created.

    Requests are written without waiting (:meth:`send`) and answers read in order
    (:meth:`receive`), so several sessions can have a request in flight at once. Any
    failure of the stream (a timeout, a dropped server, a refused token) closes the
    session: every later request raises the same error, nothing is retried silently.
    """

    transport = "grpc"

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
        super().__init__(address, timeout)
        self._deadline: float | None = None
        self._expired = False
        self._down = False
        self._failure: BaseException | None = None
        options = [("grpc.max_send_message_length", -1), ("grpc.max_receive_message_length", -1)]
        if address.startswith("unix:"):
            # The socket path is no valid :authority for the server (docs/SERVER.md).
            options.append(("grpc.default_authority", "localhost"))
        if credentials is None:
            self._channel = grpc.insecure_channel(address, options=options)
        else:
            self._channel = grpc.secure_channel(address, credentials, options=options)
        try:
            grpc.channel_ready_future(self._channel).result(timeout=connect_timeout)
        except grpc.FutureTimeoutError:
            why = _last_attempt(self._channel)
            self._channel.close()
            tls = credentials is None and _answers_in_tls(address)
            raise TimeoutError(
                f"no env server answered at {address} within connect_timeout={connect_timeout} s"
                + (f" (the last attempt: {why})" if why else "")
                + (
                    ": it answers in TLS (a server started with --tls-cert/--tls-key), and "
                    "this channel is plaintext; pass "
                    "credentials=grpc.ssl_channel_credentials(root_certificates=...) "
                    '(docs/SERVER.md "Security")'
                    if tls
                    else ""
                )
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
            self.specs = _Specs.of_proto(joined.specs)
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
        """The answer to the oldest request sent and not yet received (a Step's: the
        observations as :meth:`observations` gives them)."""
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

    def send_reset(self, settings: dict[str, Any]) -> None:
        """Write a Reset with ``settings`` (``seed``, ``reset_mask``: Python values)."""
        packed = {k: tensor_utils.pack_tensor(v) for k, v in settings.items()}
        self.send(dm_env_rpc_pb2.ResetRequest(settings=packed), "Reset")

    def send_step(self, world: _World, actions: np.ndarray | None) -> None:
        """Write a Step of ``world`` (``actions`` int32, shaped as the action spec)."""
        self.send(world.step_request(actions), "Step")

    def step(self, world: _World, actions: np.ndarray | None) -> Any:
        """A Step's round trip; its answer as :meth:`receive` gives it."""
        return self.call(world.step_request(actions), "Step")

    @staticmethod
    def observations(answer: Any) -> dict[int, np.ndarray]:
        """A Step answer's observations, uid -> flat array."""
        out = {}
        for uid, tensor in answer.observations.items():
            field = tensor.WhichOneof("payload")
            if field in _BYTE_PAYLOADS:
                out[uid] = np.frombuffer(
                    getattr(tensor, field).array, np.int8 if field == "int8s" else np.uint8
                )
            elif field is None:
                out[uid] = np.zeros(0, np.float32)
            else:
                # np.array reads the repeated field as a buffer, ~300x np.fromiter (which
                # dm_env_rpc's packers use) on upb protobuf at N = 4096 (docs/PERFORMANCE.md
                # "Server").
                out[uid] = np.array(getattr(tensor, field).array, _PAYLOAD_DTYPES[field])
        return out

    def _status_error(self, code: int, message: str, what: str) -> Exception:
        return _status_error(self.address, code, message, what)

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

    def _leave_world(self) -> None:
        self.call(dm_env_rpc_pb2.LeaveWorldRequest(), "LeaveWorld")

    def _destroy_world(self, name: str) -> None:
        self.call(dm_env_rpc_pb2.DestroyWorldRequest(world_name=name), "DestroyWorld")

    def _shutdown(self) -> None:
        if self._failure is None:
            self._failure = ConnectionError(f"the session with {self.address} is closed")
        if self._down:
            return
        self._down = True
        _sessions.discard(self)
        self._requests.put(None)
        self._call.cancel()
        self._channel.close()


def _status_error(address: str, code: int, message: str, what: str) -> Exception:
    """The exception of an error Status the server answered ``what`` with."""
    if code == _INVALID_ARGUMENT:
        # The server checks with the core's table, in the in-process env's words.
        return _core.InvalidArgumentError(message)
    return ServerError(address, what, code, message)


#: numpy dtypes of the Tensor payload fields read as repeated numbers.
_PAYLOAD_DTYPES = {
    "floats": np.float32,
    "doubles": np.float64,
    "int32s": np.int32,
    "int64s": np.int64,
    "uint32s": np.uint32,
    "uint64s": np.uint64,
    "bools": np.bool_,
    "strings": object,
}


class _RustSession(_BaseSession):
    """One stream to one server over the extension's Rust client
    (:class:`sixaxis_avoid._core.DmEnvClient`), joined to one world it created.

    The same interface as :class:`_GrpcSession`: requests written without waiting, answers
    read in order; a Step answer is ``(state, {uid: flat array})`` decoded in Rust. The
    client's own timeouts bound every wait; a failure of the stream closes the session and
    every later request raises the same error. :meth:`send` / :meth:`call` take
    dm_env_rpc request messages too (sent encoded), for tools that speak protobuf.
    """

    transport = "rust"

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
        # _pending: the protobuf field and name of each answer awaited (None: decoded by
        # the client).
        super().__init__(address, timeout)
        self._closed = False
        self._client = _core.DmEnvClient(
            address, token=token, timeout=timeout, connect_timeout=connect_timeout
        )
        try:
            self._client.send_create_world(settings)
            self.world_name = self._client.receive()
            self._client.send_join_world(self.world_name)
            self.specs = _Specs.of_rust(self._client.receive())
            self.joined = True
        except BaseException:
            self.close()
            raise

    # Requests ------------------------------------------------------------------------------
    def send(self, request: Any, what: str) -> None:
        """Write ``request`` (a dm_env_rpc request message) without waiting for its answer."""
        env_request, field = message_utils.pack_environment_request(request)
        self._client.send_raw(env_request.SerializeToString(), what)
        self._pending.append((field, what))

    def receive(self) -> Any:
        """The answer to the oldest request sent and not yet received."""
        raw = self._pending.popleft() if self._pending else None
        answer = self._client.receive()
        if raw is None:
            return answer
        field, what = raw
        response = dm_env_rpc_pb2.EnvironmentResponse.FromString(answer)
        try:
            return message_utils.unpack_environment_response(response, field)
        except error.DmEnvRpcError as e:
            raise _status_error(self.address, e.code, e.message, what) from None

    def send_reset(self, settings: dict[str, Any]) -> None:
        """Write a Reset with ``settings`` (``seed``, ``reset_mask``: Python values)."""
        self._client.send_reset(settings)
        self._pending.append(None)

    def send_step(self, world: _World, actions: np.ndarray | None) -> None:
        """Write a Step of ``world`` (``actions`` int32, shaped as the action spec)."""
        a = None if actions is None else world.actions(actions)
        self._client.send_step(a, world.requested, world.action_uid)
        self._pending.append(None)

    def step(self, world: _World, actions: np.ndarray | None) -> Any:
        """A Step's round trip (one release of the GIL)."""
        if self._pending:
            self.send_step(world, actions)
            return self.receive()
        a = None if actions is None else world.actions(actions)
        return self._client.step(a, world.requested, world.action_uid)

    @staticmethod
    def observations(answer: Any) -> dict[int, np.ndarray]:
        """A Step answer's observations, uid -> flat array."""
        if isinstance(answer, tuple):
            return answer[1]
        return _GrpcSession.observations(answer)  # an answer to a protobuf request

    # Closing ---------------------------------------------------------------------------------
    @property
    def failed(self) -> bool:
        return self._client.failed

    def close(self) -> None:
        if getattr(self, "_client", None) is not None:
            super().close()

    def _leave_world(self) -> None:
        self._client.send_leave_world()
        self._client.receive()

    def _destroy_world(self, name: str) -> None:
        self._client.send_destroy_world(name)
        self._client.receive()

    def _shutdown(self) -> None:
        if not self._closed:
            self._closed = True
            self._pending.clear()
            self._client.close()


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

    def __init__(self, session: _BaseSession, lanes: slice, obs_type: str):
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
        # Per uid: its name and the shape with a lane axis (a 1-lane world's tensors have
        # none).
        self._unpack = {}
        for uid, name in self.uid_names.items():
            spec = specs.observations[uid]
            shape = spec.shape if self.n > 1 else (1, *spec.shape)
            self._unpack[uid] = (name, shape)
        self.action_uid = act_uids["action"]
        self.action_dtype = tensor_utils.data_type_to_np_type(specs.actions[self.action_uid].dtype)

    def step_request(self, actions: np.ndarray | None) -> Any:
        """The Step request message (dm_env_rpc's protobuf) of ``actions``."""
        req = dm_env_rpc_pb2.StepRequest(requested_observations=self.requested)
        if actions is not None:
            a = actions if self.n > 1 else actions.reshape(())
            req.actions[self.action_uid].CopyFrom(tensor_utils.pack_tensor(a, self.action_dtype))
        return req

    def actions(self, actions: np.ndarray) -> np.ndarray:
        """``actions`` (int32, one per lane) shaped as the action spec."""
        return actions if self.n > 1 else actions.reshape(())

    def decode(self, answer: Any) -> dict[str, np.ndarray]:
        """Each requested observation of a Step answer as an array with a leading axis of
        ``n`` lanes."""
        out: dict[str, np.ndarray] = {}
        unpack = self._unpack
        for uid, flat in self.session.observations(answer).items():
            entry = unpack.get(uid)
            if entry is None:
                continue
            name, shape = entry
            try:
                out[name] = flat.reshape(shape)
            except ValueError:
                raise ServerError(
                    self.session.address,
                    "Step",
                    None,
                    f"its {name!r} has {flat.size} {flat.dtype} values, its spec says "
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
    return {} if seed is None else {"seed": np.int64(seed)}
