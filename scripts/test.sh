#!/usr/bin/env bash
# The whole test suite, from a fresh checkout: installs what the interop tests need (Python's
# plyfile, GDAL's command-line tools), then checks formatting, lints and runs every test.
# This is the README's test command; CI runs it through .ci/run.
set -euo pipefail
cd "$(dirname "$0")/.."

# Interop peers used by the tests (each test skips with a message when its tool is absent).
if ! python3 -c 'import plyfile' 2>/dev/null; then
    python3 -m pip install --quiet --disable-pip-version-check plyfile==1.1.5 || true
fi
if ! command -v rio >/dev/null 2>&1 || ! rio cogeo --version >/dev/null 2>&1; then
    python3 -m pip install --quiet --disable-pip-version-check rio-cogeo==7.0.4 || true
fi
if ! python3 -c 'import copclib, laspy, lazrs' 2>/dev/null; then
    # COPC copies for tests/inputs.rs (scripts/make_copc.py) and laspy as the reference reader.
    python3 -m pip install --quiet --disable-pip-version-check copclib==2.6.3 laspy==2.7.0 \
        lazrs==0.8.2 || true
fi
if ! command -v gdalinfo >/dev/null 2>&1 && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq gdal-bin >/dev/null) || true
fi

if ! command -v parallel >/dev/null 2>&1 && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq parallel >/dev/null) || true
fi

cargo fmt --all -- --check
cargo clippy --all-targets --locked -- -D warnings
# The library as users build it (no `dev` feature: the engine is pub(crate)): no dead code.
cargo clippy --lib --locked -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --locked --quiet
cargo test --locked --quiet
# The Python package (python/): its own venv under target/, the extension built once (dev profile).
scripts/test-python.sh
