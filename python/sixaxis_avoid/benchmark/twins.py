"""The study's own check that its JAX learners and their SB3 twins agree: each JAX learner
(``jax_ppo``, ``jax_dqn``) against the SB3 learner that runs the same algorithm with its
values, at every budget both ran (docs/BENCHMARKS.md, *JAX and SB3 in the study*).

Entry points: :func:`twin_agreement` (the figures, from a v2 report's analysis) and
:func:`twin_rows` (its page section).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sixaxis_avoid.benchmark import stats
from sixaxis_avoid.benchmark.agreement import permutation_p
from sixaxis_avoid.benchmark.borrow import borrowed_status
from sixaxis_avoid.benchmark.jax_values import JAX_LEARNER
from sixaxis_avoid.benchmark.stats import fmt_ci, fmt_steps

#: Each JAX learner and the SB3 learner that runs the same algorithm with its values (the
#: study's own check that the two implementations agree, *JAX and SB3 in the study*).
TWINS = {jax: sb3 for sb3, jax in JAX_LEARNER.items()}

#: A task is listed as parting when the permutation p of its final scores is below this.
PARTING_P = 0.05


def agree_label(r: dict[str, Any]) -> str:
    """The *agree* cell of a row of :func:`twin_agreement`: ``yes`` when the two intervals
    overlap and the difference's interval holds 0; a row whose intervals overlap but whose
    difference's interval excludes 0 says so (the overlap of two 95% intervals is the
    weaker test); ``**no**`` when the intervals do not overlap."""
    if not r["overlap"]:
        return "**no**"
    lo, hi = r["diff_ci"]
    if lo <= 1e-12 and hi >= -1e-12:
        return "yes"
    return "intervals overlap; the difference's excludes 0"


def twin_agreement(a: dict[str, Any], reps: int = 2000) -> list[dict[str, Any]]:
    """For each pair of :data:`TWINS` and each budget at which both ran every task: both
    learners' mean final SPL on the seeds both ran (95% stratified-bootstrap intervals), the
    difference of the means with an interval from resampling each learner's seeds within
    each task on its own, whether the two intervals overlap, and the tasks whose exact
    two-sided permutation test of the final scores gives p < :data:`PARTING_P`.

    Where the SB3 learner's runs in the study are on values of its own search (a status
    other than :func:`borrow.borrowed_status` of the twin), the runs on the twin's values
    that they replaced (``a["replaced"]``, kept beside the study) stand in, and
    ``sb3_runs`` names their directory; without those on every task the budget gets a row
    with ``skipped`` (the study runs' statuses) and no figures."""
    out: list[dict[str, Any]] = []
    for jx, sb in TWINS.items():
        for b in a["budgets"]:
            if not {jx, sb} <= set(a["per_budget"][b]["complete"]):
                continue
            at = [r for r in a["runs"] if stats.budget_of_run(r) == b]
            twin_status = borrowed_status(jx)
            own = sorted(
                {r["spec"].get("hyperparams_status") for r in at if r["spec"]["learner"] == sb}
                - {None, twin_status}
            )
            source = None
            if own:
                # The SB3 runs here are on values of their own: the runs on the twin's values
                # that they replaced stand in, when every task has them.
                kept: dict[tuple[str, int], dict[str, Any]] = {}
                for rs in a.get("replaced", []):
                    for r in rs["runs"]:
                        spec = r["spec"]
                        if (spec["learner"] == sb and stats.budget_of_run(r) == b
                                and spec.get("hyperparams_status") == twin_status):  # fmt: skip
                            kept[(spec["task"]["id"], spec["seed"])] = r
                            source = rs["dir"]
                if {t for t, _ in kept} != set(a["tasks"]):
                    out.append({"jax": jx, "sb3": sb, "budget": b, "skipped": own})
                    continue
                at = [r for r in at if r["spec"]["learner"] != sb] + list(kept.values())
            scores, seeds = stats.score_matrices(at, [jx, sb], a["tasks"])
            if len(seeds) < 2:
                continue
            x, y = scores[jx], scores[sb]
            rng = np.random.default_rng(0)
            n = len(seeds)
            ix = rng.integers(0, n, size=(reps, n, x.shape[1]))
            iy = rng.integers(0, n, size=(reps, n, x.shape[1]))
            cols = np.arange(x.shape[1])
            diffs = x[ix, cols].mean(axis=(1, 2)) - y[iy, cols].mean(axis=(1, 2))
            mx, cx = stats.mean_ci(x, reps=reps)
            my, cy = stats.mean_ci(y, reps=reps)
            parting = []
            for j, t in enumerate(a["tasks"]):
                p = permutation_p(x[:, j], y[:, j], rng)
                if p < PARTING_P:
                    parting.append({"task": t, "jax": float(x[:, j].mean()),
                                    "sb3": float(y[:, j].mean()), "p": float(p)})  # fmt: skip
            out.append(
                {
                    "jax": jx,
                    "sb3": sb,
                    "budget": b,
                    "seeds": seeds,
                    "jax_mean": mx,
                    "jax_ci": cx,
                    "sb3_mean": my,
                    "sb3_ci": cy,
                    "diff": mx - my,
                    "diff_ci": [float(np.quantile(diffs, 0.025)), float(np.quantile(diffs, 0.975))],
                    "overlap": bool(cx[0] <= cy[1] + 1e-12 and cy[0] <= cx[1] + 1e-12),
                    "parting": parting,
                    "sb3_runs": source,
                }
            )
    return out


def twin_rows(rows: list[dict[str, Any]]) -> list[str]:
    """The *JAX and SB3 in the study* section (:func:`twin_agreement`)."""
    if not rows:
        return []
    L = [
        "## JAX and SB3 in the study",
        "",
        "Each JAX learner against the SB3 learner that runs the same algorithm with its "
        "values, on every task at every budget both ran, on the seeds both ran: mean final "
        "SPL with 95% stratified-bootstrap intervals, the difference (JAX minus SB3) with an "
        "interval from resampling each learner's seeds within each task on its own, and the "
        f"tasks where an exact permutation test of the final scores gives p < {PARTING_P} "
        "(with 21 tasks, about one such task is expected by chance at that level). "
        "*Agree*: the two intervals overlap and the difference's interval holds 0 (a row "
        "whose intervals overlap while the difference's interval excludes 0 says so: the "
        "overlap of two 95% intervals is the weaker test). Where the SB3 learner's runs in "
        "the study are on values of its own search, its earlier runs on the JAX learner's "
        "values, which they replaced and which are kept beside the study "
        "(`docs/results/v2-replaced`), stand in, and the row names them.",
        "",
        "| JAX | SB3 | budget | seeds | JAX mean | SB3 mean | difference | agree | tasks with "
        f"p < {PARTING_P} |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    shown = [r for r in rows if "skipped" not in r]
    for r in shown:
        parting = "; ".join(
            f"{p['task']} ({p['jax']:.2f} vs {p['sb3']:.2f}, p {p['p']:.3f})" for p in r["parting"]
        )
        sb3 = r["sb3"] + (
            f" (its runs on {r['jax']}'s values that the study replaced, `{r['sb3_runs']}`)"
            if r.get("sb3_runs")
            else ""
        )
        L.append(
            f"| {r['jax']} | {sb3} | {fmt_steps(r['budget'])} | {len(r['seeds'])} | "
            f"{fmt_ci(r['jax_mean'], r['jax_ci'])} | {fmt_ci(r['sb3_mean'], r['sb3_ci'])} | "
            f"{r['diff']:+.3f} [{r['diff_ci'][0]:+.3f}, {r['diff_ci'][1]:+.3f}] | "
            f"{agree_label(r)} | {parting or 'none'} |"
        )
    apart = [r for r in shown if agree_label(r) != "yes"]
    if apart:
        L += [
            "",
            "**Where they part**: "
            + "; ".join(
                f"{r['jax']} against {r['sb3']} at {fmt_steps(r['budget'])} (difference "
                f"{r['diff']:+.3f} [{r['diff_ci'][0]:+.3f}, {r['diff_ci'][1]:+.3f}], "
                f"{'intervals apart' if not r['overlap'] else 'intervals overlap'})"
                for r in apart
            )
            + f". With {len(shown)} rows, about {0.05 * len(shown):.1f} whose difference's "
            "95% interval excludes 0 are expected by chance where the two implementations "
            "agree; the tasks in the last column are where to look.",
        ]
    skipped = [r for r in rows if "skipped" in r]
    if skipped:
        L += [
            "",
            "Not compared: "
            + "; ".join(
                f"{r['sb3']} at {fmt_steps(r['budget'])} runs on other values than "
                f"{r['jax']}'s ({', '.join(r['skipped'])}), and none of its runs on "
                f"{r['jax']}'s values are kept"
                for r in skipped
            )
            + ".",
        ]
    return [*L, ""]
