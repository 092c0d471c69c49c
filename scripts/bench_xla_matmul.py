"""How close the JAX learners come to the machine's arithmetic: XLA's single-threaded
batched matrix product rate, and the dense-layer arithmetic of a PPO candidate per env step.

The rate is floating-point operations per CPU second of this process (so a loaded machine
lowers it less than a wall-clock rate would), for ``x @ w`` with ``w`` of ``--hidden`` x
``--hidden`` and ``--rows`` rows per product, ``--batch`` products in one call (a tuning
group vmaps its candidates and seeds the same way). The arithmetic counts what rejax's PPO
does per env step with an actor and a critic of two hidden layers each (13 observation
values, 6 actions, 1 value): one forward pass of both to act, and per epoch a forward and
a backward pass (about 3 forward passes) of both. Biases, activations and Adam are left
out (a few per cent). docs/PERFORMANCE.md, *JAX learners*, uses both figures::

    taskset -c 0 python scripts/bench_xla_matmul.py --hidden 256 --epochs 3
"""

from __future__ import annotations

import argparse
import json
import os
import time

from sixaxis_avoid.env import VECTOR_OBS_DIM as OBS  # the core's vector observation (13)

ACTIONS = 6  # the six moves of eq. 3


def ppo_flops_per_env_step(hidden: int, epochs: int) -> int:
    """Dense-layer floating-point operations of one env step of rejax's PPO (see above)."""
    actor = 2 * (OBS * hidden + hidden * hidden + hidden * ACTIONS)
    critic = 2 * (OBS * hidden + hidden * hidden + hidden * 1)
    return (actor + critic) * (1 + 3 * epochs)


def matmul_rate(hidden: int, rows: int, batch: int, seconds: float) -> dict[str, float]:
    """Floating-point operations per CPU second and per wall second of a jitted batched
    product, repeated for about ``seconds``."""
    import jax
    import jax.numpy as jnp

    w = jnp.full((batch, hidden, hidden), 1e-3, jnp.float32)
    x = jnp.ones((batch, rows, hidden), jnp.float32)
    f = jax.jit(lambda x, w: jnp.einsum("bij,bjk->bik", x, w))
    f(x, w).block_until_ready()
    flops_per_call = 2 * batch * rows * hidden * hidden
    calls, c0, t0 = 0, time.process_time(), time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        f(x, w).block_until_ready()
        calls += 1
    cpu, wall = time.process_time() - c0, time.perf_counter() - t0
    return {
        "gflop_per_cpu_s": flops_per_call * calls / cpu / 1e9,
        "gflop_per_wall_s": flops_per_call * calls / wall / 1e9,
        "calls": calls,
    }


def main(argv: list[str] | None = None) -> dict[str, object]:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--hidden", type=int, default=256, help="hidden layer width")
    p.add_argument("--epochs", type=int, default=3, help="PPO epochs per update")
    p.add_argument("--rows", type=int, default=128, help="rows per product (a minibatch)")
    p.add_argument("--batch", type=int, default=48, help="products per call (C x S)")
    p.add_argument("--seconds", type=float, default=5.0, help="time to repeat for")
    a = p.parse_args(argv)
    for name in ("hidden", "epochs", "rows", "batch"):
        if getattr(a, name) < 1:
            p.error(f"--{name}: {getattr(a, name)} must be >= 1")
    out = {
        "hidden": a.hidden,
        "epochs": a.epochs,
        "ppo_flops_per_env_step": ppo_flops_per_env_step(a.hidden, a.epochs),
        **matmul_rate(a.hidden, a.rows, a.batch, a.seconds),
    }
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    # One XLA thread, set before jax is imported: a per-core figure.
    os.environ.setdefault(
        "XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
    )
    main()
