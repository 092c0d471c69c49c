"""Smoke test of the rejax learners on the JAX twin (the study itself is not run in CI):
a tiny PPO run of two vmapped seeds gives the JSON record the docs read."""

from __future__ import annotations

import importlib
import json
import sys

import pytest
from gymnasium.error import DependencyNotInstalled
from sixaxis_avoid.benchmark import jax_learners


def test_tiny_ppo_run_records_its_flags_speed_and_evaluations(tmp_path):
    out = tmp_path / "ppo.json"
    rec = jax_learners.main(
        [
            "--seeds", "2", "--total-timesteps", "2048", "--eval-freq", "1024",
            "--num-envs", "4", "--num-steps", "16", "--num-minibatches", "2",
            "--num-epochs", "1", "--hidden", "16,16", "--max-episode-steps", "50",
            "--sb3-steps", "512", "--out", str(out),
        ]
    )  # fmt: skip
    assert json.loads(out.read_text()) == rec
    assert rec["seeds"] == [0, 1] and rec["task"] == "paper_simple"
    assert rec["flags"]["hidden"] == "16,16" and rec["rejax_config"]["num_steps"] == 16
    assert rec["rejax_config"]["agent_kwargs"]["hidden_layer_sizes"] == [16, 16]
    # Evaluations at 0, 1024 and 2048 env steps, per seed.
    assert rec["eval_env_steps"] == [0, 1024, 2048]
    for key in ("success", "spl"):
        assert len(rec[key]) == 2 and all(len(r) == 3 for r in rec[key])
        assert all(0.0 <= v <= 1.0 for r in rec[key] for v in r)
    # SPL is at most the success, and positive only where the target was reached.
    for s_row, p_row in zip(rec["success"], rec["spl"]):
        assert all(p <= s and (p > 0) == (s > 0) for s, p in zip(s_row, p_row))
    assert rec["env_steps_per_s"] > 0 and rec["compile_s"] > 0
    # The SB3 PPO of the same values, timed.
    assert rec["sb3_ppo"]["env_steps"] == 512 and rec["sb3_ppo"]["env_steps_per_s"] > 0
    assert rec["speedup_vs_sb3"] == rec["env_steps_per_s"] / rec["sb3_ppo"]["env_steps_per_s"]


def test_missing_rejax_names_the_jax_learners_extra(monkeypatch):
    for mod in [m for m in sys.modules if m == "rejax" or m.startswith("rejax.")]:
        monkeypatch.delitem(sys.modules, mod)
    monkeypatch.setitem(sys.modules, "rejax", None)
    with pytest.raises(DependencyNotInstalled, match=r"sixaxis-avoid\[jax-learners\]"):
        jax_learners.main(["--seeds", "1", "--total-timesteps", "64"])


def test_gymnax_interface_module_names_its_extra(monkeypatch):
    for mod in [m for m in sys.modules if m == "gymnax" or m.startswith("gymnax.")]:
        monkeypatch.delitem(sys.modules, mod)
    monkeypatch.delitem(sys.modules, "sixaxis_avoid.jax.gymnax_compat", raising=False)
    monkeypatch.setitem(sys.modules, "gymnax", None)
    with pytest.raises(DependencyNotInstalled, match=r"sixaxis-avoid\[jax-learners\]"):
        importlib.import_module("sixaxis_avoid.jax.gymnax_compat")
