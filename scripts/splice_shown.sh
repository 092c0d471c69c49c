#!/usr/bin/env bash
# `... | bash scripts/splice_shown.sh DOC NAME`: stdin becomes section NAME of DOC
# (scripts/docsections.py) and is shown on stderr. The copy goes to the inherited stderr
# (`>&2`), never to a re-opened /dev/stderr: when the caller logs with `> log 2>&1`,
# opening /dev/stderr (as `tee /dev/stderr` did) truncates the log and everything written
# before it is lost (tests/test_main_log.py).
set -euo pipefail
if [ $# -ne 2 ]; then
  echo "usage: ... | bash scripts/splice_shown.sh DOC NAME" >&2
  exit 2
fi
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
cat > "$tmp"
cat "$tmp" >&2
"${PYTHON:-python}" "$(dirname "$0")/docsections.py" "$1" "$2" < "$tmp"
