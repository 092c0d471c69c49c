"""Hostile input at every boundary: the process survives, every failure is a ValueError
subclass (TypeError where Python convention says so) naming the argument, and a rejected
call changes nothing.

The crash regressions run in a child process, so that a regression fails one test instead
of killing the run. The property tests use Hypothesis; the number of examples comes from the
profile (conftest.py: "ci" when the CI variable is set, HYPOTHESIS_PROFILE to choose).
"""

from __future__ import annotations

import copy
import json
import operator
import subprocess
import sys

import numpy as np
import pytest
import sixaxis_avoid as sa
from hypothesis import assume, given
from hypothesis import strategies as st
from sixaxis_avoid.env import SixAxisAvoidEnv
from sixaxis_avoid.vector import SixAxisAvoidVectorEnv

# ------------------------------------------------------------------ crash regressions

_PRELUDE = """
import sixaxis_avoid as sa
from sixaxis_avoid import _core
class HugeLen:
    def __init__(self, n): self.n = n
    def __len__(self): return self.n
    def __getitem__(self, i):
        if i >= 7: raise IndexError(i)
        return 0.0
class SelfToList:
    def tolist(self): return SelfToList()
class BytesPath:
    def __fspath__(self): return b"/tmp/x.json"
def nested(depth):
    x = 0
    for _ in range(depth): x = [x]
    return x
d = sa.Scenario().to_dict()
"""

# Each of these killed the interpreter (SIGSEGV / SIGABRT) or leaked a non-ValueError before
# the fix; the expected exception class follows.
CRASHES = {
    "self-referential dict": ("d['notes'] = d; sa.Scenario(d)", "ScenarioParseError"),
    "self-referential list": (
        "x = [1]; x.append(x); d['start'] = x; sa.Scenario(d)",
        "ScenarioParseError",
    ),
    "100000-deep list": ("d['obstacles'] = nested(100_000); sa.Scenario(d)", "ScenarioParseError"),
    "100000-deep dict": (
        "x = {}\nfor _ in range(100_000): x = {'k': x}\nsa.Scenario(x)",
        "ScenarioParseError",
    ),
    "tolist() returning another": (
        "d['notes'] = SelfToList(); sa.Scenario(d)",
        "ScenarioParseError",
    ),
    "replace() with a self-reference": (
        "x = {}; x['x'] = x; sa.Scenario().replace(learning=x)",
        "ScenarioParseError",
    ),
    "fk of a sequence claiming 2**40 items": (
        "sa.Arm().fk(HugeLen(2**40))",
        "InvalidArgumentError",
    ),
    "fk of a sequence claiming 2**62 items": (
        "sa.Arm().fk(HugeLen(2**62))",
        "InvalidArgumentError",
    ),
    "ik rotation claiming 2**40 rows": (
        "sa.Arm().ik((0, -200, 400), rotation=HugeLen(2**40))",
        "InvalidArgumentError",
    ),
    "Arm(dh=...) claiming 2**40 rows": ("sa.Arm(dh=HugeLen(2**40))", "InvalidArgumentError"),
    "vector seeds claiming 2**40 items": (
        "_core.VecEnvCore(num_envs=2, max_episode_steps=5).seed(HugeLen(2**40))",
        "InvalidArgumentError",
    ),
    "deep list as an action": (
        "e = _core.EnvCore(); e.step(nested(100_000))",
        "InvalidArgumentError",
    ),
    "bounds of 2**96 cells": (
        "d['bounds'] = {'min': [-2**31] * 3, 'max': [2**31 - 1] * 3}; sa.Scenario(d)",
        "ScenarioError",
    ),
    "bounds whose cell count wrapped to 0": (
        "d['bounds'] = {'min': [-2**21, -2**21, -2**19], 'max': [2**21 - 1, 2**21 - 1, 2**19 - 1]};"
        " sa.Scenario(d)",
        "ScenarioError",
    ),
    "train(episodes=2**70)": ("sa.train(episodes=2**70)", "InvalidArgumentError"),
    "__fspath__ returning bytes": ("sa.Scenario(BytesPath())", "InvalidArgumentError"),
    "/dev/zero as a scenario": ("sa.Scenario('/dev/zero')", "SixAxisIOError"),
}


@pytest.mark.parametrize("name", sorted(CRASHES))
def test_crash_regression_is_a_clean_error(name):
    code, expected = CRASHES[name]
    script = (
        _PRELUDE
        + "try:\n    "
        + code.replace("\n", "\n    ")
        + "\n    print('ACCEPTED')\n"
        + "except BaseException as e:\n"
        + "    print(type(e).__name__, isinstance(e, ValueError), str(e)[:300])\n"
    )
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, f"{name}: the process died ({r.returncode}): {r.stderr[-800:]}"
    kind, is_value_error, *_ = [*r.stdout.split(" ", 2), "", ""]
    assert kind == expected, f"{name}: {r.stdout}"
    assert is_value_error == "True", r.stdout


# ------------------------------------------------------------------ hostile values


class _Odd:
    """Objects with odd protocols."""

    class RaisingIndex:
        def __index__(self):
            raise RuntimeError("no index")

    class RaisingRepr:
        def __repr__(self):
            raise RuntimeError("no repr")

    class IntSub(int):
        pass


def _nested(depth: int):
    x: object = 0
    for _ in range(depth):
        x = [x]
    return x


def _self_ref():
    x: list = [0]
    x.append(x)
    return x


_json_leaf = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(),
    st.floats(),
    st.text(max_size=8),
)
hostile = st.one_of(
    _json_leaf,
    st.recursive(
        _json_leaf,
        lambda c: st.lists(c, max_size=4) | st.dictionaries(st.text(max_size=4), c, max_size=3),
        max_leaves=10,
    ),
    st.binary(max_size=8),
    st.sampled_from([64, 65, 500, 5000]).map(_nested),
    st.builds(_self_ref),
    st.builds(_Odd.RaisingIndex),
    st.builds(_Odd.RaisingRepr),
    st.integers(-5, 5).map(_Odd.IntSub),
    st.sampled_from(
        [np.float32(1.5), np.int64(3), np.uint64(2**64 - 1), np.bool_(True), np.zeros((2, 3))]
    ),
    st.sampled_from([{1, 2}, frozenset(), complex(1, 1), (i for i in range(3))]),
)

BASE = sa.Scenario().to_dict()


def _paths(v, prefix=()):
    yield prefix
    if isinstance(v, dict):
        for k, x in v.items():
            yield from _paths(x, (*prefix, k))
    elif isinstance(v, list):
        for i, x in enumerate(v):
            yield from _paths(x, (*prefix, i))


FIELD_PATHS = [p for p in _paths(BASE) if p]


@given(path=st.sampled_from(FIELD_PATHS), value=hostile)
def test_scenario_dict_with_any_value_is_valid_or_a_scenario_error(path, value):
    d = copy.deepcopy(BASE)
    cur = d
    for k in path[:-1]:
        cur = cur[k]
    cur[path[-1]] = value
    try:
        s = sa.Scenario(d)
    except sa.ScenarioError as e:
        if type(e) is sa.ScenarioError:
            assert e.field, e  # names the field
        else:  # a parse error names the field it could not read
            assert f"field `{path[0]}" in str(e), (path, str(e))
        return
    s.validate()
    assert sa.Scenario.from_json(s.to_json()) == s


@given(text=st.text(max_size=200))
def test_scenario_from_any_text_is_an_error(text):
    with pytest.raises(ValueError):  # ScenarioParseError, or UnicodeEncodeError for surrogates
        sa.Scenario.from_json(text)


@given(data=st.data())
def test_scenario_json_with_character_edits(data):
    text = sa.Scenario().to_json()
    for _ in range(data.draw(st.integers(1, 3))):
        i = data.draw(st.integers(0, len(text)))
        text = text[:i] + data.draw(st.text(max_size=4)) + text[i + data.draw(st.integers(0, 4)) :]
    try:
        s = sa.Scenario.from_json(text)
    except ValueError:
        return
    assert sa.Scenario.from_json(s.to_json()) == s


@given(blob=st.binary(max_size=300))
def test_scenario_from_a_file_of_any_bytes(tmp_path_factory, blob):
    p = tmp_path_factory.mktemp("scen") / "s.json"
    p.write_bytes(blob)
    with pytest.raises(ValueError):
        sa.Scenario(p)


def test_scenario_from_a_directory_or_a_missing_file(tmp_path):
    with pytest.raises(sa.SixAxisIOError):
        sa.Scenario(str(tmp_path) + "/")
    with pytest.raises(sa.SixAxisIOError):
        sa.Scenario(tmp_path / "missing.json")


# ------------------------------------------------------------------ Arm

_number = st.one_of(st.floats(), st.integers(), st.integers(-(10**400), 10**400))


@given(joints=st.one_of(st.lists(_number, max_size=8), hostile))
def test_fk_takes_six_finite_numbers_or_names_the_argument(joints):
    try:
        ok = len(joints) == 6 and all(np.isfinite(float(x)) for x in joints)
    except (TypeError, ValueError, OverflowError, RuntimeError):
        ok = False
    if isinstance(joints, (str, bytes, dict)):
        ok = False
    try:
        pos, rot = sa.Arm().fk(joints)
    except sa.InvalidArgumentError as e:
        assert not ok, e
        assert e.name == "joints_rad"
        return
    assert ok, joints
    assert pos.shape == (3,) and rot.shape == (3, 3)


@given(position=st.lists(_number, min_size=0, max_size=4), rpy=st.lists(_number, max_size=4))
def test_ik_inputs_are_checked(position, rpy):
    try:
        sols = sa.Arm().ik(position, rpy_deg=rpy)
    except sa.InvalidArgumentError as e:
        assert e.name in ("position_mm", "rpy_deg")
        return
    assert sols.ndim == 2 and sols.shape[1] == 6


@given(dh=hostile)
def test_arm_dh_of_anything(dh):
    assume(dh is not None)  # None is the paper's arm
    with pytest.raises(sa.InvalidArgumentError) as info:
        sa.Arm(dh=dh)
    assert info.value.name == "dh"


# ------------------------------------------------------------------ env actions

NUMPY_SCALARS = [
    np.int8, np.int16, np.int32, np.int64, np.uint8, np.uint16, np.uint32, np.uint64,
    np.float16, np.float32, np.float64, np.bool_, np.complex64,
]  # fmt: skip


def _expected_action(v):
    if isinstance(v, (np.bool_, np.ndarray)) and not (isinstance(v, np.ndarray) and v.ndim == 0):
        return None
    if isinstance(v, np.bool_):
        return None
    try:
        i = operator.index(v)
    except (TypeError, RuntimeError):
        return None
    return i if 0 <= i < 6 else None


actions = st.one_of(
    st.integers(),
    st.integers(-(2**80), 2**80),
    st.floats(),
    st.tuples(st.sampled_from(NUMPY_SCALARS), st.integers(-3, 8)).map(
        lambda t: np.array(t[1]).astype(t[0])[()]  # wraps like a C cast: uint8(-1) = 255
    ),
    st.integers(-2, 8).map(np.array),
    st.lists(st.integers(0, 5), max_size=3).map(np.array),
    hostile,
)


@pytest.fixture(scope="module")
def env():
    e = SixAxisAvoidEnv()
    e.reset(seed=0)
    return e


@given(action=actions)
def test_env_step_accepts_0_to_5_and_rejects_the_rest_unchanged(env, action):
    expected = _expected_action(action)
    before = (env.cell, env._core.steps)
    try:
        env.step(action)
    except sa.InvalidArgumentError as e:
        assert expected is None, (action, e)
        assert e.name == "action"
        assert (env.cell, env._core.steps) == before
        return
    assert expected is not None, action
    if env._core.steps > 200:
        env.reset()


@pytest.fixture(scope="module")
def vec():
    v = SixAxisAvoidVectorEnv(num_envs=4)
    v.reset(seed=0)
    return v


@given(
    dtype=st.sampled_from(["i1", "u1", "i4", "i8", "u8", "f4", "f8", "bool", "O"]),
    shape=st.sampled_from([(4,), (4, 1), (1, 4), (2, 2), (3,), (5,), (), (0,), (8,)]),
    fill=st.integers(-3, 8),
    strided=st.booleans(),
)
def test_vector_actions_of_any_shape_dtype_and_layout(vec, dtype, shape, fill, strided):
    n = int(np.prod(shape)) if shape else 1
    values = np.array([(fill + i) % 9 - 1 for i in range(n)])
    if strided and len(shape) == 1:
        big = np.zeros(2 * n, dtype=dtype)
        a = big[::2]
        a[:] = values.astype(dtype)
    else:
        a = values.astype(dtype).reshape(shape)
    valid = dtype in ("i1", "u1", "i4", "i8", "u8") and a.size == 4 and ((a >= 0) & (a < 6)).all()
    before = (vec._core.steps.copy(), vec._core.cells.copy())
    try:
        vec.step(a)
    except sa.InvalidArgumentError as e:
        assert not valid, (a, e)
        assert e.name == "actions"
        assert (vec._core.steps == before[0]).all() and (vec._core.cells == before[1]).all()
        return
    assert valid, a


# ------------------------------------------------------------------ train / plan keywords

_not_a_count = st.one_of(
    st.integers(max_value=0),
    st.integers(min_value=2**32),
    st.floats(),
    st.text(max_size=4),
    st.booleans(),
    st.builds(list),
)


@given(name=st.sampled_from(["episodes", "max_steps_per_episode"]), value=_not_a_count)
def test_train_rejects_bad_counts_naming_them(near_target, name, value):
    with pytest.raises(sa.InvalidArgumentError) as info:
        sa.train(near_target, **{name: value})
    assert info.value.name == name


@given(
    value=st.one_of(
        st.integers(max_value=-1), st.integers(min_value=2**64), st.floats(), st.text(max_size=3)
    )
)
def test_train_and_plan_reject_bad_seeds(near_target, value):
    for fn in (sa.train, sa.plan):
        with pytest.raises(sa.InvalidArgumentError) as info:
            fn(near_target, seed=value)
        assert info.value.name == "seed"


@given(episodes=st.integers(1, 30), seed=st.integers(0, 2**64 - 1), steps=st.integers(1, 20))
def test_train_accepts_every_valid_keyword(near_target, episodes, seed, steps):
    r = sa.train(near_target, episodes=episodes, seed=seed, max_steps_per_episode=steps)
    assert r.episodes == episodes and r.seed == seed


@given(name=st.sampled_from(["episodes", "max_replans"]), value=_not_a_count)
def test_plan_rejects_bad_counts_naming_them(near_target, name, value):
    assume(
        not (
            name == "max_replans"
            and isinstance(value, int)
            and not isinstance(value, bool)
            and 0 <= value < 2**32
        )
    )
    with pytest.raises(sa.InvalidArgumentError) as info:
        sa.plan(near_target, **{name: value})
    assert info.value.name == name


# ------------------------------------------------------------------ Q-table files


@pytest.fixture(scope="module")
def saved_q(tmp_path_factory, near_target):
    r = sa.train(near_target, episodes=50, seed=1)
    p = tmp_path_factory.mktemp("q") / "q.bin"
    r.save_q(p)
    return p.read_bytes(), r.q


@given(data=st.data())
def test_qtable_truncated_or_bit_flipped_is_an_error(tmp_path_factory, near_target, saved_q, data):
    blob, q = saved_q
    kind = data.draw(st.sampled_from(["truncate", "flip", "append"]))
    b = bytearray(blob)
    if kind == "truncate":
        b = b[: data.draw(st.integers(0, len(b) - 1))]
    elif kind == "flip":
        i = data.draw(st.integers(0, len(b) - 1))
        b[i] ^= 1 << data.draw(st.integers(0, 7))
    else:
        b += data.draw(st.binary(min_size=1, max_size=16))
    p = tmp_path_factory.mktemp("qm") / "q.bin"
    p.write_bytes(bytes(b))
    try:
        got = sa.load_q(p, near_target)
    except (sa.SixAxisIOError, sa.QTableMismatchError) as e:
        assert str(e) and "None: " not in str(e)
        return
    # A flip in the JSON header's insignificant whitespace could parse; values must match.
    np.testing.assert_array_equal(got, q)


def test_qtable_of_another_world_is_a_mismatch(saved_q, tmp_path, near_target):
    p = tmp_path / "q.bin"
    p.write_bytes(saved_q[0])
    for other in (sa.Scenario("paper_simple"), near_target.replace(obstacles=[(1, 1, 1)])):
        with pytest.raises(sa.QTableMismatchError):
            sa.load_q(p, other)


def test_qtable_with_a_non_finite_value_is_refused(saved_q, tmp_path, near_target):
    # A NaN written with a correct checksum (a buggy writer, not a flipped bit).
    blob, q = saved_q
    head, body = blob.rsplit(b"\n", 1)[0], None
    magic, header = blob.split(b"\n", 2)[:2]
    body = np.array(q, dtype="<f8")
    body[0, 0] = np.nan
    raw = body.tobytes()
    h = json.loads(header)
    ck = 0xCBF29CE484222325
    for byte in raw:
        ck = ((ck ^ byte) * 0x100000001B3) % 2**64
    h["values_checksum"] = f"{ck:016x}"
    p = tmp_path / "nan.bin"
    p.write_bytes(magic + b"\n" + json.dumps(h, separators=(",", ":")).encode() + b"\n" + raw)
    del head
    with pytest.raises(sa.SixAxisIOError, match="not a finite number"):
        sa.load_q(p, near_target)
