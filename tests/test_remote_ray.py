"""A two-node Ray cluster started on loopback: start_ray_servers (docs/SERVER.md "Across
machines (Ray)": one server per node, pinned there, driven by one RemoteVectorEnv), and the
benchmark's quick suite run on it from another driver (docs/BENCHMARKS.md, *How to run*).

The cluster is two `ray start` nodes with their own temp dirs; cleanup ends exactly the
processes of those two nodes (found by their temp dirs and port, then their children), never
every Ray process of the machine as `ray stop` would.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
import ray
from _helpers import assert_same_trials
from sixaxis_avoid.remote import RemoteVectorEnv, start_ray_servers
from sixaxis_avoid.vector import SixAxisAvoidVectorEnv

RAY = str(Path(sys.executable).with_name("ray"))
# Token auth of the Ray cluster itself off: a token left in ~/.ray would switch it on.
ENV = {**os.environ, "RAY_AUTH_MODE": "disabled", "RAY_USAGE_STATS_ENABLED": "0"}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _pids_of(markers: list[str], port: int) -> set[int]:
    """Ray's processes whose command line holds a marker (a temp dir) or the head's port,
    and all their descendants."""
    found: set[int] = set()
    parents: dict[int, int] = {}
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            cmd = (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            ppid = int((proc / "stat").read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        parents[int(proc.name)] = ppid
        if any(m in cmd for m in markers) or ("ray" in cmd and f":{port} " in f"{cmd} "):
            found.add(int(proc.name))
    grew = True
    while grew:
        grew = False
        for pid, ppid in parents.items():
            if ppid in found and pid not in found:
                found.add(pid)
                grew = True
    found.discard(os.getpid())
    return found


def _end(pids: set[int]) -> None:
    for sig in (signal.SIGTERM, signal.SIGKILL):
        for pid in pids:
            try:
                os.kill(pid, sig)
            except ProcessLookupError:
                pass
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and any(Path(f"/proc/{p}").exists() for p in pids):
            time.sleep(0.2)


@pytest.fixture(scope="module")
def two_node_cluster():
    port = _free_port()
    dirs = [tempfile.mkdtemp(prefix="sixaxis-ray-head-"), tempfile.mkdtemp(prefix="sixaxis-ray-")]
    common = ["--node-ip-address=127.0.0.1", "--num-cpus=1", "--disable-usage-stats"]
    try:
        subprocess.run(
            [RAY, "start", "--head", f"--port={port}", f"--temp-dir={dirs[0]}", *common,
             "--include-dashboard=false"],
            env=ENV, check=True, capture_output=True, timeout=180,
        )  # fmt: skip
        subprocess.run(
            [RAY, "start", f"--address=127.0.0.1:{port}", f"--temp-dir={dirs[1]}", *common],
            env=ENV, check=True, capture_output=True, timeout=180,
        )  # fmt: skip
        os.environ["RAY_AUTH_MODE"] = "disabled"
        ray.init(address=f"127.0.0.1:{port}", log_to_driver=False)
        deadline = time.monotonic() + 60
        while len([n for n in ray.nodes() if n["Alive"]]) < 2 and time.monotonic() < deadline:
            time.sleep(0.5)
        yield f"127.0.0.1:{port}"
    finally:
        if ray.is_initialized():
            ray.shutdown()
        _end(_pids_of(dirs, port))
        for d in dirs:
            shutil.rmtree(d, ignore_errors=True)


def test_one_server_per_node_driven_by_one_vector_env(two_node_cluster):
    nodes = [n for n in ray.nodes() if n["Alive"]]
    assert len(nodes) == 2
    servers = start_ray_servers()
    try:
        assert len(servers) == 2 and all(isinstance(a, str) for a in servers)
        assert sorted(servers.node_ids) == sorted(n["NodeID"] for n in nodes)
        assert len(set(servers)) == 2  # two servers, two ports
        # Each binds its node's address; off loopback only with a (generated) token.
        ips = {n["NodeID"]: n["NodeManagerAddress"] for n in nodes}
        for address, node in zip(servers, servers.node_ids):
            assert address.rsplit(":", 1)[0] == ips[node]
        if any(not ip.startswith("127.") for ip in ips.values()):
            assert servers.token is not None and len(servers.token) >= 32
        # Each actor runs on the node it was pinned to.
        where = ray.get([a.node_id.remote() for a in servers.actors])
        assert where == servers.node_ids
        n, kw = 6, {"random_target": True, "max_episode_steps": 10}
        native = SixAxisAvoidVectorEnv(n, **kw)
        with RemoteVectorEnv(servers, n, token=servers.token, **kw) as remote:
            np.testing.assert_array_equal(remote.reset(seed=1)[0], native.reset(seed=1)[0])
            for a in np.random.default_rng(0).integers(0, 6, size=(25, n)):
                for x, y in zip(remote.step(a)[:4], native.step(a)[:4]):
                    np.testing.assert_array_equal(x, y)
    finally:
        servers.stop()
    assert servers.actors == []


def test_a_given_token_is_used(two_node_cluster):
    with start_ray_servers(token="given-token-0123456789") as servers:
        assert servers.token == "given-token-0123456789"
        with pytest.raises(PermissionError):
            RemoteVectorEnv(servers, 2, connect_timeout=20)
        with RemoteVectorEnv(servers, 2, token=servers.token) as remote:
            remote.reset(seed=0)
            remote.step(np.array([0, 1]))


def test_the_benchmark_quick_suite_runs_on_both_nodes(two_node_cluster, tmp_path):
    """``benchmark run --address`` from a driver of its own, as a user joins a cluster: every
    run lands, the runs are spread over both nodes, each file records its machine, and a
    run's result equals the same spec run here, outside Ray."""
    from sixaxis_avoid.benchmark.runner import execute_run, load_runs

    out = tmp_path / "quick"
    learners = "q_assist,bfs,ppo"
    subprocess.run(
        [sys.executable, "-m", "sixaxis_avoid.benchmark", "run", "--suite", "quick",
         "--learners", learners, "--address", two_node_cluster, "--out-dir", str(out),
         "--no-progress"],
        env=ENV, check=True, capture_output=True, timeout=900,
    )  # fmt: skip
    runs = load_runs(out)
    want = {(lr, t, s) for lr in learners.split(",") for t in
            ("paper_simple", "gen-easy-0", "goal-paper_simple") for s in (0, 1)}  # fmt: skip
    got = {(r["spec"]["learner"], r["spec"]["task"]["id"], r["spec"]["seed"]) for r in runs}
    assert got == want
    alive = {n["NodeID"] for n in ray.nodes() if n["Alive"]}
    where = {r["host"]["ray_node"] for r in runs}
    assert where == alive and len(where) == 2
    assert all(r["host"]["machine"] for r in runs)
    one = next(r for r in runs if r["spec"]["learner"] == "q_assist")
    here = execute_run(one["spec"])
    assert here["result"]["curve"] == one["result"]["curve"]
    assert here["result"]["paths"] == one["result"]["paths"]


def test_jax_groups_run_as_ray_tasks_on_the_cluster(two_node_cluster, tmp_path):
    """A JAX learner's runs on a cluster: each group (its seeds of one task, vmapped) is a
    Ray task on a node (``--jax-cpus`` capped at the nodes' one CPU, so it is scheduled),
    and its records equal the same group run here, outside Ray."""
    from sixaxis_avoid.benchmark import jax_runs
    from sixaxis_avoid.benchmark.runner import load_runs

    out = tmp_path / "quick-jax"
    tiny = ["net_arch=[16,16]", "n_envs=4", "n_steps=16", "batch_size=32", "n_epochs=1"]
    subprocess.run(
        [sys.executable, "-m", "sixaxis_avoid.benchmark", "run", "--suite", "quick",
         "--learners", "jax_ppo", "--address", two_node_cluster, "--out-dir", str(out),
         "--jax-cpus", "2", "--no-progress", *[f"--set=jax_ppo.{t}" for t in tiny]],
        env=ENV, check=True, capture_output=True, timeout=900,
    )  # fmt: skip
    runs = load_runs(out)
    got = {(r["spec"]["task"]["id"], r["spec"]["seed"]) for r in runs}
    assert got == {(t, s) for t in ("paper_simple", "gen-easy-0", "goal-paper_simple")
                   for s in (0, 1)}  # fmt: skip
    # Three groups on two one-CPU nodes: both nodes train (in the driver, all would be one).
    alive = {n["NodeID"] for n in ray.nodes() if n["Alive"]}
    assert {r["host"]["ray_node"] for r in runs} == alive and len(alive) == 2
    one = [r for r in runs if r["spec"]["task"]["id"] == "paper_simple"]
    here = jax_runs.run_group([r["spec"] for r in sorted(one, key=lambda r: r["spec"]["seed"])])
    for a, b in zip(here, sorted(one, key=lambda r: r["spec"]["seed"])):
        assert a["result"]["curve"] == b["result"]["curve"]
        assert a["result"]["paths"] == b["result"]["paths"]


def test_a_jax_search_trains_its_groups_on_the_cluster(two_node_cluster, tmp_path):
    """``jax_tune --address``: each compiled group (a task here) is a Ray task, and the
    trials equal the same search run in this process."""
    from sixaxis_avoid.benchmark import jax_tune

    fixed = ["net_arch=[16,16]", "n_envs=4", "n_steps=16", "batch_size=32", "n_epochs=1",
             "max_episode_steps=50"]  # fmt: skip
    argv = ["--algo", "ppo", "--suite", "v1", "--tasks", "tune-gen-easy-1000,tune-gen-medium-1001",
            "--budget", "512", "--trials", "3", "--seeds", "2",
            *[f"--set={f}" for f in fixed]]  # fmt: skip
    out = tmp_path / "ray" / "t.json"
    subprocess.run(
        [sys.executable, "-m", "sixaxis_avoid.benchmark.jax_tune", *argv, "--address",
         two_node_cluster, "--out", str(out), "--hyperparams", str(tmp_path / "ray" / "hp.json")],
        env=ENV, check=True, capture_output=True, timeout=900,
    )  # fmt: skip
    remote = json.loads(out.read_text())
    assert remote["ray"] == two_node_cluster and remote["resumed_groups"] == 0
    assert [t["task"] for t in remote["per_task_timing"]] == ["tune-gen-easy-1000",
                                                             "tune-gen-medium-1001"]  # fmt: skip
    here = jax_tune.main([*argv, "--out", str(tmp_path / "here" / "t.json"),
                          "--hyperparams", str(tmp_path / "here" / "hp.json")])  # fmt: skip
    assert_same_trials(here, remote)
    assert not (tmp_path / "ray" / "t.json.parts").exists()
