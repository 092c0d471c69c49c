"""Atomic file writes: a temporary file in the same directory, flushed to disk, then renamed
over the target, so a reader (or a restarted study) never sees half a file. The core's
``write_atomic`` does it when the installed core has it; otherwise the same steps here."""

from __future__ import annotations

import io
import os
import tempfile
from pathlib import Path
from typing import Any


def _umask_mode() -> int:
    """0o666 less the process umask: what a plain ``open(..., "w")`` would give."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def _replace(tmp: str, path: Path) -> None:
    os.chmod(tmp, _umask_mode())  # mkstemp makes 0600 files
    os.replace(tmp, path)
    try:  # make the rename itself durable
        fd = os.open(path.parent, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _core_write() -> Any:
    from sixaxis_avoid import _core

    return getattr(_core, "write_atomic", None)


def atomic_write_text(path: Path, text: str) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write = _core_write()
    if write is not None:
        write(path, text)
        return
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        _replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def atomic_savefig(fig: Any, path: Path, dpi: int = 110) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write = _core_write()
    if write is not None:
        buf = io.BytesIO()
        fig.savefig(buf, dpi=dpi, format=path.suffix.lstrip(".") or "png")
        write(path, buf.getvalue())
        return
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=dpi)
        _replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
