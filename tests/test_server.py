"""The env server beyond the protocol's compliance suite: parity with the in-process vector
env, authentication, hostile requests, vanishing clients, limits, health (docs/SERVER.md)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import grpc
import numpy as np
import pytest
import sixaxis_avoid
from _helpers import wait_for
from dm_env_rpc.v1 import connection, error, tensor_utils
from dm_env_rpc.v1 import dm_env_rpc_pb2 as pb
from sixaxis_avoid.vector import SixAxisAvoidGoalVectorEnv, SixAxisAvoidVectorEnv

INVALID_ARGUMENT, NOT_FOUND, FAILED_PRECONDITION, RESOURCE_EXHAUSTED = 3, 5, 9, 8

OBS, REWARD, DISCOUNT, ACHIEVED, DESIRED = 1, 2, 3, 4, 5
TERMINATED, TRUNCATED, IS_SUCCESS, COLLIDED, DISTANCE, CELL, DETOUR = 6, 7, 8, 9, 10, 11, 12


def pack(value, dtype=None):
    return tensor_utils.pack_tensor(value, dtype=dtype)


@pytest.fixture(scope="module")
def server():
    with sixaxis_avoid.serve(max_envs_per_world=64, max_worlds_per_session=4) as s:
        yield s


def connect(address: str, token: str | None = None) -> tuple[grpc.Channel, connection.Connection]:
    channel = grpc.insecure_channel(address)
    md = [("authorization", f"Bearer {token}")] if token is not None else None
    return channel, connection.Connection(channel, metadata=md)


def create(conn, **settings) -> str:
    req = pb.CreateWorldRequest(settings={k: pack(v) for k, v in settings.items()})
    return conn.send(req).world_name


def step(conn, actions=None, uids=(OBS,)):
    acts = {} if actions is None else {1: pack(np.asarray(actions, dtype=np.int32))}
    r = conn.send(pb.StepRequest(actions=acts, requested_observations=list(uids)))
    return r.state, {u: tensor_utils.unpack_tensor(t) for u, t in r.observations.items()}


ALL = (OBS, REWARD, DISCOUNT, TERMINATED, TRUNCATED, IS_SUCCESS, COLLIDED, DISTANCE, CELL, DETOUR)


@pytest.mark.parametrize("num_envs", [1, 8])
@pytest.mark.parametrize("obs_type", ["vector", "goal"])
def test_parity_with_the_native_vector_env(server, num_envs, obs_type):
    kw = {"random_target": True, "max_episode_steps": 9, "reward_scale": 0.37}
    cls = SixAxisAvoidGoalVectorEnv if obs_type == "goal" else SixAxisAvoidVectorEnv
    vec = cls(num_envs=num_envs, **kw)
    uids = ALL + ((ACHIEVED, DESIRED) if obs_type == "goal" else ())
    rng = np.random.default_rng(0)
    channel, conn = connect(server.address)
    with channel, conn:
        name = create(conn, num_envs=num_envs, obs_type=obs_type, seed=7, **kw)
        conn.send(pb.JoinWorldRequest(world_name=name))

        def check(got, obs, reward, term, trunc, info):
            shape = (num_envs,)
            o = obs["observation"] if obs_type == "goal" else obs
            assert np.asarray(got[OBS]).reshape(o.shape).tobytes() == o.tobytes()
            if obs_type == "goal":
                for uid, key in ((ACHIEVED, "achieved_goal"), (DESIRED, "desired_goal")):
                    assert np.asarray(got[uid]).reshape(-1, 3).tobytes() == obs[key].tobytes()
            r = np.asarray(got[REWARD], dtype=np.float64).reshape(shape)
            assert r.tobytes() == np.asarray(reward, dtype=np.float64).tobytes()
            assert np.array_equal(np.asarray(got[TERMINATED]).reshape(shape), term)
            assert np.array_equal(np.asarray(got[TRUNCATED]).reshape(shape), trunc)
            assert np.array_equal(np.asarray(got[DISCOUNT]).reshape(shape), (~term).astype("f4"))
            assert np.array_equal(np.asarray(got[COLLIDED]).reshape(shape), info["collided"])
            assert np.array_equal(np.asarray(got[IS_SUCCESS]).reshape(shape), info["is_success"])
            d = np.asarray(got[DISTANCE]).reshape(shape)
            assert d.tobytes() == info["distance_to_target"].tobytes()
            assert np.array_equal(np.asarray(got[CELL]).reshape(num_envs, 3), info["cell"])
            p = np.asarray(got[DETOUR]).reshape(shape)
            assert p.tobytes() == info["detour_penalty"].tobytes()

        ends = 0
        for seed in (7, 11):
            obs, info = vec.reset(seed=seed)
            if seed != 7:
                conn.send(pb.ResetRequest(settings={"seed": pack(seed)}))
            _, got = step(conn, uids=uids)  # the first Step: the reset
            zeros = np.zeros(num_envs, dtype=bool)
            check(got, obs, np.zeros(num_envs), zeros, zeros, info)
            for _ in range(40):
                a = rng.integers(0, 6, size=num_envs)
                obs, reward, term, trunc, info = vec.step(a)
                state, got = step(conn, a if num_envs > 1 else a[0], uids)
                check(got, obs, reward, term, trunc, info)
                ends += int(term.sum() + trunc.sum())
                if num_envs == 1:
                    want = 2 if term[0] else 3 if trunc[0] else 1  # TERMINATED/INTERRUPTED/RUNNING
                    assert state == want
                else:
                    assert state == 1
        assert ends > 0
        conn.send(pb.LeaveWorldRequest())
        conn.send(pb.DestroyWorldRequest(world_name=name))


def test_token_refused_without_it_and_accepted_with_it():
    with sixaxis_avoid.serve(token="s3cret-token") as s:
        for token in (None, "wrong", "s3cret-token-longer", "s3cret-tokeN"):
            channel, conn = connect(s.address, token)
            with channel, pytest.raises(grpc.RpcError) as e:
                create(conn)
            assert e.value.code() == grpc.StatusCode.UNAUTHENTICATED
            assert "Bearer" in e.value.details()
        channel, conn = connect(s.address, "s3cret-token")
        with channel, conn:
            name = create(conn, num_envs=2)
            conn.send(pb.JoinWorldRequest(world_name=name))
            assert step(conn)[0] == 1
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match=r"`address` = 0\.0\.0\.0:0"):
        sixaxis_avoid.serve("0.0.0.0:0")
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="`token`"):
        sixaxis_avoid.serve(token="two\nlines")


def _code(fn) -> int:
    with pytest.raises(error.DmEnvRpcError) as e:
        fn()
    return e.value.code


def test_hostile_requests_get_a_status_and_the_stream_goes_on(server):
    channel, conn = connect(server.address)
    with channel, conn:
        assert _code(lambda: conn.send(pb.JoinWorldRequest(world_name="nope"))) == NOT_FOUND
        assert _code(lambda: step(conn)) == FAILED_PRECONDITION
        assert _code(lambda: create(conn, num_envs=65)) == RESOURCE_EXHAUSTED
        assert _code(lambda: create(conn, num_envs=2**40)) == INVALID_ARGUMENT
        assert _code(lambda: create(conn, num_envs=np.float32(2.0))) == INVALID_ARGUMENT
        assert _code(lambda: create(conn, num_envs=np.array([1, 2]))) == INVALID_ARGUMENT
        bad = pb.CreateWorldRequest(settings={"scenario": pack("{not json")})
        assert _code(lambda: conn.send(bad)) == INVALID_ARGUMENT
        name = create(conn, num_envs=4)
        conn.send(pb.JoinWorldRequest(world_name=name))
        step(conn)
        for wrong in (
            {1: pack(np.zeros(4, dtype=np.float64))},  # dtype
            {1: pack(np.zeros(5, dtype=np.int32))},  # shape
            {1: pack(np.zeros((4, 1), dtype=np.int32))},  # rank
            {1: pack(np.array([0, 1, 6, 0], dtype=np.int32))},  # value
            {2: pack(np.zeros(4, dtype=np.int32))},  # uid
            {},  # missing
        ):
            with pytest.raises(error.DmEnvRpcError) as e:
                conn.send(pb.StepRequest(actions=wrong))
            assert e.value.code == INVALID_ARGUMENT
        with pytest.raises(error.DmEnvRpcError) as e:
            conn.send(pb.StepRequest(actions={1: pack(np.array([0, 1, 6, 0], dtype=np.int32))}))
        assert "`action` = 6 at index 2" in e.value.message
        assert step(conn, [0, 1, 2, 3])[0] == 1  # still serving this stream
        for mask in (np.ones(3, dtype=bool), np.ones(4, dtype=np.int32), "all"):
            with pytest.raises(error.DmEnvRpcError) as e:
                conn.send(pb.ResetRequest(settings={"reset_mask": pack(mask)}))
            assert e.value.code == INVALID_ARGUMENT and "`reset_mask`" in e.value.message
        with pytest.raises(error.DmEnvRpcError) as e:
            conn.send(pb.ResetRequest(settings={"lanes": pack(np.int32(1))}))
        assert "the settings are seed, reset_mask" in e.value.message
        assert step(conn, [0, 1, 2, 3])[0] == 1  # not reset by the refused masks
        # A flood of CreateWorld: past --max-worlds-per-session every one is refused.
        extra = [create(conn) for _ in range(3)]
        for _ in range(20):
            assert _code(lambda: create(conn)) == RESOURCE_EXHAUSTED
        assert _code(lambda: conn.send(pb.DestroyWorldRequest(world_name=name))) == (
            FAILED_PRECONDITION
        )
        conn.send(pb.LeaveWorldRequest())
        for w in [name, *extra]:
            conn.send(pb.DestroyWorldRequest(world_name=w))
    assert wait_for(lambda: server.worlds == 0)


def test_garbage_bytes_end_that_stream_only(server):
    channel = grpc.insecure_channel(server.address)
    raw = channel.stream_stream(
        "/dm_env_rpc.v1.Environment/Process",
        request_serializer=lambda b: b,
        response_deserializer=pb.EnvironmentResponse.FromString,
    )
    other_channel, other = connect(server.address)
    with channel, other_channel, other:
        name = create(other)
        for garbage in (b"\xff\xff\xff\xff\x0f", b"\x0a\x05abc", bytes(range(256))):
            responses = raw(iter([garbage]))
            got = []
            with pytest.raises(grpc.RpcError) as e:
                got.extend(responses)
            assert e.value.code() == grpc.StatusCode.INVALID_ARGUMENT
            assert got and got[0].error.code == INVALID_ARGUMENT
            assert "malformed request" in got[0].error.message
        other.send(pb.JoinWorldRequest(world_name=name))  # the other client goes on
        assert step(other)[0] == 1


def test_sessions_limit_and_vanishing_clients_free_their_worlds():
    with sixaxis_avoid.serve(max_sessions=2) as s:
        a_ch, a = connect(s.address)
        b_ch, b = connect(s.address)
        create(a)
        create(b)
        c_ch, c = connect(s.address)
        with pytest.raises(grpc.RpcError) as e:
            create(c)
        assert e.value.code() == grpc.StatusCode.RESOURCE_EXHAUSTED
        c_ch.close()
        a.close()
        a_ch.close()
        assert wait_for(lambda: s.worlds == 1 and s.sessions == 1)
        c_ch, c = connect(s.address)
        create(c)
        assert s.worlds == 2
        for ch, conn in ((b_ch, b), (c_ch, c)):
            conn.close()
            ch.close()
        assert wait_for(lambda: s.worlds == 0 and s.sessions == 0)

        # A client process killed mid-stream (SIGKILL: no goodbye) frees its worlds.
        script = textwrap.dedent(
            f"""
            import sys, time, grpc
            from dm_env_rpc.v1 import connection, dm_env_rpc_pb2 as pb, tensor_utils
            conn = connection.Connection(grpc.insecure_channel({s.address!r}))
            for _ in range(2):
                conn.send(pb.CreateWorldRequest(
                    settings={{"num_envs": tensor_utils.pack_tensor(300)}}))
            print("ready", flush=True)
            time.sleep(60)
            """
        )
        p = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
        try:
            assert p.stdout is not None and p.stdout.readline().strip() == "ready"
            assert s.worlds == 2
            p.kill()
        finally:
            p.wait(timeout=30)
        assert wait_for(lambda: s.worlds == 0 and s.sessions == 0)


def test_idle_streams_are_closed_and_their_worlds_freed():
    with sixaxis_avoid.serve(idle_timeout=0.3) as s:
        channel, conn = connect(s.address)
        with channel:
            create(conn)
            assert s.worlds == 1
            assert wait_for(lambda: s.worlds == 0)
            with pytest.raises(grpc.RpcError) as e:
                create(conn)
            assert e.value.code() == grpc.StatusCode.DEADLINE_EXCEEDED


def test_health_and_uds(tmp_path):
    path = tmp_path / "env.sock"
    with sixaxis_avoid.serve(uds=path) as s:
        assert s.address == f"unix:{path}" and s.port is None
        # grpcio sends the socket path as :authority, which HTTP/2 servers built on the `h2`
        # crate reject: a grpcio client of a Unix socket names an authority (docs/SERVER.md).
        channel = grpc.insecure_channel(s.address, options=[("grpc.default_authority", "x")])
        with channel:
            check = channel.unary_unary(
                "/grpc.health.v1.Health/Check",
                request_serializer=lambda b: b,
                response_deserializer=lambda b: b,
            )
            # HealthCheckResponse{status: SERVING (1)} for the server and the env service.
            assert check(b"") == b"\x08\x01"
            name = b"dm_env_rpc.v1.Environment"
            assert check(b"\x0a" + bytes([len(name)]) + name) == b"\x08\x01"
            conn = connection.Connection(channel)
            create(conn)
            conn.close()
    assert not path.exists()
    assert not s.running


def test_cli_serve_prints_its_address_and_drains_on_sigterm(tmp_path):
    import json
    import os
    import signal

    exe = os.path.join(os.path.dirname(__file__), "..", "target", "release", "sixaxis")
    p = subprocess.Popen(
        [exe, "serve", "--address", "127.0.0.1:0", "--max-sessions", "3"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert p.stdout is not None
        line = json.loads(p.stdout.readline())
        assert line["port"] > 0 and line["address"].endswith(f":{line['port']}")
        channel, conn = connect(line["address"])
        with channel, conn:
            create(conn)
            p.send_signal(signal.SIGTERM)
            assert p.wait(timeout=20) == 0
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    assert p.stderr is not None and "drained" in p.stderr.read()
    bad = subprocess.run(
        [exe, "serve", "--address", "0.0.0.0:0"], capture_output=True, text=True, timeout=30
    )
    assert bad.returncode == 2 and "`address` = 0.0.0.0:0" in bad.stderr
    for flag in ("--keepalive-interval", "--keepalive-timeout", "--idle-timeout"):
        bad = subprocess.run([exe, "serve", flag, "0"], capture_output=True, text=True, timeout=30)
        assert bad.returncode == 2 and f"`{flag}` = 0: must be a number of seconds" in bad.stderr


def test_the_duration_options_are_checked_naming_them():
    for name in ("keepalive_interval", "keepalive_timeout", "idle_timeout"):
        for bad in (0, -1.0, float("nan"), float("inf")):
            with pytest.raises(sixaxis_avoid.InvalidArgumentError, match=rf"`{name}` = "):
                sixaxis_avoid.serve(**{name: bad})
    with sixaxis_avoid.serve(keepalive_interval=0.5, keepalive_timeout=2.5) as s:
        channel, conn = connect(s.address)
        with channel, conn:
            create(conn)
            assert s.worlds == 1


# The Rust client of the extension (sixaxis_avoid.remote's default transport) ---------------
def test_the_rust_client_gets_statuses_and_the_stream_goes_on(server):
    """DmEnvClient against hostile requests of its own: each Status is the grpcio path's
    exception (InvalidArgumentError in the core's words, else ServerError with the code),
    and the same stream serves the next request (docs/SERVER.md "Sessions and worlds")."""
    from sixaxis_avoid import _core
    from sixaxis_avoid.remote import ServerError

    c = _core.DmEnvClient(server.address, timeout=10)
    try:
        c.send_step(np.array(0, np.int32), [1])  # Step before JoinWorld
        with pytest.raises(ServerError, match="FAILED_PRECONDITION") as e:
            c.receive()
        assert e.value.code == 9
        c.send_join_world("no-such-world")
        with pytest.raises(ServerError, match="NOT_FOUND"):
            c.receive()
        c.send_create_world({"num_envs": np.int64(0)})
        with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="`num_envs` = 0"):
            c.receive()
        c.send_create_world({"num_envs": np.int64(2), "seed": np.int64(3)})
        name = c.receive()
        c.send_join_world(name)
        specs = c.receive()
        assert specs["actions"][1][0] == "action"
        assert specs["observations"][2][:2] == ("reward", 2)  # float64
        assert c.step(None, [1])[0] == 1  # the reset step: RUNNING
        with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="`action` = 9 at index 1"):
            c.step(np.array([0, 9], np.int32), [1, 2])
        state, obs = c.step(np.array([0, 1], np.int32), [1, 2, 6])
        assert state == 1 and obs[1].dtype == np.float32 and obs[1].shape == (26,)
        assert obs[2].dtype == np.float64 and obs[6].dtype == np.bool_
        assert c.pending == 0 and not c.failed
    finally:
        c.close()
    assert c.failed
    with pytest.raises(ConnectionError, match="closed"):
        c.step(None, [1])
