"""Shared fixtures: the repository's bundled data and the CLI binary the results are
compared with (``GONIOFIT_BIN``, default ``target/release/goniofit``, built by
``cargo build --release`` or the repository's test script)."""

import json
import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
DATA = REPO / "data"


@pytest.fixture(scope="session")
def cli():
    """Run ``goniofit ARGS...`` and return (exit code, stdout)."""
    exe = pathlib.Path(os.environ.get("GONIOFIT_BIN", REPO / "target" / "release" / "goniofit"))
    if not exe.exists():
        pytest.fail(f"the goniofit CLI is not built at {exe}: run `cargo build --release`")

    def run(*args):
        p = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, cwd=REPO)
        return p.returncode, p.stdout

    return run


@pytest.fixture(scope="session")
def cli_json(cli):
    """``goniofit fit ARGS... --json`` as a dict (exit code 0 or 3 required)."""

    def run(*args):
        code, out = cli("fit", *args, "--json")
        assert code in (0, 3), f"goniofit fit {args} exited {code}"
        return json.loads(out)

    return run


@pytest.fixture
def python_sigint():
    """Python's own SIGINT handler for the test (a shell starts background jobs with SIGINT
    ignored, and Python then installs no handler: Ctrl-C would never reach it), the earlier
    one restored after."""
    import signal

    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)
