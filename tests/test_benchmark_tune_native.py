"""``benchmark tune-native``: seeded random search for the tabular learners at one budget
in env steps, every trial exported, the best values recorded per budget."""

from __future__ import annotations

import json

import numpy as np
import pytest
from sixaxis_avoid.benchmark import __main__ as cli
from sixaxis_avoid.benchmark.tasks import load_suite
from sixaxis_avoid.benchmark.tune import (
    NATIVE_SPACE,
    best_trial,
    native_score,
    record_by_budget,
    tune_native,
)


def test_trials_are_seeded_scored_on_every_task_and_seed_and_exported(tmp_path):
    a = tune_native("quick", "q_assist", 4000, 3, [100, 101], sampler_seed=5, progress=False)
    b = tune_native("quick", "q_assist", 4000, 3, [100, 101], sampler_seed=5, progress=False)
    assert [t["values"] for t in a["trials"]] == [t["values"] for t in b["trials"]]
    assert [t["objective"] for t in a["trials"]] == [t["objective"] for t in b["trials"]]
    other = tune_native("quick", "q_assist", 4000, 1, [100], sampler_seed=6, progress=False)
    assert other["trials"][0]["values"] != a["trials"][0]["values"]
    assert len(a["trials"]) == 3 and a["tasks"] == ["tune-gen-medium-1000"]
    for t in a["trials"]:
        for k, (lo, hi, _) in NATIVE_SPACE.items():
            assert lo <= t["values"][k] <= hi
        assert len(t["runs"]) == 2 and all(r["env_steps"] == 4000 for r in t["runs"])
        assert t["objective"] == pytest.approx(np.mean([r["score"] for r in t["runs"]]))
        assert 0.0 <= t["area"] <= 1.0
        assert t["area"] == pytest.approx(np.mean([r["area"] for r in t["runs"]]))
    assert a["best"]["objective"] == max(t["objective"] for t in a["trials"])
    assert a["checkpoints"] == load_suite("quick").checkpoints(4000)
    # A run's score is the benchmark's: same values, same seed, same score (the tuning
    # run's checkpoints do not change its final score).
    t0 = a["trials"][0]

    task = load_suite("quick").tuning_tasks[0]
    again = native_score("q_assist", task, 101, 4000, t0["values"])
    assert again["score"] == t0["runs"][1]["score"]
    hp = tmp_path / "v2.json"
    record_by_budget(hp, a, "trials.json", "cmd")
    record_by_budget(hp, {**a, "budget": 8000}, "trials8k.json", "cmd")
    entry = json.loads(hp.read_text())["learners"]["q_assist"]["by_budget"]
    assert set(entry) == {"4000", "8000"}
    assert entry["4000"]["values"] == a["best"]["values"]
    assert entry["4000"]["status"] == "tuned" and entry["4000"]["trials"] == "trials.json"
    assert entry["4000"]["objective"] == a["best"]["objective"]  # a number, as jax_tune's


def test_ties_on_the_objective_go_to_the_larger_area_then_the_earlier_trial():
    t = lambda n, obj, area: {"number": n, "objective": obj, "area": area}  # noqa: E731
    assert best_trial([t(0, 1.0, 0.2), t(1, 0.9, 0.9), t(2, 1.0, 0.7)])["number"] == 2
    assert best_trial([t(0, 1.0, 0.7), t(1, 1.0, 0.7)])["number"] == 0
    # Equal up to rounding noise of a mean is a tie, not a win.
    assert best_trial([t(0, 1.0 - 1e-15, 0.9), t(1, 1.0, 0.1)])["number"] == 0
    assert best_trial([t(0, 0.5, 1.0), t(1, 0.6, 0.0)])["number"] == 1


def test_the_command_writes_the_export(tmp_path, capsys):
    out = tmp_path / "q_plain-3000.json"
    argv = ["tune-native", "--suite", "quick", "--learners", "q_plain", "--budget", "3000"]
    argv += ["--trials", "2", "--seeds", "2", "--out", str(out), "--no-progress"]
    assert cli.main(argv) == 0
    data = json.loads(out.read_text())
    assert data["learner"] == "q_plain" and data["seeds"] == [100, 101]
    assert data["command"].endswith("--no-progress") and len(data["trials"]) == 2
    with pytest.raises(SystemExit, match="q_paper"):
        cli.main(["tune-native", "--learners", "q_paper", "--budget", "3000"])
