"""Docs are the one source code comments cite: no tracked file of the code, tests, scripts
or scenarios mentions the specification file (it is not in the repository; users never see
it), and every section a file cites exists.

The citation form is ``docs/PAGE.md "Section heading"`` (the heading as written after the
``#`` marks, starting with a capital letter), e.g. docs/SCENARIOS.md "Units and the arm".
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
WORD = "SP" + "EC"  # spelt in two parts so that this file does not mention it
#: Files that still mention it, each with why. Each entry must still be needed (checked).
PENDING: set[str] = set()
CITATION = re.compile(r'docs/(\w+\.md),? \\?"([A-Z][^"\\\n]*)\\?"')


def tracked() -> list[Path]:
    out = subprocess.run(
        ["git", "ls-files", "rust", "python", "tests", "scripts", "envs"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    return [ROOT / f for f in out if (ROOT / f).is_file()]


def texts() -> dict[str, str]:
    out = {}
    for path in tracked():
        try:
            out[str(path.relative_to(ROOT))] = path.read_text()
        except UnicodeDecodeError:
            continue  # figures and other binary files
    return out


def headings(page: Path) -> set[str]:
    return {m.group(1).strip() for m in re.finditer(r"^#{1,6} (.+)$", page.read_text(), re.M)}


def test_no_file_mentions_the_spec_file():
    files = texts()
    assert len(files) > 50 and "rust/core/src/grid.rs" in files
    word = re.compile(rf"\b{WORD}\b")
    mentions = sorted(f for f, t in files.items() if word.search(t))
    assert sorted(set(mentions) - PENDING) == [], "cite docs/ instead"
    assert sorted(PENDING - set(mentions)) == [], "drop these from PENDING"


def test_every_cited_section_exists():
    # This file's own examples (docstring, test below) are not citations.
    files = {f: t for f, t in texts().items() if f != "tests/test_docs.py"}
    cited = [(f, *m.groups()) for f, t in files.items() for m in CITATION.finditer(t)]
    # The files that rely on docs/SCENARIOS.md for a fact say where it is stated.
    assert {f for f, _, _ in cited} >= {
        "rust/core/src/grid.rs",
        "rust/core/src/kinematics.rs",
        "rust/core/src/replanning.rs",
        "rust/cli/tests/cli.rs",
        "rust/core/tests/planner.rs",
        "tests/test_scenario_arm.py",
        "envs/paper_simple.json",
    }
    missing = [
        (f, page, section)
        for f, page, section in cited
        if not (ROOT / "docs" / page).is_file() or section not in headings(ROOT / "docs" / page)
    ]
    assert not missing, f"cited sections that docs/ lacks: {missing}"


def test_a_wrong_citation_is_caught():
    text = 'see docs/SCENARIOS.md "Units and the arm" and docs/SCENARIOS.md "No such section"'
    sections = [s for _, s in CITATION.findall(text)]
    assert sections == ["Units and the arm", "No such section"]
    page = headings(ROOT / "docs" / "SCENARIOS.md")
    assert [s in page for s in sections] == [True, False]


def load_docsections():
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "docsections", ROOT / "scripts" / "docsections.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_readme_sections_equal_their_generated_sources():
    ds = load_docsections()
    mine = ds.sections((ROOT / "README.md").read_text())
    assert {"reproduction-learning-time", "benchmark-aggregate", "benchmark-headline"} <= set(mine)
    pages = sorted((ROOT / "docs").glob("*.md"))
    for name, text in mine.items():
        source = ds.source_of(name, pages)
        assert text == ds.sections(source.read_text())[name], (
            f"README.md section {name} differs from {source.name}: "
            "run python scripts/docsections.py --sync README.md"
        )


def test_readme_speed_paragraph_is_derived_from_the_performance_tables():
    """README's speed paragraph is scripts/speed_summary.py's reading of the tables in
    docs/PERFORMANCE.md (copied by --sync), and a table row it needs going missing is an
    error naming the row, not a stale figure."""
    import importlib.util
    import sys

    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        spec = importlib.util.spec_from_file_location(
            "speed_summary", ROOT / "scripts" / "speed_summary.py"
        )
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
    finally:
        sys.path.remove(str(ROOT / "scripts"))
    page = (ROOT / "docs" / "PERFORMANCE.md").read_text()
    ds = load_docsections()
    assert ds.sections(page)["speed-summary"] == mod.summary(page), (
        "run python scripts/speed_summary.py, then python scripts/docsections.py --sync README.md"
    )
    moved = page.replace("| `fk` | 95.0 ns |", "| `fk` | 96.0 ns |")
    assert moved != page and "forward kinematics 96.0 ns" in mod.summary(moved)
    with pytest.raises(SystemExit, match="`fk`"):
        mod.summary(page.replace("| `fk` |", "| `forward` |"))


def test_sync_copies_a_changed_section(tmp_path):
    ds = load_docsections()
    page, readme = tmp_path / "PAGE.md", tmp_path / "README.md"
    page.write_text("# Page\n\n<!-- t:begin -->\n| a | 2 |\n<!-- t:end -->\n")
    readme.write_text("# Readme\n\n<!-- t:begin -->\n| a | 1 |\n<!-- t:end -->\n\nend\n")
    assert ds.sync(readme, [page]) == ["t"]
    assert readme.read_text() == "# Readme\n\n<!-- t:begin -->\n| a | 2 |\n<!-- t:end -->\n\nend\n"
    assert ds.sync(readme, [page]) == []
    readme.write_text("<!-- u:begin -->\nx\n<!-- u:end -->\n")
    with pytest.raises(SystemExit, match="'u': found in no page"):
        ds.sync(readme, [page])


def test_readme_ppo_example_claims_what_its_seed_study_measured():
    """README's PPO example says on how many seeds its settings reach the 9-move path; the
    figure is the one docs/results/readme-ppo-seeds.json records (scripts/readme_ppo_seeds.py),
    and the study ran the README's settings (200,000 steps)."""
    import json

    readme = (ROOT / "README.md").read_text()
    m = re.search(r"on (\d+) of (\d+) seeds here", readme)
    assert m, "README's PPO example no longer says on how many seeds it reaches the target"
    study = json.loads((ROOT / "docs" / "results" / "readme-ppo-seeds.json").read_text())
    assert (int(m.group(1)), int(m.group(2))) == (study["shortest"], len(study["runs"]))
    assert study["steps"] == 200_000 and "200_000" in readme
    assert "3e-4 * progress" in readme
