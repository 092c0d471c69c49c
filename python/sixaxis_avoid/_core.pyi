"""Type stubs of the Rust extension ``sixaxis_avoid._core`` (PyO3)."""

from collections.abc import Callable, Iterable, Sequence
from os import PathLike
from typing import Any, Literal, Protocol, TypedDict, final

import numpy as np
import numpy.typing as npt
from typing_extensions import Self

__all__ = [
    "DEFAULT_SCENARIO",
    "VECTOR_OBS_DIM",
    "VECTOR_OBS_TARGET",
    "VECTOR_OBS_TERMINAL",
    "Arm",
    "DmEnvClient",
    "EnvCore",
    "InternalError",
    "InvalidArgumentError",
    "JointEnvCore",
    "JointVecEnvCore",
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
    "VecEnvCore",
    "__version__",
    "_raise_core_error",
    "cells_reachable",
    "centres_clearance_cells",
    "check_options",
    "clear_pose_at",
    "env_tables",
    "expand_names",
    "export_scenario",
    "generate_scenario",
    "greedy_path_of",
    "interpolate",
    "load_q",
    "machine",
    "options",
    "plan",
    "serve",
    "shortest_path",
    "train",
    "unreachable_cells",
    "write_atomic",
]

__version__: str
DEFAULT_SCENARIO: str
VECTOR_OBS_DIM: int
VECTOR_OBS_TERMINAL: tuple[int, int]
VECTOR_OBS_TARGET: tuple[int, int]

_Cell = tuple[int, int, int]
_CellLike = Sequence[int] | npt.NDArray[np.integer[Any]]
# A Q-table, (num_states, 6): float64, or float32 for q_precision="f32".
_QArray = npt.NDArray[np.float64] | npt.NDArray[np.float32]

# Exceptions (created at import; every one is a ValueError through SixAxisError).
class SixAxisError(ValueError): ...

class ScenarioError(SixAxisError):
    field: str
    value: str
    reason: str

class ScenarioParseError(ScenarioError): ...

class ScenarioNotFoundError(ScenarioError, LookupError):
    name: str
    known: str

class InvalidArgumentError(SixAxisError):
    name: str
    value: str
    reason: str

class QTableMismatchError(SixAxisError): ...
class SixAxisIOError(OSError, SixAxisError): ...
class InternalError(RuntimeError): ...

@final
class Scenario:
    def __new__(
        cls, name_or_path: str | PathLike[str] | dict[str, Any] | Scenario | None = None
    ) -> Self: ...
    @staticmethod
    def load(name_or_path: str | PathLike[str]) -> Scenario: ...
    @staticmethod
    def builtin(name: str) -> Scenario: ...
    @staticmethod
    def builtin_names() -> list[str]: ...
    @staticmethod
    def from_json(text: str) -> Scenario: ...
    @staticmethod
    def from_dict(d: dict[str, Any]) -> Scenario: ...
    def to_json(self) -> str: ...
    def to_dict(self) -> dict[str, Any]: ...
    def validate(self) -> None: ...
    def replace(self, **changes: Any) -> Scenario: ...
    def regrid(self, cell_mm: float) -> Scenario: ...
    @property
    def name(self) -> str: ...
    @property
    def notes(self) -> str: ...
    @property
    def cell_mm(self) -> float: ...
    @property
    def bounds(self) -> tuple[_Cell, _Cell]: ...
    @property
    def shape(self) -> list[int]: ...
    @property
    def start(self) -> _Cell: ...
    @property
    def target(self) -> _Cell: ...
    @property
    def obstacles(self) -> list[_Cell]: ...
    @property
    def obstacle_boxes_mm(self) -> list[dict[str, Any]]: ...
    @property
    def terminal_safe_distance(self) -> float: ...
    @property
    def arm_safe_distance(self) -> float: ...
    @property
    def max_steps_per_episode(self) -> int: ...
    @property
    def rewards(self) -> dict[str, float]: ...
    @property
    def learning(self) -> dict[str, Any]: ...
    @property
    def beta0_deg(self) -> list[float]: ...
    def __eq__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...

_ScenarioLike = Scenario | str | PathLike[str] | dict[str, Any] | None

@final
class Arm:
    def __new__(cls, dh: Sequence[Sequence[float]] | None = None) -> Self: ...
    @staticmethod
    def from_scenario(scenario: _ScenarioLike) -> Arm: ...
    @property
    def dh(self) -> list[tuple[float, float, float, float]]: ...
    def fk(
        self, joints_rad: Sequence[float] | npt.NDArray[np.float64]
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
    def fk_batch(self, joints_rad: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]: ...
    def points_mm(
        self, joints_rad: Sequence[float] | npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]: ...
    def ik(
        self,
        position_mm: Sequence[float] | npt.NDArray[np.float64],
        rotation: npt.NDArray[np.float64] | None = None,
        *,
        rpy_deg: Sequence[float] | None = None,
    ) -> npt.NDArray[np.float64]: ...

class _TrainCheckpoint(TypedDict):
    env_steps: int
    episode: int
    path: list[list[int]] | None
    wall_time_s: float
    cpu_time_s: float | None

@final
class TrainResult:
    @property
    def path(self) -> list[_Cell] | None: ...
    @property
    def path_array(self) -> npt.NDArray[np.int32]: ...
    @property
    def success(self) -> bool: ...
    @property
    def steps_per_episode(self) -> npt.NDArray[np.uint32]: ...
    @property
    def reached_per_episode(self) -> npt.NDArray[np.bool_]: ...
    @property
    def converged_episode(self) -> int | None: ...
    @property
    def length_converged_episode(self) -> int | None: ...
    @property
    def checkpoints(self) -> list[_TrainCheckpoint]: ...
    @property
    def total_steps(self) -> int: ...
    @property
    def wall_time_s(self) -> float: ...
    @property
    def seed(self) -> int: ...
    @property
    def episodes(self) -> int: ...
    def to_dict(self) -> dict[str, Any]: ...
    @property
    def q(self) -> _QArray: ...
    @property
    def q_precision(self) -> Literal["f64", "f32"]: ...
    @property
    def state_cells(self) -> npt.NDArray[np.int32]: ...
    @property
    def scenario(self) -> Scenario: ...
    def state_of(self, c: _CellLike) -> int | None: ...
    def save_q(self, path: str | PathLike[str]) -> None: ...

def train(
    scenario: _ScenarioLike = None,
    *,
    extra_obstacles: Iterable[_CellLike] | None = None,
    initial_q: Literal["zero", "distance"] | _QArray | None = None,
    progress: Callable[[int], object] | None = None,
    checkpoints: Sequence[int] | None = None,
    # options:train >>>
    assist: bool | None = None,
    episodes: int | Literal["auto"] | None = None,
    seed: int | None = None,
    detour: bool | None = None,
    distance: bool | None = None,
    max_steps_per_episode: int | None = None,
    q_precision: Literal["f64", "f32"] | None = None,
    alpha: float | None = None,
    gamma: float | None = None,
    epsilon_start: float | None = None,
    epsilon_decay_episodes: int | None = None,
    max_env_steps: int | None = None,
    epsilon_schedule: Literal["episodes", "env_steps"] | None = None,
    epsilon_decay_fraction: float | None = None,
    episode_cap: int | None = None,
    # <<< options:train
) -> TrainResult: ...
def check_options(function: Literal["env", "joint"], **kwargs: Any) -> dict[str, Any]: ...
def options(
    function: Literal["train", "plan", "generate_scenario", "env", "joint"] = "train",
    scenario: _ScenarioLike = None,
) -> list[dict[str, Any]]: ...
def load_q(
    path: str | PathLike[str],
    scenario: _ScenarioLike = None,
    *,
    extra_obstacles: Iterable[_CellLike] | None = None,
) -> _QArray: ...
def greedy_path_of(
    q: _QArray,
    scenario: _ScenarioLike = None,
    *,
    max_steps: int | None = None,
    extra_obstacles: Iterable[_CellLike] | None = None,
) -> list[_Cell] | None: ...
def shortest_path(
    scenario: _ScenarioLike = None, *, extra_obstacles: Iterable[_CellLike] | None = None
) -> list[_Cell] | None: ...
def unreachable_cells(scenario: _ScenarioLike = None) -> list[_Cell]: ...
def clear_pose_at(
    scenario: _ScenarioLike, cell_xyz: _CellLike
) -> npt.NDArray[np.float64] | None: ...
def cells_reachable(
    cells: Iterable[_CellLike], scenario: _ScenarioLike = None
) -> npt.NDArray[np.bool_]: ...
def interpolate(
    q0: Sequence[float], q1: Sequence[float], steps: int
) -> npt.NDArray[np.float64]: ...
def centres_clearance_cells(
    scenario: _ScenarioLike, poses_rad: npt.NDArray[np.float64], cell_mm: float | None = None
) -> npt.NDArray[np.float64]: ...
def _raise_core_error(kind: str) -> None: ...

@final
class PosePlanner:
    def __new__(cls, scenario: _ScenarioLike = None, *, round: int = 0) -> Self: ...
    @property
    def scenario(self) -> Scenario: ...
    @property
    def orientation_divisions(self) -> int: ...
    def cell_reachable(self, cell_xyz: _CellLike) -> bool: ...
    def best_clearance_at(
        self, cell_xyz: _CellLike
    ) -> tuple[float, npt.NDArray[np.float64], tuple[float, float, float]] | None: ...
    def plan_poses(
        self, path: Iterable[_CellLike], beta0_rad: Sequence[float] | None = None
    ) -> dict[str, Any]: ...

@final
class EnvCore:
    def __new__(
        cls,
        scenario: _ScenarioLike = None,
        *,
        obs: str = "vector",
        assist: bool | None = None,
        reward_scale: float = 1.0,
        random_target: bool = False,
        extra_obstacles: Iterable[_CellLike] | None = None,
        track_path: bool = False,
    ) -> Self: ...
    def seed(self, seed: int) -> None: ...
    def reset(self) -> tuple[Any, dict[str, Any]]: ...
    def step(self, action: int) -> tuple[Any, float, bool, dict[str, Any]]: ...
    def vector_observation(self) -> npt.NDArray[np.float32]: ...
    def cell_of(self, state: int) -> _Cell: ...
    def state_of(self, c: _CellLike) -> int | None: ...
    def compute_reward(
        self,
        achieved_goal: npt.NDArray[np.float64],
        desired_goal: npt.NDArray[np.float64],
        collided: npt.NDArray[np.bool_],
        detour_penalty: npt.NDArray[np.float64],
    ) -> npt.NDArray[np.float64]: ...
    def goal_to_cell(self, goal: npt.NDArray[np.float64]) -> npt.NDArray[np.int64]: ...
    scenario: Scenario
    num_states: int
    state: int
    steps: int
    cell: _Cell
    target_cell: _Cell
    start_cell: _Cell
    obstacles: list[_Cell]
    extra_obstacles: list[_Cell]
    target_candidates: list[_Cell]
    blocked: npt.NDArray[np.bool_]
    path: list[_Cell]
    start_distance: float
    reward_scale: float
    assist: tuple[bool, bool]

@final
class VecEnvCore:
    def __new__(
        cls,
        scenario: _ScenarioLike = None,
        *,
        num_envs: int,
        max_episode_steps: int,
        obs: str = "vector",
        assist: bool | None = None,
        reward_scale: float = 1.0,
        random_target: bool = False,
        extra_obstacles: Iterable[_CellLike] | None = None,
    ) -> Self: ...
    def seed(self, seeds: Sequence[int]) -> None: ...
    def reset(self, mask: npt.NDArray[np.bool_] | None = None) -> None: ...
    def step(self, actions: npt.NDArray[np.int64]) -> None: ...
    def cell_of(self, state: int) -> _Cell: ...
    def state_of(self, c: _CellLike) -> int | None: ...
    def compute_reward(
        self,
        achieved_goal: npt.NDArray[np.float64],
        desired_goal: npt.NDArray[np.float64],
        collided: npt.NDArray[np.bool_],
        detour_penalty: npt.NDArray[np.float64],
    ) -> npt.NDArray[np.float64]: ...
    def goal_to_cell(self, goal: npt.NDArray[np.float64]) -> npt.NDArray[np.int64]: ...
    num_envs: int
    num_states: int
    max_episode_steps: int
    observations: npt.NDArray[Any]
    rewards: npt.NDArray[np.float64]
    terminated: npt.NDArray[np.bool_]
    truncated: npt.NDArray[np.bool_]
    collided: npt.NDArray[np.bool_]
    distance_to_target: npt.NDArray[np.float64]
    cells: npt.NDArray[np.int32]
    detour_penalty: npt.NDArray[np.float64]
    steps: npt.NDArray[np.uint32]
    current_targets: npt.NDArray[np.int32]
    target_candidates: list[_Cell]
    obstacles: list[_Cell]
    extra_obstacles: list[_Cell]
    reward_scale: float
    random_target: bool
    assist: tuple[bool, bool]

@final
class JointEnvCore:
    def __new__(
        cls, scenario: _ScenarioLike = None, options: dict[str, Any] | None = None
    ) -> Self: ...
    def reset(self) -> tuple[npt.NDArray[np.float32], dict[str, Any]]: ...
    def step(
        self, action: Sequence[float] | npt.NDArray[np.floating[Any]]
    ) -> tuple[npt.NDArray[np.float32], float, bool, dict[str, Any]]: ...
    def pose_is_clear(self, q: Sequence[float]) -> bool: ...
    def link_gaps_mm(self, q: Sequence[float]) -> list[float]: ...
    def substeps(self, from_q: Sequence[float], to_q: Sequence[float]) -> int: ...
    def compute_reward(
        self,
        previous_achieved_goal: npt.NDArray[np.float32],
        achieved_goal: npt.NDArray[np.float32],
        desired_goal: npt.NDArray[np.float32],
        refused: npt.NDArray[np.bool_],
        detour_penalty: npt.NDArray[np.float64],
    ) -> npt.NDArray[np.float64]: ...
    obs_dim: int
    obs_layout: dict[str, Any]
    num_links: int
    links: list[int]
    reach_mm: float
    safe_distance_mm: float
    link_radius_mm: float
    target_mm: tuple[float, float, float]
    beta0_rad: list[float]
    joint_limits_rad: list[tuple[float, float]]
    max_episode_steps: int
    options: dict[str, Any]
    max_joint_step_deg: float
    target_tolerance_mm: float
    scenario: Scenario
    joints: list[float]
    terminal_mm: tuple[float, float, float]
    steps: int

@final
class JointVecEnvCore:
    def __new__(
        cls,
        scenario: _ScenarioLike = None,
        *,
        num_envs: int,
        options: dict[str, Any] | None = None,
    ) -> Self: ...
    def reset(self, mask: npt.NDArray[np.bool_] | None = None) -> None: ...
    def step(self, actions: npt.NDArray[np.float64]) -> None: ...
    def pose_is_clear(self, q: Sequence[float]) -> bool: ...
    def link_gaps_mm(self, q: Sequence[float]) -> list[float]: ...
    def substeps(self, from_q: Sequence[float], to_q: Sequence[float]) -> int: ...
    def compute_reward(
        self,
        previous_achieved_goal: npt.NDArray[np.float32],
        achieved_goal: npt.NDArray[np.float32],
        desired_goal: npt.NDArray[np.float32],
        refused: npt.NDArray[np.bool_],
        detour_penalty: npt.NDArray[np.float64],
    ) -> npt.NDArray[np.float64]: ...
    obs_dim: int
    obs_layout: dict[str, Any]
    num_links: int
    links: list[int]
    reach_mm: float
    safe_distance_mm: float
    link_radius_mm: float
    target_mm: tuple[float, float, float]
    beta0_rad: list[float]
    joint_limits_rad: list[tuple[float, float]]
    max_episode_steps: int
    options: dict[str, Any]
    max_joint_step_deg: float
    target_tolerance_mm: float
    num_envs: int
    observations: npt.NDArray[np.float32]
    rewards: npt.NDArray[np.float64]
    terminated: npt.NDArray[np.bool_]
    truncated: npt.NDArray[np.bool_]
    refused: npt.NDArray[np.bool_]
    distance_to_target: npt.NDArray[np.float64]
    clearance: npt.NDArray[np.float64]
    detour_penalty: npt.NDArray[np.float64]
    joints: npt.NDArray[np.float64]
    terminal_mm: npt.NDArray[np.float64]
    previous_achieved_goal: npt.NDArray[np.float32]
    steps: npt.NDArray[np.uint32]

@final
class PlanResult:
    @property
    def success(self) -> bool: ...
    @property
    def path(self) -> list[_Cell]: ...
    @property
    def poses_rad(self) -> npt.NDArray[np.float64]: ...
    @property
    def orientations_rpy_deg(self) -> npt.NDArray[np.float64]: ...
    @property
    def replans(self) -> int: ...
    @property
    def added_obstacles(self) -> list[_Cell]: ...
    @property
    def failure(self) -> str | None: ...
    @property
    def rounds(self) -> list[dict[str, Any]]: ...
    @property
    def wall_time_s(self) -> float: ...
    @property
    def seed(self) -> int: ...
    @property
    def min_centre_clearance_cells(self) -> float | None: ...
    @property
    def min_cube_distance_mm(self) -> float | None: ...
    @property
    def obstacles(self) -> list[_Cell]: ...
    @property
    def obstacle_boxes_mm(self) -> list[dict[str, Any]]: ...
    @property
    def cell_mm(self) -> float: ...
    @property
    def arm_safe_distance(self) -> float: ...
    @property
    def interpolation_steps(self) -> int: ...
    @property
    def clearance_model(self) -> dict[str, Any]: ...
    @property
    def start(self) -> _Cell: ...
    @property
    def target(self) -> _Cell: ...
    def to_dict(self) -> dict[str, Any]: ...
    def to_json(self) -> str: ...

class _PathLearnerObject(Protocol):
    def learn_path(
        self, scenario: Scenario, seed: int
    ) -> Sequence[_CellLike] | dict[str, Any] | None: ...

_PathLearner = (
    Literal["qlearning", "bfs"]
    | Callable[[Scenario, int], Sequence[_CellLike] | dict[str, Any] | None]
    | _PathLearnerObject
)

def plan(
    scenario: _ScenarioLike = None,
    *,
    learner: _PathLearner | None = None,
    # options:plan >>>
    assist: bool | None = None,
    episodes: int | Literal["auto"] | None = None,
    seed: int | None = None,
    detour: bool | None = None,
    distance: bool | None = None,
    max_steps_per_episode: int | None = None,
    initial_q: Literal["zero", "distance"] | None = None,
    q_precision: Literal["f64", "f32"] | None = None,
    alpha: float | None = None,
    gamma: float | None = None,
    epsilon_start: float | None = None,
    epsilon_decay_episodes: int | None = None,
    max_env_steps: int | None = None,
    epsilon_schedule: Literal["episodes", "env_steps"] | None = None,
    epsilon_decay_fraction: float | None = None,
    episode_cap: int | None = None,
    max_replans: int | None = None,
    # <<< options:plan
) -> PlanResult: ...
def export_scenario(
    scenario: _ScenarioLike = None,
    format: str = "mjcf",
    path: str | PathLike[str] | None = None,
) -> str: ...
def env_tables(
    scenario: _ScenarioLike = None,
    *,
    assist: bool | None = None,
    reward_scale: float | None = None,
    random_target: bool | None = None,
    arm_aware: bool | None = None,
    max_episode_steps: int | None = None,
) -> dict[str, npt.NDArray[Any]]: ...
def generate_scenario(
    seed: int,
    *,
    bounds: tuple[_CellLike, _CellLike] | dict[str, _CellLike] | None = None,
    # options:generate_scenario >>>
    density: float | None = None,
    min_start_target_distance: float | None = None,
    require_arm_reachable: bool | None = None,
    max_attempts: int | None = None,
    template: str | None = None,
    # <<< options:generate_scenario
) -> Scenario: ...
def write_atomic(path: str | PathLike[str], data: bytes | str) -> None: ...
def machine() -> str: ...
def expand_names(names: str) -> list[str]: ...

# The env server (dm_env_rpc v1 over gRPC; docs/SERVER.md).
@final
class Server:
    @property
    def address(self) -> str: ...
    @property
    def port(self) -> int | None: ...
    @property
    def running(self) -> bool: ...
    @property
    def worlds(self) -> int: ...
    @property
    def sessions(self) -> int: ...
    def stop(self) -> None: ...
    def __enter__(self) -> Self: ...
    def __exit__(self, *_args: object) -> bool: ...

# The env server's client (sixaxis_avoid.remote's default transport; docs/SERVER.md).
@final
class DmEnvClient:
    def __new__(
        cls,
        address: str,
        *,
        token: str | None = None,
        timeout: float = 30.0,
        connect_timeout: float = 10.0,
    ) -> Self: ...
    @property
    def address(self) -> str: ...
    @property
    def pending(self) -> int: ...
    @property
    def failed(self) -> bool: ...
    def send_create_world(self, settings: dict[str, object] | None = None) -> None: ...
    def send_join_world(self, world_name: str) -> None: ...
    def send_reset(self, settings: dict[str, object] | None = None) -> None: ...
    def send_step(
        self,
        actions: npt.NDArray[np.int32] | None,
        requested: Sequence[int],
        action_uid: int = 1,
    ) -> None: ...
    def send_leave_world(self) -> None: ...
    def send_destroy_world(self, world_name: str) -> None: ...
    def send_raw(self, request: bytes, what: str) -> None: ...
    def receive(self) -> Any: ...
    def step(
        self,
        actions: npt.NDArray[np.int32] | None,
        requested: Sequence[int],
        action_uid: int = 1,
    ) -> tuple[int, dict[int, Any]]: ...
    def close(self) -> None: ...

def serve(
    address: str = "127.0.0.1:0",
    *,
    uds: str | PathLike[str] | None = None,
    token: str | None = None,
    tls_cert: str | PathLike[str] | None = None,
    tls_key: str | PathLike[str] | None = None,
    max_sessions: int | None = None,
    max_worlds_per_session: int | None = None,
    max_envs_per_world: int | None = None,
    max_total_envs: int | None = None,
    max_message_bytes: int | None = None,
    idle_timeout: float | None = None,
    keepalive_interval: float | None = None,
    keepalive_timeout: float | None = None,
) -> Server: ...
