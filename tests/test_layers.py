"""The Python package's modules stack without cycles, like the core's
(rust/core/tests/layers.rs): every module of ``sixaxis_avoid`` imports only modules declared
below it in ``LAYERS``. Imports are read with ``ast`` (nothing is imported), including the
ones inside functions: a lazy import still ties two modules together.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "python" / "sixaxis_avoid"

#: Bottom first: a module may import the modules before it, never one after it. The
#: extension ``_core`` (Rust) is below everything. A new module gets its place here.
LAYERS = [
    "sixaxis_avoid._core",
    "sixaxis_avoid._deps",
    "sixaxis_avoid._checks",
    "sixaxis_avoid._ids",
    "sixaxis_avoid._goal",
    "sixaxis_avoid._arm",
    "sixaxis_avoid.render",
    "sixaxis_avoid.env",
    "sixaxis_avoid.vector",
    "sixaxis_avoid.joint",
    "sixaxis_avoid.sb3",
    "sixaxis_avoid.remote._session",
    "sixaxis_avoid.remote.env",
    "sixaxis_avoid.remote.vector",
    "sixaxis_avoid.remote._sb3",
    "sixaxis_avoid.remote.ray",
    "sixaxis_avoid.remote",
    "sixaxis_avoid.verify",
    "sixaxis_avoid.animate",
    "sixaxis_avoid",
    # The JAX twin: the env from the core's tables, then what builds on it.
    "sixaxis_avoid.jax.env",
    "sixaxis_avoid.jax",
    "sixaxis_avoid.jax.gymnax_compat",
    "sixaxis_avoid.jax.bench",
    # The benchmark: tools first, then tasks and learners, the runner, the reports, and
    # the command line on top.
    "sixaxis_avoid.benchmark._io",
    "sixaxis_avoid.benchmark.stats",
    "sixaxis_avoid.benchmark.hyperparams",
    "sixaxis_avoid.benchmark.cli",
    "sixaxis_avoid.benchmark.tasks",
    "sixaxis_avoid.benchmark.algorithm2",
    "sixaxis_avoid.benchmark.vec_env",
    "sixaxis_avoid.benchmark.errors",
    "sixaxis_avoid.benchmark.implementation",
    "sixaxis_avoid.benchmark.interface",
    "sixaxis_avoid.benchmark.sb3_learners",
    "sixaxis_avoid.benchmark.learners",
    "sixaxis_avoid.benchmark.runner",
    # The JAX learners build on the learners and the runner's records; the runner reaches
    # them through the learner class (learners.PLUGINS), not by import.
    "sixaxis_avoid.benchmark.jax_values",
    "sixaxis_avoid.benchmark.jax_state",
    "sixaxis_avoid.benchmark.jax_groups",
    "sixaxis_avoid.benchmark.jax_rejax",
    "sixaxis_avoid.benchmark.jax_learners",
    "sixaxis_avoid.benchmark.jax_runs",
    "sixaxis_avoid.benchmark.jax_tune",
    "sixaxis_avoid.benchmark.borrow",
    "sixaxis_avoid.benchmark.sb3_tune",
    "sixaxis_avoid.benchmark.agreement",
    "sixaxis_avoid.benchmark.longer",
    "sixaxis_avoid.benchmark.report",
    "sixaxis_avoid.benchmark.report_compute",
    "sixaxis_avoid.benchmark.report_howto",
    "sixaxis_avoid.benchmark.report_pending",
    "sixaxis_avoid.benchmark.twins",
    "sixaxis_avoid.benchmark.report_setups",
    "sixaxis_avoid.benchmark.report_v2",
    "sixaxis_avoid.benchmark.tune",
    "sixaxis_avoid.benchmark",
    "sixaxis_avoid.benchmark.__main__",
]


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


@functools.cache
def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def imports(path: Path, known: set[str]) -> set[str]:
    """The package's modules that ``path`` imports: ``from A import B`` counts as module
    ``A.B`` when that is a module, else as ``A``; relative imports are resolved."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join([*anchor, *([base] if base else [])])
            for a in node.names:
                sub = f"{base}.{a.name}"
                found.add(sub if sub in known else base)
    return {m for m in found if m in known and m != name}


@functools.cache
def graph() -> dict[str, set[str]]:
    known = set(modules()) | {"sixaxis_avoid._core"}
    return {m: imports(p, known) for m, p in modules().items()}


def test_the_graph_is_read():
    g = graph()
    assert len(g) >= 20, sorted(g)
    assert "sixaxis_avoid.benchmark.tasks" in g["sixaxis_avoid.benchmark.runner"]
    # A lazy import inside a function counts, and `from PACKAGE import MODULE` names it.
    assert "sixaxis_avoid.benchmark.tune" in g["sixaxis_avoid.benchmark.__main__"]
    assert "sixaxis_avoid.benchmark.stats" in g["sixaxis_avoid.benchmark.longer"]
    assert "sixaxis_avoid._core" in g["sixaxis_avoid.env"]


def test_every_module_has_a_layer():
    assert sorted(modules()) == sorted(m for m in LAYERS if m != "sixaxis_avoid._core")
    assert len(set(LAYERS)) == len(LAYERS)


@pytest.mark.parametrize("module", sorted(modules()))
def test_imports_only_lower_layers(module):
    g = graph()
    rank = {m: i for i, m in enumerate(LAYERS)}
    upward = sorted(d for d in g[module] if rank[d] >= rank[module])
    assert not upward, f"{module} imports {upward}, declared above it in LAYERS"


def test_no_cycles():
    g = graph()

    def reaches(start: str) -> set[str]:
        seen: set[str] = set()
        todo = [start]
        while todo:
            for d in g.get(todo.pop(), set()):
                if d not in seen:
                    seen.add(d)
                    todo.append(d)
        return seen

    on_cycle = sorted(m for m in g if m in reaches(m))
    assert not on_cycle, f"modules on an import cycle: {on_cycle}"
