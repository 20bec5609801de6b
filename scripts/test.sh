#!/usr/bin/env bash
# The whole test suite, from a fresh checkout: installs what the interop tests need (Python's
# plyfile, laspy, copclib, rio-cogeo in the repository's own venv; GDAL's command-line tools and
# GNU parallel from Debian packages when run as root), then checks formatting, lints and runs
# every test. The real test data are committed in tests/data (docs/DATA.md): nothing is needed
# beside the checkout. This is the README's test command; CI runs it through .ci/run.
set -euo pipefail
cd "$(dirname "$0")/.."

# Debian packages (as root only): GDAL's tools and parallel for the interop tests, nginx for the
# remote ones, Chromium for the report's browser test (tests/plan_report.rs), and the venv
# module, which Debian's python3 leaves out.
missing=()
command -v gdalinfo >/dev/null 2>&1 || missing+=(gdal-bin)
command -v parallel >/dev/null 2>&1 || missing+=(parallel)
# nginx serves the remote-input tests' files (tests/remote.rs).
command -v nginx >/dev/null 2>&1 || [ -x /usr/sbin/nginx ] || missing+=(nginx)
command -v chromium >/dev/null 2>&1 || missing+=(chromium)
python3 -c 'import ensurepip, venv' 2>/dev/null || missing+=(python3-venv)
if [ ${#missing[@]} -gt 0 ] && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" \
        >/dev/null) || echo "test.sh: could not install ${missing[*]}" >&2
fi

# Python peers in the repository's own venv, never the system Python: target/venv-py, the one
# scripts/test-python.sh uses. The tests run the `python3`, `rio` and `moto_server` (an S3 server
# for tests/remote.rs, with boto3 to fill it) on the PATH, so its bin/
# goes first. plyfile reads our PLY, rio-cogeo (with rasterio) validates COGs, copclib writes the
# COPC copies for tests/inputs.rs (scripts/make_copc.py), laspy + lazrs are the reference reader.
# Each test whose tool is missing fails under CI=true and is skipped with a message otherwise.
VENV=target/venv-py
[ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --no-cache-dir \
    plyfile==1.1.5 rio-cogeo==7.0.4 copclib==2.6.3 laspy==2.7.0 lazrs==0.8.2 'moto[server]==5.2.6' ||
    echo "test.sh: could not install the Python peers in $VENV" >&2
export PATH="$PWD/$VENV/bin:$PATH"

cargo fmt --all -- --check
cargo clippy --all-targets --locked -- -D warnings
# The library as users build it (no `dev` feature: the engine is pub(crate)): no dead code.
cargo clippy --lib --locked -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --locked --quiet
# The library's unit tests, the binary's and the one integration-test binary (tests/all.rs), then
# the doc tests. The developer examples are not built again: clippy --all-targets checked them.
cargo test --locked --quiet --tests
cargo test --locked --quiet --doc
# The Python package (python/): its own venv under target/, the extension built once (dev profile).
scripts/test-python.sh
