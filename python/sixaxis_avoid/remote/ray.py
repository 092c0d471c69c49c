"""Env servers on every node of a Ray cluster (:func:`start_ray_servers`)."""

from __future__ import annotations

import secrets
from collections.abc import Iterable
from typing import Any

import numpy as np
from gymnasium.error import DependencyNotInstalled

from sixaxis_avoid import _core
from sixaxis_avoid._checks import invalid

_LOOPBACK = ("127.", "localhost", "::1", "[::1]")
#: Servers started by start_ray_servers and not stopped (their actors live while held).
_ray_servers: list[RayServers] = []


class RayServers(list):
    """The addresses of the servers :func:`start_ray_servers` started (a ``list[str]``),
    with ``token`` (pass it to the remote envs), ``node_ids`` (the Ray node of each
    address), ``actors`` and :meth:`stop`. The servers live until :meth:`stop` (or the end
    of the Ray driver); it is also a context manager."""

    def __init__(
        self, addresses: Iterable[str], token: str | None, node_ids: list[str], actors: list[Any]
    ):
        super().__init__(addresses)
        self.token = token
        self.node_ids = node_ids
        self.actors = actors

    def stop(self) -> None:
        """Stop every server and end its actor."""
        import ray

        actors, self.actors = self.actors, []
        if actors:
            ray.get([a.stop.remote() for a in actors])
            for a in actors:
                ray.kill(a)
        if self in _ray_servers:
            _ray_servers.remove(self)

    def __enter__(self) -> RayServers:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.stop()

    def __eq__(self, other: object) -> bool:
        return self is other

    __hash__ = object.__hash__


class _ServerHolder:
    """The body of the Ray actor: one ``sixaxis_avoid.serve()`` server on its node."""

    def __init__(self, host: str, token: str | None, serve_kwargs: dict[str, Any]):
        self.server = _core.serve(f"{host}:0", token=token, **serve_kwargs)

    def address(self) -> str:
        return self.server.address

    def node_id(self) -> str:
        import ray

        return ray.get_runtime_context().get_node_id()

    def stop(self) -> None:
        self.server.stop()


def start_ray_servers(
    num_per_node: int = 1,
    *,
    token: str | None = None,
    actor_options: dict[str, Any] | None = None,
    **serve_kwargs: Any,
) -> RayServers:
    """Start ``num_per_node`` env servers on every alive node of the connected Ray cluster
    (``ray.init(...)`` first; the package must be installed on every node) and return their
    addresses, reachable from the driver: each server binds its node's IP address on a free
    port.

    Each server is ``sixaxis_avoid.serve(...)`` held by a Ray actor pinned to its node
    (``NodeAffinitySchedulingStrategy``, not soft); ``serve_kwargs`` go to ``serve``,
    ``actor_options`` to the actor (default ``num_cpus=0``: the server's threads are not
    Ray tasks). A server on a non-loopback address needs a token: without ``token`` one is
    generated (``secrets.token_urlsafe``) and returned as ``.token`` of the result::

        servers = start_ray_servers()
        envs = RemoteVectorEnv(servers, num_envs=64, token=servers.token)
        ...
        servers.stop()
    """
    try:
        import ray
        from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy
    except ImportError as e:
        raise DependencyNotInstalled(
            "start_ray_servers needs ray, which is not installed: pip install ray"
        ) from e
    if (
        isinstance(num_per_node, bool)
        or not isinstance(num_per_node, (int, np.integer))
        or (num_per_node < 1)
    ):
        raise invalid("num_per_node", num_per_node, "must be an integer >= 1")
    if not ray.is_initialized():
        raise invalid("ray", None, "start_ray_servers needs ray.init(...) first")
    nodes = [n for n in ray.nodes() if n.get("Alive")]
    if token is None and any(not n["NodeManagerAddress"].startswith(_LOOPBACK) for n in nodes):
        token = secrets.token_urlsafe(32)
    options = {"num_cpus": 0, **(actor_options or {})}
    holder = ray.remote(_ServerHolder)
    actors, node_ids = [], []
    for node in nodes:
        for _ in range(int(num_per_node)):
            actor = holder.options(
                scheduling_strategy=NodeAffinitySchedulingStrategy(node["NodeID"], soft=False),
                **options,
            ).remote(node["NodeManagerAddress"], token, serve_kwargs)
            actors.append(actor)
            node_ids.append(node["NodeID"])
    try:
        addresses = ray.get([a.address.remote() for a in actors])
    except BaseException:
        for a in actors:
            ray.kill(a)
        raise
    servers = RayServers(addresses, token, node_ids, actors)
    _ray_servers.append(servers)
    return servers
