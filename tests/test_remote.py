"""The Gymnasium envs over the env server (sixaxis_avoid.remote; docs/SERVER.md
"Gymnasium over the server"): checkers, parity with the in-process envs, errors, timeouts, a
dropped server, closing, SB3, and a short load test (scripts/load_test.py). The tests marked
with the ``transport`` fixture run over both transports: the Rust client of the extension
(the default) and grpcio."""

from __future__ import annotations

import importlib
import os
import re
import shutil
import signal
import subprocess
import sys
import textwrap
import threading
import time
from concurrent import futures
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import sixaxis_avoid
from _helpers import wait_for
from sixaxis_avoid.env import SixAxisAvoidEnv
from sixaxis_avoid.remote import RemoteEnv, RemoteVectorEnv, ServerError
from sixaxis_avoid.vector import SixAxisAvoidGoalVectorEnv, SixAxisAvoidVectorEnv

ROOT = Path(__file__).resolve().parent.parent


def _load_test_module():
    """scripts/load_test.py, importable by name (its client processes are spawned and
    import it again; spawn passes sys.path on)."""
    scripts = str(ROOT / "scripts")
    if scripts not in sys.path:
        sys.path.insert(0, scripts)
    return importlib.import_module("load_test")


@pytest.fixture(scope="module")
def server():
    with sixaxis_avoid.serve() as s:
        yield s


@pytest.fixture(params=["rust", "grpc"])
def transport(request):
    return request.param


@pytest.fixture(scope="module")
def second_server():
    with sixaxis_avoid.serve() as s:
        yield s


# Keywords ---------------------------------------------------------------------------------------
BAD_KEYWORDS = [
    {"reward_scale": -1},
    {"reward_scale": float("nan")},
    {"obs_type": "pixels"},
    {"obs_type": "index", "random_target": True},
    {"arm_aware": 3},
    {"assist": "yes"},
    {"random_target": "no"},
    {"max_episode_steps": 0},
    {"scenario": "no_such_scenario"},
    {"render_mode": "human"},
]


@pytest.mark.parametrize("kw", BAD_KEYWORDS, ids=lambda kw: ",".join(kw))
def test_bad_keywords_give_the_in_process_errors(kw):
    """Checked before any connection, by the in-process envs' own checks: same type and
    words (the vector env takes max_episode_steps; the native envs refuse to render)."""
    with pytest.raises(Exception) as theirs:
        SixAxisAvoidVectorEnv(2, **kw)
    for make in (lambda: RemoteEnv("127.0.0.1:9", **kw), lambda: RemoteVectorEnv("x:1", 2, **kw)):
        with pytest.raises(type(theirs.value)) as ours:
            make()
        if "render_mode" not in kw:
            assert str(ours.value) == str(theirs.value)
        else:
            assert "render_mode" in str(ours.value)


def test_unknown_keyword_is_a_type_error_naming_it():
    with pytest.raises(TypeError, match="unexpected keyword argument 'rewardscale'"):
        RemoteEnv("127.0.0.1:9", rewardscale=1.0)
    with pytest.raises(TypeError, match="unexpected keyword argument 'nope'"):
        RemoteVectorEnv("127.0.0.1:9", 2, nope=1)


def test_bad_vector_arguments():
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="num_envs"):
        RemoteVectorEnv("127.0.0.1:9", 0)
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="more servers"):
        RemoteVectorEnv(["a:1", "b:2", "c:3"], 2)
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="address"):
        RemoteVectorEnv([], 2)
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="address"):
        RemoteEnv(42)


# Checkers ------------------------------------------------------------------------------------
@pytest.mark.parametrize("obs_type", ["vector", "index", "goal"])
def test_gymnasium_check_env(server, obs_type, transport):
    from gymnasium.utils.env_checker import check_env

    kw = {"random_target": True} if obs_type != "index" else {}
    with RemoteEnv(server, obs_type=obs_type, transport=transport, **kw) as env:
        check_env(env, skip_render_check=True)


def test_sb3_check_env(server):
    from stable_baselines3.common.env_checker import check_env

    with RemoteEnv(server.address, random_target=True) as env:
        check_env(env, warn=True)


def test_observation_spaces_equal_the_in_process_ones(server, paper_simple):
    for obs_type, local in (
        ("vector", SixAxisAvoidEnv()),
        ("index", SixAxisAvoidEnv(obs_type="index")),
        ("goal", gym.make("SixAxisAvoidGoal-v0").unwrapped),
    ):
        with RemoteEnv(server, obs_type=obs_type) as env:
            assert env.observation_space == local.observation_space
            assert env.action_space == local.action_space


# Parity -------------------------------------------------------------------------------------
def _assert_same(a, b):
    if isinstance(b, dict):
        assert set(a) == set(b)
        for k in b:
            _assert_same(a[k], b[k])
        return
    np.testing.assert_array_equal(a, b)
    assert np.asarray(a).dtype == np.asarray(b).dtype


@pytest.mark.parametrize(
    ("obs_type", "kw"),
    [
        ("vector", {"random_target": True}),
        ("index", {"assist": False}),
        ("goal", {"random_target": True, "arm_aware": True, "reward_scale": 1e-4}),
    ],
)
def test_single_env_matches_in_process_step_for_step(server, near_target, obs_type, kw, transport):
    """Same seed and actions: same observations, rewards, flags and info, across resets
    (truncation by the server at the scenario's cap, by TimeLimit in process)."""
    env_id = "SixAxisAvoidGoal-v0" if obs_type == "goal" else "SixAxisAvoid-v0"
    local_kw = kw if obs_type == "goal" else {"obs_type": obs_type, **kw}
    local = sixaxis_avoid.make(env_id, near_target, **local_kw)
    rng = np.random.default_rng(7)
    ends = 0
    with RemoteEnv(
        server, scenario=near_target, obs_type=obs_type, transport=transport, **kw
    ) as env:
        for seed in (3, None, 11):
            o_r, i_r = env.reset(seed=seed)
            o_l, i_l = local.reset(seed=seed)
            _assert_same(o_r, o_l)
            assert i_r == i_l
            for _ in range(60):
                a = int(rng.integers(0, 6))
                r, lo = env.step(a), local.step(a)
                _assert_same(r[0], lo[0])
                assert r[1:4] == lo[1:4]
                assert r[4] == lo[4]
                if r[2] or r[3]:
                    ends += 1
                    break
    assert ends >= 2  # episodes ended, both ways on near_target's 12-step cap


def test_vector_env_matches_native_over_two_servers(server, second_server, near_target, transport):
    """Lanes split over two servers (and two worlds on one), stepped concurrently: bit for
    bit the native vector env's trajectories, across autoresets and reseeding."""
    n, kw = 7, {"scenario": near_target, "random_target": True, "max_episode_steps": 9}
    native = SixAxisAvoidVectorEnv(n, **kw)
    addresses = [server.address, second_server.address, server.address]
    rng = np.random.default_rng(1)
    ends = 0
    with RemoteVectorEnv(addresses, n, transport=transport, **kw) as remote:
        assert [w.n for w in remote._worlds] == [3, 2, 2]
        for seed in (5, None, [20 + i for i in range(n)]):
            _assert_same(remote.reset(seed=seed)[0], native.reset(seed=seed)[0])
            for _ in range(40):
                a = rng.integers(0, 6, size=n)
                ours, theirs = remote.step(a), native.step(a)
                for x, y in zip(ours[:4], theirs[:4]):
                    _assert_same(x, y)
                for key, value in ours[4].items():
                    _assert_same(value, theirs[4][key])
                ends += int(theirs[2].sum() + theirs[3].sum())
    assert ends > 10


def test_goal_vector_env_matches_native(server, near_target, transport):
    n, kw = 3, {"scenario": near_target, "random_target": True}
    native = SixAxisAvoidGoalVectorEnv(n, **kw)
    with RemoteVectorEnv(server, n, obs_type="goal", transport=transport, **kw) as remote:
        assert remote.single_observation_space == native.single_observation_space
        _assert_same(remote.reset(seed=2)[0], native.reset(seed=2)[0])
        for a in np.random.default_rng(0).integers(0, 6, size=(30, n)):
            for x, y in zip(remote.step(a)[:4], native.step(a)[:4]):
                _assert_same(x, y)


@pytest.mark.parametrize("lanes_per_world", [1, None])
def test_reset_mask_matches_native(server, near_target, transport, lanes_per_world):
    """`reset(options={"reset_mask": mask})` on one-lane worlds (each reset or not) and on
    one world of four lanes (a Reset with the `reset_mask` setting; docs/SERVER.md
    "Episodes"): the native vector env's trajectories."""
    n, kw = 4, {"scenario": near_target, "random_target": True}
    native = SixAxisAvoidVectorEnv(n, **kw)
    rng = np.random.default_rng(3)
    with RemoteVectorEnv(
        server, n, lanes_per_world=lanes_per_world, transport=transport, **kw
    ) as remote:
        assert len(remote._worlds) == (n if lanes_per_world == 1 else 1)
        _assert_same(remote.reset(seed=0)[0], native.reset(seed=0)[0])
        for k in range(50):
            a = rng.integers(0, 6, size=n)
            for x, y in zip(remote.step(a)[:4], native.step(a)[:4]):
                _assert_same(x, y)
            if k % 7 == 3:
                mask = rng.random(n) < 0.5
                _assert_same(
                    remote.reset(options={"reset_mask": mask})[0],
                    native.reset(options={"reset_mask": mask})[0],
                )


def test_vector_env_gymnasium_contract(server, near_target):
    """What Gymnasium's vector API promises: spaces hold what is returned, next-step
    autoreset (the step after an end: reward 0, not done), copies unless copy=False."""
    n = 3
    with RemoteVectorEnv(server, n, scenario=near_target) as envs:
        assert envs.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
        obs, info = envs.reset(seed=0)
        assert envs.observation_space.contains(obs)
        assert set(info) >= {"is_success", "_is_success"}
        # Lane 0 walks to the target (one cell below the start): action 5 is -z.
        _, _, term, _, info = envs.step(np.array([5, 0, 0]))
        assert term.tolist() == [True, False, False] and info["is_success"][0]
        obs2, rew2, term2, trunc2, _ = envs.step(np.array([0, 0, 0]))
        assert rew2[0] == 0.0 and not term2[0] and not trunc2[0]
        assert envs.observation_space.contains(obs2)
        obs3 = envs.step(envs.action_space.sample())[0]
        assert obs3 is not obs2
        with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="actions"):
            envs.step(np.array([0, 6, 0]))
        with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="actions"):
            envs.step(np.zeros(2, dtype=int))
        with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="seed"):
            envs.reset(seed=[1, 5, 9])


# Errors, timeouts, a dropped server, closing ------------------------------------------------
class _Silent:
    """A gRPC server that accepts the stream and never answers."""

    def __init__(self):
        import grpc
        from dm_env_rpc.v1 import dm_env_rpc_pb2_grpc

        release = self.release = threading.Event()

        class Servicer(dm_env_rpc_pb2_grpc.EnvironmentServicer):
            def Process(self, request_iterator, context):
                release.wait(30)
                return iter(())

        self.server = grpc.server(futures.ThreadPoolExecutor(max_workers=4))
        dm_env_rpc_pb2_grpc.add_EnvironmentServicer_to_server(Servicer(), self.server)
        self.address = f"127.0.0.1:{self.server.add_insecure_port('127.0.0.1:0')}"
        self.server.start()

    def stop(self):
        self.release.set()
        self.server.stop(0)


def test_a_silent_server_times_out_naming_it(transport):
    silent = _Silent()
    try:
        t0 = time.monotonic()
        with pytest.raises(TimeoutError, match=rf"{silent.address}.*CreateWorld.*timeout=0.3"):
            RemoteEnv(silent.address, timeout=0.3, transport=transport)
        assert time.monotonic() - t0 < 5
    finally:
        silent.stop()


def test_no_server_is_a_connect_timeout(transport):
    import socket

    with socket.socket() as s:  # a free port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(TimeoutError, match=rf"127.0.0.1:{port}.*connect_timeout"):
        RemoteEnv(f"127.0.0.1:{port}", connect_timeout=0.5, transport=transport)


def test_a_dropped_server_fails_every_later_call(sixaxis_bin, transport):
    load_test = _load_test_module()
    proc, address = load_test.start_server(sixaxis_bin)
    try:
        env = RemoteEnv(address, transport=transport)
        envs = RemoteVectorEnv(address, 2, transport=transport)
        env.reset(seed=0)
        envs.reset(seed=0)
        env.step(0)
        proc.kill()
        proc.wait(10)
        t0 = time.monotonic()
        for _ in range(2):  # the first failure and every call after it
            with pytest.raises(ConnectionError, match=address):
                env.step(0)
            with pytest.raises(ConnectionError, match=address):
                envs.step(np.zeros(2, dtype=int))
        assert time.monotonic() - t0 < 5  # at once, not after a timeout
        env.close()  # closing a broken env does not raise
        envs.close()
    finally:
        if proc.poll() is None:
            proc.kill()


def _wait_stopped(pid: int) -> None:
    """Until every thread of process ``pid`` is stopped (SIGSTOP is delivered
    asynchronously)."""
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        states = [
            (Path(f"/proc/{pid}/task/{t}/stat").read_text().rsplit(")", 1)[1].split()[0])
            for t in os.listdir(f"/proc/{pid}/task")
        ]
        if all(s == "T" for s in states):
            return
        time.sleep(0.01)
    raise AssertionError(f"process {pid} did not stop")


def test_a_stopped_server_times_out_and_the_session_stays_closed(sixaxis_bin, transport):
    """A server that stops answering (SIGSTOP) mid-session: the step raises TimeoutError
    after `timeout`, naming the server and the request; no hang, and every later call
    fails the same way even once the server runs again."""
    proc, address = _load_test_module().start_server(sixaxis_bin)
    try:
        env = RemoteEnv(address, timeout=0.5, transport=transport)
        env.reset(seed=0)
        env.step(0)
        os.kill(proc.pid, signal.SIGSTOP)
        _wait_stopped(proc.pid)
        t0 = time.monotonic()
        with pytest.raises(TimeoutError, match=rf"{address}.*Step.*timeout=0.5"):
            env.step(1)
        assert 0.4 < time.monotonic() - t0 < 5
        os.kill(proc.pid, signal.SIGCONT)
        with pytest.raises(TimeoutError, match="session is closed"):
            env.step(1)
        env.close()
    finally:
        os.kill(proc.pid, signal.SIGCONT)
        proc.kill()
        proc.wait(10)


def test_the_token_is_required_and_accepted(transport):
    with sixaxis_avoid.serve(token="s3cret-token") as guarded:
        with pytest.raises(PermissionError, match=r"UNAUTHENTICATED.*token"):
            RemoteEnv(guarded.address, transport=transport)
        with pytest.raises(PermissionError, match="token"):
            RemoteEnv(guarded.address, token="wrong", transport=transport)
        with RemoteEnv(guarded.address, token="s3cret-token", transport=transport) as env:
            env.reset(seed=0)
            env.step(1)


def test_close_leaves_and_destroys_the_world(server, transport):
    import grpc
    from dm_env_rpc.v1 import connection, dm_env_rpc_pb2, error

    env = RemoteEnv(server, transport=transport)
    env.reset(seed=0)
    name = env._session.world_name
    env.close()
    env.close()  # twice is fine
    with pytest.raises(ConnectionError, match="closed"):
        env.step(0)
    with connection.Connection(grpc.insecure_channel(server.address)) as conn:
        with pytest.raises(error.DmEnvRpcError):
            conn.send(dm_env_rpc_pb2.JoinWorldRequest(world_name=name))


def _refusal(address, settings, transport):
    from sixaxis_avoid.remote._session import _Session

    with pytest.raises(Exception) as e:
        _Session(
            address,
            settings,
            token=None,
            credentials=None,
            timeout=10,
            connect_timeout=5,
            transport=transport,
        )
    return e.value


@pytest.mark.parametrize(
    ("settings", "cls", "words"),
    [
        ({"num_envs": np.int64(-3)}, sixaxis_avoid.InvalidArgumentError, "`num_envs` = -3"),
        ({"obs_type": "pixels"}, sixaxis_avoid.InvalidArgumentError, "`obs_type`"),
        ({"num_envs": 2.5}, sixaxis_avoid.InvalidArgumentError, "num_envs"),
        ({"reward_scale": np.float64(-1.0)}, sixaxis_avoid.InvalidArgumentError, "reward_scale"),
        ({"nope": True}, sixaxis_avoid.InvalidArgumentError, "nope"),
        ({"scenario": "no_such_scenario"}, ServerError, "NOT_FOUND.*no_such_scenario"),
    ],
    ids=["num_envs", "obs_type", "float", "reward_scale", "unknown", "scenario"],
)
def test_a_refused_setting_is_the_same_exception_over_both_transports(server, settings, cls, words):
    """The server's own check, in the in-process words (InvalidArgumentError naming the
    setting); other refusals are ServerError with the code. Both transports raise the same
    class with the same message."""
    errors = {t: _refusal(server.address, settings, t) for t in ("rust", "grpc")}
    for e in errors.values():
        assert type(e) is cls, repr(e)
        assert re_search(words, str(e)), str(e)
    assert str(errors["rust"]) == str(errors["grpc"])
    if cls is ServerError:
        assert errors["rust"].code == errors["grpc"].code == 5
    assert issubclass(ServerError, RuntimeError)


def re_search(pattern: str, text: str) -> bool:
    import re

    return re.search(pattern, text) is not None


def test_the_transport_keyword_is_checked():
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="transport"):
        RemoteEnv("127.0.0.1:9", transport="tcp")
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match=r"transport.*TLS"):
        RemoteVectorEnv("127.0.0.1:9", 2, transport="rust", credentials=object())


def test_a_unix_socket_over_both_transports(tmp_path, near_target, transport):
    """`unix:PATH` addresses (grpcio is given the authority the server takes; docs/SERVER.md)."""
    path = tmp_path / "s.sock"
    with sixaxis_avoid.serve(uds=str(path)) as s:
        assert s.address == f"unix:{path}"
        local = sixaxis_avoid.make("SixAxisAvoid-v0", near_target, random_target=True)
        with RemoteEnv(s, scenario=near_target, random_target=True, transport=transport) as env:
            _assert_same(env.reset(seed=4)[0], local.reset(seed=4)[0])
            for a in np.random.default_rng(4).integers(0, 6, size=30):
                r, lo = env.step(int(a)), local.step(int(a))
                _assert_same(r[0], lo[0])
                assert r[1:] == lo[1:]
                if r[2] or r[3]:
                    env.reset(seed=5)
                    local.reset(seed=5)


# TLS -----------------------------------------------------------------------------------------
def _self_signed(directory: Path, name: str) -> tuple[Path, Path]:
    """A self-signed certificate for ``localhost`` and ``127.0.0.1`` and its key, made now
    by the ``openssl`` command (on every CI image; no Python package needed)."""
    cert, key = directory / f"{name}.crt", directory / f"{name}.key"
    subprocess.run(
        [
            shutil.which("openssl") or "/usr/bin/openssl",
            "req",
            "-x509",
            "-newkey",
            "ec",
            "-pkeyopt",
            "ec_paramgen_curve:prime256v1",
            "-nodes",
            "-keyout",
            str(key),
            "-out",
            str(cert),
            "-days",
            "2",
            "-subj",
            "/CN=localhost",
            "-addext",
            "subjectAltName=DNS:localhost,IP:127.0.0.1",
        ],
        check=True,
        capture_output=True,
        timeout=60,
    )
    return cert, key


@pytest.fixture(scope="module")
def tls_files(tmp_path_factory):
    """The server's certificate and key, and another certificate (a CA that did not sign
    the server's)."""
    d = tmp_path_factory.mktemp("tls")
    cert, key = _self_signed(d, "server")
    other, _ = _self_signed(d, "other")
    return cert, key, other


@pytest.fixture(scope="module")
def tls_server(tls_files):
    cert, key, _ = tls_files
    with sixaxis_avoid.serve(tls_cert=cert, tls_key=key) as s:
        yield s


def test_tls_trajectories_equal_the_in_process_env(tls_server, tls_files, near_target):
    """`credentials=` selects grpcio over TLS (docs/SERVER.md "The Rust transport"); reset and
    steps give the in-process env's trajectory, across episodes."""
    import grpc

    credentials = grpc.ssl_channel_credentials(root_certificates=tls_files[0].read_bytes())
    local = sixaxis_avoid.make("SixAxisAvoid-v0", near_target, random_target=True)
    rng = np.random.default_rng(2)
    ends = 0
    with RemoteEnv(
        tls_server, scenario=near_target, random_target=True, credentials=credentials
    ) as env:
        assert env._session.transport == "grpc"
        for seed in (6, None):
            _assert_same(env.reset(seed=seed)[0], local.reset(seed=seed)[0])
            for _ in range(40):
                a = int(rng.integers(0, 6))
                r, lo = env.step(a), local.step(a)
                _assert_same(r[0], lo[0])
                assert r[1:] == lo[1:]
                if r[2] or r[3]:
                    ends += 1
                    break
        assert tls_server.worlds == 1
    assert ends == 2
    assert wait_for(lambda: tls_server.worlds == 0)


def test_a_plaintext_client_of_a_tls_server_fails_within_its_timeout(tls_server, transport):
    """No hang: grpcio never gets a ready channel (TimeoutError at connect_timeout, with
    gRPC's account of the last attempt); the Rust client's HTTP/2 handshake is answered with
    TLS bytes (ConnectionError at once). Both messages say the server answers in TLS and
    name the `credentials=` keyword, after the transport's own account."""
    t0 = time.monotonic()
    with pytest.raises((TimeoutError, ConnectionError)) as e:
        RemoteEnv(tls_server, transport=transport, connect_timeout=1.0, timeout=5.0)
    assert time.monotonic() - t0 < 5
    message = str(e.value)
    assert tls_server.address in message
    assert "TLS" in message and "credentials=grpc.ssl_channel_credentials(" in message
    if transport == "grpc":
        assert e.type is TimeoutError and "connect_timeout=1.0" in message
        assert "(the last attempt: " in message
    else:
        assert e.type is ConnectionError
        # tonic's own words are kept before the hint. Which words depends on when the TLS
        # bytes reach its HTTP/2 client: a transport error, or (seen on a loaded machine)
        # an h2 protocol error.
        assert re.search(
            r"during CreateWorld \((UNKNOWN: transport error|INTERNAL: h2 protocol error)", message
        ), message
    assert wait_for(lambda: tls_server.sessions == 0)


def test_a_server_that_is_not_http2_gets_no_tls_hint(transport):
    """The TLS hint is a diagnosis, not a guess: a plaintext server that answers the HTTP/2
    preface with HTTP/1.1 and closes fails the session the same way, and is not said to be
    a TLS server."""
    import socket

    listener = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def answer():
        listener.settimeout(0.1)
        while not stop.is_set():
            try:
                conn, _ = listener.accept()
            except OSError:
                continue
            with conn:
                conn.sendall(b"HTTP/1.1 400 Bad Request\r\nConnection: close\r\n\r\n")

    thread = threading.Thread(target=answer, daemon=True)
    thread.start()
    address = f"127.0.0.1:{listener.getsockname()[1]}"
    try:
        with pytest.raises((TimeoutError, ConnectionError)) as e:
            RemoteEnv(address, transport=transport, connect_timeout=1.0, timeout=5.0)
    finally:
        stop.set()
        thread.join()
        listener.close()
    assert address in str(e.value)
    assert "TLS" not in str(e.value) and "credentials" not in str(e.value)


def test_a_client_trusting_another_ca_is_refused(tls_server, tls_files):
    """A certificate the client's roots did not sign: the TLS handshake fails, the error says
    so (gRPC's words: CERTIFICATE_VERIFY_FAILED) within connect_timeout."""
    import grpc

    credentials = grpc.ssl_channel_credentials(root_certificates=tls_files[2].read_bytes())
    t0 = time.monotonic()
    with pytest.raises(TimeoutError, match=r"(?i)connect_timeout=1\.0 s.*certificate"):
        RemoteEnv(tls_server, credentials=credentials, connect_timeout=1.0)
    assert time.monotonic() - t0 < 5
    assert tls_server.worlds == 0


def test_tls_alone_may_bind_a_non_loopback_address(tls_files):
    """The rule of docs/SERVER.md "Security": off loopback only with a token or TLS (the
    refusal without either is tested through the CLI in tests/test_server.py)."""
    cert, key, _ = tls_files
    with sixaxis_avoid.serve("0.0.0.0:0", tls_cert=cert, tls_key=key) as s:
        assert s.running and s.port > 0


# Keepalive -----------------------------------------------------------------------------------
def test_the_rust_client_answers_keepalive_pings_while_idle():
    """The Rust client's keeper thread drives its connection while the client is idle
    (docs/SERVER.md "The Rust transport"). With a ping after 1 s of silence and 1 s to
    answer it, a client idle for 4 s keeps its stream and world, while a client process
    frozen (SIGSTOP) for those 4 s, which answers no ping, loses both: its next step is a
    ConnectionError."""
    frozen_client = textwrap.dedent(
        """
        import sys
        from sixaxis_avoid.remote import RemoteEnv

        env = RemoteEnv(sys.argv[1], transport="rust")
        env.reset(seed=0)
        print("ready", flush=True)
        sys.stdin.readline()
        try:
            env.step(0)
            print("stepped", flush=True)
        except ConnectionError as e:
            print("ConnectionError", e, flush=True)
        """
    )
    with sixaxis_avoid.serve(keepalive_interval=1.0, keepalive_timeout=1.0) as s:
        with RemoteEnv(s, transport="rust") as env:
            env.reset(seed=0)
            env.step(4)
            proc = subprocess.Popen(
                [sys.executable, "-c", frozen_client, s.address],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                text=True,
            )
            try:
                assert proc.stdout is not None and proc.stdin is not None
                assert proc.stdout.readline().strip() == "ready"
                assert s.worlds == 2
                os.kill(proc.pid, signal.SIGSTOP)
                _wait_stopped(proc.pid)
                time.sleep(4.0)
                assert s.worlds == 1 and s.sessions == 1  # the frozen client's are gone
                os.kill(proc.pid, signal.SIGCONT)
                proc.stdin.write("\n")
                proc.stdin.flush()
                assert proc.stdout.readline().startswith("ConnectionError")
                assert proc.wait(30) == 0
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.wait()
            env.step(4)  # the idle client's world is still there
            env.reset(seed=1)


def test_the_rust_client_releases_the_gil_while_it_waits():
    """A Python thread counts while the main thread waits 1 s in the Rust client for a
    server that never answers: it counts as fast as it does alone, so the wait held no
    GIL."""
    counts = []
    stop = threading.Event()

    def count():
        n = 0
        while not stop.is_set():
            n += 1
        counts.append(n)

    def counted(seconds_or_fn):
        counts.clear()
        stop.clear()
        t = threading.Thread(target=count)
        t.start()
        t0 = time.monotonic()
        if callable(seconds_or_fn):
            seconds_or_fn()
        else:
            time.sleep(seconds_or_fn)
        took = time.monotonic() - t0
        stop.set()
        t.join()
        return counts[0] / took

    silent = _Silent()
    try:
        alone = counted(0.5)

        def wait():
            with pytest.raises(TimeoutError):
                RemoteEnv(silent.address, timeout=1.0, transport="rust")

        waiting = counted(wait)
    finally:
        silent.stop()
    # Holding the GIL for the whole second would leave the counter near 0.
    assert waiting > 0.3 * alone, (waiting, alone)


# Stable-Baselines3 ----------------------------------------------------------------------------
@pytest.mark.parametrize("lanes_per_world", [1, None])
def test_sb3_vecenv_matches_the_native_one(server, near_target, lanes_per_world):
    """Step for step SixAxisVecEnv's, with a world per lane (the default) or one world of
    three lanes whose ended lanes are reset by a Reset with ``reset_mask``."""
    from sixaxis_avoid.remote import RemoteSB3VecEnv
    from sixaxis_avoid.sb3 import SixAxisVecEnv

    kw = {"scenario": near_target, "random_target": True, "max_episode_steps": 8}
    ours = RemoteSB3VecEnv(server, 3, seed=4, lanes_per_world=lanes_per_world, **kw)
    theirs = SixAxisVecEnv(3, seed=4, **kw)
    assert len(ours.venv._worlds) == (3 if lanes_per_world == 1 else 1)
    np.testing.assert_array_equal(ours.reset(), theirs.reset())
    dones = 0
    for a in np.random.default_rng(2).integers(0, 6, size=(60, 3)):
        o1, r1, d1, i1 = ours.step(a)
        o2, r2, d2, i2 = theirs.step(a)
        np.testing.assert_array_equal(o1, o2)
        np.testing.assert_array_equal(r1, r2)
        np.testing.assert_array_equal(d1, d2)
        for x, y in zip(i1, i2):
            assert set(x) == set(y)
            for k in x:
                np.testing.assert_array_equal(x[k], y[k])
        dones += int(d1.sum())
    assert dones > 5
    ours.close()


def test_sb3_ppo_trains_through_remote_envs(server):
    """PPO on four remote lanes: the run completes with finite losses and the policy's
    greedy episode reaches the target more often than the untrained one (near target)."""
    from sixaxis_avoid.remote import RemoteSB3VecEnv
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecMonitor

    venv = VecMonitor(RemoteSB3VecEnv(server, 4, seed=0, reward_scale=1e-4, max_episode_steps=40))
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=128,
        batch_size=128,
        n_epochs=4,
        seed=0,
        device="cpu",
        policy_kwargs={"net_arch": [32]},
    )
    model.learn(total_timesteps=2048)
    assert model.num_timesteps >= 2048
    losses = model.logger.name_to_value
    assert np.isfinite(losses["train/loss"]) and np.isfinite(losses["train/value_loss"])
    assert len(model.ep_info_buffer) >= 40  # episodes ended at the 40-step cap and counted
    venv.close()


# Load -----------------------------------------------------------------------------------------
def test_short_load_no_step_lost_or_crossed_and_memory_flat(sixaxis_bin):
    """16 concurrent sessions x 1,000 steps, each checked step for step against the
    in-process env (scripts/load_test.py runs 64 x 10,000)."""
    res = _load_test_module().run(16, 1000, sixaxis_bin, warmup_steps=100)
    assert res["errors"] == [] and res["warmup_errors"] == []
    assert res["steps_checked"] == 16 * 1000
    assert res["episodes"] > 16 * 10
    assert res["server_alive"]
    # Flat: the load after the warm-up adds no more than a few MB (its sessions are gone).
    assert res["rss_kib_after_load"] - res["rss_kib_after_warmup"] < 8 * 1024, res


def test_worlds_are_freed_on_close_and_when_an_env_is_dropped(transport):
    """The server's world count (Server.worlds): close() destroys the world; an env dropped
    without close() ends its stream, and the server frees the world."""
    import gc

    with sixaxis_avoid.serve() as s:
        env = RemoteEnv(s, transport=transport)
        envs = RemoteVectorEnv([s, s], 4, transport=transport)
        assert wait_for(lambda: s.worlds == 3, 10), s.worlds
        envs.close()
        assert wait_for(lambda: s.worlds == 1, 10), s.worlds
        env.reset(seed=0)
        del env
        gc.collect()
        assert wait_for(lambda: s.worlds == 0, 10), s.worlds


def test_start_ray_servers_checks_its_arguments():
    import ray
    from sixaxis_avoid.remote import start_ray_servers

    for bad in (0, -1, 1.5, True):
        with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="num_per_node"):
            start_ray_servers(bad)
    assert not ray.is_initialized()
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match=r"ray\.init"):
        start_ray_servers()
