#!/usr/bin/env bash
# The long fuzzing run: INPUTS (default 1,000,000) inputs per Rust target (scenario JSON by
# tree and by byte mutations, Q-table bytes), then PY_INPUTS (default 20,000) inputs of the
# Python boundary fuzzer. Rust runs in release with overflow checks on (an overflow is a
# panic, hence a finding), in its own target directory so the normal build is untouched.
# Counts and rates go to stdout and fuzz-results/ (JSON for the Python fuzzer).
#   INPUTS=1000000 PY_INPUTS=20000 SEED=0 nice -n 15 bash scripts/fuzz_long.sh
set -euo pipefail
cd "$(dirname "$0")/.."
INPUTS=${INPUTS:-1000000}
PY_INPUTS=${PY_INPUTS:-20000}
SEED=${SEED:-0}
mkdir -p fuzz-results
echo "== Rust: $INPUTS inputs per target, seed $SEED"
SIXAXIS_FUZZ_INPUTS=$INPUTS SIXAXIS_FUZZ_SEED=$SEED \
  CARGO_PROFILE_RELEASE_OVERFLOW_CHECKS=true CARGO_TARGET_DIR=target/fuzz-long \
  cargo test --release -p sixaxis-core --test fuzz -- --nocapture --test-threads 1 2>&1 \
  | tee fuzz-results/rust.log | grep -oE "fuzz [A-Za-z].*\)|test result.*|panicked.*"
if [ "$PY_INPUTS" -gt 0 ]; then
  echo "== Python boundary fuzzer: $PY_INPUTS inputs, seed $SEED"
  # shellcheck disable=SC1091
  [ -f .venv/bin/activate ] && source .venv/bin/activate
  python scripts/fuzz_python.py --inputs "$PY_INPUTS" --seed "$SEED" \
    --out fuzz-results/python.json > /dev/null \
    && echo "python: $PY_INPUTS inputs, no finding (fuzz-results/python.json)" \
    || { echo "python: findings, see fuzz-results/python.json"; exit 1; }
fi
