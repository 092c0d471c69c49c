"""Atomic file writes through the core's one helper (``_core.write_atomic``: a temporary file
in the same directory, flushed to disk, renamed over the target, the directory synced), so a
reader or a restarted study never sees half a file."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

from sixaxis_avoid import _core


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (parent directories made as needed)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    _core.write_atomic(path, text)


def atomic_savefig(fig: Any, path: Path, dpi: int = 110) -> None:
    """Save a matplotlib figure to ``path`` atomically, in the format its suffix names."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    fig.savefig(buf, dpi=dpi, format=path.suffix.lstrip(".") or "png")
    _core.write_atomic(path, buf.getvalue())
