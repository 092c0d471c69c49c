#!/usr/bin/env bash
# The slow tests (pytest marker `slow`): minutes-long learning runs that scripts/test.sh leaves
# out to keep CI quick, e.g. the README's PPO example reaching the target (200k PPO steps).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# shellcheck disable=SC1091
source .venv/bin/activate
python -m pytest tests -q -m slow "$@"
