"""Generated sections of a Markdown document, each owned by one script.

A section sits between ``<!-- NAME:begin -->`` and ``<!-- NAME:end -->``; a script rewrites
its own section and leaves the rest of the document as it is (docs/PERFORMANCE.md gathers
the sections of scripts/bench.py, scripts/bench_scale.py and scripts/bench_sb3.py).

README.md shows copies of generated sections: ``--sync README.md`` copies each of its
sections from the one page of docs/ that carries a section of that name (scripts/main.sh
runs it; tests/test_docs.py checks that the copies equal their sources).
"""

from __future__ import annotations

import re
from pathlib import Path

DOCS = Path(__file__).resolve().parent.parent / "docs"
SECTION = re.compile(r"<!-- ([\w.-]+):begin -->\n(.*?)\n?<!-- \1:end -->", re.S)


def sections(body: str) -> dict[str, str]:
    """Every section of a document: name -> its text between the markers."""
    return {m.group(1): m.group(2).strip() for m in SECTION.finditer(body)}


def source_of(name: str, pages: list[Path]) -> Path:
    """The one page of ``pages`` that carries section ``name``."""
    found = [p for p in pages if name in sections(p.read_text())]
    if len(found) != 1:
        where = ", ".join(map(str, found)) or "no page"
        raise SystemExit(f"section {name!r}: found in {where}; expected exactly one page")
    return found[0]


def sync(doc: Path, pages: list[Path] | None = None) -> list[str]:
    """Copy each section of ``doc`` from its source page (default: docs/*.md); returns the
    names of the sections that changed."""
    pages = sorted(DOCS.glob("*.md")) if pages is None else pages
    mine = sections(doc.read_text())
    changed = []
    for name, text in mine.items():
        source = sections(source_of(name, pages).read_text())[name]
        if source != text:
            splice(doc, name, source)
            changed.append(name)
    return changed


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
    """``python scripts/docsections.py DOC NAME`` replaces section NAME of DOC with stdin;
    ``python scripts/docsections.py --sync DOC`` copies DOC's sections from docs/."""
    import argparse
    import sys

    p = argparse.ArgumentParser(description=main.__doc__)
    p.add_argument("doc", type=Path, help="the Markdown document")
    p.add_argument("name", nargs="?", help="the section's name (between <!-- NAME:begin/end -->)")
    p.add_argument("--sync", action="store_true", help="copy DOC's sections from docs/*.md")
    a = p.parse_args()
    if a.sync == (a.name is not None):
        p.error("give either NAME (stdin replaces it) or --sync")
    if a.sync:
        for name in sync(a.doc):
            print(f"{a.doc}: section {name} copied from docs/", file=sys.stderr)
    else:
        splice(a.doc, a.name, sys.stdin.read())


if __name__ == "__main__":
    main()
