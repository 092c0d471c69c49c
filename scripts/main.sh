#!/usr/bin/env bash
# The main job: set up, then reproduce the paper's experiments (figures, JSON and
# docs/REPRODUCTION.md). Extra arguments go to `sixaxis reproduce`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# shellcheck disable=SC1091
source .venv/bin/activate
./target/release/sixaxis reproduce "$@"
# Interop: every shipped scenario's plan as an animation, and the plans replayed in MuJoCo
# under both clearance models (docs/INTEROP.md shows the tables).
for s in paper_simple paper_complex replan_clutter; do
  python -m sixaxis_avoid.animate --scenario "$s" --out "docs/figures/${s}_plan.gif"
done
for r in 30 10; do
  python -m sixaxis_avoid.verify --table --link-radius-mm "$r" --json "docs/figures/verify_table_${r}mm.json" \
    | bash scripts/splice_shown.sh docs/INTEROP.md "verify-${r}mm"
done
# README.md shows copies of generated sections (the tables above): refresh them.
python scripts/docsections.py --sync README.md
