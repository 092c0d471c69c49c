"""``sixaxis_avoid.plan`` (Algorithm 2) and ``sixaxis_avoid.generate_scenario``."""

from __future__ import annotations

import json
import math
import subprocess

import numpy as np
import pytest
import sixaxis_avoid as sa

WALL_TIME_KEYS = {"wall_time_s", "learning_time_s"}


def without_wall_times(value):
    """The value with every wall-time field dropped, at any depth."""
    if isinstance(value, dict):
        return {k: without_wall_times(v) for k, v in value.items() if k not in WALL_TIME_KEYS}
    if isinstance(value, list):
        return [without_wall_times(v) for v in value]
    return value


def rpy_matrix(rpy_deg) -> np.ndarray:
    """R = Rz(rt_z) Ry(rt_y) Rx(rt_x) (eq. 12)."""
    x, y, z = np.radians(rpy_deg)
    rx = np.array([[1, 0, 0], [0, math.cos(x), -math.sin(x)], [0, math.sin(x), math.cos(x)]])
    ry = np.array([[math.cos(y), 0, math.sin(y)], [0, 1, 0], [-math.sin(y), 0, math.cos(y)]])
    rz = np.array([[math.cos(z), -math.sin(z), 0], [math.sin(z), math.cos(z), 0], [0, 0, 1]])
    return rz @ ry @ rx


@pytest.fixture(scope="module")
def simple_plan() -> sa.PlanResult:
    return sa.plan("paper_simple", seed=3)


@pytest.fixture(scope="module")
def clutter_plan() -> sa.PlanResult:
    return sa.plan("replan_clutter", seed=0)


def test_plan_paper_simple_succeeds_without_replans(simple_plan):
    r = simple_plan
    assert isinstance(r, sa.PlanResult)
    assert r.success and r.failure is None
    assert r.replans == 0 and r.added_obstacles == []
    assert r.path[0] == (0, -2, 4) and r.path[-1] == (0, 3, 0)
    assert r.poses_rad.shape == (len(r.path), 6)
    assert r.orientations_rpy_deg.shape == (len(r.path), 3)
    assert r.seed == 3
    assert r.cell_mm == 100.0
    assert r.arm_safe_distance == pytest.approx(0.76)
    assert r.interpolation_steps == 50
    assert r.obstacles == sa.Scenario("paper_simple").obstacles
    assert r.obstacle_boxes_mm == [] and r.to_dict()["obstacle_boxes_mm"] == []
    assert r.clearance_model == {"kind": "centres"}
    assert len(r.rounds) == 1 and r.rounds[0]["blocked_at"] is None
    assert r.rounds[0]["path"] == [list(c) for c in r.path]
    assert r.wall_time_s > 0
    assert "success=True" in repr(r)


def test_to_dict_equals_cli_json(simple_plan, sixaxis_bin):
    out = subprocess.run(
        [str(sixaxis_bin), "plan", "--scenario", "paper_simple", "--seed", "3", "-q"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    cli = json.loads(out)
    ours = simple_plan.to_dict()
    assert set(ours) == set(cli)
    assert without_wall_times(ours) == without_wall_times(cli)
    assert json.loads(simple_plan.to_json()) == ours


def test_plan_of_a_physical_world_lists_its_boxes(sixaxis_bin, tmp_path):
    """paper_simple re-gridded to 50 mm: the plan result carries the scenario's boxes (its
    obstacle cells are empty), the same in the CLI's JSON as in Python."""
    s = sa.Scenario("paper_simple").regrid(50)
    boxes = s.obstacle_boxes_mm
    assert len(boxes) == 19 and boxes == s.to_dict()["obstacle_boxes_mm"]
    r = sa.plan(s, seed=0, initial_q="distance")
    assert r.success and r.obstacles == []
    assert r.obstacle_boxes_mm == boxes
    ours = r.to_dict()
    assert ours["obstacle_boxes_mm"] == boxes
    scenario_file = tmp_path / "s50.json"
    scenario_file.write_text(s.to_json())
    cmd = [str(sixaxis_bin), "plan", "--scenario", str(scenario_file), "--seed", "0"]
    cmd += ["--initial-q", "distance", "-q"]
    cli = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
    assert cli["obstacle_boxes_mm"] == ours["obstacle_boxes_mm"]
    assert without_wall_times(cli) == without_wall_times(ours)


def test_plan_replan_clutter_needs_a_replan(clutter_plan):
    r = clutter_plan
    assert r.success, r.failure
    assert r.replans >= 1
    assert len(r.added_obstacles) == r.replans
    assert len(r.rounds) == r.replans + 1
    assert all(rd["blocked_at"] is not None for rd in r.rounds[:-1])
    for cell in r.added_obstacles:
        assert cell not in r.path


@pytest.mark.parametrize("which", ["simple_plan", "clutter_plan"])
def test_poses_reproduce_path_cells(which, request):
    r = request.getfixturevalue(which)
    arm = sa.Arm.from_scenario(
        sa.Scenario("paper_simple" if which == "simple_plan" else "replan_clutter")
    )
    # The start pose is the scenario's beta_0 (Table 1, printed to 4 decimals): its terminal
    # lies within 0.1 mm of the start cell (docs/SCENARIOS.md "Units and the arm").
    start_pos, _ = arm.fk(r.poses_rad[0])
    np.testing.assert_allclose(start_pos, np.array(r.path[0]) * r.cell_mm, atol=0.1)
    for cell, q, rpy in zip(r.path[1:], r.poses_rad[1:], r.orientations_rpy_deg[1:]):
        pos, rot = arm.fk(q)
        np.testing.assert_allclose(pos, np.array(cell) * r.cell_mm, atol=1e-6, rtol=0)
        np.testing.assert_allclose(rot, rpy_matrix(rpy), atol=1e-9)


def test_plan_is_deterministic_and_assist_switches(simple_plan):
    again = sa.plan("paper_simple", seed=3)
    assert without_wall_times(again.to_dict()) == without_wall_times(simple_plan.to_dict())
    off = sa.plan("paper_simple", seed=3, assist=False)
    learned = sa.train("paper_simple", seed=3, assist=False)
    assert off.rounds[0]["path"] == [list(c) for c in learned.path]
    assert off.rounds[0]["total_steps"] == learned.total_steps


def test_plan_episodes_and_max_replans(clutter_plan):
    few = sa.plan("paper_simple", seed=0, episodes=50)
    assert few.rounds[0]["total_steps"] == sa.train("paper_simple", seed=0, episodes=50).total_steps
    capped = sa.plan("replan_clutter", seed=0, max_replans=0)
    assert not capped.success
    assert "re-plan cap (0)" in capped.failure
    assert capped.added_obstacles == clutter_plan.added_obstacles[:1]
    assert capped.poses_rad.shape == (0, 6)


@pytest.mark.parametrize("seed", [0, 3, 11])
def test_generate_scenario_deterministic_connected_reachable(seed):
    s = sa.generate_scenario(seed)
    assert s == sa.generate_scenario(seed)
    assert s == sa.Scenario.load(f"generated:{seed}")
    assert s.name == f"generated:{seed}"
    assert s.start != s.target and s.start not in s.obstacles and s.target not in s.obstacles
    assert math.dist(s.start, s.target) >= 4.0
    path = sa.shortest_path(s)
    assert path is not None and path[0] == s.start and path[-1] == s.target
    planner = sa.PosePlanner(s)
    assert planner.cell_reachable(s.start) and planner.cell_reachable(s.target)
    # beta_0 is a pose at the start cell.
    pos, _ = sa.Arm.from_scenario(s).fk(np.radians(s.beta0_deg))
    np.testing.assert_allclose(pos, np.array(s.start) * s.cell_mm, atol=1e-6)


def test_generate_scenario_options():
    a, b = sa.generate_scenario(1), sa.generate_scenario(2)
    assert a != b
    box = ((-2, -2, -1), (2, 3, 3))
    s = sa.generate_scenario(5, density=0.2, bounds=box, min_start_target_distance=3.0)
    assert s.bounds == box
    assert s == sa.generate_scenario(
        5, density=0.2, bounds={"min": box[0], "max": box[1]}, min_start_target_distance=3.0
    )
    n_cells = 5 * 6 * 5
    assert len(s.obstacles) == round(0.2 * n_cells)
    empty = sa.generate_scenario(4, density=0.0, require_arm_reachable=False)
    assert empty.obstacles == []
    assert sa.generate_scenario(4, template="paper_complex").terminal_safe_distance == 0.95


BAD_PLAN = [
    ({"seed": -1}, "seed", "-1"),
    ({"seed": "x"}, "seed", "'x'"),
    ({"seed": True}, "seed", "True"),
    ({"episodes": 0}, "episodes", "0"),
    ({"episodes": 2**40}, "episodes", str(2**40)),
    ({"max_replans": -2}, "max_replans", "-2"),
]


@pytest.mark.parametrize(("kwargs", "name", "value"), BAD_PLAN)
def test_plan_bad_keywords(kwargs, name, value):
    with pytest.raises(sa.InvalidArgumentError) as info:
        sa.plan("paper_simple", **kwargs)
    assert info.value.name == name
    assert info.value.value == value
    assert name in str(info.value) and value in str(info.value)


BAD_GENERATE = [
    ({"density": 0.9}, "density", "0.9"),
    ({"density": math.nan}, "density", "NaN"),
    ({"min_start_target_distance": 0.5}, "min_start_target_distance", "0.5"),
    ({"bounds": (1, 2)}, "bounds", "1"),
    ({"bounds": ((0, 0, 0),)}, "bounds", "((0, 0, 0),)"),
    ({"bounds": ((0, 0, 0), (-1, 0, 0))}, "bounds", "[0, 0, 0]..[-1, 0, 0]"),
    ({"max_attempts": 0}, "max_attempts", "0"),
]


@pytest.mark.parametrize(("kwargs", "name", "value"), BAD_GENERATE)
def test_generate_scenario_bad_keywords(kwargs, name, value):
    with pytest.raises(sa.InvalidArgumentError) as info:
        sa.generate_scenario(1, **kwargs)
    assert info.value.name == name
    assert info.value.value == value


def test_generate_scenario_bad_seed_and_template():
    with pytest.raises(sa.InvalidArgumentError, match="seed"):
        sa.generate_scenario(-3)
    with pytest.raises(sa.ScenarioNotFoundError, match="nope"):
        sa.generate_scenario(1, template="nope")
    # No room for the distance asked for: a clear error naming the seed, not a hang.
    with pytest.raises(sa.InvalidArgumentError, match="seed"):
        sa.generate_scenario(
            1, bounds=((0, 0, 0), (1, 1, 1)), min_start_target_distance=5.0, max_attempts=5
        )


# --- Algorithm 2 over any path learner: every learner goes through the core's loop ---------


def test_plan_with_bfs_learner_runs_the_core_loop():
    s = sa.Scenario("replan_clutter")
    r = sa.plan(s, learner="bfs")
    assert r.success and r.replans >= 1
    # Each round's path is the breadth-first path of that round's world.
    for k, rnd in enumerate(r.rounds):
        added = r.added_obstacles[: rnd["added_obstacles"]]
        assert rnd["path"] == [list(c) for c in sa.shortest_path(s, extra_obstacles=added)], k
        assert rnd["total_steps"] == 0 and rnd["converged_episode"] is None
    assert r.path == sa.shortest_path(s, extra_obstacles=r.added_obstacles)
    capped = sa.plan(s, learner="bfs", max_replans=0)
    assert not capped.success and "re-plan cap (0)" in capped.failure


def test_plan_with_python_learner_is_called_per_round_by_the_core():
    s = sa.Scenario("replan_clutter")
    calls = []

    def learner(world, seed):
        calls.append((world, seed))
        return {"path": sa.shortest_path(world), "total_steps": 7}

    r = sa.plan(s, seed=5, learner=learner)
    bfs = sa.plan(s, learner="bfs")
    assert r.success and r.path == bfs.path and r.added_obstacles == bfs.added_obstacles
    assert len(calls) == len(r.rounds) == r.replans + 1 >= 2
    for k, (world, seed) in enumerate(calls):
        assert isinstance(world, sa.Scenario) and seed == 5
        # The round's world: the scenario with every point added so far appended.
        added = r.added_obstacles[: r.rounds[k]["added_obstacles"]]
        assert world.obstacles == s.obstacles + added
        assert (world.start, world.target) == (s.start, s.target)
    assert all(rnd["total_steps"] == 7 for rnd in r.rounds)

    class Learner:
        def __init__(self):
            self.rounds = 0

        def learn_path(self, world, seed):
            self.rounds += 1
            return sa.shortest_path(world)

    obj = Learner()
    assert sa.plan(s, learner=obj).path == bfs.path and obj.rounds == len(calls)


def test_plan_python_learner_errors():
    s = sa.Scenario("paper_simple")
    good = sa.shortest_path(s)

    class Boom(Exception):
        pass

    def raises(world, seed):
        raise Boom("from the learner")

    with pytest.raises(Boom, match="from the learner"):
        sa.plan(s, learner=raises)
    jump = [good[0], good[2], *good[3:]]
    for bad, words in [
        (good[1:], "must start at the start cell"),
        (good[:-1], "must end at the target cell"),
        (jump, "is not a move to one of the six neighbouring cells"),
        ([s.start, *[(0, 3, 9)], s.target], "out of bounds"),
    ]:
        with pytest.raises(sa.InvalidArgumentError, match=words) as info:
            sa.plan(s, learner=lambda world, seed, bad=bad: bad)
        assert info.value.name == "path"
    none = sa.plan(s, learner=lambda world, seed: None)
    assert not none.success and "returned no path (round 0)" in none.failure
    # A learner may say why it found no path; the core appends the round.
    said = sa.plan(s, learner=lambda world, seed: {"path": None, "reason": "no env here"})
    assert not said.success and said.failure == "no env here (round 0)"
    unsaid = sa.plan(s, learner=lambda world, seed: {"path": None, "reason": None})
    assert "returned no path (round 0)" in unsaid.failure
    with pytest.raises(sa.InvalidArgumentError, match="must be a string or None") as info:
        sa.plan(s, learner=lambda world, seed: {"path": None, "reason": 7})
    assert info.value.name == "learner result `reason`"
    with pytest.raises(sa.InvalidArgumentError, match="learner"):
        sa.plan(s, learner="dqn")
    with pytest.raises(sa.InvalidArgumentError, match="learner"):
        sa.plan(s, learner=3)
    with pytest.raises(sa.InvalidArgumentError, match="must return a list"):
        sa.plan(s, learner=lambda world, seed: 5)


def wrap(a: np.ndarray) -> np.ndarray:
    """Angles wrapped to (-pi, pi]."""
    return np.pi - np.mod(np.pi - a, 2 * np.pi)


def polyline_cube_distance_mm(points: np.ndarray, obstacles, cell_mm: float, samples: int):
    """Distance from a polyline (mm) to the nearest obstacle cube, sampled along each segment:
    at least the exact distance, and above it by at most half a sample spacing."""
    t = np.linspace(0.0, 1.0, samples)[:, None]
    pts = np.concatenate([a + (b - a) * t for a, b in zip(points[:-1], points[1:])])
    centres = np.asarray(obstacles, dtype=float) * cell_mm
    d = np.maximum(np.abs(pts[:, None, :] - centres[None, :, :]) - cell_mm / 2, 0.0)
    return float(np.linalg.norm(d, axis=2).min())


def test_paper_complex_paper_mode_result_keys_and_clearances():
    """Table 3 in the paper mode: one re-plan, n_d 8 then 16; both clearance figures of the
    final motion re-checked here over every interpolation step."""
    r = sa.plan("paper_complex", seed=0)
    assert r.success and r.replans == 1 and r.added_obstacles == [(0, 2, 0)]
    assert [rd["orientation_divisions"] for rd in r.rounds] == [8, 16]
    assert [rd["mode"] for rd in r.rounds] == ["paper", "paper"]
    d = r.to_dict()
    assert d["min_centre_clearance_cells"] == r.min_centre_clearance_cells
    assert d["min_cube_distance_mm"] == r.min_cube_distance_mm
    arm = sa.Arm.from_scenario(sa.Scenario("paper_complex"))
    centre, cube = math.inf, math.inf
    samples = 150
    steps = r.interpolation_steps
    for q0, q1 in zip(r.poses_rad[:-1], r.poses_rad[1:]):
        for k in range(steps + 1):
            q = wrap(q0 + wrap(q1 - q0) * k / steps)
            pts = np.asarray(arm.points_mm(q))
            for a, b in zip(pts[:-1], pts[1:]):
                for o in r.obstacles:
                    c = np.asarray(o, dtype=float) * r.cell_mm
                    w = np.clip(np.dot(c - a, b - a) / max(np.dot(b - a, b - a), 1e-300), 0, 1)
                    centre = min(centre, float(np.linalg.norm(a + w * (b - a) - c)) / r.cell_mm)
            cube = min(cube, polyline_cube_distance_mm(pts, r.obstacles, r.cell_mm, samples))
    assert r.min_centre_clearance_cells == pytest.approx(centre, abs=1e-9)
    assert r.min_centre_clearance_cells > r.arm_safe_distance
    # Longest link 300 mm: samples every 300 / 149 mm, so at most ~1 mm above the exact value.
    assert r.min_cube_distance_mm <= cube + 1e-9
    assert cube - r.min_cube_distance_mm < 1.1
    failed = sa.plan("paper_complex", seed=0, max_replans=0)
    assert failed.min_cube_distance_mm is None and failed.min_centre_clearance_cells is None


def test_pose_planner_round_follows_the_nd_rule():
    s = sa.Scenario("paper_complex")
    assert [sa.PosePlanner(s, round=k).orientation_divisions for k in range(5)] == [
        8,
        16,
        32,
        64,
        64,
    ]
    fixed = sa.Scenario("replan_clutter")
    assert sa.PosePlanner(fixed, round=3).orientation_divisions == 8
    d = json.loads(s.to_json())
    d["planning"]["orientation_divisions_max"] = 48
    with pytest.raises(sa.ScenarioError) as e:
        sa.Scenario.from_json(json.dumps(d))
    assert e.value.field == "planning.orientation_divisions_max" and e.value.value == "48"
