"""Generated sections of a Markdown document, each owned by one script.

A section sits between ``<!-- NAME:begin -->`` and ``<!-- NAME:end -->``; a script rewrites
its own section and leaves the rest of the document as it is (docs/PERFORMANCE.md gathers
the sections of scripts/bench.py, scripts/bench_scale.py and scripts/bench_sb3.py).
"""

from __future__ import annotations

from pathlib import Path


def splice(doc: Path, name: str, text: str) -> None:
    """Replace section ``name`` of ``doc`` with ``text`` (appended if the section is new);
    the document is written atomically (the core's write_atomic)."""
    from sixaxis_avoid import _core

    begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
    body = doc.read_text() if doc.exists() else ""
    section = f"{begin}\n{text.strip()}\n{end}"
    if begin in body and end in body:
        body = body[: body.index(begin)] + section + body[body.index(end) + len(end) :]
    else:
        body = body.rstrip("\n") + ("\n\n" if body.strip() else "") + section + "\n"
    doc.parent.mkdir(parents=True, exist_ok=True)
    _core.write_atomic(doc, body)


def main() -> None:
    """``python scripts/docsections.py DOC NAME`` replaces section NAME of DOC with stdin."""
    import argparse
    import sys

    p = argparse.ArgumentParser(description=main.__doc__)
    p.add_argument("doc", type=Path, help="the Markdown document")
    p.add_argument("name", help="the section's name (between <!-- NAME:begin/end -->)")
    a = p.parse_args()
    splice(a.doc, a.name, sys.stdin.read())


if __name__ == "__main__":
    main()
