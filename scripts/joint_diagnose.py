"""Can the joint-space env's target be reached at all, and what does greedy descent do?
(docs/JOINT.md, "Baselines"). For each scenario, without any learning:

- the clear IK poses at the target (a 30-degree grid of terminal orientations, within the
  joint limits, every link farther than the safe distance from every box);
- a joint-space RRT-Connect from beta_0 to those poses whose every edge is cut into moves
  of at most ``max_joint_step_deg`` on every joint, each checked with the env's own
  sub-steps (``JointEnvCore.substeps``, ``pose_is_clear``); the path is shortcut, then
  replayed in ``SixAxisAvoidJoint-v0`` (steps, refusals, return, terminal path mm);
- a Jacobian-greedy policy: each step moves the terminal straight at the target
  (pseudo-inverse of a finite-difference Jacobian), the direction the progress reward
  favours; its closest distance, refusals and return over ``--max-episode-steps``;
- whether the straight line from the start terminal to the target passes within a
  cube's box (least gap, mm).

    python scripts/joint_diagnose.py paper_simple generated:1 --json diagnose.json
"""

from __future__ import annotations

import argparse
import itertools
import json
import time

import gymnasium as gym
import numpy as np
import sixaxis_avoid
from sixaxis_avoid import _core


def load(name: str) -> _core.Scenario:
    if name.startswith("generated:"):
        return sixaxis_avoid.generate_scenario(int(name.split(":")[1]))
    return _core.Scenario(name)


class Checker:
    """The env's step check on any joint-space segment: moves of at most one env step on
    every joint, each refused as the env refuses it."""

    def __init__(self, core, step_rad: float):
        self.c, self.step = core, step_rad

    def move_ok(self, a: np.ndarray, b: np.ndarray) -> bool:
        n = self.c.substeps(list(a), list(b))
        return all(self.c.pose_is_clear(list(a + (b - a) * k / n)) for k in range(1, n + 1))

    def edge_ok(self, a: np.ndarray, b: np.ndarray) -> bool:
        m = max(1, int(np.ceil(np.max(np.abs(b - a)) / self.step)))
        prev = a
        for j in range(1, m + 1):
            q = a + (b - a) * j / m
            if not self.move_ok(prev, q):
                return False
            prev = q
        return True


def rrt_connect(check, start, goals, lo, hi, budget_s, rng, ext_deg=10.0):
    ext = np.radians(ext_deg)
    trees = [([start], [-1]), (list(goals), [-1] * len(goals))]

    def extend(tree, q):
        nodes, parents = tree
        i = int(np.argmin(np.sum((np.array(nodes) - q) ** 2, axis=1)))
        d = q - nodes[i]
        length = float(np.linalg.norm(d))
        new = q if length <= ext else nodes[i] + d / length * ext
        if not check.edge_ok(nodes[i], new):
            return None, False
        nodes.append(new)
        parents.append(i)
        return len(nodes) - 1, length <= ext

    def back(tree, i):
        out = []
        while i != -1:
            out.append(tree[0][i])
            i = tree[1][i]
        return out

    t0, iterations, swapped = time.perf_counter(), 0, False
    while time.perf_counter() - t0 < budget_s:
        iterations += 1
        j, _ = extend(trees[0], rng.uniform(lo, hi))
        if j is not None:
            while True:
                k, reached = extend(trees[1], trees[0][0][j])
                if k is None or reached:
                    break
            if k is not None:
                a, b = back(trees[0], j)[::-1], back(trees[1], k)
                path = a + b[1:]
                return (path[::-1] if swapped else path), iterations
        trees.reverse()
        swapped = not swapped
    return None, iterations


def shortcut(check, path, rng, tries=3000):
    for _ in range(tries):
        if len(path) < 3:
            break
        i, j = sorted(rng.choice(len(path), 2, replace=False))
        if j - i >= 2 and check.edge_ok(path[i], path[j]):
            path = path[: i + 1] + path[j:]
    return path


def replay(env, waypoints, step_rad):
    """Follow the waypoints in the env, one straight joint-space move of at most one step
    at a time; returns what the env reports."""
    u = env.unwrapped
    points, total, n, refused, done, info = [u.terminal_mm], 0.0, 0, 0, False, {}
    for q in waypoints[1:]:
        while not done:
            dq = q - u.joints
            if np.max(np.abs(dq)) < 1e-9:
                break
            a = dq / step_rad
            _, r, te, tr, info = env.step(a / max(1.0, float(np.max(np.abs(a)))))
            n, total = n + 1, total + float(r)
            refused += int(info["refused"])
            points.append(u.terminal_mm)
            done = te or tr or bool(info["refused"])
        if done:
            break
    pts = np.array(points)
    return {
        "steps": n,
        "refused": refused,
        "success": bool(info.get("is_success", False)),
        "final_distance_mm": float(info.get("distance_to_target", np.nan)),
        "return": total,
        "terminal_path_mm": float(np.sum(np.linalg.norm(np.diff(pts, axis=0), axis=1))),
    }


def jacobian_greedy(env, arm, step_rad):
    u = env.unwrapped
    done, total, n, refused, closest, info = False, 0.0, 0, 0, np.inf, {}

    def term(q):
        return np.array(arm.points_mm(q))[-1]

    while not done:
        q = np.array(u.joints)
        p = term(q)
        jac = np.stack([(term(q + e) - p) / 1e-6 for e in np.eye(6) * 1e-6], axis=1)
        a = np.linalg.pinv(jac) @ (np.array(u.target_mm) - p) / step_rad
        _, r, te, tr, info = env.step(a / max(1.0, float(np.max(np.abs(a)))))
        n, total = n + 1, total + float(r)
        refused += int(info["refused"])
        closest = min(closest, float(info["distance_to_target"]))
        done = te or tr
    return {
        "steps": n,
        "refused": refused,
        "success": bool(info["is_success"]),
        "closest_distance_mm": closest,
        "return": total,
    }


def diagnose(name: str, max_episode_steps: int, budget_s: float, seed: int) -> dict:
    s = load(name)
    env = gym.make(sixaxis_avoid.JOINT_ENV_ID, scenario=s, max_episode_steps=max_episode_steps)
    env.reset(seed=seed)
    c = env.unwrapped._core
    arm = _core.Arm.from_scenario(s)
    step = np.radians(c.max_joint_step_deg)
    lim = np.array(c.joint_limits_rad)
    lo, hi = lim[:, 0], lim[:, 1]
    target, start = np.array(c.target_mm), np.array(c.terminal_mm)
    line = start + (target - start) * np.linspace(0, 1, 400)[:, None]
    cubes = np.array(s.obstacles, dtype=float) * s.cell_mm
    line_gap = min(
        float(np.linalg.norm(np.maximum(np.abs(line - cc) - s.cell_mm / 2, 0), axis=1).min())
        for cc in cubes
    )
    goals = [
        q
        for rpy in itertools.product(range(-180, 180, 30), repeat=3)
        for q in arm.ik(target, rpy_deg=rpy)
        if np.all(q >= lo) and np.all(q <= hi) and c.pose_is_clear(list(q))
    ]
    out: dict = {
        "scenario": name,
        "obstacle_cells": len(s.obstacles),
        "start_distance_mm": float(np.linalg.norm(target - start)),
        "straight_line_least_gap_to_a_cube_mm": line_gap,
        "clear_ik_poses_at_target": len(goals),
        "best_clear_ik_gap_mm": max((min(c.link_gaps_mm(list(g))) for g in goals), default=None),
    }
    check = Checker(c, step)
    rng = np.random.default_rng(seed)
    path, iterations = (
        rrt_connect(check, np.array(c.beta0_rad), goals, lo, hi, budget_s, rng)
        if goals
        else (None, 0)
    )
    out["rrt_iterations"] = iterations
    out["rrt_found"] = path is not None
    if path is not None:
        path = shortcut(check, path, rng)
        env.reset(seed=seed)
        out["rrt_replay"] = replay(env, path, step)
    env.reset(seed=seed)
    out["jacobian_greedy"] = jacobian_greedy(env, arm, step)
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scenarios", nargs="+")
    p.add_argument("--max-episode-steps", type=int, default=200)
    p.add_argument("--rrt-seconds", type=float, default=30.0, help="RRT budget per scenario")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", default=None)
    a = p.parse_args(argv)
    rows = []
    for name in a.scenarios:
        rows.append(diagnose(name, a.max_episode_steps, a.rrt_seconds, a.seed))
        print(json.dumps(rows[-1]), flush=True)
    if a.json:
        out = {"machine": _core.machine(), "args": vars(a), "scenarios": rows}
        _core.write_atomic(a.json, json.dumps(out, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
