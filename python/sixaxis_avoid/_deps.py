"""Optional dependencies: import one, or say which extra installs it.

Every optional feature imports its dependency through :func:`require`, so a missing one
raises Gymnasium's ``DependencyNotInstalled`` (an ``ImportError`` is never shown bare) with
the ``pip install "sixaxis-avoid[EXTRA]"`` line that fixes it.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from gymnasium.error import DependencyNotInstalled

#: The extra of pyproject.toml that installs each optional top-level module.
EXTRAS = {
    "matplotlib": "render",
    "imageio": "video",
    "imageio_ffmpeg": "video",
    "mujoco": "mujoco",
    "yourdfpy": "urdf",
    "stable_baselines3": "sb3",
    "jax": "jax",
    "jaxlib": "jax",
    "gymnax": "jax-learners",
    "rejax": "jax-learners",
}


def require(module: str, purpose: str) -> ModuleType:
    """Import ``module`` (dotted names allowed), or raise ``DependencyNotInstalled`` naming
    the package, what needs it (``purpose``) and the extra that installs it."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        top = module.split(".")[0]
        extra = EXTRAS.get(top, "interop")
        raise DependencyNotInstalled(
            f'{purpose} needs {top}, which is not installed: pip install "sixaxis-avoid[{extra}]"'
            f' (or "sixaxis-avoid[interop]" for every optional feature)'
        ) from e
