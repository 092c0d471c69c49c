"""Mutation fuzzer of the places where a Python object becomes a Rust value.

Each input is the paper's simple scenario as a dict with one value replaced (at a random
field path) by a hostile Python object, or such an object passed straight to another
boundary (``Arm(dh=...)``, ``Arm().fk/ik``, ``env.step``, ``extra_obstacles``, the vector
env's ``step`` and ``seed``). Inputs run in a child process, so that a crash (SIGSEGV,
SIGABRT) is observed rather than fatal: the parent reads which input was in flight, records
it, and restarts the child after it. Besides crashes and hangs, an exception that is not a
``ValueError`` / ``TypeError`` (e.g. a ``PanicException`` or an ``OverflowError``) is a
finding.

    python scripts/fuzz_python.py --inputs 20000 --seed 0 --out fuzz_python.json

Exit status 1 if anything was found. The summary (inputs per target, outcomes, findings
with the input that caused each) is printed as JSON and written to ``--out``.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import random
import subprocess
import sys
import tempfile
import time
from typing import Any

# ---------------------------------------------------------------- hostile values


class HugeLen:
    """A sequence that claims 2**40 items (PyO3 pre-allocated len() items)."""

    def __init__(self, n: int = 2**40):
        self.n = n

    def __len__(self):
        return self.n

    def __getitem__(self, i):
        if i >= 6:
            raise IndexError(i)
        return 0.0


class SelfToList:
    """An object whose ``tolist()`` returns another one of itself."""

    def tolist(self):
        return SelfToList()


class BadIndex:
    def __index__(self):
        raise RuntimeError("__index__ raises")


class BadFloat(float):
    def __float__(self):
        raise RuntimeError("__float__ raises")


class BadRepr:
    def __repr__(self):
        raise RuntimeError("__repr__ raises")


class BytesPath:
    def __fspath__(self):
        return b"/tmp/x.json"


class IntSub(int):
    pass


class StrSub(str):
    pass


class DictKeysRaise(dict):
    def keys(self):
        raise RuntimeError("keys raises")


class ListIterRaise(list):
    def __iter__(self):
        raise RuntimeError("__iter__ raises")


def nested(depth: int, kind: str) -> Any:
    x: Any = 0
    for _ in range(depth):
        x = [x] if kind == "list" else {"k": x}
    return x


def self_ref(kind: str) -> Any:
    if kind == "list":
        x: list = [0, 0]
        x.append(x)
        return x
    d: dict = {"a": 1}
    d["self"] = d
    return d


def hostile(rng: random.Random) -> tuple[str, Any]:
    """One hostile value and a short description of it."""
    import numpy as np

    k = rng.randrange(24)
    if k == 0:
        d = rng.choice([10, 100, 1000, 10_000, 100_000])
        kind = rng.choice(["list", "dict"])
        return f"nested {kind} depth {d}", nested(d, kind)
    if k == 1:
        kind = rng.choice(["list", "dict"])
        return f"self-referential {kind}", self_ref(kind)
    if k == 2:
        v = rng.choice([2**31, -(2**31) - 1, 2**63, -(2**63) - 1, 2**64, 10**100, -(10**5000)])
        return f"int of {v.bit_length()} bits, sign {(v > 0) - (v < 0)}", v
    if k == 3:
        v = rng.choice([float("nan"), float("inf"), -float("inf"), 1e308, -0.0, 5e-324])
        return f"float {v}", v
    if k == 4:
        n = rng.choice([2**40, 2**62, sys.maxsize])
        return f"sequence with len {n}", HugeLen(n)
    if k == 5:
        return "object whose tolist() returns another", SelfToList()
    if k == 6:
        return "__index__ raises", BadIndex()
    if k == 7:
        return "float subclass whose __float__ raises", BadFloat(1.0)
    if k == 8:
        return "__repr__ raises", BadRepr()
    if k == 9:
        return "__fspath__ returns bytes", BytesPath()
    if k == 10:
        return "int subclass", IntSub(rng.randrange(-5, 5))
    if k == 11:
        return "str subclass", StrSub("paper_simple")
    if k == 12:
        return "dict subclass whose keys() raises", DictKeysRaise(a=1)
    if k == 13:
        return "list subclass whose __iter__ raises", ListIterRaise([1, 2, 3])
    if k == 14:
        dt = rng.choice(["i1", "u1", "i8", "u8", "f2", "f4", "f8", "c16", "bool", "O", "U3"])
        shape = rng.choice([(), (3,), (6,), (2, 3), (6, 4), (0,), (3, 0)])
        try:
            a = np.zeros(shape, dtype=dt)
        except (TypeError, ValueError):
            a = np.zeros(3)
        if rng.random() < 0.5 and a.ndim == 2:
            a = a.T
        return f"ndarray {dt} {shape}", a
    if k == 15:
        dt = rng.choice([np.int8, np.uint64, np.float16, np.float32, np.float64, np.bool_])
        return f"numpy scalar {dt.__name__}", dt(rng.choice([0, 1, 3]))
    if k == 16:
        return "bytes", rng.choice([b"", b"\x00\xff", bytearray(b"abc"), memoryview(b"xyz")])
    if k == 17:
        return "set", rng.choice([{1, 2, 3}, frozenset([0, -2, 4])])
    if k == 18:
        return "complex", complex(1, 2)
    if k == 19:
        import decimal
        import fractions

        return "Decimal/Fraction", rng.choice([decimal.Decimal("1.5"), fractions.Fraction(1, 3)])
    if k == 20:
        return "str with NUL / surrogate", rng.choice(["a\x00b", "\ud800", "", "x" * 100_000])
    if k == 21:
        return "None / bool", rng.choice([None, True, False])
    if k == 22:
        return "generator", (i for i in range(3))
    return "odd tuple", rng.choice([(), (0,), (0, -2, 4, 1), ((0, 0), (1,))])


# ---------------------------------------------------------------- targets


def set_at(d: Any, rng: random.Random, value: Any) -> str:
    """Replace a random field (any depth) of the scenario dict `d` by `value`."""
    path = []
    cur = d
    while True:
        if isinstance(cur, dict) and cur:
            key = rng.choice(sorted(cur))
        elif isinstance(cur, list) and cur:
            key = rng.randrange(len(cur))
        else:
            break
        path.append(key)
        if rng.random() < 0.4 or not isinstance(cur[key], (dict, list)):
            cur[key] = value
            return ".".join(map(str, path))
        cur = cur[key]
    return "<root>"


TARGETS = [
    "Scenario(dict)",
    "Scenario.replace",
    "Scenario(any)",
    "Arm(dh)",
    "Arm.fk",
    "Arm.ik",
    "env.step",
    "EnvCore(extra_obstacles)",
    "VecEnvCore.step",
    "VecEnvCore.seed",
]


def run_one(rng: random.Random, base: dict) -> tuple[str, str]:
    """Run one input; returns (target, description)."""
    import copy

    import sixaxis_avoid as sa
    from sixaxis_avoid import _core

    desc, value = hostile(rng)
    target = rng.choice(TARGETS)
    if target == "Scenario(dict)":
        d = copy.deepcopy(base)
        where = set_at(d, rng, value)
        _RUN.inflight(target, f"{where} = {desc}")
        sa.Scenario(d)
    elif target == "Scenario.replace":
        key = rng.choice(sorted(base))
        _RUN.inflight(target, f"{key}= {desc}")
        sa.Scenario().replace(**{key: value})
    elif target == "Scenario(any)":
        _RUN.inflight(target, desc)
        sa.Scenario(value)
    elif target == "Arm(dh)":
        rows = [list(r) for r in sa.Arm().dh]
        if rng.random() < 0.5:
            rows[rng.randrange(6)][rng.randrange(4)] = value
            dh: Any = rows
        else:
            dh = value
        _RUN.inflight(target, desc)
        sa.Arm(dh=dh)
    elif target == "Arm.fk":
        _RUN.inflight(target, desc)
        sa.Arm().fk(value)
    elif target == "Arm.ik":
        _RUN.inflight(target, desc)
        if rng.random() < 0.5:
            sa.Arm().ik(value, rpy_deg=(0, 0, 0))
        else:
            sa.Arm().ik((0, -200, 400), rotation=value)
    elif target == "env.step":
        env = _RUN.env()
        _RUN.inflight(target, desc)
        env.step(value)
    elif target == "EnvCore(extra_obstacles)":
        _RUN.inflight(target, desc)
        _core.EnvCore(extra_obstacles=value)
    elif target == "VecEnvCore.step":
        vec = _RUN.vec()
        _RUN.inflight(target, desc)
        vec.step(value)
    else:
        vec = _RUN.vec()
        _RUN.inflight(target, desc)
        vec.seed(value)
    return target, desc


class _Child:
    """State of the child process: the log of the input in flight, cached envs."""

    def __init__(self, log: str):
        self.log = log
        self._env = None
        self._vec = None

    def inflight(self, target: str, desc: str) -> None:
        with open(self.log, "w") as f:
            f.write(json.dumps({"index": self.index, "target": target, "input": desc}))
            f.flush()
            os.fsync(f.fileno())

    def env(self):
        if self._env is None:
            from sixaxis_avoid.env import SixAxisAvoidEnv

            self._env = SixAxisAvoidEnv()
            self._env.reset(seed=0)
        return self._env

    def vec(self):
        if self._vec is None:
            from sixaxis_avoid import _core

            self._vec = _core.VecEnvCore(num_envs=3, max_episode_steps=100)
        return self._vec


_RUN: _Child


def child(args: argparse.Namespace) -> None:
    global _RUN
    import resource

    # A runaway allocation fails fast instead of swapping the machine.
    resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))
    import sixaxis_avoid as sa

    base = sa.Scenario().to_dict()
    _RUN = _Child(args.log)
    # One line per finished input, appended at once: what ran before a crash still counts.
    with open(args.log + ".jsonl", "a") as out:
        for i in range(args.start, args.start + args.count):
            _RUN.index = i
            rng = random.Random(f"{args.seed}:{i}")
            rec: dict = {}
            try:
                target, _desc = run_one(rng, base)
                rec = {"outcome": f"{target}: accepted"}
            except (ValueError, TypeError) as e:
                rec = {"outcome": f"{_target_of(args.log, i)}: {type(e).__name__}"}
            except BaseException as e:  # every other kind is a finding
                found = {**_last(args.log), "target": _target_of(args.log, i)}
                found.update(kind="exception", exception=f"{type(e).__name__}: {e}"[:300])
                rec = {"outcome": f"{found['target']}: {type(e).__name__}", "finding": found}
            out.write(json.dumps(rec) + "\n")
            out.flush()


def _target_of(log: str, index: int) -> str:
    """The target of input `index`, or "making the input" if it failed before its call."""
    rec = _last(log)
    return rec["target"] if rec["index"] == index else "making the input"


def _last(log: str) -> dict:
    try:
        with open(log) as f:
            return json.loads(f.read())
    except (OSError, ValueError):
        return {"index": -1, "target": "?", "input": "?"}


def parent(args: argparse.Namespace) -> int:
    t0 = time.time()
    outcomes: collections.Counter = collections.Counter()
    findings: list = []
    with tempfile.TemporaryDirectory() as tmp:
        log = os.path.join(tmp, "inflight.json")
        start, end = 0, args.inputs
        while start < end:
            n = min(args.chunk, end - start)
            cmd = [sys.executable, __file__, "--child", "--start", str(start), "--count", str(n)]
            cmd += ["--seed", str(args.seed), "--log", log]
            for p in (log, log + ".jsonl"):
                if os.path.exists(p):
                    os.remove(p)
            try:
                proc = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
                rc = proc.returncode
            except subprocess.TimeoutExpired:
                rc = None
            if os.path.exists(log + ".jsonl"):
                with open(log + ".jsonl") as f:
                    for line in f:
                        rec = json.loads(line)
                        outcomes[rec["outcome"]] += 1
                        if "finding" in rec:
                            findings.append(rec["finding"])
            if rc == 0:
                start += n
                continue
            rec = _last(log)
            kind = "hang" if rc is None else f"process died (exit {rc})"
            if rc is not None and rc < 0:
                kind = f"process killed by signal {-rc}"
            findings.append({**rec, "kind": kind})
            outcomes[f"{rec['target']}: CRASH"] += 1
            # Count the inputs that ran before the crash, then go on after it.
            start = max(start, rec["index"]) + 1 if rec["index"] >= 0 else start + n
    summary = {
        "inputs": args.inputs,
        "seed": args.seed,
        "seconds": round(time.time() - t0, 1),
        "outcomes": dict(sorted(outcomes.items())),
        "findings": findings,
    }
    text = json.dumps(summary, indent=2)
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text + "\n")
    return 1 if findings else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--inputs", type=int, default=2000, help="inputs in all")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--chunk", type=int, default=500, help="inputs per child process")
    ap.add_argument("--timeout", type=float, default=300.0, help="seconds per chunk")
    ap.add_argument("--out", default=None, help="write the JSON summary here too")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--start", type=int, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--count", type=int, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--log", default="", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args)
        return 0
    return parent(args)


if __name__ == "__main__":
    sys.exit(main())
