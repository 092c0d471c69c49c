"""Implementation variants of the SB3 learners: what SB3's PPO and DQN do differently from
rejax 0.1.3's (the ``jax_ppo`` and ``jax_dqn`` learners) with the same hyperparameters, each
as a setting of the benchmark's SB3 ``ppo`` or ``dqn`` learner, and the preset
``implementation: rejax`` that makes SB3 do what rejax does (docs/BENCHMARKS.md, *JAX against
SB3*: the ablation that found which of PPO's matters).

Entry points: :data:`PPO_IMPLEMENTATION` and :data:`DQN_IMPLEMENTATION` (the settings and
their choices), :data:`PPO_IMPLEMENTATIONS` and :data:`DQN_IMPLEMENTATIONS` (the named
presets), :func:`expand_implementation` and :func:`check_implementation` (hyperparameters to
settings, for either algorithm), and the pieces that apply them to an SB3 model:
:func:`lecun_init`, :func:`per_network_clipping`, :func:`truncation_as_termination`,
:func:`train_freq_as_envs`, :func:`squared_error_updates`.
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


#: DQN's implementation variants, SB3's defaults first. rejax 0.1.3's DQN (the ``jax_dqn``
#: learner) differs from SB3's in each; ``"rejax"`` settings make SB3 DQN do what rejax does:
#:
#: - ``init``: ``"torch"`` (SB3's Q-network: PyTorch's default ``nn.Linear`` init) or
#:   ``"lecun"`` (flax's default, rejax's);
#: - ``bootstrap_truncated``: True (SB3's replay buffer bootstraps a time-limit truncation
#:   from the next observation's value) or False (rejax: ``done`` ends the return);
#: - ``train_freq_as_envs``: False (SB3: ``n_envs`` envs, an update phase every
#:   ``train_freq`` vector steps) or True (rejax: ``train_freq`` envs stepped once between
#:   update phases; the SB3 learner then runs ``train_freq`` envs with ``train_freq`` 1, the
#:   same env steps between update phases and updates per env step);
#: - ``her``: True (the SB3 learner's hindsight experience replay on goal tasks) or False
#:   (rejax: plain replay; the target is in the observation either way);
#: - ``loss``: ``"huber"`` (SB3: smooth L1 with delta 1) or ``"squared"`` (rejax:
#:   ``optax.l2_loss``, half the squared TD error). The two part wherever a TD error passes
#:   1, which the benchmark's scaled rewards (down to about -24 a step) often do.
#:
#: Left as it is: exploration (SB3 draws one random-or-greedy choice for all envs of a
#: vector step, rejax one per env).
DQN_IMPLEMENTATION: dict[str, tuple[Any, ...]] = {
    "init": ("torch", "lecun"),
    "bootstrap_truncated": (True, False),
    "train_freq_as_envs": (False, True),
    "her": (True, False),
    "loss": ("huber", "squared"),
}

#: Named sets of DQN's implementation variants (hyperparameter ``"implementation"``):
#: ``"rejax"`` is what rejax 0.1.3's DQN does (``jax_dqn``).
DQN_IMPLEMENTATIONS: dict[str, dict[str, Any]] = {
    "sb3": {k: v[0] for k, v in DQN_IMPLEMENTATION.items()},
    "rejax": {"init": "lecun", "bootstrap_truncated": False, "train_freq_as_envs": True,
              "her": False, "loss": "squared"},
}  # fmt: skip

#: Each algorithm's settings and presets, by the SB3 learner's name.
IMPLEMENTATIONS: dict[str, tuple[dict[str, tuple[Any, ...]], dict[str, dict[str, Any]]]] = {
    "ppo": (PPO_IMPLEMENTATION, PPO_IMPLEMENTATIONS),
    "dqn": (DQN_IMPLEMENTATION, DQN_IMPLEMENTATIONS),
}


def expand_implementation(algo: str, hp: dict[str, Any]) -> dict[str, Any]:
    """``hp`` with its ``"implementation"`` (a preset name of ``algo``'s, e.g.
    :data:`PPO_IMPLEMENTATIONS`; without one, SB3's own defaults apply) replaced by the
    settings it names. A setting given on its own in ``hp`` as well must agree with the
    preset (:class:`LearnerError` otherwise)."""
    presets = IMPLEMENTATIONS[algo][1]
    hp = dict(hp)
    name = hp.pop("implementation", None)
    if name is None:
        return hp
    if name not in presets:
        raise LearnerError(f"implementation: {name!r} is not one of {', '.join(presets)}")
    for k, v in presets[name].items():
        if v == "clip_range":
            v = hp.get("clip_range", 0.2)  # SB3's default clip_range
        if k in hp and hp[k] != v:
            raise LearnerError(
                f"{k}: {hp[k]!r} contradicts implementation {name!r}, which sets {v!r}"
            )
        hp[k] = v
    return hp


def check_implementation(algo: str, impl: dict[str, Any]) -> dict[str, Any]:
    """``impl`` over SB3's defaults (the first choice of each setting of ``algo``'s, e.g.
    :data:`PPO_IMPLEMENTATION`), checked: a value not among the choices raises
    :class:`LearnerError`."""
    table = IMPLEMENTATIONS[algo][0]
    out = {k: v[0] for k, v in table.items()}
    for k, v in impl.items():
        if k not in table or v not in table[k]:
            raise LearnerError(
                f"{k}: {v!r} is not one of {table.get(k, ())} ({algo.upper()}'s implementation "
                f"variants: {', '.join(table)})"
            )
        out[k] = v
    return out


def train_freq_as_envs(hp: dict[str, Any]) -> dict[str, Any]:
    """DQN's ``hp`` run as rejax runs it (``train_freq_as_envs``): ``train_freq`` envs
    stepped once between update phases (``n_envs`` = ``train_freq``, ``train_freq`` 1), so
    the env steps between update phases and the updates per env step are unchanged."""
    hp = dict(hp)
    if int(hp.get("n_envs", 1)) != 1:
        raise LearnerError(
            f"n_envs: {hp['n_envs']!r} with train_freq_as_envs (the envs are train_freq's)"
        )
    hp["n_envs"], hp["train_freq"] = int(hp.get("train_freq", 4)), 1  # SB3's train_freq 4
    return hp


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
    """``vec`` without the ``TimeLimit.truncated`` flag in its infos, so that SB3's PPO (and
    DQN's replay buffer) does not bootstrap a truncated episode from its last observation's
    value (rejax: ``done`` is terminated or truncated, and both end the return)."""
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


def squared_error_updates(model: Any) -> None:
    """SB3 DQN ``model``'s updates with rejax's loss, half the squared TD error
    (``optax.l2_loss``), in place of SB3's Huber loss; everything else as SB3's
    ``DQN.train`` does it: the target network's max over next actions, one gradient-norm
    clip to ``max_grad_norm``, the learning rate from its schedule."""
    import torch

    def train(gradient_steps: int, batch_size: int = 100) -> None:
        model.policy.set_training_mode(True)
        model._update_learning_rate(model.policy.optimizer)
        losses = []
        for _ in range(gradient_steps):
            data = model.replay_buffer.sample(batch_size, env=model._vec_normalize_env)
            discounts = data.discounts if data.discounts is not None else model.gamma
            with torch.no_grad():
                next_q = model.q_net_target(data.next_observations).max(dim=1).values
                target = data.rewards + (1 - data.dones) * discounts * next_q.reshape(-1, 1)
            q = torch.gather(model.q_net(data.observations), dim=1, index=data.actions.long())
            loss = 0.5 * ((q - target) ** 2).mean()
            losses.append(loss.item())
            model.policy.optimizer.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(model.policy.parameters(), model.max_grad_norm)
            model.policy.optimizer.step()
        model._n_updates += gradient_steps
        model.logger.record("train/n_updates", model._n_updates, exclude="tensorboard")
        model.logger.record("train/loss", float(sum(losses) / max(len(losses), 1)))

    model.train = train
