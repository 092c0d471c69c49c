"""SB3 PPO or DQN against rejax's (jax_ppo, jax_dqn) at suite v2's 30k values: which
implementation difference makes the SB3 learner fail where the JAX one succeeds (issue 25)?

    python scripts/implementation_ablation.py run --algo ppo --out-dir /work/runs/ppo-agree
    python scripts/implementation_ablation.py summary --algo ppo --runs /work/runs/ppo-agree \
        --out docs/results/agreement/ppo-v2-ablation.json
    python scripts/implementation_ablation.py merge-v2 --algo ppo --new /work/runs/ppo-agree/v2

``run`` trains the SB3 learner (the benchmark's ``ppo`` or ``dqn``, through the benchmark's
own runner) with the JAX learner's tuned 30k values on a few v2 tasks and seeds, once with
SB3's implementation and once per factor changed toward rejax 0.1.3's
(``learners.PPO_IMPLEMENTATION`` / ``DQN_IMPLEMENTATION``), then with all of them
(``implementation: rejax``); each variant into its own directory. ``summary`` gathers the
final scores per variant, task and seed with the JAX learner's committed runs on the same
tasks and seeds (docs/results/v2) into one JSON, with the commands that made them.
``merge-v2`` merges a learner's runs made outside the checkout into the committed v2 study
(replacing a re-run's old ones).
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
HP = "python/sixaxis_avoid/benchmark/hyperparams/v2.json"
#: Per algorithm: the tasks and seeds, each variant's ``--set`` overrides of the learner
#: (SB3's names / the learner's implementation keys) on top of ``<algo>.implementation=null``
#: (SB3's own implementation), what each changes, and the question.
ALGOS: dict[str, dict] = {
    "ppo": {
        "tasks": ["gen-easy-1", "gen-easy-2", "gen-medium-3"],
        "seeds": 3,
        "variants": {
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
        },
        "what": {
            "sb3": "SB3's PPO as the benchmark ran it (orthogonal init, policy head gain 0.01; "
            "one gradient norm clip over actor and critic; truncation bootstrapped; no value "
            "clipping)",
            "init": "only the initialisation changed: LeCun normal, zero biases (flax's "
            "default, rejax's)",
            "vfclip": "only value clipping added: clip_range_vf = clip_range = 0.3 (rejax clips "
            "the value with clip_eps)",
            "gradclip": "only the gradient clipping changed: actor and critic each clipped to "
            "max_grad_norm on its own (rejax: one optimiser per network)",
            "notrunc": "only truncation changed: a truncated episode ends the return (rejax: "
            "done = terminated or truncated, no bootstrap)",
            "torchinit": "only the initialisation changed: PyTorch's default nn.Linear init "
            "(SB3's ortho_init=False), no 0.01-gain policy head",
            "rejax": "all four changed (implementation 'rejax')",
        },
        "question": "SB3 PPO with jax_ppo's tuned v2 30k values scored mean SPL 0.055 on suite "
        "v2 where jax_ppo scored 0.633 (issue 25): which implementation difference explains it?",
        "command_note": "the ablation ran before hyperparams/v2.json's ppo entry named "
        "implementation 'rejax', so its commands had no --set ppo.implementation=null (the "
        "file's values were SB3's implementation then); the commands here add it to reproduce "
        "the same runs with the file as committed",
    },
    "dqn": {
        "tasks": ["gen-easy-0", "gen-medium-0", "gen-medium-1"],
        "seeds": 3,
        "variants": {
            "sb3": [],
            "squared": ["dqn.loss=squared"],
            "huber": [
                "dqn.init=lecun",
                "dqn.bootstrap_truncated=false",
                "dqn.train_freq_as_envs=true",
                "dqn.her=false",
                "dqn.loss=huber",
            ],
            "rejax": [
                "dqn.init=lecun",
                "dqn.bootstrap_truncated=false",
                "dqn.train_freq_as_envs=true",
                "dqn.her=false",
                "dqn.loss=squared",
            ],
        },
        "what": {
            "sb3": "SB3's DQN with jax_dqn's values (Huber loss, PyTorch's init, one env with "
            "train_freq 16, truncation bootstrapped)",
            "squared": "only the loss changed: half the squared TD error (rejax's optax.l2_loss)",
            "huber": "everything but the loss changed toward rejax: LeCun init, truncation as "
            "termination, 16 envs stepped once between update phases (SB3's Huber loss kept)",
            "rejax": "all changed (implementation 'rejax')",
        },
        "question": "SB3 DQN with jax_dqn's tuned v2 30k values and every implementation "
        "setting of rejax's but the loss scored above 0 in 3 of its first 21 v2 runs (seed 0, "
        "one per task; mean SPL 0.10) where jax_dqn reached the target on most tasks: which "
        "difference explains it?",
        "command_note": "",
    },
}


def command(algo: str, variant: str, out_dir: Path) -> list[str]:
    cfg = ALGOS[algo]
    cmd = [
        "python", "-m", "sixaxis_avoid.benchmark", "run", "--suite", "v2", "--learners", algo,
        "--budgets", "30000", "--tasks", ",".join(cfg["tasks"]), "--seeds", str(cfg["seeds"]),
        "--hyperparams", HP,
    ]  # fmt: skip
    # The v2 file's entry names implementation 'rejax'; null takes SB3's own back.
    for s in [f"{algo}.implementation=null", *cfg["variants"][variant]]:
        cmd += ["--set", s]
    return [*cmd, "--no-ray", "--no-progress", "--out-dir", str(out_dir / variant)]


def final_scores(algo: str, run_dir: Path, learner: str) -> dict[str, list[float]]:
    cfg = ALGOS[algo]
    out: dict[str, list[float]] = {}
    for t in cfg["tasks"]:
        out[t] = []
        for s in range(cfg["seeds"]):
            f = run_dir / "runs" / f"{t}__{learner}__s{s}__b30000.json"
            out[t].append(float(json.loads(f.read_text())["result"]["score"]))
    return out


def summary(algo: str, runs: Path, v2: Path) -> dict:
    cfg, jax_name = ALGOS[algo], f"jax_{algo}"
    jax = final_scores(algo, v2, jax_name)
    rows = {}
    for v in cfg["variants"]:
        d = runs / v
        scores = final_scores(algo, d, algo)
        spec = json.loads(next((d / "runs").glob("*.json")).read_text())["spec"]
        flat = [x for t in cfg["tasks"] for x in scores[t]]
        rows[v] = {
            "what": cfg["what"][v],
            "command": shlex.join(command(algo, v, Path("RUNS"))),
            "hyperparams": spec["hyperparams"],
            "final_spl": scores,
            "mean_spl": float(np.mean(flat)),
            "successes": int(sum(x > 0 for x in flat)),
            "runs": len(flat),
        }
    gradnorms = {}
    for v in ("sb3", "init", "vfclip") if algo == "ppo" else ():
        f = runs / f"gradnorms-{v}.json"
        if f.exists():
            gradnorms[v] = json.loads(f.read_text())
    jflat = [x for t in cfg["tasks"] for x in jax[t]]
    out = {
        "algo": algo,
        "question": cfg["question"],
        "tasks": cfg["tasks"],
        "seeds": list(range(cfg["seeds"])),
        "budget": 30000,
        jax_name: {
            "source": f"docs/results/v2/runs/<task>__{jax_name}__s<seed>__b30000.json (committed)",
            "final_spl": jax,
            "mean_spl": float(np.mean(jflat)),
            "successes": int(sum(x > 0 for x in jflat)),
            "runs": len(jflat),
        },
        "variants": rows,
        "runs_dir_note": "RUNS: the --out-dir of `python scripts/implementation_ablation.py "
        "run` (outside the checkout); the run files are not committed, their final scores are "
        "here",
    }
    if algo == "ppo":
        out["gradnorms"] = gradnorms
        out["gradnorms_commands"] = [  # with the same note as command_note
            f"python scripts/ppo_gradnorms.py --task gen-easy-1 --seed 0 "
            f"--set implementation=null {extra}--out RUNS/gradnorms-{name}.json"
            for name, extra in (
                ("sb3", ""),
                ("init", "--set init=lecun "),
                ("vfclip", "--set clip_range_vf=0.3 "),
            )
        ]
    if cfg["command_note"]:
        out["command_note"] = cfg["command_note"]
    return out


def keep_replaced(
    learner: str, old_runs: list[Path], v2: Path, removed: list[str], replaced_by: str
) -> Path:
    """Keep a re-run's old run files beside the study, in ``<v2>-replaced/<learner>-<budgets>``
    (``-2``, ``-3``, ... when that is taken), with ``replaced.json``: the learner, budgets,
    run count, the commands that made them and the command that replaced them. No figure of
    the study reads them; the page's check of JAX against SB3 does where the SB3 runs that
    replaced them no longer use the JAX learner's values (docs/results/v2-replaced/README.md)."""
    budgets = sorted({int(f.name.rsplit("__b", 1)[1].removesuffix(".json")) for f in old_runs})
    root = v2.parent / f"{v2.name}-replaced"
    base = f"{learner}-{'-'.join(str(b) for b in budgets)}"
    dest, k = root / base, 1
    while dest.exists():
        k += 1
        dest = root / f"{base}-{k}"
    (dest / "runs").mkdir(parents=True)
    for f in old_runs:
        (dest / "runs" / f.name).write_text(f.read_text())
    about = {
        "learner": learner,
        "budgets": budgets,
        "runs": len(old_runs),
        "commands": removed,
        "replaced_by": replaced_by,
        "date": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
    }
    (dest / "replaced.json").write_text(json.dumps(about, indent=1) + "\n")
    return dest


def merge_v2(learner: str, new: Path, v2: Path, extra_wall_s: float = 0.0) -> dict:
    """Merge a run of ``learner`` into ``new`` (outside the checkout) into suite v2's
    committed study ``v2``: its run files come in, and the manifest gains its command with
    the ``--out-dir`` rewritten to ``v2`` (the repository's path, as earlier merges did) and
    the wall time of every command into ``new`` (its ``wall_time_s_total``: a command that
    was stopped and resumed counts up to its last finished run; ``extra_wall_s`` adds
    attempts whose time no manifest holds); a path inside the checkout becomes relative to
    it. A directory whose last command was stopped (``finished: false``) is refused. A re-run
    replaces the learner's runs at those budgets (the same set of run files): the old files
    leave the study, with their commands and their own wall times, and are kept beside it
    (:func:`keep_replaced`). Run files none of which the study has
    (the learner's first runs at those budgets, or more seeds there) are added, and the
    earlier commands stay."""
    new_runs = sorted((new / "runs").glob(f"*__{learner}__*.json"))
    budgets = {f.name.rsplit("__", 1)[1] for f in new_runs}
    old_runs = sorted(
        f
        for f in (v2 / "runs").glob(f"*__{learner}__*.json")
        if f.name.rsplit("__", 1)[1] in budgets
    )
    if not {f.name for f in old_runs} & {f.name for f in new_runs}:
        old_runs = []  # more seeds (or tasks) at those budgets: added beside the others
    elif {f.name for f in old_runs} != {f.name for f in new_runs}:
        raise SystemExit(f"{new}: its {learner} runs are not the same set as {v2}'s")
    old_wall = sum(json.loads(f.read_text())["timing"]["run_wall_time_s"] for f in old_runs)
    man, fresh = (json.loads((d / "study.json").read_text()) for d in (v2, new))
    if fresh.get("finished") is False:
        raise SystemExit(f"{new}: its last command was stopped; run it again to finish the set")
    if fresh.get("failures"):
        # A command whose runs failed (or whose Ray went down under it) left them unmade.
        n = len(fresh["failures"])
        raise SystemExit(f"{new}: its last command left {n} runs failed; run it again")
    command = fresh["command"].replace(f"--out-dir {new}", f"--out-dir {v2}")
    command = command.replace(f"{ROOT}/", "")  # paths in the checkout, as the page's commands
    budget_flag = re.search(r"--budgets (\S+)", command)
    keep = [
        c
        for c in man["commands"]
        if not old_runs
        or f"--learners {learner} " not in c
        or (budget_flag is not None and f"--budgets {budget_flag.group(1)}" not in c)
    ]
    if old_runs:
        keep_replaced(learner, old_runs, v2, removed=[c for c in man["commands"] if c not in keep],
                      replaced_by=command)  # fmt: skip
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
            + fresh["wall_time_s_total"]
            + extra_wall_s,
            "failures": [*man.get("failures", []), *fresh["failures"]],
            "learners": [
                *man["learners"],
                *[x for x in fresh["learners"] if x not in man["learners"]],
            ],
            "runs": man["runs"] - len(old_runs) + len(new_runs),
            **{k: fresh[k] for k in ("date", "machine", "versions", "load_average")},
        }
    )
    (v2 / "study.json").write_text(json.dumps(man, indent=1) + "\n")
    return {"replaced": len(new_runs), "old_wall_s": old_wall, "command": command}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--out-dir", type=Path, required=True)
    r.add_argument("--variants", default=None, help="comma list (default: all of --algo's)")
    s = sub.add_parser("summary")
    s.add_argument("--runs", type=Path, required=True)
    s.add_argument("--v2", type=Path, default=ROOT / "docs/results/v2")
    s.add_argument("--out", type=Path, required=True)
    m = sub.add_parser("merge-v2", help="merge a learner's runs into docs/results/v2")
    m.add_argument("--learner", default=None, help="default: --algo (e.g. jax_dqn)")
    m.add_argument("--new", type=Path, required=True, help="the re-run's --out-dir")
    m.add_argument("--v2", type=Path, default=Path("docs/results/v2"))
    m.add_argument(
        "--extra-wall-s",
        type=float,
        default=0.0,
        help="wall time of earlier attempts into --new that stopped before writing study.json",
    )
    for q in (r, s, m):
        q.add_argument("--algo", choices=tuple(ALGOS), default="ppo")
    a = p.parse_args(argv)
    if a.cmd == "merge-v2":
        print(json.dumps(merge_v2(a.learner or a.algo, a.new, a.v2, a.extra_wall_s)))
        return 0
    if a.cmd == "run":
        for v in (a.variants or ",".join(ALGOS[a.algo]["variants"])).split(","):
            cmd = command(a.algo, v, a.out_dir)
            print("$", shlex.join(cmd), flush=True)
            subprocess.run([sys.executable, *cmd[1:]], check=True, cwd=ROOT)
        return 0
    data = summary(a.algo, a.runs, a.v2)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(data, indent=1) + "\n")
    for v, row in data["variants"].items():
        print(f"{v:9s} mean SPL {row['mean_spl']:.3f}  {row['successes']}/{row['runs']}")
    j = data[f"jax_{a.algo}"]
    print(f"{'jax_' + a.algo:9s} mean SPL {j['mean_spl']:.3f}  {j['successes']}/{j['runs']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
