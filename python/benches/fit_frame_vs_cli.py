"""Benchmark: goniofit.fit_frame on N small scans against the CLI's `fit --by-group` on
the same samples, and Dask (LocalCluster, 2 worker processes) against fit_frame, in one
run, the tools interleaved run by run.

    python python/benches/fit_frame_vs_cli.py [N=2000] [repeats=7]

The scans are the texel batch of `benches/texels.py gen` (N in-plane KBS scans of 66
samples from `goniofit synth`, 1 % noise); the CSV is read into pandas exactly (Python's
float() of each field), so both tools fit the same numbers (checked: every
group's cost agrees). Needs the package installed (tests/all.sh's virtual environment has
everything) and the CLI built (`cargo build --release`; GONIOFIT_BIN overrides the path).
Prints medians:
- CLI: the whole process (read CSV, fit, write JSON) and its own `seconds` (the fits);
- fit_frame: the call, from an in-memory DataFrame to the result table;
- Dask: fit_groups(...).compute() on a persisted Dask DataFrame with P partitions, and the
  overhead per partition (Dask − fit_frame on the same 2 cores) / P.
"""

import csv
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

import goniofit  # noqa: E402
import goniofit.dask  # noqa: E402

REPO = HERE.parents[1]


def texel_batch(exe, n, tmp):
    """The texel CSV of `n` scans (benches/texels.py gen) and it as a DataFrame."""
    import pandas as pd

    path = tmp / "texels.csv"
    subprocess.run([sys.executable, str(REPO / "benches" / "texels.py"), "gen", "--goniofit",
                    exe, "--texels", str(n), "--out", str(path)], check=True)
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    # float() of the text is the value the CLI parses (correctly rounded, as Rust's).
    df = pd.DataFrame({k: [float(r[k]) for r in rows] for k in ("theta_i", "theta_r", "phi_r", "L")})
    df["group"] = [r["group"] for r in rows]
    return path, df


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 7
    exe = os.environ.get("GONIOFIT_BIN", str(REPO / "target" / "release" / "goniofit"))
    tmp = pathlib.Path(tempfile.mkdtemp())
    path, df = texel_batch(exe, n, tmp)
    print(f"{n} scans of {len(df) // n} samples (KBS, λ = 1), {repeats} runs each, {os.cpu_count()} cores")

    cli_wall, cli_fit, frame = [], [], []
    for _ in range(repeats):
        t = time.perf_counter()
        out = subprocess.run([exe, "fit", "--wavelength", "1", "--by-group", "--json", "--quiet",
                              str(path)], capture_output=True, text=True, check=False)
        cli_wall.append(time.perf_counter() - t)
        report = json.loads(out.stdout)
        cli_fit.append(report["seconds"])
        t = time.perf_counter()
        table = goniofit.fit_frame(df, by="group", wavelength=1.0)
        frame.append(time.perf_counter() - t)
    assert len(table) == n
    cli_cost = {f["input"].rsplit("[", 1)[-1].rstrip("]"): f["cost"] for f in report["fits"]}
    same = sum(cli_cost[str(g)] == c for g, c in table["cost"].items())
    print(f"same cost as the CLI          : {same} of {n} groups")
    med = statistics.median
    print(f"CLI --by-group, whole process : {med(cli_wall):.3f} s")
    print(f"CLI --by-group, fits (seconds): {med(cli_fit):.3f} s")
    print(f"fit_frame                     : {med(frame):.3f} s")
    ratios = [f / c for f, c in zip(frame, cli_fit)]
    print(f"fit_frame / CLI fits          : {med(ratios):.3f} (per-run {min(ratios):.3f}..{max(ratios):.3f})")
    ratios = [f / c for f, c in zip(frame, cli_wall)]
    print(f"fit_frame / CLI process       : {med(ratios):.3f} (per-run {min(ratios):.3f}..{max(ratios):.3f})")
    dask_overhead(df, n, repeats, med(frame))


def dask_overhead(df, n, repeats, frame_median):
    import dask.dataframe as dd
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        base = df.set_index("group")
        for parts in (2, 8, 32, 128):
            ddf = dd.from_pandas(base, npartitions=parts, sort=True).persist()
            client.wait_for_workers(2)
            goniofit.dask.fit_groups(ddf, by="group", wavelength=1.0, threads=1).compute()  # warm
            times, frames = [], []
            for _ in range(repeats):
                t = time.perf_counter()
                out = goniofit.dask.fit_groups(ddf, by="group", wavelength=1.0, threads=1).compute()
                times.append(time.perf_counter() - t)
                t = time.perf_counter()
                goniofit.fit_frame(df, by="group", wavelength=1.0)
                frames.append(time.perf_counter() - t)
            assert len(out) == n
            d, f = statistics.median(times), statistics.median(frames)
            per = [(a - b) / parts for a, b in zip(times, frames)]
            print(f"Dask 2 workers, {parts:>3} partitions: {d:.3f} s vs fit_frame {f:.3f} s "
                  f"(ratio {d / f:.3f}); overhead per partition {1e3 * statistics.median(per):.1f} ms")


if __name__ == "__main__":
    main()
