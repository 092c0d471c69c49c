"""dm_env_rpc's own compliance suite (``dm_env_rpc.v1.compliance``) against
``sixaxis_avoid.serve()``, and ``DmEnvAdaptor`` running episodes (docs/SERVER.md)."""

from __future__ import annotations

import grpc
import numpy as np
import sixaxis_avoid
from dm_env_rpc.v1 import compliance, connection, dm_env_adaptor, tensor_utils
from dm_env_rpc.v1 import dm_env_rpc_pb2 as pb

_SERVER: sixaxis_avoid.Server | None = None


def setup_module() -> None:
    global _SERVER
    _SERVER = sixaxis_avoid.serve()


def teardown_module() -> None:
    assert _SERVER is not None
    _SERVER.stop()


def pack(value, dtype=None):
    return tensor_utils.pack_tensor(value, dtype=dtype)


class _Connected:
    """A fresh stream to the module's server per test; worlds made here are destroyed."""

    WORLD_SETTINGS: dict = {}  # noqa: RUF012

    def setUp(self):
        assert _SERVER is not None
        self._channel = grpc.insecure_channel(_SERVER.address)
        self._connection = connection.Connection(self._channel)
        self._worlds: list[str] = []
        super().setUp()

    def tearDown(self):
        try:
            super().tearDown()
            self._connection.send(pb.LeaveWorldRequest())
            for w in self._worlds:
                self._connection.send(pb.DestroyWorldRequest(world_name=w))
        finally:
            self._connection.close()
            self._channel.close()

    @property
    def connection(self):
        return self._connection

    def _create(self) -> str:
        settings = {k: pack(v) for k, v in self.WORLD_SETTINGS.items()}
        name = self._connection.send(pb.CreateWorldRequest(settings=settings)).world_name
        self._worlds.append(name)
        return name


class CreateDestroyWorldTest(_Connected, compliance.CreateDestroyWorld):
    @property
    def required_world_settings(self):
        return {}

    @property
    def invalid_world_settings(self):
        return {
            "num_envs": pack(0),
            "obs_type": pack("pixels"),
            "reward_scale": pack(-1.0),
            "max_episode_steps": pack(0),
            "arm_aware": pack(3),
            "scenario": pack("no_such_scenario"),
            "seed": pack(-1),
            "colour": pack("red"),
        }

    @property
    def has_multiple_world_support(self):
        return True


class JoinLeaveWorldTest(_Connected, compliance.JoinLeaveWorld):
    def setUp(self):
        super().setUp()
        self._world = self._create()

    @property
    def world_name(self):
        return self._world

    @property
    def invalid_join_settings(self):
        return {"num_envs": pack(2)}


class ResetTest(_Connected, compliance.Reset):
    def join_world(self):
        name = self._create()
        return self._connection.send(pb.JoinWorldRequest(world_name=name)).specs


class ResetWorldTest(_Connected, compliance.ResetWorld):
    def setUp(self):
        super().setUp()
        self._world = self._create()

    @property
    def world_name(self):
        return self._world

    @property
    def required_reset_world_settings(self):
        return {"seed": pack(5)}


class _StepBase(_Connected, compliance.Step):
    def setUp(self):
        super().setUp()
        name = self._create()
        self._specs = self._connection.send(pb.JoinWorldRequest(world_name=name)).specs

    @property
    def specs(self):
        return self._specs

    @property
    def required_actions(self):
        n = self.WORLD_SETTINGS.get("num_envs", 1)
        value = np.int32(0) if n == 1 else np.zeros(n, dtype=np.int32)
        return {1: pack(value)}


class StepOneEnvTest(_StepBase):
    WORLD_SETTINGS = {"num_envs": 1, "seed": 1}  # noqa: RUF012


class StepBatchTest(_StepBase):
    WORLD_SETTINGS = {"num_envs": 8, "random_target": True, "seed": 2}  # noqa: RUF012


class StepGoalTest(_StepBase):
    WORLD_SETTINGS = {"num_envs": 3, "obs_type": "goal", "seed": 3}  # noqa: RUF012


class StepIndexTest(_StepBase):
    WORLD_SETTINGS = {"num_envs": 1, "obs_type": "index"}  # noqa: RUF012


# DmEnvAdaptor -------------------------------------------------------------------------


def _adaptor(conn, **settings):
    name = conn.send(
        pb.CreateWorldRequest(settings={k: pack(v) for k, v in settings.items()})
    ).world_name
    specs = conn.send(pb.JoinWorldRequest(world_name=name)).specs
    return name, dm_env_adaptor.DmEnvAdaptor(conn, specs)


def _path_actions(scenario: sixaxis_avoid.Scenario) -> list[int]:
    moves = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    cells = sixaxis_avoid.shortest_path(scenario)
    pairs = zip(cells, cells[1:])
    return [moves.index(tuple(int(b[i] - a[i]) for i in range(3))) for a, b in pairs]


def test_dm_env_adaptor_runs_episodes_to_the_target_and_to_truncation():
    assert _SERVER is not None
    with (
        grpc.insecure_channel(_SERVER.address) as channel,
        connection.Connection(channel) as conn,
    ):
        path = _path_actions(sixaxis_avoid.Scenario("paper_simple"))
        assert len(path) > 3
        name, env = _adaptor(conn, seed=0)
        for _ in range(2):  # two episodes: the Step after LAST starts the next
            ts = env.reset()
            assert ts.first() and ts.reward is None
            assert ts.observation["observation"].shape == (13,)
            for k, a in enumerate(path):
                ts = env.step({"action": a})
                assert ts.last() == (k == len(path) - 1)
            assert ts.discount == 0.0 and ts.reward > 0
            assert bool(ts.observation["terminated"]) and bool(ts.observation["is_success"])
            ts = env.step({"action": 0})  # its action is ignored: it starts the next episode
            assert ts.first()
        conn.send(pb.LeaveWorldRequest())
        conn.send(pb.DestroyWorldRequest(world_name=name))

        name, env = _adaptor(conn, max_episode_steps=4, seed=0)
        ts = env.reset()
        kinds = []
        for _ in range(10):
            ts = env.step({"action": 1})
            kinds.append(ts.step_type)
        # 4 steps then LAST (INTERRUPTED: discount 1), then FIRST of the next episode.
        assert [k.name for k in kinds] == ["MID"] * 3 + ["LAST", "FIRST"] + ["MID"] * 3 + [
            "LAST",
            "FIRST",
        ]
        conn.send(pb.LeaveWorldRequest())
        conn.send(pb.DestroyWorldRequest(world_name=name))
    assert _SERVER.worlds == 0
