"""SixAxisAvoid: a six-axis arm that learns to reach a target through clutter."""

from sixaxis_avoid._core import (
    Arm,
    InternalError,
    InvalidArgumentError,
    QTableMismatchError,
    Scenario,
    ScenarioError,
    ScenarioNotFoundError,
    ScenarioParseError,
    SixAxisError,
    SixAxisIOError,
    __version__,
)

__all__ = [
    "Arm",
    "InternalError",
    "InvalidArgumentError",
    "QTableMismatchError",
    "Scenario",
    "ScenarioError",
    "ScenarioNotFoundError",
    "ScenarioParseError",
    "SixAxisError",
    "SixAxisIOError",
    "__version__",
]
