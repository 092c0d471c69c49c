"""The Stable-Baselines3 ``VecEnv`` over env servers (:class:`RemoteSB3VecEnv`, made on
first use: SB3 is an optional extra)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from sixaxis_avoid.remote.vector import RemoteVectorEnv

_sb3_class: type | None = None


def _remote_sb3_vec_env() -> type:
    """:class:`sixaxis_avoid.sb3.SixAxisVecEnv` driving a :class:`RemoteVectorEnv` (made on
    first use: SB3 is an optional extra)."""
    global _sb3_class
    if _sb3_class is not None:
        return _sb3_class
    from sixaxis_avoid import sb3

    class RemoteSB3VecEnv(sb3.SixAxisVecEnv):
        """SB3's ``VecEnv`` over env servers: :class:`sixaxis_avoid.sb3.SixAxisVecEnv`'s
        semantics (reset at once, ``terminal_observation``, ``TimeLimit.truncated``) and code,
        with a :class:`RemoteVectorEnv` in place of the native vector env.

        ``RemoteSB3VecEnv(addresses, n_envs, seed=None, token=None, **env_kwargs)``; the
        keywords are :class:`RemoteVectorEnv`'s. SB3 resets each lane as soon as its
        episode ends: with the default ``lanes_per_world=None`` (one world per server) the
        ended lanes are reset by a Reset with ``reset_mask`` (docs/SERVER.md "Episodes");
        ``lanes_per_world=1`` makes a world per lane, all stepped at once (slower: one
        stream per lane).
        """

        def __init__(
            self, address_or_addresses: Any, n_envs: int, seed: int | None = None, **kwargs: Any
        ):
            self.env_id = "remote"
            self.venv = RemoteVectorEnv(address_or_addresses, n_envs, copy=False, **kwargs)
            v = self.venv
            self.render_mode = None
            self.render_arm = False
            self._render_size = 512
            self._user_attrs = [{} for _ in range(v.num_envs)]
            self._renderers = {}
            self._paths = None
            sb3.VecEnv.__init__(self, v.num_envs, v.single_observation_space, v.single_action_space)
            self.metadata = {"render_modes": [], "render_fps": 8}
            self._index = v.obs_type == "index"
            self._actions = None
            if seed is not None:
                self.seed(seed)

        @staticmethod
        def _infos(info: dict[str, Any], idx: Sequence[int] | None = None) -> list[dict]:
            # The keys the server sends (is_success always), per env, as SixAxisVecEnv's.
            sel = slice(None) if idx is None else list(idx)
            cols = {k: v[sel].tolist() for k, v in info.items() if not k.startswith("_")}
            n = len(cols["is_success"])
            rows = [
                {k: (tuple(v[i]) if k == "cell" else v[i]) for k, v in cols.items()}
                for i in range(n)
            ]
            return rows

    _sb3_class = RemoteSB3VecEnv
    return _sb3_class
