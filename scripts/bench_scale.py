"""Scale table: paper_simple re-gridded to finer cells, learned with ``--episodes auto``.

For each cell size, each initial-Q rule (``--initial-q``: ``zero``, the paper's learner,
and ``distance``, ours) and each Q-value type (``--q-precision``: ``f64``, the default, and
``f32``): ``sixaxis regrid`` writes the world, ``sixaxis train --episodes auto --initial-q
RULE --q-precision P`` learns it and ``sixaxis plan`` with the same flags runs the whole
Algorithm 2 on it, each under ``/usr/bin/time -v`` for the peak RSS. An f32 row also learns
the same world in f64 (untimed) and records whether the two learned paths are equal. The
table (states, Q-table bytes, episodes and env steps to the optimal path, wall times, peak
RSS, against the goals of issue 13) replaces the text between the ``scale`` markers of
docs/PERFORMANCE.md; the raw figures go to --out, each row with its time and load average.

    python scripts/bench_scale.py                    # 100, 50, 25, 12.5 mm, both rules, f64
    python scripts/bench_scale.py --cells 100 50 --initial-q distance   # a subset
    python scripts/bench_scale.py --q-precision f64 f32 --skip 12.5/zero/f32   # with f32 rows
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
PRECISIONS = ("f64", "f32")


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
    p.add_argument(
        "--q-precision",
        nargs="+",
        choices=PRECISIONS,
        default=["f64"],
        help="Q-value types to measure (learning.q_precision); one table row per cell, rule "
        "and type",
    )
    p.add_argument(
        "--skip",
        nargs="*",
        default=[],
        metavar="CELL/RULE/TYPE",
        help="combinations not to measure, e.g. 12.5/zero/f32 (Q = 0 at 12.5 mm takes minutes)",
    )
    p.add_argument("--from-json", help="render the table from figures saved by --out")
    p.add_argument(
        "--reuse",
        help="figures saved by --out: rows found there (same cell, rule and type) are kept, "
        "not re-run",
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


def precision_of(row: dict) -> str:
    """A row's Q-value type (rows saved before the option existed are f64)."""
    return row.get("q_precision", "f64")


def key(cell: float, rule: str, precision: str) -> str:
    """The ``--skip`` spelling of a combination, e.g. ``12.5/zero/f32``."""
    return f"{cell:g}/{rule}/{precision}"


def measure(
    binary: str, scenario: str, cell: float, rule: str, precision: str, seed: int, tmp: Path
) -> dict:
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
    common += ["--initial-q", rule, "--q-precision", precision]
    load = getloadavg()[0]
    train, train_rss = timed([binary, "train", *common, "--no-curve"])
    plan, plan_rss = timed([binary, "plan", *common])
    extra = {}
    if precision != "f64":
        f64_cmd = [binary, "train", *common[:-1], "f64", "--no-curve"]
        f64 = json.loads(subprocess.run(f64_cmd, capture_output=True, check=True).stdout)
        extra["f64_path_length"] = f64["path_length"]
        extra["same_path_as_f64"] = f64["path"] == train["path"]
    return {
        "cell_mm": cell,
        "initial_q": rule,
        "q_precision": precision,
        "measured_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
        "load_average_1min": round(load, 2),
        "states": states,
        "q_table_bytes": train["q_table_bytes"],
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
        **extra,
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
        "| cell | initial Q | Q values | states | Q-table | optimum (moves) | learned "
        "| episodes to optimum | env steps to optimum | episodes run | learning wall "
        "| peak RSS (train) | Algorithm 2 wall (points, re-plans) | peak RSS (plan) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        c = r["cell_mm"]
        rss_goal = RSS_GOAL_KB.get(c)
        train_rss = goal(r["train_peak_rss_kb"] / 1024, rss_goal and rss_goal / 1024, "{:.0f} MB")
        failed = "" if r["plan_success"] else ", failed"
        learned = str(r["path_length"])
        if "same_path_as_f64" in r:
            learned += " (= f64 path)" if r["same_path_as_f64"] else " (≠ f64 path)"
        lines.append(
            f"| {c:g} mm | {rule_of(r)} | {precision_of(r)} | {r['states']:,} "
            f"| {r['q_table_bytes'] / 1e6:.2f} MB "
            f"| {r['shortest_path_length']} | {learned} "
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
        known = {key(r["cell_mm"], rule_of(r), precision_of(r)): r for r in kept}
        rows = []
        with tempfile.TemporaryDirectory() as d:
            for c in a.cells:
                for rule in a.initial_q:
                    for precision in a.q_precision:
                        k = key(c, rule, precision)
                        row = known.get(k)
                        if row is None and k in a.skip:
                            continue
                        if row is None:
                            row = measure(a.binary, a.scenario, c, rule, precision, a.seed, Path(d))
                            print(f"measured {k}", flush=True)
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
