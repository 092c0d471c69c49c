#!/usr/bin/env bash
# The main job: set up, then reproduce the paper's experiments (figures, JSON and
# docs/REPRODUCTION.md). Extra arguments go to `sixaxis reproduce`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# shellcheck disable=SC1091
source .venv/bin/activate
./target/release/sixaxis reproduce "$@"
