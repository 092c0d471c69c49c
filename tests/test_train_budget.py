"""The learner's env-step budget, its env-step epsilon schedule and the greedy-path
checkpoints of ``sixaxis_avoid.train`` (docs/SCENARIOS.md, "The learner: choices where the
paper is silent")."""

from __future__ import annotations

import numpy as np
import pytest
import sixaxis_avoid as sa


def fnv1a(data: bytes) -> int:
    h = 0xCBF29CE484222325
    for b in data:
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h


def test_the_episode_schedule_is_bit_identical_to_before():
    # Figures of the same call before the budget and env-step schedule existed.
    r = sa.train("paper_simple", episodes=2000, seed=3)
    assert r.total_steps == 162_916
    assert r.converged_episode == 1999
    assert fnv1a(np.ascontiguousarray(r.q, dtype="<f8").tobytes()) == 0x223FF8F74B563B48
    assert r.to_dict()["epsilon_schedule"] == "episodes"
    assert r.checkpoints == []


@pytest.mark.parametrize("schedule", ["episodes", "env_steps"])
@pytest.mark.parametrize("budget", [1, 1001, 25_000])
def test_a_budget_stops_at_exactly_max_env_steps(schedule, budget):
    r = sa.train(
        "paper_simple", seed=2, episodes=budget, max_env_steps=budget, epsilon_schedule=schedule
    )
    assert r.total_steps == budget
    assert int(np.sum(r.steps_per_episode)) == budget
    assert r.to_dict()["max_env_steps"] == budget


def test_epsilon_depends_on_the_step_and_d_only():
    # D = 2,500 in both runs (0.5 x 5,000 and 1.0 x 2,500): the longer run's first 2,500
    # steps are the shorter run, whose last episode is cut at the budget.
    kw = dict(seed=4, episodes=5000, epsilon_schedule="env_steps", epsilon_start=1.0)
    long = sa.train(
        "paper_simple", max_env_steps=5000, epsilon_decay_fraction=0.5, checkpoints=[2500], **kw
    )
    short = sa.train("paper_simple", max_env_steps=2500, epsilon_decay_fraction=1.0, **kw)
    k = len(short.steps_per_episode)
    assert np.array_equal(long.steps_per_episode[: k - 1], short.steps_per_episode[:-1])
    assert long.steps_per_episode[k - 1] >= short.steps_per_episode[-1]
    want = None if short.path is None else [list(p) for p in short.path]
    assert long.checkpoints[0]["path"] == want
    # epsilon_start 1 explores at every step before D: a different run from fraction 0 (no
    # exploration at all).
    greedy = sa.train("paper_simple", max_env_steps=5000, epsilon_decay_fraction=0.0, **kw)
    assert not np.array_equal(greedy.q, long.q)


def test_checkpoints_equal_runs_stopped_there():
    budget = 200_000
    # fraction 0.5: D = 100,000; a run stopped at c keeps D with fraction 100,000 / c (exact
    # in binary for these c).
    cps = [1, 6_250, 50_000, 80_000, 100_000, 128_000, 160_000, 200_000]
    for schedule in ("episodes", "env_steps"):
        kw = dict(
            seed=11,
            episodes=budget,
            epsilon_schedule=schedule,
            epsilon_decay_episodes=1500,
        )
        with_cp = sa.train(
            "paper_simple",
            max_env_steps=budget,
            epsilon_decay_fraction=0.5,
            checkpoints=cps,
            **kw,
        )
        plain = sa.train("paper_simple", max_env_steps=budget, epsilon_decay_fraction=0.5, **kw)
        assert np.array_equal(with_cp.q, plain.q)
        got = with_cp.checkpoints
        assert [c["env_steps"] for c in got] == cps
        for c in got:
            again = sa.train(
                "paper_simple",
                max_env_steps=c["env_steps"],
                epsilon_decay_fraction=100_000 / c["env_steps"],
                **kw,
            )
            want = None if again.path is None else [list(p) for p in again.path]
            assert c["path"] == want, (schedule, c["env_steps"])
            assert c["episode"] == len(again.steps_per_episode) - 1
            assert c["wall_time_s"] >= 0 and (c["cpu_time_s"] is None or c["cpu_time_s"] >= 0)
        assert got[0]["path"] is None and got[-1]["path"] is not None
        assert got[-1]["path"] == [list(p) for p in with_cp.path]
        assert with_cp.to_dict()["checkpoints"] == got
        twice = sa.train(
            "paper_simple",
            max_env_steps=budget,
            epsilon_decay_fraction=0.5,
            checkpoints=cps,
            **kw,
        )
        assert [(c["episode"], c["path"]) for c in twice.checkpoints] == [
            (c["episode"], c["path"]) for c in got
        ]


def test_bad_values_name_the_field():
    with pytest.raises(ValueError, match=r"`epsilon_schedule` = env_steps: needs a budget"):
        sa.train("paper_simple", epsilon_schedule="env_steps")
    with pytest.raises(ValueError, match=r"`checkpoints` = 0"):
        sa.train("paper_simple", episodes=5, checkpoints=[0])
    with pytest.raises(ValueError, match=r"`checkpoints` = 101: is beyond max_env_steps = 100"):
        sa.train("paper_simple", max_env_steps=100, checkpoints=[50, 101])
    with pytest.raises(ValueError, match=r"`checkpoints`"):
        sa.train("paper_simple", episodes=5, checkpoints="often")
    with pytest.raises(ValueError, match=r"`epsilon_decay_fraction` = -1"):
        sa.train("paper_simple", max_env_steps=10, epsilon_decay_fraction=-1.0)
