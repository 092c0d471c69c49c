"""The learner benchmark: versioned task suites, a small Learner interface, runs on Ray,
rliable statistics and a generated report (``python -m sixaxis_avoid.benchmark``).

Entry points:

- :class:`Learner`, :class:`RunContext` — write your own learner; name it ``module:Class``.
- :func:`load_suite` — a suite (``quick``, ``v1``) or a suite file.
- :func:`plan_runs`, :func:`run_study`, :func:`execute_run` — a study's runs, on Ray.
- :func:`write_report` (in :mod:`sixaxis_avoid.benchmark.report`) — docs/BENCHMARKS.md.

Numerics: importing this package pins PyTorch's CPU arithmetic (:data:`runner.NUMERICS_ENV`:
MKL's conditional numerical reproducibility and ATen's AVX2 kernels, both before torch is
imported) and every Ray worker gets the same settings, so a deep learner's run gives the same
result on machines of one CPU vendor whatever their instruction set (AVX2 or AVX-512). Across
vendors it can differ: runs first made on an Intel Xeon differed when re-run on an AMD EPYC
(python/README.md), so each run records its machine (``host.machine``) and the report says
when a study's runs came from several. A variable already set in the environment is kept
(and recorded in each run's ``host.numerics``).

Needs the ``bench`` extra (``pip install sixaxis-avoid[bench]``: ray, optuna, rliable,
stable-baselines3, sb3-contrib).
"""

from sixaxis_avoid.benchmark.runner import pin_numerics

pin_numerics()  # before anything below imports torch

from sixaxis_avoid.benchmark.learners import BUILTIN, Learner, RunContext, resolve  # noqa: E402
from sixaxis_avoid.benchmark.runner import (  # noqa: E402
    execute_run,
    load_runs,
    plan_runs,
    run_study,
)
from sixaxis_avoid.benchmark.tasks import Suite, Task, load_suite  # noqa: E402

__all__ = [
    "BUILTIN",
    "Learner",
    "RunContext",
    "Suite",
    "Task",
    "execute_run",
    "load_runs",
    "load_suite",
    "plan_runs",
    "resolve",
    "run_study",
]
