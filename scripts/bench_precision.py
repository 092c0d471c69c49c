"""Q-values in f32 against f64 on the paper's scenarios, at the paper's settings.

For each scenario (``paper_simple``, ``paper_complex``, ``replan_clutter``) and seed, the
learner runs twice with the scenario's own ``learning`` section (the paper's 10,000 episodes,
Q = 0, eqs. 9 and 10 on), once with ``q_precision="f64"`` (the default) and once with
``"f32"``, and Algorithm 2 (``plan``) likewise. The table says how often the f32 learned path
equals the f64 one, how often each reaches the target and is as short as the breadth-first
optimum, and how often Algorithm 2 succeeds and ends with the same path; it replaces the
text between the ``precision`` markers of docs/PERFORMANCE.md, and every run's figures go to
--out.

    python scripts/bench_precision.py                      # 3 scenarios, seeds 0..9
    python scripts/bench_precision.py --seeds 20 --no-doc  # print only
    python scripts/bench_precision.py --no-assist --no-doc --out results/precision_eq5.json
"""

from __future__ import annotations

import argparse
import json
import time
from os import getloadavg
from pathlib import Path

import sixaxis_avoid as sa
from docsections import splice  # scripts/ is on sys.path when this script runs

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = ("paper_simple", "paper_complex", "replan_clutter")


def parse_args() -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenarios", nargs="+", default=list(SCENARIOS))
    p.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1")
    p.add_argument(
        "--no-assist", action="store_true", help="eq. 5 alone (the paper's other learner)"
    )
    p.add_argument("--out", default=str(ROOT / "results" / "precision.json"))
    p.add_argument("--doc", default=str(ROOT / "docs" / "PERFORMANCE.md"))
    p.add_argument("--no-doc", action="store_true", help="print the table only")
    p.add_argument("--from-json", help="render the table from figures saved by --out")
    return p.parse_args()


def path_length(path: list | None) -> int | None:
    return None if path is None else len(path) - 1


def measure(scenario: str, seed: int, assist: bool) -> dict:
    """One seed of one scenario: train and plan in f64 and in f32."""
    row: dict = {"scenario": scenario, "seed": seed, "assist": assist}
    shortest = sa.shortest_path(scenario)
    row["shortest_path_length"] = path_length(shortest)
    for p in ("f64", "f32"):
        t = sa.train(scenario, seed=seed, assist=assist, q_precision=p)
        plan = sa.plan(scenario, seed=seed, assist=assist, q_precision=p)
        row[p] = {
            "path": None if t.path is None else [list(c) for c in t.path],
            "path_length": path_length(t.path),
            "converged_episode": t.converged_episode,
            "total_steps": t.total_steps,
            "train_wall_s": t.wall_time_s,
            "q_table_bytes": t.q.nbytes,
            "plan_success": plan.success,
            "plan_replans": plan.replans,
            "plan_path": [list(c) for c in plan.path],
        }
    return row


def count(rows: list[dict], test) -> str:
    return f"{sum(1 for r in rows if test(r))}/{len(rows)}"


def optimal(row: dict, precision: str) -> bool:
    """Whether the learned path of ``precision`` is as short as the BFS optimum."""
    return row[precision]["path_length"] == row["shortest_path_length"]


def mean(rows: list[dict], precision: str, field: str) -> float:
    """Mean of a figure over the rows where it is set (nan if none)."""
    vals = [r[precision][field] for r in rows if r[precision][field] is not None]
    return sum(vals) / len(vals) if vals else float("nan")


def table(rows: list[dict]) -> str:
    lines = [
        "| scenario | BFS optimum (moves) | Q-table f64 → f32 | reaches the target f64 / f32 "
        "| optimal f64 / f32 | f32 path = f64 path (same seed) "
        "| f64 path = f64 path (seed + 1) | converged episode, mean f64 / f32 "
        "| Algorithm 2 succeeds f64 / f32 | same Algorithm 2 path |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    names = list(dict.fromkeys(r["scenario"] for r in rows))
    for name in names:
        rs = [r for r in rows if r["scenario"] == name]
        best = rs[0]["shortest_path_length"]
        pairs = list(zip(rs[:-1], rs[1:], strict=True))
        same_seeds = sum(1 for x, y in pairs if x["f64"]["path"] == y["f64"]["path"])

        lines.append(
            f"| {name} | {best} "
            f"| {rs[0]['f64']['q_table_bytes']:,} → {rs[0]['f32']['q_table_bytes']:,} bytes "
            f"| {count(rs, lambda r: r['f64']['path'] is not None)} / "
            f"{count(rs, lambda r: r['f32']['path'] is not None)} "
            f"| {count(rs, lambda r: optimal(r, 'f64'))} / "
            f"{count(rs, lambda r: optimal(r, 'f32'))} "
            f"| {count(rs, lambda r: r['f32']['path'] == r['f64']['path'])} "
            f"| {same_seeds}/{len(pairs)} "
            f"| {mean(rs, 'f64', 'converged_episode'):,.0f} / "
            f"{mean(rs, 'f32', 'converged_episode'):,.0f} "
            f"| {count(rs, lambda r: r['f64']['plan_success'])} / "
            f"{count(rs, lambda r: r['f32']['plan_success'])} "
            f"| {count(rs, lambda r: r['f32']['plan_path'] == r['f64']['plan_path'])} |"
        )
    return "\n".join(lines)


def dump(meta: dict, rows: list[dict]) -> str:
    """The figures as JSON text, one run per line."""
    runs = ",\n".join("  " + json.dumps(r) for r in rows)
    head = json.dumps(meta)[:-1]
    return f'{head}, "runs": [\n{runs}\n]}}\n'


def main() -> None:
    a = parse_args()
    if a.from_json:
        rows = json.loads(Path(a.from_json).read_text())["runs"]
    else:
        load = getloadavg()[0]
        assist = not a.no_assist
        rows = [measure(s, seed, assist) for s in a.scenarios for seed in range(a.seeds)]
        out = Path(a.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        meta = {
            "measured_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
            "load_average_1min": round(load, 2),
            "seeds": a.seeds,
        }
        out.write_text(dump(meta, rows))
    text = table(rows)
    print(text)
    if not a.no_doc:
        splice(Path(a.doc), "precision", text)


if __name__ == "__main__":
    main()
