"""Shared fixtures. Tests run headless: Matplotlib uses Agg."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

os.environ.setdefault("MPLBACKEND", "Agg")

# Hypothesis profiles: "ci" (few examples, the CI run; chosen when the CI variable is set),
# "dev" (the default), "long" (a thorough local run). HYPOTHESIS_PROFILE overrides:
#   HYPOTHESIS_PROFILE=long python -m pytest tests/test_hardening.py -q
_COMMON = {"deadline": None, "suppress_health_check": [HealthCheck.too_slow]}
settings.register_profile("ci", max_examples=25, derandomize=True, **_COMMON)
settings.register_profile("dev", max_examples=100, **_COMMON)
settings.register_profile("long", max_examples=3000, **_COMMON)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci" if os.environ.get("CI") else "dev"))

import sixaxis_avoid  # noqa: E402


@pytest.fixture(scope="session")
def paper_simple() -> sixaxis_avoid.Scenario:
    return sixaxis_avoid.Scenario("paper_simple")


@pytest.fixture(scope="session")
def near_target(paper_simple) -> sixaxis_avoid.Scenario:
    """Target one cell below the start, short step cap: episodes end often both ways."""
    return paper_simple.replace(
        name="near_target", target=(0, -2, 3), learning={"max_steps_per_episode": 12}
    )


@pytest.fixture(scope="session")
def paper_simple_plan():
    """Algorithm 2 on paper_simple, seed 0 (a success)."""
    p = sixaxis_avoid.plan("paper_simple", seed=0)
    assert p.success, p.failure
    return p


ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def sixaxis_bin() -> Path:
    """The release `sixaxis` binary; built here if scripts/setup.sh has not built it yet."""
    path = Path(os.environ.get("SIXAXIS_BIN", ROOT / "target" / "release" / "sixaxis"))
    if not path.exists():
        subprocess.run(
            ["cargo", "build", "--release", "-q", "-p", "sixaxis-cli"], cwd=ROOT, check=True
        )
    assert path.exists(), f"no sixaxis binary at {path}"
    return path
