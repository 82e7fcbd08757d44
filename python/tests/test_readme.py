"""The README's "From Python" example runs as printed and prints the garnet fit's report."""

import contextlib
import io
import os
import re

from conftest import REPO


def test_readme_python_example_runs():
    readme = (REPO / "README.md").read_text()
    section = readme.split("## From Python", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    assert len(code.strip().splitlines()) == 5
    out = io.StringIO()
    cwd = os.getcwd()
    os.chdir(REPO)
    try:
        with contextlib.redirect_stdout(out):
            exec(compile(code, "README.md", "exec"), {})
    finally:
        os.chdir(cwd)
    text = out.getvalue()
    assert "verdict         = rough regime: only T/sigma and the amplitude are determined" in text
    # T/σ as in the README's CLI output, the same fit from the command line (degrees
    # round-trip: last digits).
    cli = float(re.search(r"T/sigma\s+= (\S+)", readme).group(1))
    t_sigma = float(re.search(r"T/sigma\s+= (\S+)", text).group(1))
    assert abs(t_sigma - cli) < 1e-5 * cli
