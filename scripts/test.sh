#!/usr/bin/env bash
# Every check and test: formatting, lints, Rust tests (unit, integration, doc), Python tests.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# shellcheck disable=SC1091
source .venv/bin/activate
echo "== cargo fmt";    cargo fmt --all -- --check
echo "== cargo clippy"; cargo clippy --workspace --all-targets --quiet -- -D warnings
echo "== cargo doc";    RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --quiet -p sixaxis-core -p sixaxis-cli -p sixaxis-server
echo "== ruff";         ruff check python tests scripts && ruff format --check python tests scripts
# The hand-written stub python/sixaxis_avoid/_core.pyi against the built extension.
echo "== stubtest";     python -m mypy.stubtest sixaxis_avoid._core
# What files hold of the core's option declarations (stub keywords, docs table) is current.
echo "== options";      python scripts/derive_options.py --check
echo "== cargo test";   cargo test --workspace --release
# Slow learning runs (marker `slow`) are left out here; scripts/test_slow.sh runs them.
echo "== pytest";       python -m pytest tests -q -m "not slow" --ignore=tests/test_remote_ray.py
# Ray's driver state is per process: the two-node cluster test gets a process of its own,
# not one where the benchmark tests already started and stopped a local Ray.
echo "== pytest (Ray cluster)"; python -m pytest tests/test_remote_ray.py -q
