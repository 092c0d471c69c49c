"""The core's tabular learner in env steps/s with and without greedy-path checkpoints
(``sixaxis_avoid.train(..., checkpoints=[...])``), on one budget in env steps with epsilon
over env steps (benchmark v2's tabular runs). Runs alternate, and the best of ``--reps`` is
kept for each, so that other jobs on the machine weigh the same on both.

    python scripts/bench_checkpoints.py --scenario paper_simple --budget 1000000 --reps 5
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import sixaxis_avoid as sa


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--scenario", default="paper_simple")
    p.add_argument("--budget", type=int, default=1_000_000)
    p.add_argument("--checkpoints", type=int, default=12, help="on a geometric grid")
    p.add_argument("--reps", type=int, default=5)
    a = p.parse_args()
    grid = np.unique(np.geomspace(max(1, a.budget // 100), a.budget, a.checkpoints).round())
    cps = [int(c) for c in grid]
    kw = dict(seed=0, episodes=a.budget, max_env_steps=a.budget, epsilon_schedule="env_steps")
    best: dict[str, dict[str, float]] = {}
    for _ in range(a.reps):
        for label, c in (("without", None), ("with", cps)):
            c0 = time.process_time()
            r = sa.train(a.scenario, checkpoints=c, **kw)
            cpu = time.process_time() - c0
            rate = {"wall": r.total_steps / r.wall_time_s, "cpu": r.total_steps / cpu}
            old = best.get(label)
            best[label] = rate if old is None or rate["cpu"] > old["cpu"] else old
    out = {
        "scenario": a.scenario,
        "budget": a.budget,
        "checkpoints": len(cps),
        "reps": a.reps,
        "steps_per_s": best,
        "ratio_cpu": best["with"]["cpu"] / best["without"]["cpu"],
        "machine": sa._core.machine(),
    }
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
