"""The SB3 learners' entries derived from their JAX twin's tuned values
(``python -m sixaxis_avoid.benchmark.borrow``)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from sixaxis_avoid.benchmark import borrow, sb3_tune
from sixaxis_avoid.benchmark.hyperparams import HYPERPARAMS_DIR

V2 = HYPERPARAMS_DIR / "v2.json"


def test_committed_sb3_entries_are_borrowed_or_won_by_their_own_search():
    # Every SB3 ppo/dqn entry of the committed file is either the one borrow derives from
    # its twin's entry at the same budget (the 30k entries were written before the tool
    # existed, so their free-text source may differ), or the winner of SB3's own search at
    # that budget (sb3_tune --record): a complete search whose candidates include the
    # borrowed values, and whose best trial by the tie rule gave the entry's values.
    data = json.loads(V2.read_text())
    root = HYPERPARAMS_DIR.parents[3]
    found = 0
    for learner in borrow.TWIN:
        for budget, entry in data["learners"].get(learner, {}).get("by_budget", {}).items():
            want = borrow.borrowed_entry(data, learner, int(budget))
            found += 1
            if "best_candidate" not in entry:
                for k in ("values", "status", "trials", "objective", "command", "date"):
                    assert entry[k] == want[k], (learner, budget, k)
                continue
            trials = json.loads((root / entry["trials"]).read_text())
            assert (trials["learner"], trials["budget"]) == (learner, int(budget))
            assert "sb3_tune" in entry["command"] and entry["status"] == "tuned"
            by_name = {t["name"]: t for t in trials["trials"]}
            assert by_name[sb3_tune.TWIN_CANDIDATE]["values"] == want["values"]
            runs = len(trials["seeds"]) * len(trials["tasks"])
            for t in trials["trials"]:
                scores = [x for xs in t["final_score"].values() for x in xs]
                assert len(scores) == runs and t["objective"] == pytest.approx(np.mean(scores))
            best = sb3_tune.best_trial(trials["trials"])
            assert trials["best_trial"] == best["number"]
            assert entry["best_candidate"] == best["name"] and entry["values"] == best["values"]
            assert entry["objective"] == best["objective"]
            assert entry["n_trials"] == len(trials["trials"]) >= 33
    assert found >= 2


def test_borrow_writes_the_entry_and_keeps_the_rest(tmp_path):
    hp = tmp_path / "hp.json"
    twin = {
        "values": {"learning_rate": 1e-3, "activation": "relu", "replay_sample": "with_replacement",
                   "gamma": 0.9},
        "status": "tuned", "trials": "t.json", "objective": 0.5, "command": "c", "date": "d",
        "n_trials": 32, "seeds": [1, 2, 3], "tasks": ["a", "b"],
    }  # fmt: skip
    hp.write_text(json.dumps({"note": "n", "learners": {"jax_dqn": {"by_budget": {"100": twin}},
                                                         "q_assist": {"x": 1}}}))  # fmt: skip
    entry = borrow.borrow(hp, "dqn", 100, "cmd")
    data = json.loads(hp.read_text())
    assert data["learners"]["dqn"]["by_budget"]["100"] == entry
    assert data["learners"]["q_assist"] == {"x": 1} and data["note"] == "n"
    assert entry["values"] == {"learning_rate": 1e-3, "gamma": 0.9, "implementation": "rejax"}
    assert entry["derived_by"] == "cmd" and entry["objective"] == 0.5
    assert "32 trials x 3 seeds x 2 tuning tasks" in entry["source"]
    assert "with replacement, as both draw them" in entry["source"]


def test_borrow_errors_name_the_field():
    base = {"status": "tuned", "values": {"activation": "tanh"}}
    data = {"learners": {"jax_dqn": {"by_budget": {"100": base}}}}
    with pytest.raises(borrow.BorrowError, match=r"values.activation: 'tanh' is not SB3's DQN"):
        borrow.borrowed_entry(data, "dqn", 100)
    with pytest.raises(borrow.BorrowError, match=r"learners.jax_ppo.by_budget.100: no tuned"):
        borrow.borrowed_entry(data, "ppo", 100)
    with pytest.raises(borrow.BorrowError, match=r"learner: 'a2c' has no JAX twin"):
        borrow.borrowed_entry(data, "a2c", 100)
