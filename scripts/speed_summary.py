"""The speed paragraph of README.md, derived from docs/PERFORMANCE.md's generated tables.

The figures live once, in the sections that scripts/bench.py (``core``) and
scripts/bench_sb3.py (``sb3``) write; this script reads those tables and writes the
``speed-summary`` section of docs/PERFORMANCE.md, which ``docsections.py --sync README.md``
copies into the README. bench.py runs it after each report; tests/test_docs.py checks that
the section is what the tables give::

    python scripts/speed_summary.py            # rewrite the section from the tables
    python scripts/speed_summary.py --check    # exit 1 if the section is stale
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

from docsections import sections, splice  # scripts/ is on sys.path when this script runs

PERFORMANCE = Path(__file__).resolve().parent.parent / "docs" / "PERFORMANCE.md"
NAME = "speed-summary"


class StaleTable(SystemExit):
    """A row or figure the summary needs is missing from the tables."""


def cells(text: str, first: str) -> list[str]:
    """The cells of the table row of ``text`` whose first cell starts with ``first``."""
    for line in text.splitlines():
        row = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("|") and row and row[0].startswith(first):
            return row
    raise StaleTable(f"docs/PERFORMANCE.md: no table row starting with {first!r}")


def rate(figure: str) -> str:
    """``1,025,125`` steps/s as ``1.0 M``."""
    return f"{int(figure.replace(',', '')) / 1e6:.1f} M"


def times(ratio: str) -> str:
    """``6.0x ...`` or ``179.7x`` as ``6x`` / ``180x``."""
    m = re.match(r"([\d.]+)x", ratio)
    if m is None:
        raise StaleTable(f"docs/PERFORMANCE.md: {ratio!r} is not a ratio")
    return f"{float(m.group(1)):.0f}x"


def summary(page: str) -> str:
    """The paragraph, from the ``core`` and ``sb3`` sections of ``page``."""
    got = sections(page)
    missing = [s for s in ("core", "sb3") if s not in got]
    if missing:
        raise StaleTable(f"docs/PERFORMANCE.md: no section {', '.join(missing)}")
    core, sb3 = got["core"], got["sb3"]
    m = re.search(r"Measured by `python scripts/bench.py` on (.+?), (\d+) cores", core)
    if m is None:
        raise StaleTable("docs/PERFORMANCE.md: the core section names no machine")
    median = {k: cells(core, f"`{k}`")[1] for k in (
        "fk", "ik_full_solve_8_solutions", "centres_clearance_cells_19_obstacles",
        "algorithm2/plan_paper_simple",
        "algorithm2/plan_replan_clutter")}  # fmt: skip
    train = cells(core, "`train_paper_simple_10k/assist`")
    one = cells(core, "`gym.make('SixAxisAvoid-v0')`")
    vec = cells(core, "native vector env, N = 1024")
    dummy = re.search(r"`(\w+-v\d+)`", one[2])
    sb3_64 = cells(sb3, "64")
    return (
        f"Speed (release, one core of a {m.group(2)}-core {m.group(1)}; derived from the "
        "tables of `docs/PERFORMANCE.md` by `scripts/speed_summary.py`): "
        f"forward kinematics {median['fk']}, inverse kinematics (all 8 solutions) "
        f"{median['ik_full_solve_8_solutions']}, one pose's clearance against 19 obstacles "
        f"{median['centres_clearance_cells_19_obstacles']}, 10,000 learning episodes "
        f"{train[1]} ({train[2]}), a whole Algorithm 2 run "
        f"{median['algorithm2/plan_paper_simple']} (paper_simple) to "
        f"{median['algorithm2/plan_replan_clutter']} (replan_clutter); `gym.make` env "
        f"{rate(one[1])} steps/s ({times(one[2])} `{dummy.group(1) if dummy else '?'}`), "
        f"native vector env {rate(vec[1])} steps/s at N = 1024 ({times(vec[2])} "
        f"`SyncVectorEnv`); the SB3 `VecEnv` on the same batch {rate(sb3_64[1])} steps/s at "
        f"N = 64 ({times(sb3_64[4])} `DummyVecEnv`, {times(sb3_64[5])} `SubprocVecEnv`)."
    )


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    want = summary(PERFORMANCE.read_text())
    if "--check" in argv:
        have = sections(PERFORMANCE.read_text()).get(NAME)
        if have != want:
            print(f"docs/PERFORMANCE.md: section {NAME} is stale: run "
                  "python scripts/speed_summary.py", file=sys.stderr)  # fmt: skip
            return 1
        return 0
    splice(PERFORMANCE, NAME, want)
    return 0


if __name__ == "__main__":
    sys.exit(main())
