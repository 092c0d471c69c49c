"""Collect every speed figure of the project into one table, docs/PERFORMANCE.md.

Runs the criterion benchmarks of the Rust core (forward and inverse kinematics, clearance,
the Q-learner, Algorithm 2) and the Python environment benchmark (scripts/bench_env.py),
then writes the medians beside their goals, with the machine they ran on. The raw figures
go to --out as JSON.

    python scripts/bench.py                       # full run (a few minutes)
    python scripts/bench.py --quick               # shorter measurement times
    python scripts/bench.py --server              # only the env server's section (~1 min)
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import speed_summary
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
    p.add_argument(
        "--server",
        action="store_true",
        help="measure only the env server (section `server`; JSON to --server-out)",
    )
    p.add_argument("--server-out", type=Path, default=ROOT / "results" / "bench" / "server.json")
    p.add_argument(
        "--load-json",
        type=Path,
        default=ROOT / "results" / "bench" / "load_test.json",
        help="JSON of scripts/load_test.py --json, shown in the `server` section when present",
    )
    p.add_argument(
        "--server-render-only", action="store_true", help="rewrite `server` from --server-out"
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
    if path == speed_summary.PERFORMANCE:  # README's speed paragraph, from these tables
        speed_summary.main([])


# The env server (docs/SERVER.md): in-process vs raw TCP vs the server ---------------------------
SERVER_BATCH_SIZES = (1, 4, 16, 64, 256, 1024, 4096)
SERVER_CLIENTS = (1, 4, 16, 64)


def _percentiles_us(seconds: list[float] | np.ndarray) -> dict:
    a = np.asarray(seconds) * 1e6
    return {"p50_us": float(np.percentile(a, 50)), "p99_us": float(np.percentile(a, 99))}


def _timed(fn, n: int) -> np.ndarray:
    t = np.empty(n)
    clock = time.perf_counter
    for i in range(n):
        t0 = clock()
        fn(i)
        t[i] = clock() - t0
    return t


_ECHO = """
import socket, sys
req, resp = int(sys.argv[1]), int(sys.argv[2])
srv = socket.socket(); srv.bind(("127.0.0.1", 0)); srv.listen(1)
print(srv.getsockname()[1], flush=True)
conn, _ = srv.accept(); conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
out = bytes(resp)
while True:
    got = 0
    while got < req:
        b = conn.recv(req - got)
        if not b:
            sys.exit(0)
        got += len(b)
    conn.sendall(out)
"""


def tcp_floor(req_bytes: int, resp_bytes: int, n: int) -> dict:
    """Round trips of a Python socket client and a Python echo server in another process
    exchanging a Step's byte counts (the floor any Python client over TCP pays)."""
    proc = subprocess.Popen(
        [sys.executable, "-c", _ECHO, str(req_bytes), str(resp_bytes)],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        port = int(proc.stdout.readline())
        c = socket.create_connection(("127.0.0.1", port))
        c.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        msg = bytes(req_bytes)

        def trip(_):
            c.sendall(msg)
            got = 0
            while got < resp_bytes:
                got += len(c.recv(resp_bytes - got))

        _timed(trip, 200)
        res = _percentiles_us(_timed(trip, n))
        c.close()
        return res
    finally:
        proc.kill()
        proc.wait()


def _clients_process(address: str, clients: int, seconds: float, out) -> None:
    """``clients`` threads, each a RemoteEnv stepping random actions for ``seconds``."""
    import threading

    from sixaxis_avoid.remote import RemoteEnv

    envs = [RemoteEnv(address, max_episode_steps=200) for _ in range(clients)]
    for e in envs:
        e.reset(seed=0)
    results = []
    lock = threading.Lock()
    start = threading.Barrier(clients)

    def run(k: int) -> None:
        env = envs[k]
        acts = np.random.default_rng(k).integers(0, 6, size=1 << 16)
        lat = []
        start.wait()
        end = time.perf_counter() + seconds
        i = 0
        while True:
            t0 = time.perf_counter()
            if t0 >= end:
                break
            _, _, term, trunc, _ = env.step(int(acts[i & 0xFFFF]))
            lat.append(time.perf_counter() - t0)
            if term or trunc:
                env.reset()
            i += 1
        with lock:
            results.append(lat)

    threads = [threading.Thread(target=run, args=(k,)) for k in range(clients)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for e in envs:
        e.close()
    out.put(results)


def concurrent_clients(address: str, clients: int, seconds: float) -> dict:
    """``clients`` concurrent single-env sessions (threads over up to 4 client processes):
    aggregate steps/s and the step round trip's percentiles."""
    import multiprocessing as mp

    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    procs_n = min(clients, 4)
    split = [clients // procs_n + (1 if k < clients % procs_n else 0) for k in range(procs_n)]
    procs = [ctx.Process(target=_clients_process, args=(address, c, seconds, q)) for c in split]
    for p in procs:
        p.start()
    lat = []
    for _ in procs:
        lat += q.get(timeout=600)
    for p in procs:
        p.join()
    steps = sum(len(x) for x in lat)
    return {
        "clients": clients,
        "client_processes": procs_n,
        "steps_per_s": steps / seconds,
        **_percentiles_us(np.concatenate([np.asarray(x) for x in lat])),
    }


def run_server(quick: bool) -> dict:
    import grpc
    from dm_env_rpc.v1 import connection, dm_env_rpc_pb2, message_utils
    from load_test import rss_kib, start_server
    from sixaxis_avoid.env import SixAxisAvoidEnv
    from sixaxis_avoid.remote import RemoteEnv, RemoteVectorEnv
    from sixaxis_avoid.vector import SixAxisAvoidVectorEnv

    n_single = 2000 if quick else 10_000
    seconds = 1.0 if quick else 3.0
    proc, address = start_server()
    out: dict = {"address": "sixaxis serve --address 127.0.0.1:0 (a separate process)"}
    try:
        # Single env: in process, through the server, and dm_env_rpc's own client.
        local = SixAxisAvoidEnv()
        local.reset(seed=0)
        acts = np.random.default_rng(0).integers(0, 6, size=n_single)

        def local_step(i):
            if local.step(int(acts[i]))[2]:
                local.reset()

        _timed(local_step, 500)
        out["in_process"] = _percentiles_us(_timed(local_step, n_single))

        # RemoteEnv over both transports (docs/SERVER.md "What a step costs").
        for key, transport in (("remote_env_grpc", "grpc"), ("remote_env", "rust")):
            env = RemoteEnv(address, max_episode_steps=10**6, transport=transport)
            env.reset(seed=0)

            def remote_step(i, env=env):
                if env.step(int(acts[i]))[2]:
                    env.reset()

            _timed(remote_step, 500)
            out[key] = _percentiles_us(_timed(remote_step, n_single))
            if transport == "grpc":
                env.close()
        w = env._world
        req, _ = message_utils.pack_environment_request(w.step_request(np.int32(0)))
        resp = env._session.call(w.step_request(np.int32(0)), "Step")
        env.close()
        req_bytes = req.ByteSize()
        resp_bytes = dm_env_rpc_pb2.EnvironmentResponse(step=resp).ByteSize()
        out["step_bytes"] = {"request": req_bytes, "response": resp_bytes}
        out["tcp_floor"] = tcp_floor(req_bytes, resp_bytes, n_single)

        with connection.Connection(grpc.insecure_channel(address)) as conn:
            name = conn.send(dm_env_rpc_pb2.CreateWorldRequest(settings={})).world_name
            conn.send(dm_env_rpc_pb2.JoinWorldRequest(world_name=name))
            step = w.step_request(np.int32(2))
            conn.send(w.step_request(None))

            def raw_step(_):
                conn.send(step)

            _timed(raw_step, 500)
            out["dm_env_rpc_connection"] = _percentiles_us(_timed(raw_step, n_single))
            conn.send(dm_env_rpc_pb2.LeaveWorldRequest())
            conn.send(dm_env_rpc_pb2.DestroyWorldRequest(world_name=name))

        # Batched worlds, one client: env steps/s against the native vector env.
        out["batched"] = []
        for n in SERVER_BATCH_SIZES:
            actions = np.random.default_rng(n).integers(0, 6, size=(64, n))
            rates = {}
            for kind in ("native", "remote", "remote_grpc"):
                if kind == "native":
                    venv = SixAxisAvoidVectorEnv(n)
                else:
                    transport = "grpc" if kind == "remote_grpc" else "rust"
                    venv = RemoteVectorEnv(address, n, transport=transport)
                venv.reset(seed=0)
                for a in actions[:8]:
                    venv.step(a)
                calls, t0 = 0, time.perf_counter()
                while time.perf_counter() - t0 < seconds / 2:
                    venv.step(actions[calls & 63])
                    calls += 1
                rates[kind] = calls * n / (time.perf_counter() - t0)
                venv.close()
            out["batched"].append(
                {
                    "num_envs": n,
                    "native_steps_per_s": rates["native"],
                    "remote_steps_per_s": rates["remote"],
                    "remote_grpc_steps_per_s": rates["remote_grpc"],
                    "ratio": rates["remote"] / rates["native"],
                }
            )
        # Concurrent clients.
        rss0 = rss_kib(proc.pid)
        out["clients"] = [concurrent_clients(address, c, seconds) for c in SERVER_CLIENTS]
        out["server_rss_kib"] = {"before_clients": rss0, "after_clients": rss_kib(proc.pid)}
    finally:
        proc.terminate()
        proc.wait(10)
    out["cpus"] = os.cpu_count()
    out["load_average_at_end"] = os.getloadavg()[0]
    return out


def server_section(data: dict) -> str:
    s = data["server"]
    floor = s["tcp_floor"]["p50_us"]
    lines = [
        "## Server",
        "",
        f"Measured by `python scripts/bench.py --server{' --quick' if data['quick'] else ''}`"
        f" on {data['machine']} ({s['cpus']} cores shared with other work: load average"
        f" {s['load_average_at_end']:.1f} at the end), against `{s['address']}`; the clients are",
        "`sixaxis_avoid.remote` (Python) over its two transports: `rust` (the default, the",
        "extension's tonic client with the GIL released) and `grpc` (grpcio via dm-env-rpc).",
        "Goals (issue 23) are targets,",
        "not test assertions. The load test (`python scripts/load_test.py`, 64 clients x 10,000",
        "checked steps) is separate.",
        "",
        f"Single-env step round trip (a Step of {s['step_bytes']['request']} bytes answered by"
        f" {s['step_bytes']['response']}):",
        "",
        "| path | p50 | p99 | p50 / raw TCP |",
        "|---|---|---|---|",
    ]
    rows = [
        ("in process: `SixAxisAvoidEnv.step`", s["in_process"]),
        ("raw loopback TCP floor: Python socket echo, same byte counts", s["tcp_floor"]),
        ("dm_env_rpc `Connection.send(StepRequest)` to the server", s["dm_env_rpc_connection"]),
        ('`RemoteEnv.step` (Gymnasium), `transport="grpc"`', s.get("remote_env_grpc")),
        ('`RemoteEnv.step` (Gymnasium), `transport="rust"` (default)', s["remote_env"]),
    ]
    rows = [(label, r) for label, r in rows if r is not None]
    for label, r in rows:
        lines.append(
            f"| {label} | {r['p50_us']:.1f} µs | {r['p99_us']:.1f} µs | {r['p50_us'] / floor:.2f} |"
        )
    p50 = s["remote_env"]["p50_us"]
    lines += [
        "",
        f"Goals: p50 ≤ 100 µs — {p50:.0f} µs, {'met' if p50 <= 100 else 'not met'}; and ≤ 3x"
        f" the raw-TCP floor — {p50 / floor:.1f}x, {'met' if p50 <= 3 * floor else 'not met'}"
        " (the default transport). Over grpcio the round trip is grpcio's Python stream:"
        " dm_env_rpc's own `Connection` pays about the same. The Rust transport writes the"
        " request and reads the answer on the calling thread (a current-thread tokio runtime,"
        " the GIL released) and hands NumPy arrays back; what remains above the tonic client's"
        " round trip (57 µs, docs/SERVER.md) is `RemoteEnv`'s Gymnasium conversions. The p99s"
        " move with the machine's load (other work on the same 2 cores).",
        "",
        "Batched world, one client (`RemoteVectorEnv(address, N)`: one Step carries N lanes)"
        " against the native vector env at the same N:",
        "",
        "| N | native env steps/s | server env steps/s, rust | ratio | server, grpc |",
        "|---|---|---|---|---|",
    ]
    for r in s["batched"]:
        grpc_rate = r.get("remote_grpc_steps_per_s")
        lines.append(
            f"| {r['num_envs']} | {r['native_steps_per_s']:,.0f} | {r['remote_steps_per_s']:,.0f}"
            f" | {r['ratio']:.3f} | {'' if grpc_rate is None else f'{grpc_rate:,.0f}'} |"
        )
    n1024 = next((r for r in s["batched"] if r["num_envs"] == 1024), None)
    if n1024:
        ok = n1024["remote_steps_per_s"] >= 2e6
        lines += [
            "",
            f"Goal at N = 1024: ≥ 2 M env steps/s: {n1024['remote_steps_per_s'] / 1e6:.2f} M"
            f" — {'met' if ok else 'not met'}.",
        ]
    lines += [
        "",
        "Concurrent single-env clients (threads over up to 4 client processes, each a"
        " `RemoteEnv`, random actions):",
        "",
        "| clients | aggregate steps/s | p50 | p99 |",
        "|---|---|---|---|",
    ]
    for r in s["clients"]:
        lines.append(
            f"| {r['clients']} | {r['steps_per_s']:,.0f} | {r['p50_us']:.0f} µs"
            f" | {r['p99_us']:.0f} µs |"
        )
    rss = s["server_rss_kib"]
    lines += [
        "",
        "The client reads observation tensors with `np.array` over the protobuf repeated field;"
        " `dm_env_rpc`'s packers use `np.fromiter`, which took 4 ms for the 4096 x 13 floats of"
        " one N = 4096 observation against 13 µs (upb protobuf), and capped the batched world"
        " at about 200 k env steps/s.",
        "",
        f"Server resident memory before / after the client runs: {rss['before_clients'] / 1024:.1f}"
        f" / {rss['after_clients'] / 1024:.1f} MiB.",
        "",
    ]
    load = data.get("load_test")
    if load:
        lines += [
            f"Load test (`python scripts/load_test.py --clients {load['clients']} --steps"
            f" {load['steps_per_client']}`, run separately): {load['clients']} concurrent"
            f" sessions, {load['steps_checked']:,} steps and {load['episodes']:,} episodes each"
            " checked step for step against the in-process env:"
            f" {len(load['errors'])} differences or errors, server alive; server resident memory"
            f" {load['rss_kib_after_warmup'] / 1024:.1f} MiB after a warm-up round, "
            f"{load['rss_kib_after_load'] / 1024:.1f} MiB after the load; "
            f"{load['steps_per_s']:,.0f} checked steps/s in {load['seconds']:.0f} s"
            f" (p50 {load['p50_us'] / 1e3:.1f} ms, p99 {load['p99_us'] / 1e3:.1f} ms per step; the"
            " clients are threads of a few processes on the same cores as the server).",
            "",
        ]
    return "\n".join(lines)


def main() -> None:
    args = parse_args()
    if args.server or args.server_render_only:
        if args.server_render_only:
            data = json.loads(args.server_out.read_text())
        else:
            data = {"machine": machine(), "quick": args.quick, "server": run_server(args.quick)}
            write_atomic(args.server_out, json.dumps(data, indent=2))
        if args.load_json.exists():
            data["load_test"] = json.loads(args.load_json.read_text())
        splice(args.report, "server", server_section(data))
        print(f"wrote the `server` section of {args.report}")
        return
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
