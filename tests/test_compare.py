"""scripts/compare_learners.py: the learner comparison runs end to end and is sane."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = ROOT / "scripts" / "compare_learners.py"
LEARNERS = {"q_assist", "q_plain", "dqn", "bfs"}


def load_script():
    spec = importlib.util.spec_from_file_location("compare_learners", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("compare")
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--out-dir", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out, json.loads((out / "compare.json").read_text())


def test_quick_run_has_every_learner_and_scenario(quick):
    _, result = quick
    scenarios = set(result["config"]["scenarios"])
    assert len(scenarios) == 2
    assert any(s.startswith("generated:") for s in scenarios)
    assert any(not s.startswith("generated:") for s in scenarios)
    assert set(result["summary"]) == LEARNERS
    seeds = result["config"]["seeds"]
    assert len(seeds) >= 2
    for learner in LEARNERS:
        for name in scenarios:
            runs = [r for r in result["runs"] if r["learner"] == learner and r["scenario"] == name]
            assert sorted(r["seed"] for r in runs) == sorted(seeds), (learner, name)
            assert name in result["summary"][learner]
        assert "all" in result["summary"][learner]
    hp = result["dqn_hyperparameters"]
    assert "rl-baselines3-zoo" in hp["source"]
    assert hp["total_timesteps"] == result["config"]["dqn_steps"]
    assert 0 < hp["reward_scale"] < 1


def test_quick_run_values_are_sane(quick):
    _, result = quick
    for r in result["runs"]:
        opt = result["scenarios"][r["scenario"]]["optimal_length"]
        assert isinstance(r["success"], bool)
        if r["success"]:
            path = r["path"]
            assert path[0] == result["scenarios"][r["scenario"]]["start"]
            assert path[-1] == result["scenarios"][r["scenario"]]["target"]
            assert r["path_length"] == len(path) - 1 >= opt
            assert r["length_ratio"] >= 1.0
        else:
            assert r["path_length"] is None and r["length_ratio"] is None
        if r["learner"] == "bfs":
            assert r["success"] and r["length_ratio"] == 1.0
        for key in ("first_success", "convergence"):
            if r[key] is not None:
                assert r[key]["env_steps"] >= 0 and r[key]["wall_time_s"] >= 0
        assert (r["convergence"] is not None) == r["success"] or r["learner"] == "bfs"
        assert r["algorithm2"]["replans"] >= 0
    for learner, per in result["summary"].items():
        for group, s in per.items():
            for key in ("success_rate", "algorithm1_pass_rate", "algorithm2_success_rate"):
                assert 0.0 <= s[key] <= 1.0, (learner, group, key)
            if s["length_ratio_mean"] is not None:
                assert s["length_ratio_mean"] >= 1.0
    assert result["summary"]["bfs"]["all"]["length_ratio_mean"] == 1.0
    assert result["summary"]["bfs"]["all"]["success_rate"] == 1.0
    # With the quick budget the tabular learners still find the target.
    assert result["summary"]["q_assist"]["all"]["success_rate"] > 0


def test_quick_run_writes_figures_and_report(quick):
    out, result = quick
    assert result["figures"]
    for name in result["figures"]:
        png = out / name
        assert png.exists() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "summary.png").exists()
    assert len(list(out.glob("curves_*.png"))) == len(result["scenarios"])
    report = (out / "BENCHMARKS.md").read_text()
    assert "--quick" in report and "| scenario | learner |" in report
    assert not list(out.glob(".*.tmp")), "a temporary file was left behind"


def test_arguments():
    cmp = load_script()
    assert cmp.expand_names("a, generated:2..4") == [
        "a",
        "generated:2",
        "generated:3",
        "generated:4",
    ]
    assert cmp.parse_seeds("3") == [0, 1, 2]
    assert cmp.parse_seeds("4,7") == [4, 7]
    args = cmp.parse_args([])
    assert len(args.scenario_names) == 13 and len(args.seed_list) >= 5
    assert args.report == ROOT / "docs" / "BENCHMARKS.md"
    quick = cmp.parse_args(["--quick", "--out-dir", "/tmp/x"])
    assert quick.report == Path("/tmp/x/BENCHMARKS.md")
    with pytest.raises(SystemExit):
        cmp.parse_args(["--learners", "ppo"])
    with pytest.raises(SystemExit):
        cmp.parse_args(["--dqn-steps", "0"])
