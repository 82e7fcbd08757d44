#!/usr/bin/env bash
# Every test of the project in one command: the Rust suite (`cargo test --release`), then
# the Python package's (python/tests, pytest) against a fresh build of the binding in a
# virtual environment (`target/py-venv`, or $GONIOFIT_VENV) that this script creates and
# fills from PyPI: maturin, pytest, numpy, pandas, dask[dataframe,distributed].
set -euo pipefail
cd "$(dirname "$0")/.."

cargo test --release

venv="${GONIOFIT_VENV:-target/py-venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check \
    maturin pytest numpy pandas "dask[dataframe,distributed]"
# The documented install: `pip install ./python` builds the abi3 wheel with maturin.
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check ./python

# The CLI the Python results are compared with is the one `cargo test --release` built.
export GONIOFIT_BIN="${CARGO_TARGET_DIR:-$PWD/target}/release/goniofit"
set +e
"$venv/bin/python" -m pytest -q -p no:cacheprovider --rootdir python/tests python/tests
code=$?
set -e
case "$code" in
    0) ;;
    5) echo "tests/all.sh: pytest collected no tests (python/tests)" >&2; exit 1 ;;
    *) echo "tests/all.sh: pytest failed (exit code $code)" >&2; exit "$code" ;;
esac
