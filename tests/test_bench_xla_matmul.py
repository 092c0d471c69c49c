"""scripts/bench_xla_matmul.py: the PPO arithmetic per env step that docs/PERFORMANCE.md
divides by the measured CPU time, and a rate measurement that runs. Its rates are reported
in the docs, never asserted."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "bench_xla_matmul.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_xla_matmul", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_ppo_arithmetic_counts_acting_and_three_passes_per_epoch(bench):
    # 13 observation values, 6 actions: actor 13-h-h-6, critic 13-h-h-1, two FLOPs a weight.
    h = 64
    per_pass = 2 * (13 * h + h * h + h * 6) + 2 * (13 * h + h * h + h)
    assert bench.ppo_flops_per_env_step(h, 10) == per_pass * 31 == 638_848
    assert bench.ppo_flops_per_env_step(256, 3) == 2_790_400  # docs/PERFORMANCE.md's figure
    # More epochs, more arithmetic; the acting pass stays.
    assert bench.ppo_flops_per_env_step(256, 0) == bench.ppo_flops_per_env_step(256, 3) // 10


def test_the_measurement_runs_and_refuses_bad_sizes(bench, capsys):
    out = bench.main(["--hidden", "8", "--rows", "4", "--batch", "2", "--seconds", "0.05"])
    assert out["calls"] >= 1 and out["gflop_per_cpu_s"] > 0 and out["gflop_per_wall_s"] > 0
    assert '"hidden": 8' in capsys.readouterr().out
    with pytest.raises(SystemExit):
        bench.main(["--hidden", "0"])
    assert "--hidden: 0 must be >= 1" in capsys.readouterr().err
