"""Run sets in progress beside a study: ``<results>-pending/<dir>``, each one `run` command
(or one ``sb3_tune`` search, its log directory, or one ``jax_tune`` search, its parts
directory) too long for one sitting, committed part way
so that the same command resumes it on another day or machine
(docs/results/v2-pending/README.md). No figure reads them; the v2 page names them in its
headline.

Entry points: :func:`sets_in_progress` (each set's learners, budgets, runs made of its
command's, wall time so far) and :func:`in_progress_sentence` (the page's line).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from sixaxis_avoid.benchmark.jax_groups import saved_groups_count
from sixaxis_avoid.benchmark.runner import load_runs, run_key
from sixaxis_avoid.benchmark.stats import fmt_steps


def sets_in_progress(results: Path) -> list[dict[str, Any]]:
    """Run sets in progress beside the study ``results``: ``<results>-pending/<dir>``, each
    filled by one `run` command that is too long for one sitting and committed part way, so
    the command in its ``study.json`` resumes it on another day or machine. No figure reads
    them; a complete set is merged into the study (``scripts/implementation_ablation.py
    merge-v2``) and its directory removed."""
    root = results.parent / f"{results.name}-pending"
    out = []
    for manifest in sorted(root.glob("*/study.json")):
        man = json.loads(manifest.read_text())
        runs = load_runs(manifest.parent) if (manifest.parent / "runs").is_dir() else []
        # "jax_tune": a JAX search's parts directory; its units are compiled groups, each
        # saved as TASK--IDENT.json (jax_groups.group_part), or one such file per seed for
        # a group split by seed, not run files.
        groups = (
            saved_groups_count(manifest.parent, len(man.get("seeds", [])))
            if man.get("kind") == "jax_tune"
            else None
        )
        out.append(
            {
                "dir": str(manifest.parent),
                "learners": man["learners"],
                "budgets": [int(man["budget"])]
                if groups is not None
                else sorted({int(r["spec"]["budget"]) for r in runs}),
                "made": len(runs) if groups is None else groups,
                "of": int(man["runs"]),
                "finished": bool(man.get("finished", True)),
                "wall_time_s_total": float(man.get("wall_time_s_total", 0.0)),
                "command": man["command"],
                # "sb3_tune": SB3's own search (its log directory's manifest); else runs.
                "kind": man.get("kind", "run"),
                "candidates": man.get("candidates"),
                "seeds": man.get("seeds", []),
                "tasks": man.get("tasks", []),
                # A re-run (new values at a budget): its run files replace the study's
                # files of the same names once merged; how many the study has of them.
                "replaces": sum(
                    (results / "runs" / f"{run_key(r['spec'])}.json").exists() for r in runs
                ),
            }
        )
    return out


def _describe(p: dict[str, Any]) -> str:
    budgets = ", ".join(fmt_steps(b) for b in p["budgets"]) or "—"
    what = f"{', '.join(p['learners'])} at {budgets}"
    unit = "runs"
    if p["kind"] == "sb3_tune":
        what = (
            f"SB3's own search for {what} ({p['candidates']} candidates x {len(p['seeds'])} "
            f"seeds x {len(p['tasks'])} tuning tasks)"
        )
    elif p["kind"] == "jax_tune":
        what = (
            f"the JAX search for {what} ({p['candidates']} candidates x {len(p['seeds'])} "
            f"seeds x {len(p['tasks'])} tuning tasks)"
        )
        unit = "compiled groups"
    elif p.get("replaces"):
        what = f"{what} again on its current hyperparameters (to replace the study's runs there)"
    return (
        f"{what}, {p['made']} of {p['of']} {unit} in `{p['dir']}` "
        f"({p['wall_time_s_total'] / 3600:.1f} h of wall time so far)"
    )


def in_progress_sentence(pending: list[dict[str, Any]]) -> str:
    """The run sets in progress (:func:`sets_in_progress`): a paragraph under the headline."""
    if not pending:
        return ""
    return (
        "In progress, committed part way beside the study and not in any figure until "
        "complete (the same command, in each directory's `study.json`, runs the rest): "
        + "; ".join(_describe(p) for p in pending)
        + "."
    )


def replaced_sets(results: Path) -> list[dict[str, Any]]:
    """Run files a re-run replaced in the study ``results``, kept beside it in
    ``<results>-replaced/<dir>`` (``scripts/implementation_ablation.py merge-v2``): each
    set's ``dir``, ``learner``, ``budgets`` (env steps), the ``commands`` that made them, the
    command that ``replaced_by`` them, and its ``runs`` (the records). No figure of the study
    reads them; the check of JAX against SB3 does (:mod:`twins`) where the SB3 runs that
    replaced them are on other values than the JAX learner's."""
    root = results.parent / f"{results.name}-replaced"
    out = []
    for about in sorted(root.glob("*/replaced.json")):
        meta = json.loads(about.read_text())
        out.append({"dir": str(about.parent), **meta, "runs": load_runs(about.parent)})
    return out
