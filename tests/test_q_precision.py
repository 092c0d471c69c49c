"""``q_precision="f32"``: Q-values stored as float32 (half the memory per state), from the
CLI and from Python alike; the default stays the paper's float64."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest
import sixaxis_avoid as sa

EPISODES = 10000  # the paper's


@pytest.fixture(scope="module")
def f32_run(paper_simple):
    return sa.train(paper_simple, seed=2, episodes=EPISODES, q_precision="f32")


def test_f32_result_is_float32_and_deterministic(f32_run, paper_simple):
    assert f32_run.q_precision == "f32"
    assert f32_run.q.dtype == np.float32 and f32_run.q.shape == (7 * 9 * 8, 6)
    again = sa.train(paper_simple, seed=2, episodes=EPISODES, q_precision="f32")
    np.testing.assert_array_equal(again.q, f32_run.q)
    assert again.path == f32_run.path
    np.testing.assert_array_equal(again.steps_per_episode, f32_run.steps_per_episode)
    f64 = sa.train(paper_simple, seed=2, episodes=EPISODES)
    assert f64.q_precision == "f64" and f64.q.dtype == np.float64
    assert sa.greedy_path_of(f32_run.q, paper_simple) == f32_run.path


def test_f32_cli_equals_python_and_file_round_trip(sixaxis_bin, tmp_path, f32_run, paper_simple):
    q_file = tmp_path / "q.bin"
    cmd = [str(sixaxis_bin), "train", "--scenario", "paper_simple", "--seed", "2", "-q"]
    cmd += ["--episodes", str(EPISODES), "--q-precision", "f32", "--q-out", str(q_file)]
    cli = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
    assert cli["q_precision"] == "f32"
    assert cli["q_table_bytes"] == 7 * 9 * 8 * 6 * 4
    assert f32_run.success and [tuple(c) for c in cli["path"]] == f32_run.path
    assert cli["steps_per_episode"] == f32_run.steps_per_episode.tolist()
    loaded = sa.load_q(q_file, paper_simple)
    assert loaded.dtype == np.float32
    np.testing.assert_array_equal(loaded, f32_run.q)  # the CLI's table, bit for bit
    # Python's own save: the same bytes as the CLI's.
    f32_run.save_q(tmp_path / "py.bin")
    assert (tmp_path / "py.bin").read_bytes() == q_file.read_bytes()


def test_a_table_of_either_dtype_resumes_either_run(f32_run, paper_simple):
    # A float32 table in an f64 run is widened exactly; the result has the run's precision.
    a = sa.train(paper_simple, seed=5, episodes=20, initial_q=f32_run.q)
    b = sa.train(paper_simple, seed=5, episodes=20, initial_q=f32_run.q.astype(np.float64))
    assert a.q.dtype == np.float64
    np.testing.assert_array_equal(a.q, b.q)
    # A float64 table in an f32 run is rounded to float32 first.
    c = sa.train(paper_simple, seed=5, episodes=20, initial_q=b.q, q_precision="f32")
    d = sa.train(
        paper_simple, seed=5, episodes=20, initial_q=b.q.astype(np.float32), q_precision="f32"
    )
    assert c.q.dtype == np.float32
    np.testing.assert_array_equal(c.q, d.q)
    with pytest.raises(sa.InvalidArgumentError) as info:
        sa.train(paper_simple, episodes=1, initial_q=np.zeros(f32_run.q.shape, np.float16))
    assert info.value.name == "initial_q"


def test_scenario_field_sets_the_default(paper_simple):
    d = paper_simple.to_dict()
    assert d["learning"]["q_precision"] == "f64"
    d["learning"]["q_precision"] = "f32"
    r = sa.train(sa.Scenario(d), seed=0, episodes=50)
    assert r.q.dtype == np.float32
    assert sa.train(sa.Scenario(d), seed=0, episodes=50, q_precision="f64").q.dtype == np.float64
    d["learning"]["q_precision"] = "half"
    with pytest.raises(sa.ScenarioError, match=r"`learning.q_precision` = half: must be one of"):
        sa.Scenario(d)


def test_plan_with_f32_values(paper_simple):
    p = sa.plan(paper_simple, seed=0, q_precision="f32")
    assert p.success
    assert p.path[0] == paper_simple.start and p.path[-1] == paper_simple.target


def test_cli_resumes_an_f32_file_in_an_f64_run(sixaxis_bin, tmp_path, f32_run, paper_simple):
    """``--q-in`` of an f32 file into the default f64 run: widened exactly, as from Python."""
    q32 = tmp_path / "q32.bin"
    f32_run.save_q(q32)
    q_out = tmp_path / "out.bin"
    cmd = [str(sixaxis_bin), "train", "--scenario", "paper_simple", "--seed", "7", "-q"]
    cmd += ["--episodes", "30", "--q-in", str(q32), "--q-out", str(q_out)]
    cli = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
    py = sa.train(paper_simple, seed=7, episodes=30, initial_q=sa.load_q(q32, paper_simple))
    assert cli["q_precision"] == "f64" and cli["total_steps"] == py.total_steps
    out = sa.load_q(q_out, paper_simple)
    assert out.dtype == np.float64
    np.testing.assert_array_equal(out, py.q)
