"""SIGKILL at random moments of every file write of the CLI (and of a benchmark study's
result files) leaves the old file or the new one, never a partial; Ctrl-C (SIGINT) during
train, plan and reproduce exits with code 130 quickly and writes nothing.

KILL_ROUNDS (default 12 per output, the CI run) sets how many kills each output gets:
    KILL_ROUNDS=200 python -m pytest tests/test_kill_interrupt.py -q
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import time
from pathlib import Path

import pytest
import sixaxis_avoid as sa

ROUNDS = int(os.environ.get("KILL_ROUNDS", "12"))


def _timed(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def _kill_loop(cmd: list[str], targets: list[Path], check_new) -> dict[str, int]:
    """Run `cmd` ROUNDS times, SIGKILL it at a random moment of its run, and check that each
    target holds its old bytes or a complete new file."""
    duration = _timed(cmd)
    for t in targets:
        check_new(t)  # a complete run writes files the checker accepts
    counts = {"old": 0, "new": 0}
    rng = random.Random(0)
    for _ in range(ROUNDS):
        old = {t: f"old {t.name} {rng.random()}".encode() for t in targets}
        for t, b in old.items():
            t.write_bytes(b)
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        # Most kills land near the end of the run, where the writes are.
        time.sleep(duration * rng.uniform(0.3, 1.1))
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        for t in targets:
            data = t.read_bytes()
            if data == old[t]:
                counts["old"] += 1
            else:
                check_new(t)
                counts["new"] += 1
    return counts


def _json_ok(p: Path) -> None:
    json.loads(p.read_text())


def test_sigkill_during_out_write(sixaxis_bin, tmp_path):
    out = tmp_path / "train.json"
    cmd = [str(sixaxis_bin), "train", "--scenario", "paper_simple", "--episodes", "3000"]
    cmd += ["--quiet", "--out", str(out)]
    counts = _kill_loop(cmd, [out], _json_ok)
    print(f"SIGKILL rounds: {counts}")
    assert counts["old"] + counts["new"] == ROUNDS


BENCH_WRITER = """
import sys
from sixaxis_avoid.benchmark import load_suite, plan_runs
from sixaxis_avoid.benchmark.runner import write_run
spec = plan_runs(load_suite("quick"), ["bfs"], seeds=[0])[0]
record = {"spec": spec, "result": {"curve": list(range(200_000))}}
for _ in range(20):
    write_run(sys.argv[1], record)
"""


def test_sigkill_during_benchmark_result_write(tmp_path):
    """A benchmark study's per-run result file (runner.write_run) is whole after a SIGKILL."""
    import sys

    from sixaxis_avoid.benchmark import load_suite, plan_runs
    from sixaxis_avoid.benchmark.runner import run_path

    spec = plan_runs(load_suite("quick"), ["bfs"], seeds=[0])[0]
    target = run_path(tmp_path, spec)
    target.parent.mkdir(parents=True)
    cmd = [sys.executable, "-c", BENCH_WRITER, str(tmp_path)]

    def whole(p: Path) -> None:
        assert len(json.loads(p.read_text())["result"]["curve"]) == 200_000

    counts = _kill_loop(cmd, [target], whole)
    print(f"SIGKILL rounds: {counts}")
    assert counts["old"] + counts["new"] == ROUNDS


def test_sigkill_during_qtable_save(sixaxis_bin, tmp_path):
    q = tmp_path / "q.bin"
    cmd = [str(sixaxis_bin), "train", "--scenario", "paper_simple", "--episodes", "3000"]
    cmd += ["--quiet", "--q-out", str(q)]
    scenario = sa.Scenario("paper_simple")

    def q_ok(p: Path) -> None:
        assert sa.load_q(p, scenario).shape[1] == 6

    counts = _kill_loop(cmd, [q], q_ok)
    print(f"SIGKILL rounds: {counts}")
    assert counts["old"] + counts["new"] == ROUNDS


def test_sigkill_during_reproduce_outputs(sixaxis_bin, tmp_path):
    out_dir = tmp_path / "repro"
    report = tmp_path / "REPORT.md"
    cmd = [str(sixaxis_bin), "reproduce", "--scenarios", "paper_simple", "--seeds", "1"]
    cmd += ["--episodes", "300", "--no-figures", "--quiet"]
    cmd += ["--out-dir", str(out_dir), "--report", str(report)]
    _timed(cmd)
    jsons = sorted(out_dir.glob("*.json"))
    assert jsons, "reproduce wrote no JSON"

    def ok(p: Path) -> None:
        if p.suffix == ".json":
            _json_ok(p)
        else:
            assert p.read_text().strip(), "empty report"

    counts = _kill_loop(cmd, [*jsons, report], ok)
    print(f"SIGKILL rounds: {counts}")
    assert counts["old"] + counts["new"] == ROUNDS * (len(jsons) + 1)


LONG_RUNS = {
    "train": ["train", "--scenario", "paper_simple", "--episodes", "100000000", "--quiet"],
    "plan": ["plan", "--scenario", "paper_simple", "--episodes", "100000000", "--quiet"],
}


@pytest.mark.parametrize("name", [*sorted(LONG_RUNS), "train --q-out", "reproduce"])
def test_ctrl_c_exits_130_quickly_and_writes_nothing(sixaxis_bin, tmp_path, name):
    out = tmp_path / "out"
    out.mkdir()
    if name == "reproduce":
        args = ["reproduce", "--scenarios", "paper_simple", "--seeds", "1"]
        args += ["--episodes", "100000000", "--no-figures", "--quiet"]
        args += ["--out-dir", str(out / "repro"), "--report", str(out / "REPORT.md")]
    elif name == "train --q-out":
        args = [*LONG_RUNS["train"], "--q-out", str(out / "q.bin")]
    else:
        args = [*LONG_RUNS[name], "--out", str(out / "result.json")]
    proc = subprocess.Popen(
        [str(sixaxis_bin), *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    time.sleep(0.7)
    assert proc.poll() is None, "the run ended before the interrupt"
    t0 = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=10)
    waited = time.perf_counter() - t0
    assert proc.returncode == 130, (proc.returncode, stderr[-500:])
    assert waited < 5.0, f"took {waited:.1f} s to stop"
    assert stdout == b"", "an interrupted run prints no partial result"
    left = [p for p in out.rglob("*") if p.is_file()]
    assert left == [], f"an interrupted run wrote {left}"
