#!/usr/bin/env bash
# Sets up everything SixAxisAvoid needs on a fresh machine with Rust and Python 3.9+:
# a virtual environment in .venv with the Python dependencies, the extension module
# built in release mode and installed into it, and the release `sixaxis` binary.
# Idempotent: a second run only rebuilds what changed.
set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  # --system-site-packages: reuse what the machine already has (torch is large).
  "$PYTHON" -m venv --system-site-packages .venv
fi
# shellcheck disable=SC1091
source .venv/bin/activate
python -m pip install --quiet --upgrade pip
python -m pip install --quiet "maturin>=1.7,<2"
# requirements-dev.txt includes the optional extras (render, sb3, mujoco, urdf, video).
python -m pip install --quiet -r requirements-dev.txt
maturin develop --release --quiet
cargo build --release --quiet -p sixaxis-cli
echo "setup done: .venv (python $(python -c 'import sys; print(sys.version.split()[0])')), target/release/sixaxis"
