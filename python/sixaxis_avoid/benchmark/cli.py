"""Command-line helpers shared by the subcommands of ``python -m sixaxis_avoid.benchmark``
(``__main__`` parses the flags, ``tune`` runs the Optuna study); a module of its own so
that neither imports the other (tests/test_layers.py checks the order).
"""

from __future__ import annotations

import shlex


def command_line(argv: list[str]) -> str:
    """The command that ran, as a shell line (recorded in every result file)."""
    return "python -m sixaxis_avoid.benchmark " + " ".join(shlex.quote(a) for a in argv)


def parse_seeds(text: str | None) -> list[int] | None:
    """``--seeds``: a count N (seeds 0..N-1) or a comma list; one seed k is ``k,``."""
    if text is None:
        return None
    text = text.strip()
    parts = split(text)
    try:
        seeds = [int(s) for s in parts]
    except ValueError:
        raise SystemExit(f"--seeds: {text!r}: not a count or a comma list of integers") from None
    if "," not in text and seeds:
        seeds = list(range(seeds[0]))
    if not seeds or any(s < 0 for s in seeds):
        hint = " (a count; seed 0 alone is --seeds 0,)" if text == "0" else ""
        raise SystemExit(f"--seeds: {text!r}: need at least one seed, all >= 0{hint}")
    return seeds


def split(text: str) -> list[str]:
    """A comma list's non-empty items, stripped."""
    return [x.strip() for x in text.split(",") if x.strip()]
