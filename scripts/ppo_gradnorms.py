"""Where SB3 PPO's updates go at jax_ppo's v2 30k values (issue 25): the actor's and the
critic's gradient norms at each minibatch update, SB3's joint clipping factor, and the
actor's clipped gradient against Adam's eps.

    python scripts/ppo_gradnorms.py --task gen-easy-1 --seed 0 --set init=lecun \\
        --out /work/runs/ppo-agree/gradnorms-lecun.json

Trains the benchmark's ``ppo`` learner once (suite v2, the hyperparameter file's 30k values,
``--set`` changes one) with ``torch.nn.utils.clip_grad_norm_`` wrapped to record, per update,
the global norms of the actor's and the critic's gradients before clipping and the factor the
clip applied; prints their medians over the first and the last third of the updates.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--task", default="gen-easy-1")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--set", action="append", default=[], metavar="KEY=JSON")
    p.add_argument("--out", type=Path)
    a = p.parse_args(argv)

    import torch
    from sixaxis_avoid.benchmark import execute_run, load_suite, plan_runs

    suite = load_suite("v2")
    over = {}
    for s in a.set:
        k, _, v = s.partition("=")
        try:
            over[k] = json.loads(v)
        except json.JSONDecodeError:
            over[k] = v
    spec = plan_runs(
        suite, ["ppo"], seeds=[a.seed], tasks=[suite.task(a.task)], hyperparams="v2",
        budgets=[30000], overrides={"ppo": over},
    )[0]  # fmt: skip
    records: list[dict[str, float]] = []
    orig = torch.nn.utils.clip_grad_norm_

    def norm(ps: list) -> float:
        gs = [q.grad.detach().flatten() for q in ps if q.grad is not None]
        return float(torch.linalg.vector_norm(torch.cat(gs))) if gs else 0.0

    def rms(ps: list) -> float:
        gs = [q.grad.detach().flatten() for q in ps if q.grad is not None]
        return float(torch.cat(gs).pow(2).mean().sqrt()) if gs else 0.0

    state: dict = {}

    def wrapped(parameters, max_norm, *args, **kw):
        ps = list(parameters)
        pol = state.get("policy")
        if pol is not None and len(ps) == len(list(pol.parameters())):
            critic = {id(q) for q in pol.mlp_extractor.value_net.parameters()}
            critic |= {id(q) for q in pol.value_net.parameters()}
            actor = [q for q in ps if id(q) not in critic]
            crit = [q for q in ps if id(q) in critic]
            total = norm(ps)
            out = orig(ps, max_norm, *args, **kw)
            records.append(
                {
                    "actor_norm": norm(actor) / max(min(1.0, max_norm / max(total, 1e-12)), 1e-30),
                    "critic_norm": norm(crit) / max(min(1.0, max_norm / max(total, 1e-12)), 1e-30),
                    "clip_factor": min(1.0, max_norm / max(total, 1e-12)),
                    "actor_rms_after_clip": rms(actor),
                }
            )
            return out
        return orig(ps, max_norm, *args, **kw)

    import stable_baselines3.common.policies as pols

    init = pols.ActorCriticPolicy._build

    def build(self, lr_schedule):
        init(self, lr_schedule)
        state["policy"] = self

    pols.ActorCriticPolicy._build = build
    torch.nn.utils.clip_grad_norm_ = wrapped
    try:
        res = execute_run(spec)["result"]
    finally:
        torch.nn.utils.clip_grad_norm_ = orig
        pols.ActorCriticPolicy._build = init
    n = len(records)
    summary = {}
    for part, sl in (("first third", slice(0, n // 3)), ("last third", slice(2 * n // 3, n))):
        rs = records[sl]
        summary[part] = {k: float(np.median([r[k] for r in rs])) for k in rs[0] if rs}
    out = {
        "task": a.task,
        "seed": a.seed,
        "set": over,
        "hyperparams": spec["hyperparams"],
        "score": res["score"],
        "updates": n,
        "median": summary,
        "note": "norms before clipping; SB3 clips the joint norm of actor and critic to "
        "max_grad_norm (clip_factor); actor_rms_after_clip against Adam's eps 1e-5. With "
        "grad_clip per_network SB3's joint clip is off and these are not recorded",
    }
    print(json.dumps({k: out[k] for k in ("set", "score", "updates", "median")}, indent=1))
    if a.out:
        a.out.write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
