"""Load test of the env server: many concurrent clients, each checking its own trajectory.

Starts `sixaxis serve --address 127.0.0.1:0` (the release binary) as a subprocess, then
runs CLIENTS concurrent sessions of STEPS steps each (threads spread over a few client
processes). Client ``c`` plays ``RemoteEnv(..., random_target=True)`` seeded ``c`` with
its own random actions and compares every step (observation, reward, flags) with the
in-process env played the same way: a step lost, duplicated or crossed between sessions
changes the trajectory and fails the run. The server's resident memory (``VmRSS`` of
/proc/PID/status) is read after a warm-up round and after the load; it should stay flat.

    python scripts/load_test.py                      # 64 clients x 10,000 steps
    python scripts/load_test.py --clients 16 --steps 2000 --json out.json

tests/test_remote.py runs a short version (`run`, the same code).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import re
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
#: The release binary (SIXAXIS_BIN overrides, as in tests/conftest.py).
BINARY = Path(os.environ.get("SIXAXIS_BIN", ROOT / "target" / "release" / "sixaxis"))
#: Episode cap of the clients' worlds: short, so every client crosses many resets.
EPISODE_STEPS = 40


def start_server(binary: Path = BINARY, *extra: str) -> tuple[subprocess.Popen, str]:
    """`sixaxis serve --address 127.0.0.1:0` and the address it reports it listens on."""
    proc = subprocess.Popen(
        [str(binary), "serve", "--address", "127.0.0.1:0", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    deadline = time.monotonic() + 30
    seen = []
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        seen.append(line)
        m = re.search(r"(127\.0\.0\.1:\d+)", line)
        if m:
            # Keep draining the server's output so it never blocks on a full pipe.
            threading.Thread(target=proc.stdout.read, daemon=True).start()
            return proc, m.group(1)
    proc.kill()
    raise RuntimeError("sixaxis serve did not report its address: " + "".join(seen))


def rss_kib(pid: int) -> int:
    """Resident memory of process ``pid`` (KiB) from /proc/PID/status."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise RuntimeError(f"no VmRSS for pid {pid}")


def client(address: str, c: int, steps: int) -> dict:
    """One session of ``steps`` steps checked against the in-process env; its counts."""
    import gymnasium as gym
    import sixaxis_avoid  # noqa: F401 - registers the ids
    from sixaxis_avoid.remote import RemoteEnv

    kw = {"random_target": True, "max_episode_steps": EPISODE_STEPS}
    local = gym.make("SixAxisAvoid-v0", **kw).unwrapped
    actions = np.random.default_rng(1000 + c).integers(0, 6, size=steps)
    episodes = 0
    lat = np.empty(steps)
    with RemoteEnv(address, **kw) as env:
        o_r, _ = env.reset(seed=c)
        o_l, _ = local.reset(seed=c)
        if not np.array_equal(o_r, o_l):
            return {"client": c, "error": "reset observation differs", "steps": 0}
        t_l = 0
        for k in range(steps):
            a = int(actions[k])
            t0 = time.perf_counter()
            r = env.step(a)
            lat[k] = time.perf_counter() - t0
            lo, lr, lterm, _, _ = local.step(a)
            t_l += 1
            ltrunc = not lterm and t_l >= EPISODE_STEPS
            if not (np.array_equal(r[0], lo) and r[1] == lr and r[2] == lterm and r[3] == ltrunc):
                return {"client": c, "error": f"step {k} differs", "steps": k}
            if lterm or ltrunc:
                episodes += 1
                o_r, _ = env.reset()
                o_l, _ = local.reset()
                t_l = 0
                if not np.array_equal(o_r, o_l):
                    return {"client": c, "error": f"reset after step {k} differs", "steps": k}
    return {"client": c, "steps": steps, "episodes": episodes, "latencies": lat.tolist()}


def _process(address: str, clients: list[int], steps: int, out: mp.Queue) -> None:
    results: list[dict] = []
    lock = threading.Lock()

    def run(c: int) -> None:
        try:
            res = client(address, c, steps)
        except Exception as e:
            res = {"client": c, "error": f"{type(e).__name__}: {e}", "steps": 0}
        with lock:
            results.append(res)

    threads = [threading.Thread(target=run, args=(c,)) for c in clients]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    out.put(results)


def run_clients(address: str, clients: int, steps: int, processes: int | None = None) -> dict:
    """``clients`` concurrent sessions (threads over ``processes`` client processes)."""
    processes = processes or min(clients, max(2, os.cpu_count() or 2))
    ctx = mp.get_context("spawn")
    out: mp.Queue = ctx.Queue()
    groups = [list(range(p, clients, processes)) for p in range(processes)]
    t0 = time.perf_counter()
    procs = [ctx.Process(target=_process, args=(address, g, steps, out)) for g in groups if g]
    for p in procs:
        p.start()
    results: list[dict] = []
    for _ in procs:
        results += out.get(timeout=3600)
    for p in procs:
        p.join()
    seconds = time.perf_counter() - t0
    errors = [r for r in results if "error" in r]
    lat = np.concatenate([np.asarray(r["latencies"]) for r in results if "latencies" in r] or [[]])
    return {
        "clients": clients,
        "steps_per_client": steps,
        "steps_checked": int(sum(r["steps"] for r in results)),
        "episodes": int(sum(r.get("episodes", 0) for r in results)),
        "errors": errors,
        "seconds": seconds,
        "steps_per_s": float(sum(r["steps"] for r in results) / seconds),
        "p50_us": float(np.percentile(lat, 50) * 1e6) if lat.size else None,
        "p99_us": float(np.percentile(lat, 99) * 1e6) if lat.size else None,
    }


def run(clients: int, steps: int, binary: Path = BINARY, warmup_steps: int = 200) -> dict:
    """The whole test: server up, a warm-up round, the load, RSS before/after, server down."""
    proc, address = start_server(binary)
    try:
        warm = run_clients(address, clients, warmup_steps)
        rss_warm = rss_kib(proc.pid)
        load = run_clients(address, clients, steps)
        time.sleep(0.5)  # let the server free the closed sessions
        rss_after = rss_kib(proc.pid)
        return {
            "address": address,
            "warmup": {k: v for k, v in warm.items() if k != "errors"},
            "warmup_errors": warm["errors"],
            **load,
            "rss_kib_after_warmup": rss_warm,
            "rss_kib_after_load": rss_after,
            "server_alive": proc.poll() is None,
        }
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--clients", type=int, default=64)
    p.add_argument("--steps", type=int, default=10_000)
    p.add_argument("--binary", type=Path, default=BINARY)
    p.add_argument("--json", type=Path)
    args = p.parse_args()
    res = run(args.clients, args.steps, args.binary)
    text = json.dumps(res, indent=2)
    if args.json:
        args.json.write_text(text)
    print(text)
    ok = not res["errors"] and not res["warmup_errors"] and res["server_alive"]
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
