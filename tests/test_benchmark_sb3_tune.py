"""``sb3_tune``: SB3's PPO and DQN searched on their own at one budget of a budget axis:
the draws and the twin's values scored as benchmark runs without re-plans, every trial on
record, a stopped search resumed, the best recorded (docs/BENCHMARKS.md, *How to run*)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from sixaxis_avoid.benchmark import runner, sb3_tune
from sixaxis_avoid.benchmark.jax_values import check_values
from sixaxis_avoid.benchmark.learners import resolve
from sixaxis_avoid.benchmark.tasks import SUITES_DIR, load_suite

TINY = {
    "ppo": {"n_envs": 2, "n_steps": 100, "batch_size": 50, "n_epochs": 1, "net_arch": [16, 16],
            "max_episode_steps": 100},
    "dqn": {"net_arch": [16, 16], "batch_size": 16, "buffer_size": 1000, "learning_starts": 100,
            "train_freq": 4, "gradient_steps": 1, "max_episode_steps": 50,
            "target_update_interval": 100},
}  # fmt: skip


@pytest.fixture(params=["ppo", "dqn"])
def setup(request, tmp_path, monkeypatch):
    learner = request.param
    quick = json.loads((SUITES_DIR / "quick.json").read_text())
    suite = {**quick, "name": "sb3-tune-test", "budgets": {"axis": [400], "checkpoints": 2}}
    path = tmp_path / "suite.json"
    path.write_text(json.dumps(suite))
    # Two tiny draws (the space's draws are sized for the study, not for a test).
    monkeypatch.setattr(
        sb3_tune,
        "draw",
        lambda algo, trials, groups, seed: [
            check_values(algo, {**TINY[algo], "learning_rate": lr}) for lr in (3e-4, 1e-3)[:trials]
        ],
    )
    hp = tmp_path / "v2.json"
    values = check_values(learner, {**TINY[learner], "learning_rate": 2e-3})
    twin = {"values": values, "status": "tuned", "n_trials": 32, "seeds": [100],
            "tasks": ["tune-gen-medium-1000"]}  # fmt: skip
    hp.write_text(json.dumps({"learners": {f"jax_{learner}": {"by_budget": {"400": twin}}}}))
    return learner, path, hp


def test_the_search_scores_draws_and_twin_resumes_and_records(setup, tmp_path):
    learner, suite_path, hp = setup
    out = tmp_path / f"{learner}-400.json"
    argv = ["--learner", learner, "--suite", str(suite_path), "--budget", "400", "--trials", "2",
            "--seeds", "2", "--hyperparams", str(hp), "--out", str(out), "--no-ray"]  # fmt: skip
    a = sb3_tune.main(argv)
    assert [t["name"] for t in a["trials"]] == ["trial0", "trial1", "twin"]
    assert [t["values"]["implementation"] for t in a["trials"]] == ["sb3", "sb3", "rejax"]
    assert a["seeds"] == [100, 101] and a["tasks"] == ["tune-gen-medium-1000"]
    log_dir = tmp_path / f"{learner}-400.json.runs"
    runs = runner.load_runs(log_dir)
    assert len(runs) == 3 * 2 and a["runs"] == 6 and a["resumed_runs"] == 0
    defaults = dict(resolve(learner).defaults)
    overrides = load_suite(str(suite_path)).raw["overrides"][learner]
    for t in a["trials"]:
        scores = t["final_score"]["tune-gen-medium-1000"]
        assert len(scores) == 2 and t["objective"] == pytest.approx(np.mean(scores))
        mine = [r for r in runs if r["spec"]["tag"] == t["name"]]
        assert sorted(r["result"]["score"] for r in mine) == sorted(scores)
        for r in mine:
            # Exactly the candidate over the defaults, at the budget, without re-plans.
            assert r["spec"]["hyperparams"] == {**defaults, **overrides, **t["values"]}
            assert r["spec"]["max_replans"] == 0 and r["spec"]["budget"] == 400
            assert r["result"]["algorithm2"]["replans"] == 0
        assert t["curves"]["tune-gen-medium-1000"]["env_steps"][-1] <= 400
    top = max(t["objective"] for t in a["trials"])
    tied = [t for t in a["trials"] if t["objective"] == top]
    best = next((t for t in tied if t["name"] == "twin"), tied[0])
    assert a["best_trial"] == best["number"] and a["wall_time_s"] > 0 and a["cpu_time_s"] > 0

    # Stopped midway (a run lost): the same command runs that one only, with the same trials.
    lost = next((log_dir / "runs").glob("trial1__*.json"))
    lost.unlink()
    b = sb3_tune.main([*argv, "--record"])
    assert b["resumed_runs"] == 5 and b["trials"] == a["trials"]
    assert b["wall_time_s"] > a["wall_time_s"]  # the calls' wall times add up
    entry = json.loads(hp.read_text())["learners"][learner]["by_budget"]["400"]
    assert entry["values"] == best["values"] and entry["status"] == "tuned"
    assert entry["best_candidate"] == best["name"] and entry["n_trials"] == 3
    assert entry["objective"] == best["objective"] and entry["trials"] == str(out)


def test_a_budget_off_the_axis_and_an_unknown_implementation_are_refused(setup, tmp_path):
    learner, suite_path, hp = setup
    argv = ["--learner", learner, "--suite", str(suite_path), "--hyperparams", str(hp),
            "--out", str(tmp_path / "t.json"), "--no-ray"]  # fmt: skip
    with pytest.raises(SystemExit, match=r"--budget: 500 is not on suite .*\[400\]"):
        sb3_tune.main([*argv, "--budget", "500"])
    with pytest.raises(SystemExit, match=r"--implementation: 'mine' is not one of rejax, sb3"):
        sb3_tune.main([*argv, "--budget", "400", "--implementation", "mine"])
    assert not (tmp_path / "t.json").exists()


def test_a_search_stopped_on_request_is_a_set_in_progress_on_the_page(setup, tmp_path, monkeypatch):
    """With its log directory under a study's ``-pending`` directory, a search stopped on
    request (``STOP`` in the log directory, during its first run) exits 75 with that run
    kept, and its manifest names it on the page as SB3's own search in progress; the same
    command ends it (finished: true, the calls' wall times added)."""
    from sixaxis_avoid.benchmark.report_pending import in_progress_sentence, sets_in_progress

    learner, suite_path, hp = setup
    log_dir = tmp_path / "study-pending" / f"sb3_tune-{learner}-400"
    argv = ["--learner", learner, "--suite", str(suite_path), "--budget", "400", "--trials", "1",
            "--seeds", "1", "--hyperparams", str(hp), "--out", str(tmp_path / "t.json"),
            "--log-dir", str(log_dir), "--no-ray"]  # fmt: skip
    real = runner.execute_run

    def asking(spec):
        log_dir.mkdir(parents=True, exist_ok=True)
        (log_dir / runner.STOP_FILE).touch()
        return real(spec)

    monkeypatch.setattr(runner, "execute_run", asking)
    with pytest.raises(SystemExit) as stop:
        sb3_tune.main(argv)
    assert stop.value.code == runner.EXIT_STOPPED and not (tmp_path / "t.json").exists()
    man = json.loads((log_dir / "study.json").read_text())
    assert (man["kind"], man["finished"], man["ran_now"], man["runs"]) == ("sb3_tune", False, 1, 2)
    assert man["command"].startswith("python -m sixaxis_avoid.benchmark.sb3_tune --learner")
    (p,) = sets_in_progress(tmp_path / "study")
    assert (p["made"], p["of"], p["budgets"], p["finished"]) == (1, 2, [400], False)
    assert (
        f"SB3's own search for {learner} at 400 (2 candidates x 1 seeds x 1 tuning tasks), "
        f"1 of 2 runs in `{log_dir}`" in in_progress_sentence([p])
    )
    # The study has none of its run files, so it is no re-run; once the study has one of
    # the same name, the set is named as a re-run that replaces the study's runs there.
    assert p["replaces"] == 0 and "again" not in in_progress_sentence([p])
    (kept,) = (log_dir / "runs").glob("*.json")
    (tmp_path / "study" / "runs").mkdir(parents=True)
    (tmp_path / "study" / "runs" / kept.name).write_text(kept.read_text())
    (p,) = sets_in_progress(tmp_path / "study")
    assert p["replaces"] == 1 and "again" not in in_progress_sentence([p])  # a search's
    p["kind"] = "run"  # a run set (benchmark run) with those files: a re-run
    assert p["replaces"] == 1 and (
        "at 400 again on its current hyperparameters (to replace the study's runs there)"
        in in_progress_sentence([p])
    )
    (tmp_path / "study" / "runs" / kept.name).unlink()

    monkeypatch.setattr(runner, "execute_run", real)
    a = sb3_tune.main(argv)
    done = json.loads((log_dir / "study.json").read_text())
    assert done["finished"] is True and (done["skipped_now"], done["ran_now"]) == (1, 1)
    assert a["wall_time_s"] == pytest.approx(done["wall_time_s_total"])
    assert done["wall_time_s_total"] > man["wall_time_s_total"]


def test_the_best_trial_keeps_the_twins_values_unless_a_draw_scores_strictly_higher():
    """Outcomes near 0 or 1 make ties at the top common: a tie keeps the borrowed values
    (the twin's, which the study's runs already use); among draws alone, the first wins."""

    def trials(*scores):
        names = [f"trial{k}" for k in range(len(scores) - 1)] + ["twin"]
        return [{"number": k, "name": n, "objective": o}
                for k, (n, o) in enumerate(zip(names, scores))]  # fmt: skip

    assert sb3_tune.best_trial(trials(1.0, 0.4, 1.0))["name"] == "twin"
    assert sb3_tune.best_trial(trials(0.9, 1.0, 0.95))["name"] == "trial1"
    assert sb3_tune.best_trial(trials(1.0, 1.0, 0.95))["name"] == "trial0"
    no_twin = [t for t in trials(0.5, 0.7, 0.7, 0.1) if t["name"] != "twin"]
    assert sb3_tune.best_trial(no_twin)["name"] == "trial1"
