#!/usr/bin/env bash
# The tests: every Rust test of the workspace, then the Python package built from this
# checkout into .venv and its tests (scripts/python.sh). This is the README's test command and
# what CI runs. One target folder serves both.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --release --workspace --all-features
scripts/python.sh test
