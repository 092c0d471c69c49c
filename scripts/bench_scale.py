"""Scale table: paper_simple re-gridded to finer cells, learned with ``--episodes auto``.

For each cell size and each initial-Q rule (``--initial-q``: ``zero``, the paper's learner,
and ``distance``, ours): ``sixaxis regrid`` writes the world, ``sixaxis train --episodes
auto --initial-q RULE`` learns it and ``sixaxis plan --episodes auto --initial-q RULE`` runs
the whole Algorithm 2 on it, each under ``/usr/bin/time -v`` for the peak RSS. The table
(states, Q-table bytes, episodes and env steps to the optimal path, wall times, peak RSS,
against the goals of issue 13) replaces the text between the ``scale`` markers of
docs/PERFORMANCE.md; the raw figures go to --out, each row with its time and load average.

    python scripts/bench_scale.py                    # 100, 50, 25, 12.5 mm, both rules
    python scripts/bench_scale.py --cells 100 50 --initial-q distance   # a subset
    python scripts/bench_scale.py --reuse docs/figures/scale.json   # measure only missing rows
    python scripts/bench_scale.py --from-json results/scale.json   # re-render the table
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import tempfile
import time
from os import getloadavg
from pathlib import Path

from docsections import splice  # scripts/ is on sys.path when this script runs

ROOT = Path(__file__).resolve().parent.parent
# Goals of issue 13, seconds: learning the optimal path, and the whole Algorithm 2.
LEARN_GOAL_S = {50.0: 0.2, 25.0: 1.0, 12.5: 10.0}
PLAN_GOAL_S = {25.0: 2.0}
RSS_GOAL_KB = {12.5: 1024 * 1024}
RULES = ("zero", "distance")


def parse_args() -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cells", type=float, nargs="+", default=[100.0, 50.0, 25.0, 12.5])
    p.add_argument("--scenario", default="paper_simple")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--binary", default=str(ROOT / "target" / "release" / "sixaxis"))
    p.add_argument("--out", default=str(ROOT / "results" / "scale.json"))
    p.add_argument("--doc", default=str(ROOT / "docs" / "PERFORMANCE.md"))
    p.add_argument("--no-doc", action="store_true", help="print the table only")
    p.add_argument(
        "--initial-q",
        nargs="+",
        choices=RULES,
        default=list(RULES),
        help="initial-Q rules to measure (learning.initial_q); one table row per cell and rule",
    )
    p.add_argument("--from-json", help="render the table from figures saved by --out")
    p.add_argument(
        "--reuse",
        help="figures saved by --out: rows found there (same cell and rule) are kept, not re-run",
    )
    return p.parse_args()


def timed(cmd: list[str]) -> tuple[dict, int]:
    """Run ``cmd`` under /usr/bin/time -v; its JSON stdout and its peak RSS in kB."""
    proc = subprocess.run(
        ["/usr/bin/time", "-v", *cmd], capture_output=True, text=True, check=False
    )
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", proc.stderr)
    if proc.returncode not in (0, 1) or rss is None:
        raise RuntimeError(f"{' '.join(cmd)} failed: {proc.stderr[-2000:]}")
    return json.loads(proc.stdout), int(rss.group(1))


def rule_of(row: dict) -> str:
    """A row's initial-Q rule (rows saved before the option existed are the paper's)."""
    return row.get("initial_q", "zero")


def measure(binary: str, scenario: str, cell: float, rule: str, seed: int, tmp: Path) -> dict:
    world = tmp / f"world_{cell}.json"
    subprocess.run(
        [binary, "regrid", "--scenario", scenario, "--cell-mm", str(cell), "--out", str(world)],
        check=True,
    )
    spec = json.loads(world.read_text())
    b = spec["bounds"]
    states = 1
    for lo, hi in zip(b["min"], b["max"], strict=True):
        states *= hi - lo + 1
    common = ["--scenario", str(world), "--seed", str(seed), "--episodes", "auto", "-q"]
    common += ["--initial-q", rule]
    load = getloadavg()[0]
    train, train_rss = timed([binary, "train", *common, "--no-curve"])
    plan, plan_rss = timed([binary, "plan", *common])
    return {
        "cell_mm": cell,
        "initial_q": rule,
        "measured_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
        "load_average_1min": round(load, 2),
        "states": states,
        "q_table_bytes": states * 6 * 8,
        "shortest_path_length": train["shortest_path_length"],
        "path_length": train["path_length"],
        "optimal": train["path_length"] == train["shortest_path_length"],
        "converged_episode": train["converged_episode"],
        "steps_to_converged": train["steps_to_converged"],
        "episodes_run": train["episodes_run"],
        "total_steps": train["total_steps"],
        "train_wall_s": train["wall_time_s"],
        "train_peak_rss_kb": train_rss,
        "plan_success": plan["success"],
        "plan_replans": plan["replans"],
        "plan_path_points": len(plan["path"]),
        "plan_wall_s": plan["wall_time_s"],
        "plan_learning_s": sum(r["learning_time_s"] for r in plan["rounds"]),
        "plan_peak_rss_kb": plan_rss,
    }


def goal(value: float, limit: float | None, fmt) -> str:
    """``value`` in ``fmt`` (a format string or a function), with its goal's verdict."""
    show = fmt if callable(fmt) else fmt.format
    if limit is None:
        return show(value)
    verdict = "met" if value <= limit else f"missed, {value / limit:.1f}x"
    return f"{show(value)} (goal ≤ {show(limit)}: {verdict})"


def secs(value: float) -> str:
    """A wall time: milliseconds below 0.1 s, else seconds."""
    return f"{value * 1000:.1f} ms" if value < 0.1 else f"{value:.2f} s"


def table(rows: list[dict]) -> str:
    lines = [
        "| cell | initial Q | states | Q-table | optimum (moves) | learned | episodes to optimum "
        "| env steps to optimum | episodes run | learning wall | peak RSS (train) "
        "| Algorithm 2 wall (points, re-plans) | peak RSS (plan) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        c = r["cell_mm"]
        rss_goal = RSS_GOAL_KB.get(c)
        train_rss = goal(r["train_peak_rss_kb"] / 1024, rss_goal and rss_goal / 1024, "{:.0f} MB")
        failed = "" if r["plan_success"] else ", failed"
        lines.append(
            f"| {c:g} mm | {rule_of(r)} | {r['states']:,} | {r['q_table_bytes'] / 1e6:.2f} MB "
            f"| {r['shortest_path_length']} | {r['path_length']} "
            f"| {r['converged_episode']:,} | {r['steps_to_converged']:,} "
            f"| {r['episodes_run']:,} | {goal(r['train_wall_s'], LEARN_GOAL_S.get(c), secs)} "
            f"| {train_rss} "
            f"| {goal(r['plan_wall_s'], PLAN_GOAL_S.get(c), secs)} "
            f"({r['plan_path_points']}, {r['plan_replans']}{failed}) "
            f"| {r['plan_peak_rss_kb'] / 1024:.0f} MB |"
        )
    return "\n".join(lines)


def main() -> None:
    a = parse_args()
    if a.from_json:
        rows = json.loads(Path(a.from_json).read_text())
    else:
        kept = json.loads(Path(a.reuse).read_text()) if a.reuse else []
        known = {(r["cell_mm"], rule_of(r)): r for r in kept}
        rows = []
        with tempfile.TemporaryDirectory() as d:
            for c in a.cells:
                for rule in a.initial_q:
                    row = known.get((c, rule))
                    if row is None:
                        row = measure(a.binary, a.scenario, c, rule, a.seed, Path(d))
                        print(f"measured {c:g} mm, initial Q {rule}", flush=True)
                    rows.append(row)
        out = Path(a.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(rows, indent=2) + "\n")
    text = table(rows)
    print(text)
    if a.no_doc:
        return
    splice(Path(a.doc), "scale", text)


if __name__ == "__main__":
    main()
