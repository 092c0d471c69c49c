"""One request layer: the same arguments to ``sixaxis train|plan`` and to
``sixaxis_avoid.train|plan`` give the same run, or the same error text.

Every row of ``GOOD`` and ``BAD`` is a keyword dict for Python and the flags that say the
same on the command line; the CLI and the bindings only map them to the core's request.
"""

from __future__ import annotations

import json
import subprocess

import pytest
import sixaxis_avoid as sa

SCENARIO = "paper_simple"

# (Python keywords, CLI flags) meaning the same thing.
GOOD = [
    ({"episodes": 300}, ["--episodes", "300"]),
    ({"seed": 3, "episodes": 300}, ["--seed", "3", "--episodes", "300"]),
    ({"assist": False, "episodes": 300}, ["--no-assist", "--episodes", "300"]),
    ({"detour": False, "episodes": 300}, ["--no-detour", "--episodes", "300"]),
    (
        {"assist": False, "distance": True, "episodes": 300},
        ["--no-assist", "--distance", "--episodes", "300"],
    ),
    (
        {"max_steps_per_episode": 40, "seed": 1, "episodes": 300},
        ["--max-steps-per-episode", "40", "--seed", "1", "--episodes", "300"],
    ),
    ({"initial_q": "distance", "episodes": 300}, ["--initial-q", "distance", "--episodes", "300"]),
    (
        {"initial_q": "zero", "seed": 2, "episodes": 300},
        ["--initial-q", "zero", "--seed", "2", "--episodes", "300"],
    ),
    ({"q_precision": "f32", "episodes": 300}, ["--q-precision", "f32", "--episodes", "300"]),
    (
        {"q_precision": "f64", "seed": 4, "episodes": 300},
        ["--q-precision", "f64", "--seed", "4", "--episodes", "300"],
    ),
    (
        {"q_precision": "f32", "initial_q": "distance", "seed": 1, "episodes": 300},
        ["--q-precision", "f32", "--initial-q", "distance", "--seed", "1", "--episodes", "300"],
    ),
]

# (Python keywords, CLI flags, the error text both give).
BAD = [
    ({"seed": -1}, ["--seed", "-1"], "invalid argument `seed` = -1: must be an integer >= 0"),
    (
        {"seed": 2**64},
        ["--seed", str(2**64)],
        f"invalid argument `seed` = {2**64}: must be an integer >= 0",
    ),
    ({"seed": 1.5}, ["--seed", "1.5"], "invalid argument `seed` = 1.5: must be an integer >= 0"),
    (
        {"episodes": 0},
        ["--episodes", "0"],
        'invalid argument `episodes` = 0: must be an integer in 1..=4294967295 or "auto"',
    ),
    (
        {"episodes": 2**32},
        ["--episodes", str(2**32)],
        'invalid argument `episodes` = 4294967296: must be an integer in 1..=4294967295 or "auto"',
    ),
    (
        {"max_steps_per_episode": 0},
        ["--max-steps-per-episode", "0"],
        "invalid argument `max_steps_per_episode` = 0: must be an integer in 1..=4294967295",
    ),
    (
        {"initial_q": "optimistic"},
        ["--initial-q", "optimistic"],
        "invalid argument `initial_q` = optimistic: must be one of zero, distance",
    ),
    (
        {"q_precision": "f16"},
        ["--q-precision", "f16"],
        "invalid argument `q_precision` = f16: must be one of f64, f32",
    ),
    (
        {"q_precision": "F32"},
        ["--q-precision", "F32"],
        "invalid argument `q_precision` = F32: must be one of f64, f32",
    ),
]

BAD_PLAN_ONLY = [
    (
        {"max_replans": -1},
        ["--max-replans", "-1"],
        "invalid argument `max_replans` = -1: must be an integer in 0..=4294967295",
    ),
    (
        {"learner": "dqn"},
        ["--learner", "dqn"],
        "invalid argument `learner` = dqn: must be one of qlearning, bfs",
    ),
]


def cli(sixaxis_bin, command: str, flags: list[str]) -> subprocess.CompletedProcess:
    cmd = [str(sixaxis_bin), command, "--scenario", SCENARIO, "-q", *flags]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120)


def untimed(d: dict) -> dict:
    d = dict(d)
    d.pop("wall_time_s", None)
    d["rounds"] = [{k: v for k, v in r.items() if k != "learning_time_s"} for r in d["rounds"]]
    return d


@pytest.mark.parametrize(("kwargs", "flags"), GOOD)
def test_train_same_run(sixaxis_bin, kwargs, flags):
    proc = cli(sixaxis_bin, "train", flags)
    assert proc.returncode == 0, proc.stderr
    c = json.loads(proc.stdout)
    p = sa.train(SCENARIO, **kwargs)
    # One serialisation: the CLI's JSON is Python's to_dict(), field for field.
    timed = ("wall_time_s", "steps_per_second")
    assert {k: v for k, v in c.items() if k not in timed} == {
        k: v for k, v in p.to_dict().items() if k not in timed
    }
    assert (None if c["path"] is None else [tuple(x) for x in c["path"]]) == p.path
    for key in ("converged_episode", "length_converged_episode", "total_steps", "seed"):
        assert c[key] == getattr(p, key), key
    assert c["episodes"] == p.episodes
    assert c["steps_per_episode"] == p.steps_per_episode.tolist()
    assert c["reached_per_episode"] == p.reached_per_episode.tolist()


@pytest.mark.parametrize(("kwargs", "flags"), GOOD)
def test_plan_same_run_and_same_learning_as_train(sixaxis_bin, kwargs, flags):
    proc = cli(sixaxis_bin, "plan", flags)
    assert proc.returncode in (0, 1), proc.stderr
    c = json.loads(proc.stdout)
    p = sa.plan(SCENARIO, **kwargs)
    assert untimed(c) == untimed(p.to_dict())
    # train and plan share every default: round 0 of the plan is the training run.
    t = sa.train(SCENARIO, **kwargs)
    first = p.rounds[0]
    assert first["path"] == (None if t.path is None else [list(x) for x in t.path])
    assert first["total_steps"] == t.total_steps
    assert first["converged_episode"] == t.converged_episode
    assert first["length_converged_episode"] == t.length_converged_episode


@pytest.mark.parametrize("command", ["train", "plan"])
@pytest.mark.parametrize(("kwargs", "flags", "text"), BAD)
def test_same_error(sixaxis_bin, command, kwargs, flags, text):
    proc = cli(sixaxis_bin, command, flags)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.strip() == f"error: {text}"
    fn = getattr(sa, command)
    with pytest.raises(sa.InvalidArgumentError) as info:
        fn(SCENARIO, **kwargs)
    assert str(info.value) == text


@pytest.mark.parametrize(("kwargs", "flags", "text"), BAD_PLAN_ONLY)
def test_same_plan_error(sixaxis_bin, kwargs, flags, text):
    proc = cli(sixaxis_bin, "plan", flags)
    assert proc.returncode == 2 and proc.stderr.strip() == f"error: {text}"
    with pytest.raises(sa.InvalidArgumentError) as info:
        sa.plan(SCENARIO, **kwargs)
    assert str(info.value) == text


@pytest.mark.parametrize("command", ["train", "plan"])
@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"seed": True}, "seed"),
        ({"episodes": False}, "episodes"),
        ({"seed": "3"}, "seed"),
        ({"assist": 1}, "assist"),
        ({"detour": "yes"}, "detour"),
        ({"initial_q": 3}, "initial_q"),
        ({"q_precision": 32}, "q_precision"),
    ],
)
def test_python_only_values_rejected_alike(command, kwargs, name):
    """Values the command line cannot even spell (bools for integers, ints for switches)
    are rejected by train and plan alike."""
    with pytest.raises(sa.InvalidArgumentError) as info:
        getattr(sa, command)(SCENARIO, **kwargs)
    assert info.value.name == name


@pytest.mark.parametrize("command", ["train", "plan"])
def test_keyword_only_after_scenario(command):
    with pytest.raises(TypeError):
        getattr(sa, command)(SCENARIO, 0)


def test_plan_learner_flag_matches_keyword(sixaxis_bin):
    proc = cli(sixaxis_bin, "plan", ["--learner", "bfs", "--max-replans", "3"])
    assert proc.returncode in (0, 1), proc.stderr
    p = sa.plan(SCENARIO, learner="bfs", max_replans=3)
    assert untimed(json.loads(proc.stdout)) == untimed(p.to_dict())
    assert all(r["total_steps"] == 0 for r in p.rounds)


def flag_of(option: dict, value) -> list[str]:
    flag = "--" + option["key"].replace("_", "-")
    if option["kind"] == "bool":
        return [flag if value else "--no-" + flag[2:]]
    return [flag, str(value)]


@pytest.mark.parametrize("command", ["train", "plan"])
def test_every_option_is_a_flag_and_a_keyword(sixaxis_bin, command):
    """The options are declared once in the core: every one is a Python keyword and a CLI
    flag, and giving its default explicitly changes nothing."""
    help_text = subprocess.run(
        [str(sixaxis_bin), command, "--help"], capture_output=True, text=True, timeout=60
    ).stdout
    options = sa.options(command)
    assert {o["key"] for o in options} >= {"seed", "episodes", "assist", "alpha", "gamma"}
    base = {"episodes": 200, "seed": 1}
    fn = getattr(sa, command)
    reference = fn(SCENARIO, **base).to_dict()
    for o in options:
        assert flag_of(o, True)[0] in help_text, o["key"]
        assert o["doc"], o["key"]
        if o["key"] in base or o["key"] == "episode_cap":
            continue
        got = fn(SCENARIO, **base, **{o["key"]: o["default"]}).to_dict()
        assert got["seed"] == reference["seed"], o["key"]
        assert got.get("path") == reference.get("path"), o["key"]
        flags = ["--episodes", "200", "--seed", "1", *flag_of(o, o["default"])]
        proc = cli(sixaxis_bin, command, flags)
        assert proc.returncode in (0, 1), (o["key"], proc.stderr)
        assert json.loads(proc.stdout).get("path") == reference.get("path"), o["key"]


def test_options_describe_their_domains():
    by_key = {o["key"]: o for o in sa.options("plan")}
    assert by_key["alpha"]["min_exclusive"] is True and by_key["alpha"]["max"] == 1.0
    assert by_key["initial_q"]["choices"] == ["zero", "distance"]
    assert by_key["seed"]["field"] == "learning.seed"
    planning = sa.Scenario(SCENARIO).to_dict()["planning"]
    assert by_key["max_replans"]["default"] == planning["max_replans"]
    with pytest.raises(TypeError, match="unexpected keyword argument 'sede'"):
        sa.train(SCENARIO, sede=1)
    with pytest.raises(sa.InvalidArgumentError, match="`alpha` = 0: must be a number in"):
        sa.train(SCENARIO, alpha=0)


def test_stub_and_docs_follow_the_declaration():
    """The stub's option keywords and docs/SCENARIOS.md's table are derived from the core's
    declaration (scripts/derive_options.py); a stale copy fails here."""
    import pathlib
    import sys

    root = pathlib.Path(__file__).resolve().parents[1]
    proc = subprocess.run(
        [sys.executable, str(root / "scripts" / "derive_options.py"), "--check"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr


def test_env_signatures_give_the_core_tables_defaults():
    """Every env keyword's default is declared once, in the core's table (ENV_OPTIONS); the
    Gymnasium envs' signatures repeat it for users' IDEs, and must agree with it."""
    import inspect

    from sixaxis_avoid.env import ENV_DEFAULTS, SixAxisAvoidEnv, SixAxisAvoidGoalEnv
    from sixaxis_avoid.vector import SixAxisAvoidGoalVectorEnv, SixAxisAvoidVectorEnv

    rows = {o["key"]: o for o in sa.options("env")}
    assert set(rows) == set(ENV_DEFAULTS)
    assert ENV_DEFAULTS["assist"] is None and ENV_DEFAULTS["reward_scale"] == 1.0
    checked = 0
    for cls in (
        SixAxisAvoidEnv,
        SixAxisAvoidGoalEnv,
        SixAxisAvoidVectorEnv,
        SixAxisAvoidGoalVectorEnv,
    ):
        params = inspect.signature(cls.__init__).parameters
        for key, p in params.items():
            if key in rows:
                assert p.default == ENV_DEFAULTS[key], (cls.__name__, key, p.default)
                assert type(p.default) is type(ENV_DEFAULTS[key]), (cls.__name__, key)
                checked += 1
        # Every table keyword a class takes is a parameter (or fixed, as obs_type="goal").
        assert {"assist", "reward_scale", "random_target", "arm_aware"} <= set(params)
    assert checked >= 30
