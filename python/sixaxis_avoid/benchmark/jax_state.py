"""A JAX learner's group trained in pieces with its state saved as it goes, so that a long
group (hours of one core at 3M env steps) stopped midway goes on from where it was:
:func:`train_in_pieces` runs the pieces, :func:`save_state` and :func:`load_state` write and
read the state, and :func:`state_meta` reads how far it got. :meth:`jax_learners.Compiled.run`
(with ``state``) compiles the pieces and calls it; ``jax_tune --save-state`` asks for it
(docs/PERFORMANCE.md, *Tuning*).
"""

from __future__ import annotations

import json
import os
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from sixaxis_avoid._deps import require

#: The suffix of a group's saved training state beside its outcome's file in ``parts``
#: (:func:`jax_learners.train_candidates`); not committed (.gitignore): it is large, and only the
#: machine that trains the group reads it.
STATE_SUFFIX = ".state.npz"

#: A group trained with a saved state (:meth:`jax_learners.Compiled.run`) runs in pieces of at most
#: 1/STATE_PIECES of its training iterations ...
STATE_PIECES = 50
#: ... and saves its state after a piece once this many seconds of training have passed
#: since the last save (and at every checkpoint).
STATE_EVERY_S = 300.0


def save_state(path: Path, meta: dict[str, Any], leaves: list[Any]) -> None:
    """Write a training state (``leaves``: the arrays of its pytree, in order; ``meta``:
    plain JSON) to ``path`` (``.npz``), whole or not at all (a temporary file, then a
    rename)."""
    jax = require("jax", "rejax learners")
    arrays = {}
    for i, x in enumerate(leaves):
        if jax.dtypes.issubdtype(x.dtype, jax.dtypes.prng_key):
            x = jax.random.key_data(x)
        arrays[f"leaf{i}"] = np.asarray(x)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez(f, meta=np.asarray(json.dumps(meta)), **arrays)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def load_state(path: Path, mark: str, like: list[Any]) -> tuple[dict[str, Any], list[Any]] | None:
    """The state :func:`save_state` wrote at ``path``, as ``(meta, leaves)``, if it carries
    ``mark`` and its arrays have the shapes and types of ``like`` (the leaves of a fresh
    state); else None (a state from another training, or none)."""
    jax = require("jax", "rejax learners")
    if not path.exists():
        return None
    try:
        with np.load(path) as z:
            meta = json.loads(str(z["meta"]))
            arrays = [z[f"leaf{i}"] for i in range(len(like))] if meta.get("mark") == mark else []
    except (OSError, ValueError, KeyError):
        return None
    if meta.get("mark") != mark:
        return None
    out = []
    for x, y in zip(arrays, like):
        if jax.dtypes.issubdtype(y.dtype, jax.dtypes.prng_key):
            x = jax.random.wrap_key_data(x, impl=jax.random.key_impl(y))
        if x.shape != y.shape or x.dtype != y.dtype:
            return None
        out.append(x)
    return meta, out


def state_meta(path: Path) -> dict[str, Any] | None:
    """The plain-JSON part of the state :func:`save_state` wrote at ``path`` (its arrays are
    not read), or None if there is none or it cannot be read: ``segment``, the checkpoints
    evaluated; ``done``, the training iterations since the last of them; ``evaluations``;
    ``wall_s`` and ``cpu_s``, the training's seconds so far; ``resumes``; ``mark``. Needs no
    JAX."""
    try:
        with np.load(path) as z:
            meta = json.loads(str(z["meta"]))
    except (OSError, ValueError, KeyError):
        return None
    return meta if isinstance(meta, dict) else None


def train_in_pieces(
    ex: dict[str, Any],
    finish: Any,
    batch: dict[str, Any],
    ts: list[Any],
    segments: list[int],
    chunk: int,
    state: Path,
    mark: str,
) -> tuple[Any, Any, float, float, int]:
    """Train from the fresh state ``ts`` (its leaves, C x S batched) through ``segments``
    (training iterations between checkpoints) in pieces of at most ``chunk`` iterations:
    ``ex["advance"](batch, ts, n)``, then ``ex["evaluate"](batch, ts)`` at each checkpoint and
    ``finish(batch, ts, evaluations)`` at the end. The state goes to ``state`` at every
    checkpoint and after a piece once :data:`STATE_EVERY_S` seconds passed since the last
    save; a state there that carries ``mark`` is gone on from. Returns ``(out, params,
    wall_s, cpu_s, resumes)``: times (seconds) add up every call's training, ``resumes``
    counts the calls that went on from a saved state; the file goes at the end."""
    jax = require("jax", "rejax learners")
    jnp = jax.numpy
    saved = load_state(state, mark, ts)
    k, done, evs, wall0, cpu0, resumes = 0, 0, [], 0.0, 0.0, 0
    if saved is not None:
        meta, arrays = saved
        ts = [jnp.asarray(x) for x in arrays]
        k, done, wall0, cpu0 = meta["segment"], meta["done"], meta["wall_s"], meta["cpu_s"]
        evs = [tuple(np.asarray(x) for x in e) for e in meta["evaluations"]]
        resumes = meta["resumes"] + 1
    t0, c0 = time.perf_counter(), time.process_time()
    last_save = t0

    def save() -> None:
        meta = {
            "mark": mark,
            "segment": k,
            "done": done,
            "evaluations": [[x.tolist() for x in e] for e in evs],
            "wall_s": wall0 + time.perf_counter() - t0,
            "cpu_s": cpu0 + time.process_time() - c0,
            "resumes": resumes,
        }
        save_state(state, meta, ts)

    while k < len(segments):
        while done < segments[k]:
            n = min(chunk, segments[k] - done)
            ts = jax.block_until_ready(ex["advance"](batch, ts, jnp.int32(n)))
            done += n
            if time.perf_counter() - last_save >= STATE_EVERY_S:
                save()
                last_save = time.perf_counter()
        evs.append(tuple(np.asarray(x) for x in ex["evaluate"](batch, ts)))
        k, done = k + 1, 0
        if k < len(segments):
            save()
            last_save = time.perf_counter()
    ev = tuple(jnp.asarray(np.stack([e[i] for e in evs], axis=2)) for i in range(len(evs[0])))
    out, params = finish(batch, ts, ev)
    out = jax.tree_util.tree_map(np.asarray, jax.block_until_ready(out))
    wall, cpu = wall0 + time.perf_counter() - t0, cpu0 + time.process_time() - c0
    state.unlink(missing_ok=True)
    return out, params, wall, cpu, resumes
