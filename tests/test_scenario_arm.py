"""Scenario and Arm bindings."""

from __future__ import annotations

import copy
import math
import pickle

import numpy as np
import pytest
import sixaxis_avoid as sa


def test_builtins_and_properties(paper_simple):
    assert set(sa.Scenario.builtin_names()) >= {"paper_simple", "paper_complex", "replan_clutter"}
    assert paper_simple == sa.Scenario() == sa.Scenario.load("paper_simple")
    assert paper_simple.start == (0, -2, 4) and paper_simple.target == (0, 3, 0)
    assert len(paper_simple.obstacles) == 19
    assert paper_simple.bounds == ((-3, -3, -2), (3, 5, 5))
    assert paper_simple.shape == [7, 9, 8]
    assert paper_simple.terminal_safe_distance == 0.96
    assert paper_simple.arm_safe_distance == 0.76
    assert paper_simple.cell_mm == 100.0
    assert paper_simple.rewards["target_reward"] == 20000.0
    assert 'Scenario(name="paper_simple"' in repr(paper_simple)


def test_round_trips(paper_simple, tmp_path):
    assert sa.Scenario.from_dict(paper_simple.to_dict()) == paper_simple
    assert sa.Scenario.from_json(paper_simple.to_json()) == paper_simple
    assert pickle.loads(pickle.dumps(paper_simple)) == paper_simple
    assert copy.deepcopy(paper_simple) == paper_simple
    assert hash(paper_simple) == hash(sa.Scenario())
    p = tmp_path / "x.json"
    p.write_text(paper_simple.to_json())
    assert sa.Scenario(p) == paper_simple
    d = paper_simple.to_dict()
    d["obstacles"] = np.array(d["obstacles"])  # NumPy values are accepted
    d["terminal_safe_distance"] = np.float64(0.9)
    assert sa.Scenario.from_dict(d).terminal_safe_distance == 0.9


def test_replace_merges_sections(paper_simple):
    s = paper_simple.replace(learning={"episodes": 7}, target=(1, 3, 0))
    assert s.learning["episodes"] == 7
    assert s.learning["alpha"] == paper_simple.learning["alpha"]
    assert s.target == (1, 3, 0)
    assert paper_simple.learning["episodes"] == 10000  # unchanged
    s.validate()


def test_fk_reaches_start_cell_with_identity(paper_simple):
    arm = sa.Arm.from_scenario(paper_simple)
    q = np.radians(paper_simple.beta0_deg)
    pos, rot = arm.fk(q)
    np.testing.assert_allclose(pos, [0.0, -200.0, 400.0], atol=0.1)
    np.testing.assert_allclose(rot, np.eye(3), atol=1e-4)
    pts = arm.points_mm(q)
    assert pts.shape == (8, 3)
    np.testing.assert_allclose(pts[0], 0.0)
    np.testing.assert_allclose(pts[-1], pos)
    assert arm.fk_batch(np.stack([q, q])).shape == (2, 3)
    assert arm.dh == sa.Arm().dh
    assert len(arm.dh) == 6


def test_custom_dh():
    arm = sa.Arm(dh=[(0.0, 0.0, 0.0, 0.0)] * 5 + [(0.0, 0.0, 100.0, 0.0)])
    pos, _ = arm.fk([0.0] * 6)
    np.testing.assert_allclose(pos, [0, 0, 100])
    with pytest.raises(sa.InvalidArgumentError, match="dh"):
        sa.Arm(dh=[(0, 0, 0)] * 6)
    with pytest.raises(sa.InvalidArgumentError, match="dh"):
        sa.Arm(dh=[(0, 0, 0, math.inf)] * 6)


def test_ik_round_trip():
    arm = sa.Arm()
    q = np.radians([57.9948, -10.1070, -132.9377, 53.0502, 90.0002, 32.0054])
    pos, rot = arm.fk(q)
    sols = arm.ik(pos, rotation=rot)
    assert sols.ndim == 2 and sols.shape[1] == 6 and 1 <= len(sols) <= 8
    for s in sols:
        p2, r2 = arm.fk(s)
        np.testing.assert_allclose(p2, pos, atol=1e-6)
        np.testing.assert_allclose(r2, rot, atol=1e-6)


def test_ik_by_rpy_and_errors():
    arm = sa.Arm()
    sols = arm.ik([0.0, -200.0, 400.0], rpy_deg=[0.0, 0.0, 0.0])
    assert 1 <= len(sols) <= 8
    for q in sols:
        np.testing.assert_allclose(arm.fk(q)[0], [0.0, -200.0, 400.0], atol=1e-6)
    assert arm.ik([5000.0, 0.0, 0.0], rpy_deg=[0, 0, 0]).shape == (0, 6)  # out of reach
    with pytest.raises(sa.InvalidArgumentError, match="rotation"):
        arm.ik([0.0, -200.0, 400.0])
    with pytest.raises(sa.InvalidArgumentError, match="rotation"):
        arm.ik([0.0, -200.0, 400.0], np.eye(3) * 2)
    with pytest.raises(sa.InvalidArgumentError, match="position_mm"):
        arm.ik([0.0, math.nan, 400.0], np.eye(3))


def test_pose_planner(paper_simple):
    planner = sa.PosePlanner(paper_simple)
    clearance, q, _ = planner.best_clearance_at(paper_simple.target)
    # docs/SCENARIOS.md "Interpretations taken": the best clearance at the target (0,3,0) is
    # 0.87 cell.
    assert 0.85 < clearance < 0.88
    np.testing.assert_allclose(sa.Arm().fk(q)[0], [0.0, 300.0, 0.0], atol=1e-6)
    assert planner.cell_reachable(paper_simple.target)
    assert not planner.cell_reachable((0, 0, 20))
    plan = planner.plan_poses(sa.shortest_path(paper_simple))
    assert plan["complete"] and plan["blocked_cell"] is None
    assert plan["joints_rad"].shape == (plan["cells"].shape[0], 6)
    np.testing.assert_allclose(plan["joints_rad"][0], np.radians(paper_simple.beta0_deg))
    # The core's check_moves names the step (no second check in the bindings).
    with pytest.raises(sa.InvalidArgumentError, match="step 1 from") as e:
        planner.plan_poses([(0, -2, 4), (0, 0, 4)])
    assert e.value.name == "path" and "six neighbouring cells" in str(e.value)
    assert isinstance(e.value, ValueError)


def test_unreachable_cells_and_clear_pose(paper_simple):
    cells = sa.unreachable_cells(paper_simple)
    assert cells and paper_simple.target not in cells and paper_simple.start not in cells
    assert not sa.cells_reachable(cells, paper_simple).any()
    assert sa.clear_pose_at(paper_simple, cells[0]) is None
    q = sa.clear_pose_at(paper_simple, paper_simple.target)
    np.testing.assert_allclose(sa.Arm().fk(q)[0], [0.0, 300.0, 0.0], atol=1e-6)
