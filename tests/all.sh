#!/usr/bin/env bash
# Every test of the project in one command: the Rust suite (`cargo test --release`), then
# the README's Python examples and the Python package's tests (python/tests, pytest)
# against a fresh build of the binding in a virtual environment (`target/py-venv`, or
# $GONIOFIT_VENV) that this script creates afresh with `pip install './python[dask]'`
# (numpy, pandas, dask[dataframe,distributed] from PyPI), then pytest.
set -euo pipefail
cd "$(dirname "$0")/.."

cargo test --release

# The documented install in a fresh environment, exactly as the README gives it (pip
# builds the abi3 wheel with maturin in its own build environment); the README's Python
# examples (the Dask one included) run with nothing else installed; then pytest joins.
venv="${GONIOFIT_VENV:-target/py-venv}"
python3 -m venv --clear "$venv"
pip=("$venv/bin/python" -m pip install --quiet --disable-pip-version-check)
"${pip[@]}" './python[dask]'
"$venv/bin/python" tests/readme_python.py > /dev/null
"${pip[@]}" pytest

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
