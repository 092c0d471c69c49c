"""Gymnasium envs over a SixAxisAvoid env server (dm_env_rpc over gRPC; docs/SERVER.md).

:class:`RemoteEnv` is ``SixAxisAvoid-v0`` played on a server, :class:`RemoteVectorEnv` the
native vector env (``sixaxis_avoid.vector``) with its lanes on one or several servers; both
give the in-process envs' spaces, rewards, episode ends and, for the same seed and actions,
the same trajectories::

    import sixaxis_avoid
    from sixaxis_avoid.remote import RemoteEnv, RemoteVectorEnv

    with sixaxis_avoid.serve() as server:  # or `sixaxis serve` anywhere
        env = RemoteEnv(server.address, reward_scale=1e-4)
        envs = RemoteVectorEnv([server.address], num_envs=256, reward_scale=1e-4)

One server world holds all the lanes an address is given, so one Step request carries them
all; with several addresses the requests are written to every server before any answer is
read, so the servers step concurrently. :func:`start_ray_servers` starts one server per
node of a Ray cluster and returns their addresses. :class:`RemoteSB3VecEnv` is the
Stable-Baselines3 ``VecEnv`` (:class:`sixaxis_avoid.sb3.SixAxisVecEnv`) over a remote
vector env.

The stream is the extension's Rust client by default (``transport="rust"``:
:class:`sixaxis_avoid._core.DmEnvClient`, tonic, the GIL released while it waits) or grpcio
with the ``dm-env-rpc`` package's message packing (``transport="grpc"``, and for TLS
``credentials``); docs/SERVER.md "The Rust transport". This module adds the Gymnasium
semantics and the lane bookkeeping.
"""

from __future__ import annotations

from typing import Any

from sixaxis_avoid.remote._session import DEFAULT_CONNECT_TIMEOUT, DEFAULT_TIMEOUT, ServerError
from sixaxis_avoid.remote.env import RemoteEnv
from sixaxis_avoid.remote.ray import RayServers, start_ray_servers
from sixaxis_avoid.remote.vector import RemoteVectorEnv

__all__ = [
    "DEFAULT_CONNECT_TIMEOUT",
    "DEFAULT_TIMEOUT",
    "RayServers",
    "RemoteEnv",
    "RemoteVectorEnv",
    "ServerError",
    "start_ray_servers",
]


def __getattr__(name: str) -> Any:
    # RemoteSB3VecEnv is made on first use (SB3 is an optional extra).
    if name == "RemoteSB3VecEnv":
        from sixaxis_avoid.remote._sb3 import _remote_sb3_vec_env

        return _remote_sb3_vec_env()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
