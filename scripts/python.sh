#!/usr/bin/env bash
# Builds the Python package from this checkout into a virtual environment (.venv), with the
# pinned tools of python/requirements-dev.txt, and optionally runs its tests.
#   scripts/python.sh          build and install into .venv
#   scripts/python.sh test     build, install and run the Python tests (pytest)
# The wheel is built by maturin in the workspace's target folder, so the Rust crates are
# shared with `cargo test --release`.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
venv=${PROXFORM_VENV:-$root/.venv}
python=${PYTHON:-python3}
stamp=$venv/.requirements
if [ ! -x "$venv/bin/python" ]; then
    "$python" -m venv "$venv"
fi
# Install the pinned requirements once per change of the file.
if ! cmp -s python/requirements-dev.txt "$stamp" 2>/dev/null; then
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r python/requirements-dev.txt
    cp python/requirements-dev.txt "$stamp"
fi
rm -rf target/wheels
(cd python && "$venv/bin/maturin" build --quiet --release -o "$root/target/wheels" --interpreter "$venv/bin/python" >/dev/null)
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check --no-deps --force-reinstall target/wheels/proxform-*.whl
if [ "${1:-}" = test ]; then
    # From the repository's root, so that the installed package is imported, not python/proxform.
    "$venv/bin/pytest" -q -p no:cacheprovider -c python/pyproject.toml python/tests
fi
