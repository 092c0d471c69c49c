"""SB3 PPO against rejax's PPO (jax_ppo) at suite v2's 30k values: which implementation
difference makes SB3 PPO fail where jax_ppo succeeds (issue 25)?

    python scripts/ppo_ablation.py run --out-dir /work/runs/ppo-agree
    python scripts/ppo_ablation.py summary --runs /work/runs/ppo-agree \\
        --out docs/results/agreement/ppo-v2-ablation.json
    python scripts/ppo_ablation.py merge-v2 --new /work/runs/ppo-agree/v2   # the v2 re-run

``run`` trains SB3 PPO (the benchmark's ``ppo`` learner, through the benchmark's own runner)
with jax_ppo's tuned 30k values on a few v2 tasks and seeds, once with SB3's implementation
and once per factor changed toward rejax 0.1.3's (``learners.PPO_IMPLEMENTATION``), then with
all of them (``implementation: rejax``); each variant into its own directory. ``summary``
gathers the final scores per variant, task and seed with jax_ppo's committed runs on the same
tasks and seeds (docs/results/v2) into one JSON, with the commands that made them.
"""

from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
HP = "python/sixaxis_avoid/benchmark/hyperparams/v2.json"
TASKS = ["gen-easy-1", "gen-easy-2", "gen-medium-3"]
SEEDS = 3
#: Variant name -> the ``--set`` overrides of the ppo learner (SB3's names / the learner's
#: implementation keys), on top of ``ppo.implementation=null`` (SB3's own implementation:
#: the v2 file's ppo values had no implementation key when the ablation ran).
VARIANTS: dict[str, list[str]] = {
    "sb3": [],
    "init": ["ppo.init=lecun"],
    "vfclip": ["ppo.clip_range_vf=0.3"],
    "gradclip": ["ppo.grad_clip=per_network"],
    "notrunc": ["ppo.bootstrap_truncated=false"],
    "torchinit": ["ppo.init=torch"],
    "rejax": [
        "ppo.init=lecun",
        "ppo.grad_clip=per_network",
        "ppo.bootstrap_truncated=false",
        "ppo.clip_range_vf=0.3",
    ],
}
WHAT = {
    "sb3": "SB3's PPO as the benchmark ran it (orthogonal init, policy head gain 0.01; one "
    "gradient norm clip over actor and critic; truncation bootstrapped; no value clipping)",
    "init": "only the initialisation changed: LeCun normal, zero biases (flax's default, rejax's)",
    "vfclip": "only value clipping added: clip_range_vf = clip_range = 0.3 (rejax clips the "
    "value with clip_eps)",
    "gradclip": "only the gradient clipping changed: actor and critic each clipped to "
    "max_grad_norm on its own (rejax: one optimiser per network)",
    "notrunc": "only truncation changed: a truncated episode ends the return (rejax: done = "
    "terminated or truncated, no bootstrap)",
    "torchinit": "only the initialisation changed: PyTorch's default nn.Linear init (SB3's "
    "ortho_init=False), no 0.01-gain policy head",
    "rejax": "all four changed (implementation 'rejax')",
}


def command(variant: str, out_dir: Path) -> list[str]:
    cmd = [
        "python", "-m", "sixaxis_avoid.benchmark", "run", "--suite", "v2", "--learners", "ppo",
        "--budgets", "30000", "--tasks", ",".join(TASKS), "--seeds", str(SEEDS),
        "--hyperparams", HP,
    ]  # fmt: skip
    # The v2 file's ppo entry now names implementation 'rejax'; null takes SB3's own back, as
    # the file had it when the ablation ran (without this flag).
    for s in ["ppo.implementation=null", *VARIANTS[variant]]:
        cmd += ["--set", s]
    return [*cmd, "--no-ray", "--no-progress", "--out-dir", str(out_dir / variant)]


def final_scores(run_dir: Path, learner: str) -> dict[str, list[float]]:
    out: dict[str, list[float]] = {}
    for t in TASKS:
        out[t] = []
        for s in range(SEEDS):
            f = run_dir / "runs" / f"{t}__{learner}__s{s}__b30000.json"
            out[t].append(float(json.loads(f.read_text())["result"]["score"]))
    return out


def summary(runs: Path, v2: Path) -> dict:
    jax = final_scores(v2, "jax_ppo")
    rows = {}
    for v in VARIANTS:
        d = runs / v
        scores = final_scores(d, "ppo")
        spec = json.loads(next((d / "runs").glob("*.json")).read_text())["spec"]
        flat = [x for t in TASKS for x in scores[t]]
        rows[v] = {
            "what": WHAT[v],
            "command": shlex.join(command(v, Path("RUNS"))),
            "hyperparams": spec["hyperparams"],
            "final_spl": scores,
            "mean_spl": float(np.mean(flat)),
            "successes": int(sum(x > 0 for x in flat)),
            "runs": len(flat),
        }
    gradnorms = {}
    for v in ("sb3", "init", "vfclip"):
        f = runs / f"gradnorms-{v}.json"
        if f.exists():
            gradnorms[v] = json.loads(f.read_text())
    jflat = [x for t in TASKS for x in jax[t]]
    return {
        "question": "SB3 PPO with jax_ppo's tuned v2 30k values scored mean SPL 0.055 on suite "
        "v2 where jax_ppo scored 0.633 (issue 25): which implementation difference explains it?",
        "tasks": TASKS,
        "seeds": list(range(SEEDS)),
        "budget": 30000,
        "jax_ppo": {
            "source": "docs/results/v2/runs/<task>__jax_ppo__s<seed>__b30000.json (committed)",
            "final_spl": jax,
            "mean_spl": float(np.mean(jflat)),
            "successes": int(sum(x > 0 for x in jflat)),
            "runs": len(jflat),
        },
        "variants": rows,
        "gradnorms": gradnorms,
        "gradnorms_commands": [  # with the same note as command_note
            f"python scripts/ppo_gradnorms.py --task gen-easy-1 --seed 0 "
            f"--set implementation=null {extra}--out RUNS/gradnorms-{name}.json"
            for name, extra in (
                ("sb3", ""),
                ("init", "--set init=lecun "),
                ("vfclip", "--set clip_range_vf=0.3 "),
            )
        ],
        "command_note": "the ablation ran before hyperparams/v2.json's ppo entry named "
        "implementation 'rejax', so its commands had no --set ppo.implementation=null (the "
        "file's values were SB3's implementation then); the commands here add it to reproduce "
        "the same runs with the file as committed",
        "runs_dir_note": "RUNS: the --out-dir of `python scripts/ppo_ablation.py run` "
        "(outside the checkout); the run files are not committed, their final scores are here",
    }


def merge_v2(new: Path, v2: Path, extra_wall_s: float = 0.0) -> dict:
    """Replace suite v2's SB3 PPO runs (``v2``, the committed study) by those of a re-run
    into ``new`` (outside the checkout): the old ppo run files go, the new ones come in, and
    the manifest's commands drop the old ppo commands and gain the new one with its
    ``--out-dir`` rewritten to ``v2`` (the repository's path, as earlier merges did); the
    total wall time drops the old ppo runs' own wall times and adds the re-run's (and
    ``extra_wall_s``: earlier attempts into ``new`` that stopped before writing its
    manifest)."""
    old_runs = sorted((v2 / "runs").glob("*__ppo__*.json"))
    new_runs = sorted((new / "runs").glob("*__ppo__*.json"))
    if {f.name for f in old_runs} != {f.name for f in new_runs}:
        raise SystemExit(f"{new}: its ppo runs are not the same set as {v2}'s")
    old_wall = sum(json.loads(f.read_text())["timing"]["run_wall_time_s"] for f in old_runs)
    man, fresh = (json.loads((d / "study.json").read_text()) for d in (v2, new))
    command = fresh["command"].replace(f"--out-dir {new}", f"--out-dir {v2}")
    keep = [c for c in man["commands"] if "--learners ppo " not in c]
    for f in old_runs:
        f.unlink()
    for f in new_runs:
        (v2 / "runs" / f.name).write_text(f.read_text())
    man.update(
        {
            "command": command,
            "commands": [*keep, command],
            "ran_now": fresh["ran_now"],
            "skipped_now": fresh["skipped_now"],
            "wall_time_s_now": fresh["wall_time_s_now"],
            "wall_time_s_total": man["wall_time_s_total"]
            - old_wall
            + fresh["wall_time_s_now"]
            + extra_wall_s,
            "failures": fresh["failures"],
            **{k: fresh[k] for k in ("date", "machine", "versions", "load_average")},
        }
    )
    (v2 / "study.json").write_text(json.dumps(man, indent=1) + "\n")
    return {"replaced": len(new_runs), "old_ppo_wall_s": old_wall, "command": command}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--out-dir", type=Path, required=True)
    r.add_argument("--variants", default=",".join(VARIANTS))
    s = sub.add_parser("summary")
    s.add_argument("--runs", type=Path, required=True)
    s.add_argument("--v2", type=Path, default=ROOT / "docs/results/v2")
    s.add_argument("--out", type=Path, required=True)
    m = sub.add_parser("merge-v2", help="replace docs/results/v2's ppo runs by a re-run's")
    m.add_argument("--new", type=Path, required=True, help="the re-run's --out-dir")
    m.add_argument("--v2", type=Path, default=Path("docs/results/v2"))
    m.add_argument(
        "--extra-wall-s",
        type=float,
        default=0.0,
        help="wall time of earlier attempts into --new that stopped before writing study.json",
    )
    a = p.parse_args(argv)
    if a.cmd == "merge-v2":
        print(json.dumps(merge_v2(a.new, a.v2, a.extra_wall_s)))
        return 0
    if a.cmd == "run":
        for v in a.variants.split(","):
            cmd = command(v, a.out_dir)
            print("$", shlex.join(cmd), flush=True)
            subprocess.run([sys.executable, *cmd[1:]], check=True, cwd=ROOT)
        return 0
    data = summary(a.runs, a.v2)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(data, indent=1) + "\n")
    for v, row in data["variants"].items():
        print(f"{v:9s} mean SPL {row['mean_spl']:.3f}  {row['successes']}/{row['runs']}")
    j = data["jax_ppo"]
    print(f"{'jax_ppo':9s} mean SPL {j['mean_spl']:.3f}  {j['successes']}/{j['runs']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
