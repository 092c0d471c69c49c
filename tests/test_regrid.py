"""Physical worlds from Python: `Scenario.regrid`, `sixaxis regrid`, `episodes="auto"`."""

from __future__ import annotations

import json
import subprocess

import pytest
import sixaxis_avoid as sa


def test_regrid_keeps_points_and_distances_in_mm():
    s = sa.Scenario("paper_simple").regrid(50)
    assert s.cell_mm == 50.0
    assert s.start == (0, -4, 8) and s.target == (0, 6, 0)
    d = s.to_dict()
    assert d["terminal_safe_distance_mm"] == 96.0 and d["arm_safe_distance_mm"] == 76.0
    assert d["obstacles"] == [] and len(d["obstacle_boxes_mm"]) == 19
    assert all(b["distance_to"] == "centre" for b in d["obstacle_boxes_mm"])
    assert sa.Scenario(d).to_json() == s.to_json()


def test_regrid_off_grid_point_is_an_error():
    with pytest.raises(sa.InvalidArgumentError, match="start"):
        sa.Scenario("paper_simple").regrid(30)
    with pytest.raises(sa.InvalidArgumentError, match="cell_mm"):
        sa.Scenario("paper_simple").regrid(-1.0)


def test_auto_episodes_reach_the_optimum_at_50mm():
    s = sa.Scenario("paper_simple").regrid(50)
    fixed = sa.train(s, seed=0)  # the paper's 10,000 episodes (M = 9,900) are too few here
    auto = sa.train(s, seed=0, episodes="auto")
    assert fixed.path is None
    assert auto.path is not None and len(auto.path) - 1 == 18
    with pytest.raises(sa.InvalidArgumentError, match="episodes"):
        sa.train(s, episodes="forever")


def test_cli_regrid_and_auto_match_python(sixaxis_bin, tmp_path):
    out = tmp_path / "s50.json"
    cmd = [str(sixaxis_bin), "regrid", "--scenario", "paper_simple", "--cell-mm", "50"]
    subprocess.run([*cmd, "--out", str(out)], check=True)
    assert sa.Scenario(out).to_json() == sa.Scenario("paper_simple").regrid(50).to_json()
    train = [str(sixaxis_bin), "train", "--scenario", str(out), "--episodes", "auto", "-q"]
    cli = json.loads(subprocess.run(train, check=True, capture_output=True, text=True).stdout)
    py = sa.train(out, episodes="auto")
    assert [tuple(c) for c in cli["path"]] == py.path
    assert cli["episodes_auto"] is True
    assert cli["episodes_run"] == len(py.steps_per_episode)
    assert cli["converged_episode"] == py.converged_episode


def test_distance_initial_q_reaches_the_optimum_at_each_size(sixaxis_bin, tmp_path):
    """``initial_q="distance"``: the BFS optimum at 50 and 25 mm, in far fewer steps than the
    paper's Q = 0; CLI and Python give the same run; the paper's default is unchanged."""
    for cell in (50, 25):
        s = sa.Scenario("paper_simple").regrid(cell)
        assert s.to_dict()["learning"]["initial_q"] == "zero"
        r = sa.train(s, seed=0, episodes="auto", initial_q="distance")
        assert r.path is not None and len(r.path) == len(sa.shortest_path(s))
        if cell == 50:
            zero = sa.train(s, seed=0, episodes="auto")
            assert r.total_steps * 10 < zero.total_steps
        out = tmp_path / f"s{cell}.json"
        out.write_text(s.to_json())
        flags = ["--episodes", "auto", "--initial-q", "distance", "-q", "--no-curve"]
        cmd = [str(sixaxis_bin), "train", "--scenario", str(out), *flags]
        cli = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
        assert [tuple(c) for c in cli["path"]] == r.path
        assert cli["total_steps"] == r.total_steps and cli["initial_q"] == "distance"
    # The rule in the scenario file means the same as the keyword.
    d = sa.Scenario("paper_simple").regrid(25).to_dict()
    d["learning"]["initial_q"] = "distance"
    by_file = sa.train(sa.Scenario(d), seed=0, episodes="auto")
    assert by_file.total_steps == r.total_steps and by_file.path == r.path
    p = sa.plan(sa.Scenario(d), seed=0, episodes="auto")
    assert p.success and p.path == r.path
    # An explicit table still works, and the CLI refuses a table and a rule together.
    resumed = sa.train(sa.Scenario(d), seed=1, episodes=5, initial_q=by_file.q)
    assert resumed.path is not None and len(resumed.path) == len(by_file.path)
    proc = subprocess.run(
        [*cmd[:4], "--q-in", str(tmp_path / "q.bin"), "--initial-q", "distance"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2 and "initial-q" in proc.stderr
