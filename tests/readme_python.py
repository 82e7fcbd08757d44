"""Run every ```python block of README.md, in order, from the repository's root: the
examples a new user copies must work with what `pip install './python[dask]'` installs."""

import os
import pathlib
import re
import sys

root = pathlib.Path(__file__).resolve().parent.parent
os.chdir(root)
blocks = re.findall(r"```python\n(.*?)```", (root / "README.md").read_text(), re.S)
if not blocks:
    sys.exit("tests/readme_python.py: README.md has no python block")
for k, code in enumerate(blocks, 1):
    print(f"README python block {k} of {len(blocks)}", flush=True)
    exec(compile(code, f"README.md python block {k}", "exec"), {"__name__": "__main__"})
