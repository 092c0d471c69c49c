"""Collect every speed figure of the project into one table, docs/PERFORMANCE.md.

Runs the criterion benchmarks of the Rust core (forward and inverse kinematics, clearance,
the Q-learner, Algorithm 2) and the Python environment benchmark (scripts/bench_env.py),
then writes the medians beside their goals, with the machine they ran on. The raw figures
go to --out as JSON.

    python scripts/bench.py                       # full run (a few minutes)
    python scripts/bench.py --quick               # shorter measurement times
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

from docsections import splice  # scripts/ is on sys.path when this script runs

ROOT = Path(__file__).resolve().parent.parent

# Goals from the issues: (criterion id, goal in ns). Ids not listed have no goal.
RUST_GOALS = {
    "fk": 100.0,
    "ik_full_solve_8_solutions": 1_000.0,
    "centres_clearance_cells_19_obstacles": 200.0,
    "train_paper_simple_10k/assist": 100e6,
    "train_paper_simple_10k/assist_cpu": 100e6,
    "algorithm2/plan_paper_simple": 500e6,
    "algorithm2/plan_paper_complex": 500e6,
    "algorithm2/plan_replan_clutter": 500e6,
}


def parse_args() -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="short warm-up and measurement times")
    p.add_argument("--skip-rust", action="store_true")
    p.add_argument("--skip-python", action="store_true")
    p.add_argument("--out", type=Path, default=ROOT / "results" / "bench" / "bench.json")
    p.add_argument("--report", type=Path, default=ROOT / "docs" / "PERFORMANCE.md")
    p.add_argument(
        "--render-only", action="store_true", help="rewrite the report from --out, run nothing"
    )
    return p.parse_args()


def machine() -> str:
    from sixaxis_avoid import _core

    return f"{_core.machine()}, Python {platform.python_version()}"


def run_rust(quick: bool) -> list[dict]:
    extra = ["--warm-up-time", "1", "--measurement-time", "2"] if quick else []
    subprocess.run(
        ["cargo", "bench", "-p", "sixaxis-core", "--quiet", "--", *extra],
        cwd=ROOT,
        check=True,
    )
    rows = []
    for est in sorted((ROOT / "target" / "criterion").glob("**/new/estimates.json")):
        bench = json.loads((est.parent / "benchmark.json").read_text())
        data = json.loads(est.read_text())
        rows.append(
            {
                "id": bench["full_id"],
                "median_ns": data["median"]["point_estimate"],
                "throughput": bench.get("throughput"),
            }
        )
    return rows


def run_python(quick: bool) -> dict:
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "env.json"
        cmd = [
            sys.executable,
            str(ROOT / "scripts" / "bench_env.py"),
            "--out",
            str(out),
        ]
        if quick:
            cmd.append("--quick")
        subprocess.run(cmd, cwd=ROOT, check=True)
        return json.loads(out.read_text())


def fmt_ns(ns: float) -> str:
    if ns >= 1e6:
        return f"{ns / 1e6:.2f} ms"
    if ns >= 1e3:
        return f"{ns / 1e3:.2f} µs"
    return f"{ns:.1f} ns"


def goal_of(bench_id: str) -> float | None:
    return RUST_GOALS.get(bench_id)


def report(data: dict) -> str:
    lines = [
        "# Performance",
        "",
        f"Measured by `python scripts/bench.py{' --quick' if data['quick'] else ''}`"
        f" on {data['machine']}.",
        "Medians of criterion runs (Rust, release, one core) and of scripts/bench_env.py (Python).",
        "Goals come from the issues; they are targets, not test assertions.",
        "",
    ]
    if data.get("rust"):
        lines += [
            "## Rust core",
            "",
            "| benchmark | median | throughput | goal | met |",
            "|---|---|---|---|---|",
        ]
        for row in data["rust"]:
            goal = goal_of(row["id"])
            met = "—" if goal is None else ("yes" if row["median_ns"] <= goal else "no")
            goal_s = "—" if goal is None else f"≤ {fmt_ns(goal)}"
            elements = (row.get("throughput") or {}).get("Elements")
            rate = f"{elements / row['median_ns'] * 1e3:.1f} M steps/s" if elements else "—"
            lines.append(
                f"| `{row['id']}` | {fmt_ns(row['median_ns'])} | {rate} | {goal_s} | {met} |"
            )
        lines.append("")
    py = data.get("python")
    if py:
        single = py["single"]
        met = "yes" if single["speedup_vs_cliffwalking"] >= 3 else "no"
        lines += [
            "## Python environment (scripts/bench_env.py)",
            "",
            "| measurement | steps/s | ratio | goal | met |",
            "|---|---|---|---|---|",
            f"| `gym.make('SixAxisAvoid-v0')`, one env | {single['sixaxis_steps_per_s']:,.0f} "
            f"| {single['speedup_vs_cliffwalking']:.1f}x `CliffWalking-v1` "
            f"({single['cliffwalking_steps_per_s']:,.0f}) | ≥ 3x | {met} |",
        ]
        for row in py["vector"]:
            n = row["num_envs"]
            ok = row["speedup_vs_sync"] >= 100 and (n != 1024 or row["native_steps_per_s"] >= 10e6)
            goal = "≥ 100x" + (", ≥ 10M steps/s" if n == 1024 else "")
            lines.append(
                f"| native vector env, N = {n} (copy=False: "
                f"{row['native_nocopy_steps_per_s']:,.0f}) | {row['native_steps_per_s']:,.0f} "
                f"| {row['speedup_vs_sync']:.0f}x `SyncVectorEnv` ({row['sync_steps_per_s']:,.0f}) "
                f"| {goal} | {'yes' if ok else 'no'} |"
            )
        lines += [
            "",
            "The vector env pays one Python call per batched step: at N = 16 a call takes about",
            "4 µs, of which stepping the 16 envs is under 0.5 µs at the N = 1024 rate. Below N of",
            "about 100 that fixed cost dominates, so the ratio over `SyncVectorEnv` is under 100x",
            "at N = 16.",
            "",
        ]
    return "\n".join(lines) + "\n"


def sb3_section(data: dict) -> list[str]:
    """The Stable-Baselines3 section, from the JSON of scripts/bench_sb3.py (run separately:
    its PPO runs take minutes)."""
    system = data["system"]
    lines = [
        "## Stable-Baselines3 VecEnvs (scripts/bench_sb3.py)",
        "",
        "`sixaxis_avoid.sb3.SixAxisVecEnv` (one Rust call per batched step) against SB3's",
        "`DummyVecEnv` and `SubprocVecEnv` over `gym.make('SixAxisAvoid-v0')` envs, random",
        "actions, SB3 semantics (immediate reset, one info dict per env). Measured by",
        f"`python scripts/bench_sb3.py --num-envs {' '.join(map(str, data['config']['num_envs']))}"
        f" --ppo-steps {data['config']['ppo_steps']}` ({system['cpus']} cores, load average"
        f" {system['load_average_at_start']:.1f} at the start).",
        "",
        "| N | SixAxisVecEnv steps/s | DummyVecEnv steps/s | SubprocVecEnv steps/s | vs Dummy |"
        " vs Subproc |",
        "|---|---|---|---|---|---|",
    ]
    for r in data["steps_per_s"]:
        lines.append(
            f"| {r['num_envs']} | {r['native_steps_per_s']:,} | {r['dummy_steps_per_s']:,} "
            f"| {r['subproc_steps_per_s']:,} | {r['speedup_vs_dummy']}x "
            f"| {r['speedup_vs_subproc']}x |"
        )
    ppo = data.get("ppo")
    if ppo:
        n = ppo["num_envs"]
        lines += [
            "",
            "PPO (`MlpPolicy`, n_steps 256, batch 256, ent_coef 0.01, "
            f"seed {data['config']['seed']}, CPU, "
            f"{data['config'].get('torch_threads', 1)} torch thread), "
            f"{data['config']['ppo_steps']:,} timesteps on {n} envs, total wall time:",
            "",
            "| VecEnv | seconds |",
            "|---|---|",
        ]
        for kind, label in (
            ("native", "SixAxisVecEnv"),
            ("dummy", "DummyVecEnv"),
            ("subproc", "SubprocVecEnv"),
        ):
            lines.append(f"| {label} | {ppo[kind]['seconds']:.1f} |")
        lines += [
            "",
            "PPO's time is mostly the network (rollout inference and 10 epochs of updates per",
            "rollout), the same for every VecEnv; the difference between the rows is the env side.",
        ]
    return [*lines, ""]


def write_atomic(path: Path, text: str) -> None:
    from sixaxis_avoid import _core

    path.parent.mkdir(parents=True, exist_ok=True)
    _core.write_atomic(path, text)


def write_report(path: Path, data: dict) -> None:
    """This script's sections of the report (`core`, and `sb3` when scripts/bench_sb3.py has
    written its JSON); the sections of other scripts (`scale`) stay as they are."""
    splice(path, "core", report(data))
    sb3 = ROOT / "docs" / "figures" / "bench_sb3.json"
    if sb3.exists():
        splice(path, "sb3", "\n".join(sb3_section(json.loads(sb3.read_text()))))


def main() -> None:
    args = parse_args()
    if args.render_only:
        write_report(args.report, json.loads(args.out.read_text()))
        print(f"wrote {args.report} from {args.out}")
        return
    data = {"machine": machine(), "quick": args.quick}
    if not args.skip_rust:
        data["rust"] = run_rust(args.quick)
    if not args.skip_python:
        data["python"] = run_python(args.quick)
    write_atomic(args.out, json.dumps(data, indent=2))
    write_report(args.report, data)
    print(f"wrote {args.out} and {args.report}")


if __name__ == "__main__":
    main()
