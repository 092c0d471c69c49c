"""`sixaxis_avoid.train`: the core's Q-learner from Python."""

from __future__ import annotations

import numpy as np
import pytest
import sixaxis_avoid as sa


@pytest.fixture(scope="module")
def result(paper_simple):
    return sa.train(paper_simple, seed=3)  # the paper's 10,000 episodes: ~0.1 s


def test_result_fields(result, paper_simple):
    assert result.success
    assert result.path[0] == paper_simple.start and result.path[-1] == paper_simple.target
    assert result.path_array.shape == (len(result.path), 3)
    assert result.path_array.dtype == np.int32
    spe = result.steps_per_episode
    assert spe.shape == (10000,) and spe.dtype == np.uint32
    assert int(spe.sum()) == result.total_steps
    assert result.reached_per_episode.dtype == np.bool_
    assert result.q.shape == (7 * 9 * 8, 6) and result.q.dtype == np.float64
    assert result.state_cells.shape == (7 * 9 * 8, 3)
    assert result.converged_episode is not None and 0 <= result.converged_episode < 10000
    assert result.episodes == 10000 and result.seed == 3
    assert result.wall_time_s > 0
    for a, b in zip(result.path[:-1], result.path[1:]):
        assert np.abs(np.subtract(a, b)).sum() == 1
    assert repr(result).startswith("TrainResult(success=True, path_len=")


def test_same_seed_same_path_and_q(result, paper_simple):
    again = sa.train(paper_simple, seed=3)
    assert again.path == result.path
    np.testing.assert_array_equal(again.q, result.q)  # bit for bit
    np.testing.assert_array_equal(again.steps_per_episode, result.steps_per_episode)
    other = sa.train(paper_simple, seed=4)
    assert not np.array_equal(other.q, result.q)


def test_q_rows_follow_state_cells(result, paper_simple):
    # The learned path is the greedy rollout of the Q-table (eq. 8), lowest index on ties.
    assert sa.greedy_path_of(result.q, paper_simple) == result.path
    for cell in result.path[:-1]:
        s = result.state_of(cell)
        assert tuple(result.state_cells[s]) == cell


def test_keywords_default_to_the_scenario(paper_simple):
    small = paper_simple.replace(learning={"episodes": 50, "seed": 9})
    a = sa.train(small)
    b = sa.train(paper_simple, episodes=50, seed=9)
    np.testing.assert_array_equal(a.q, b.q)
    c = sa.train(paper_simple, episodes=50, seed=9, assist=False)
    assert not np.array_equal(c.q, a.q)


def test_save_load_round_trip(result, paper_simple, tmp_path):
    p = tmp_path / "q.bin"
    result.save_q(p)
    q = sa.load_q(p, paper_simple)
    np.testing.assert_array_equal(q, result.q)
    other = paper_simple.replace(target=(1, 3, 0))
    with pytest.raises(sa.QTableMismatchError):
        sa.load_q(p, other)


def test_resume_from_initial_q(result, paper_simple):
    more = sa.train(paper_simple, episodes=20, seed=5, initial_q=result.q)
    assert more.success
    assert more.q.shape == result.q.shape


def test_progress_callback_and_its_errors(paper_simple):
    seen = []
    sa.train(paper_simple, episodes=200, seed=0, progress=seen.append)
    assert seen and seen[-1] == 200 and seen == sorted(seen)

    def boom(done):
        raise KeyError("stop")

    with pytest.raises(KeyError):
        sa.train(paper_simple, episodes=50, seed=0, progress=boom)


def test_extra_obstacles(paper_simple):
    path = sa.shortest_path(paper_simple)
    blocked = path[len(path) // 2]
    detour = sa.shortest_path(paper_simple, extra_obstacles=[blocked])
    assert blocked not in detour
