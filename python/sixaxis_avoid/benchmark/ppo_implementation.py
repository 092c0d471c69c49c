"""PPO's implementation variants: what SB3's PPO does differently from rejax 0.1.3's (the
``jax_ppo`` learner) with the same hyperparameters, each as a setting of the benchmark's SB3
``ppo`` learner, and the preset ``implementation: rejax`` that makes SB3 PPO do what rejax
does (docs/BENCHMARKS.md, *JAX against SB3*: the ablation that found which of them matters).

Entry points: :data:`PPO_IMPLEMENTATION` (the settings and their choices),
:data:`PPO_IMPLEMENTATIONS` (the named presets), :func:`expand_ppo_implementation` and
:func:`check_ppo_implementation` (hyperparameters to settings), and the three pieces that
apply them to an SB3 model: :func:`lecun_init`, :func:`per_network_clipping`,
:func:`truncation_as_termination`.
"""

from __future__ import annotations

from typing import Any

from sixaxis_avoid.benchmark.errors import LearnerError

#: PPO's implementation variants, SB3's defaults first. rejax 0.1.3's PPO (the ``jax_ppo``
#: learner) differs from SB3's in each; ``"rejax"`` settings make SB3 PPO do what rejax does:
#:
#: - ``init``: ``"orthogonal"`` (SB3: orthogonal weights, gain sqrt 2 in the hidden layers,
#:   0.01 in the policy head, 1 in the value head) or ``"lecun"`` (flax's default, rejax's:
#:   LeCun normal weights, truncated at 2 standard deviations, zero biases, every layer) or
#:   ``"torch"`` (PyTorch's default ``nn.Linear`` init: SB3's ``ortho_init=False``);
#: - ``grad_clip``: ``"joint"`` (SB3: one global norm over actor and critic) or
#:   ``"per_network"`` (rejax: one optimiser per network, each clipped to max_grad_norm on
#:   its own);
#: - ``bootstrap_truncated``: True (SB3: a time-limit truncation bootstraps from the value of
#:   the last observation) or False (rejax: a truncated episode ends like a terminal one).
#:
#: Value clipping is SB3's own ``clip_range_vf`` (rejax clips with its ``clip_eps``, i.e.
#: ``clip_range``).
PPO_IMPLEMENTATION: dict[str, tuple[Any, ...]] = {
    "init": ("orthogonal", "lecun", "torch"),
    "grad_clip": ("joint", "per_network"),
    "bootstrap_truncated": (True, False),
}


#: Named sets of PPO's implementation variants, chosen by the hyperparameter
#: ``"implementation"``. ``"rejax"``: what rejax 0.1.3's PPO does (``jax_ppo``), so that SB3
#: PPO run with jax_ppo's values is the same algorithm (docs/BENCHMARKS.md, "JAX against
#: SB3"); its value clipping uses ``clip_range`` (rejax's ``clip_eps`` clips both).
PPO_IMPLEMENTATIONS: dict[str, dict[str, Any]] = {
    "sb3": {"init": "orthogonal", "grad_clip": "joint", "bootstrap_truncated": True},
    "rejax": {
        "init": "lecun",
        "grad_clip": "per_network",
        "bootstrap_truncated": False,
        "clip_range_vf": "clip_range",
    },
}


def expand_ppo_implementation(hp: dict[str, Any]) -> dict[str, Any]:
    """``hp`` with its ``"implementation"`` (a :data:`PPO_IMPLEMENTATIONS` name; without
    one, SB3's own defaults apply) replaced by the settings it names. A setting given on its
    own in ``hp`` as well must agree with the preset (:class:`LearnerError` otherwise)."""
    hp = dict(hp)
    name = hp.pop("implementation", None)
    if name is None:
        return hp
    if name not in PPO_IMPLEMENTATIONS:
        raise LearnerError(
            f"implementation: {name!r} is not one of {', '.join(PPO_IMPLEMENTATIONS)}"
        )
    for k, v in PPO_IMPLEMENTATIONS[name].items():
        if v == "clip_range":
            v = hp.get("clip_range", 0.2)  # SB3's default clip_range
        if k in hp and hp[k] != v:
            raise LearnerError(
                f"{k}: {hp[k]!r} contradicts implementation {name!r}, which sets {v!r}"
            )
        hp[k] = v
    return hp


def check_ppo_implementation(impl: dict[str, Any]) -> dict[str, Any]:
    """``impl`` over SB3's defaults (the first choice of each :data:`PPO_IMPLEMENTATION`
    entry), checked: a value not among the choices raises :class:`LearnerError`."""
    out = {k: v[0] for k, v in PPO_IMPLEMENTATION.items()}
    for k, v in impl.items():
        if k not in PPO_IMPLEMENTATION or v not in PPO_IMPLEMENTATION[k]:
            raise LearnerError(
                f"{k}: {v!r} is not one of {PPO_IMPLEMENTATION.get(k, ())} (PPO's implementation "
                f"variants: {', '.join(PPO_IMPLEMENTATION)})"
            )
        out[k] = v
    return out


def lecun_init(module: Any) -> None:
    """flax's default ``nn.Dense`` initialisation on every ``torch.nn.Linear`` of ``module``,
    in place: weights LeCun normal (variance 1/fan_in, a normal truncated at 2 standard
    deviations and rescaled, ``jax.nn.initializers.lecun_normal``), biases zero."""
    import torch

    for m in module.modules():
        if isinstance(m, torch.nn.Linear):
            # jax's truncated_normal variance_scaling: std of the untruncated normal
            # sqrt(1 / fan_in) / 0.87962566103423978, cut at +-2 of it.
            std = (1.0 / m.in_features) ** 0.5 / 0.87962566103423978
            with torch.no_grad():
                torch.nn.init.trunc_normal_(m.weight, std=std, a=-2 * std, b=2 * std)
                torch.nn.init.zeros_(m.bias)


def per_network_clipping(model: Any) -> None:
    """Clip the actor's and the critic's gradients to ``max_grad_norm`` each (rejax's two
    optimisers), not their joint norm (SB3): one Adam over two parameter groups (Adam's state
    is per parameter, so it is two Adams), clipped per group in ``step``; SB3's own joint
    clipping is switched off (max_grad_norm infinite)."""
    import torch

    policy, limit = model.policy, float(model.max_grad_norm)
    critic = [*policy.mlp_extractor.value_net.parameters(), *policy.value_net.parameters()]
    ids = {id(p) for p in critic}
    actor = [p for p in policy.parameters() if id(p) not in ids]

    class GroupClippedAdam(torch.optim.Adam):
        def step(self, closure: Any = None) -> Any:
            for group in self.param_groups:
                torch.nn.utils.clip_grad_norm_(group["params"], limit)
            return super().step(closure)

    old = policy.optimizer
    policy.optimizer = GroupClippedAdam(
        [{"params": actor}, {"params": critic}],
        lr=old.param_groups[0]["lr"],
        **policy.optimizer_kwargs,
    )
    model.max_grad_norm = float("inf")


def truncation_as_termination(vec: Any) -> Any:
    """``vec`` without the ``TimeLimit.truncated`` flag in its infos, so that SB3's PPO does
    not bootstrap a truncated episode from its last observation's value (rejax: ``done`` is
    terminated or truncated, and both end the return)."""
    from stable_baselines3.common.vec_env import VecEnvWrapper

    class TruncationAsTermination(VecEnvWrapper):
        def reset(self) -> Any:
            return self.venv.reset()

        def step_wait(self) -> Any:
            obs, rewards, dones, infos = self.venv.step_wait()
            for info in infos:
                info.pop("TimeLimit.truncated", None)
            return obs, rewards, dones, infos

    return TruncationAsTermination(vec)
