"""The main job's log survives redirection (`bash scripts/main.sh > log 2>&1`): the step
that shows a table and splices it into a doc (scripts/splice_shown.sh) must not truncate
the log it writes to. It once piped through `tee /dev/stderr`, which re-opens the log file
and cuts away everything written before it.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_a_logged_splice_keeps_the_earlier_lines(tmp_path):
    doc, log = tmp_path / "DOC.md", tmp_path / "log"
    doc.write_text("# Doc\n\n<!-- t:begin -->\nold\n<!-- t:end -->\n\nafter\n")
    job = (
        "echo first line; "
        f"for r in 1 2; do printf '| table %s |\\n' $r | bash {ROOT}/scripts/splice_shown.sh "
        f"{doc} t; done; echo last line"
    )
    env = {**os.environ, "PYTHON": sys.executable}
    with log.open("w") as out:
        subprocess.run(
            ["bash", "-c", job], stdout=out, stderr=subprocess.STDOUT, env=env, check=True
        )
    assert log.read_text().splitlines() == ["first line", "| table 1 |", "| table 2 |", "last line"]
    assert doc.read_text() == "# Doc\n\n<!-- t:begin -->\n| table 2 |\n<!-- t:end -->\n\nafter\n"


def test_the_main_job_splices_through_it():
    main = (ROOT / "scripts" / "main.sh").read_text()
    assert "scripts/splice_shown.sh docs/INTEROP.md" in main
    for script in (ROOT / "scripts").glob("*.sh"):
        code = [ln for ln in script.read_text().splitlines() if not ln.lstrip().startswith("#")]
        assert not [ln for ln in code if "/dev/stderr" in ln], script
