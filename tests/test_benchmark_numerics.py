"""A deep learner's run gives the same result on machines with other instruction sets.

One machine stands in for two: MKL_ENABLE_INSTRUCTIONS makes MKL take its AVX2 or its AVX-512
code paths, as it would on a CPU without or with AVX-512 (an AMD EPYC against an Intel Xeon,
say). With the benchmark's pinned numerics (runner.NUMERICS_ENV) a full-budget PPO run of the
v1 suite gives the same result record under both; with MKL's own dispatch (MKL_CBWR=AUTO) the
same run takes other decisions, so the equality is not an accident of a run too short to
diverge. That control needs a machine where MKL's two paths really differ: a CPU with AVX-512
whose vendor MKL takes those paths for (an Intel Xeon does; on an AMD EPYC with AVX-512 both
settings give the same bits, checked on a matrix product first, and the control has nothing to
tell apart). What it cannot stand in for is a CPU of the other vendor: DQN and A2C runs made
on an Intel Xeon differed when re-run on an AMD EPYC under the same pin (python/README.md), and
runs record their machine for that reason."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

SCRIPT = """
import hashlib, json
from sixaxis_avoid.benchmark import load_suite, plan_runs, execute_run
suite = load_suite("v1")
(spec,) = plan_runs(suite, ["ppo"], seeds=[0], tasks=[suite.task("paper_simple")])
rec = execute_run(spec)
print(json.dumps({"result": hashlib.sha256(json.dumps(rec["result"], sort_keys=True).encode())
                  .hexdigest(), "numerics": rec["host"]["numerics"]}))
"""


def isa_env(isa: str, extra: dict[str, str]) -> dict[str, str]:
    """This environment without the pinned variables, MKL held to ``isa``, plus ``extra``."""
    env = {k: v for k, v in os.environ.items() if k not in ("MKL_CBWR", "ATEN_CPU_CAPABILITY")}
    env.update(MKL_ENABLE_INSTRUCTIONS=isa, **extra)
    return env


def run_pair(extra: dict[str, str]) -> list[dict]:
    """The run with MKL's AVX2 and with its AVX-512 code paths, both at once."""
    procs = []
    for isa in ("AVX2", "AVX512"):
        env = isa_env(isa, extra)
        procs.append(
            subprocess.Popen(
                [sys.executable, "-c", SCRIPT], env=env, stdout=subprocess.PIPE, text=True
            )
        )
    out = []
    for p in procs:
        stdout, _ = p.communicate(timeout=600)
        assert p.returncode == 0
        out.append(json.loads(stdout.strip().splitlines()[-1]))
    return out


PROBE = """
import hashlib, torch
torch.set_num_threads(1)
g = torch.Generator().manual_seed(0)
a, b = torch.randn(256, 300, generator=g), torch.randn(300, 257, generator=g)
print(hashlib.sha256((a @ b).numpy().tobytes()).hexdigest())
"""


def has_avx512() -> bool:
    text = Path("/proc/cpuinfo").read_text() if Path("/proc/cpuinfo").exists() else ""
    return " avx512f" in text


def mkl_paths_differ() -> bool:
    """Whether MKL's AVX2 and AVX-512 paths give other bits for a matrix product here (they
    do on an Intel CPU with AVX-512; MKL keeps to one path on other CPUs)."""
    if not has_avx512():
        return False
    digests = set()
    for isa in ("AVX2", "AVX512"):
        env = isa_env(isa, {"MKL_CBWR": "AUTO", "ATEN_CPU_CAPABILITY": "avx512"})
        out = subprocess.run(
            [sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, check=True
        )
        digests.add(out.stdout.strip())
    return len(digests) == 2


def test_pinned_numerics_give_the_same_run_on_avx2_and_avx512():
    pinned = run_pair({})
    assert pinned[0]["numerics"]["MKL_CBWR"] == "COMPATIBLE"
    assert pinned[0]["numerics"]["torch_cpu_capability"] == "AVX2"
    assert pinned[0]["result"] == pinned[1]["result"]
    if mkl_paths_differ():
        free = run_pair({"MKL_CBWR": "AUTO", "ATEN_CPU_CAPABILITY": "avx512"})
        assert free[0]["numerics"]["MKL_CBWR"] == "AUTO"
        assert free[0]["result"] != free[1]["result"], "the control run did not diverge"
