"""Benchmark: goniofit.fit_frame on N small scans with ``warm_start=True`` against the
default (every group's start searched), interleaved run by run, on 2 threads.

    python python/benches/fit_frame_warm.py [N=2000] [repeats=7]

The scans are the texel batch of `benches/texels.py gen` (as fit_frame_vs_cli.py; the CLI
builds them: GONIOFIT_BIN or target/release/goniofit). Prints the median call time of
each, the ratio, how many groups kept their warm start, and the largest relative
difference of the two tables' costs.
"""

import os
import pathlib
import statistics
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from fit_frame_vs_cli import REPO, goniofit, texel_batch  # noqa: E402


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 7
    exe = os.environ.get("GONIOFIT_BIN", str(REPO / "target" / "release" / "goniofit"))
    _, df = texel_batch(exe, n, pathlib.Path(tempfile.mkdtemp()))
    times = {"search": [], "warm": []}
    tables = {}
    for _ in range(repeats):
        for kind in times:
            t = time.perf_counter()
            tables[kind] = goniofit.fit_frame(df, by="group", wavelength=1.0, threads=2,
                                              warm_start=kind == "warm")
            times[kind].append(time.perf_counter() - t)
    med = {k: statistics.median(v) for k, v in times.items()}
    kept = int((tables["warm"]["start_from"] == "neighbour").sum())
    rel = ((tables["warm"]["cost"] - tables["search"]["cost"]).abs() / tables["search"]["cost"]).max()
    print(f"{n} scans, {repeats} runs each (interleaved), threads=2")
    for k, m in med.items():
        print(f"  {k:6} {m:.3f} s = {n / m:7.0f} fits/s")
    print(f"  warm/search: {med['search'] / med['warm']:.2f}x faster; {kept} of {n} kept the warm "
          f"start; largest relative cost difference {rel:.1e}")


if __name__ == "__main__":
    main()
