#!/usr/bin/env bash
# The Python package's tests (python/tests, pytest) in their own venv under target/, run by
# scripts/test.sh after `cargo test` (which builds the `sweeptin` binary and the
# `triangulate_raw` example the tests compare against). Builds the extension once with maturin in
# the dev profile (`--profile dev` overrides pyproject.toml's release profile, which is for
# wheels): on the 2-core VM, after `cargo test`, 1.8 min to build and 52 s of tests, against
# 6 min and 34 s in release. Caches nothing outside the checkout (pip runs without its cache).
set -euo pipefail
cd "$(dirname "$0")/.."

VENV=target/venv-py
if [ ! -x "$VENV/bin/python" ]; then
    python3 -m venv "$VENV"
fi
PY="$VENV/bin/python"
"$PY" -m pip install --quiet --disable-pip-version-check --no-cache-dir \
    "maturin>=1.9,<2" "pytest>=7" numpy "laspy[lazrs]>=2.5" "dask[distributed]>=2024.1" "affine>=2.4"

cargo clippy --locked -p sweeptin-python --all-targets -- -D warnings
cargo build --locked --quiet --bin sweeptin --example triangulate_raw
VIRTUAL_ENV="$PWD/$VENV" PATH="$PWD/$VENV/bin:$PATH" \
    maturin develop --profile dev --locked --quiet -m python/Cargo.toml
cd python
"../$PY" -m pytest -q -p no:cacheprovider tests
