#!/usr/bin/env python3
"""Reference optima of the real-data corpus, independent of goniofit's start search.

Every fit of the corpus, kbs+lambert on the BRDF with log residuals:
  CUReT:   61 samples of data/curet/curet.csv (group 1..61), lambda = 550 nm;
  Cornell: 4 paints data/cornell/*.astm x their 28 channels (400..670 nm).
For each fit, goniofit's Levenberg-Marquardt (--no-reduce) is run from a dense set of
starts and the lowest cost (1/2 sum r^2 of the log residuals) is kept:
  - sigma/lambda in SIGMA_OVER_LAMBDA x T/sigma in T_OVER_SIGMA (42 points), each started
    twice: (a) with all four parameters given, the amplitudes (scale, scale_d) fitted here
    to the data at that (sigma, T) by a bounded scipy least_squares on the log residuals
    (the KBS shape from `goniofit eval --model kbs ... scale=1`), and (b) with sigma and T
    only (goniofit's own linear solve of the amplitudes);
  - goniofit's default start (no --init).
That is up to 85 runs per fit. It uses goniofit's solver and model (checked against
mpmath and NIST StRD elsewhere) but none of its start search; tests/ref/corpus_crosscheck.py
re-fits a handful of rows with an independent numpy model and scipy.

The table gives the best point overall and the best point inside the physical domain of
KBS (T/sigma >= 0.1, 2 pi T/lambda >= 0.1, sigma/lambda >= 1e-6, scale > 0, finite cost):
the fit `goniofit fit` gives by default must either reach cost_best (within the tolerance
of tests/trust/corpus.rs) inside the domain, or say `degenerate` when the best optimum lies at an
edge.

Usage (from the repository root; numpy and scipy, e.g. in a venv; ~2 processes, about
15 minutes on 2 cores):
  python3 tests/ref/corpus_reference.py target/release/goniofit > tests/ref/corpus_reference.csv
Output columns: corpus, file, group (CUReT sample or Cornell channel), lambda_nm, runs
(runs that returned a finite cost), cost_best (lowest cost of any run), edge_best (why the
best point is at an edge of the domain, or "none"), cost_inside (lowest cost inside the
domain, or "inf"), sigma, T, scale, scale_d (that inside point; sigma, T in nm),
T_over_sigma.
"""
import concurrent.futures as cf
import csv
import io
import json
import math
import subprocess
import sys

import numpy as np
from scipy.optimize import least_squares

SIGMA_OVER_LAMBDA = [0.003, 0.01, 0.03, 0.1, 0.3, 1.0, 3.0]
T_OVER_SIGMA = [0.5, 1.5, 4.0, 10.0, 30.0, 100.0]
COMMON = ["--model", "kbs+lambert", "--quantity", "brdf"]
FIT = ["fit", *COMMON, "--residual", "log", "--no-reduce", "--no-intervals", "--json",
       "--threads", "1"]
PAINTS = ["acryl_blue", "cayman", "garnet_red", "krylon_blue"]
CURET = "data/curet/curet.csv"
# The edges of the physical domain (as src/fit/problem/edges.rs states them).
MIN_T_OVER_SIGMA = 0.1
MIN_KT = 0.1
MIN_SIGMA_OVER_LAMBDA = 1e-6


def cornell_channels(path):
    """The channel names of an ASTM file (its VARS line after the four angles)."""
    with open(path) as f:
        for line in f:
            if line.startswith("VARS"):
                return line.split(None, 1)[1].strip().split(",")[4:]
    raise ValueError(f"{path}: no VARS line")


class Fit:
    """One fit of the corpus: how to select its data, and its measured values."""

    def __init__(self, corpus, file, group, lam, select):
        self.corpus, self.file, self.group, self.lam = corpus, file, group, lam
        self.select = select  # goniofit arguments choosing the data (file last)
        self.y = None  # measured BRDF, the order goniofit evaluates it in


def fits():
    out = []
    for g in range(1, 62):
        out.append(Fit("curet", "curet.csv", str(g), 550.0,
                       ["--wavelength", "550", "--channel", str(g), CURET]))
    for paint in PAINTS:
        path = f"data/cornell/{paint}.astm"
        for ch in cornell_channels(path):
            out.append(Fit("cornell", f"{paint}.astm", ch, float(ch[:-2]),
                           ["--channel", ch, path]))
    return out


def kbs_column(exe, fit, sigma, t):
    """(measured values, KBS BRDF at scale 1) at the fit's angles, from `goniofit eval`."""
    out = subprocess.run([exe, "eval", "--model", "kbs", "--quantity", "brdf", "--params",
                          f"sigma={sigma!r},T={t!r},scale=1", *fit.select],
                         capture_output=True, text=True)
    if out.returncode != 0:
        return None
    rows = list(csv.reader(io.StringIO(out.stdout)))
    head = rows[0]
    yk = 5 if fit.corpus == "cornell" else head.index("L")
    data = np.array([[float(r[yk]), float(r[-1])] for r in rows[1:]])
    return data[:, 0], data[:, 1]


def amplitudes(y, f):
    """(scale, scale_d) > 0 minimising 1/2 sum (ln max(s f + s_d, floor) - ln max(y, floor))^2
    (goniofit's log residual, floor 1e-6 max|y|), by scipy least_squares in ln s, ln s_d from
    three starts; None when the KBS column is not finite and positive somewhere."""
    floor = 1e-6 * np.max(np.abs(y))
    ly = np.log(np.maximum(y, floor))
    if not np.all(np.isfinite(f)) or np.max(f) <= 0:
        return None

    def r(x):
        return np.log(np.maximum(np.exp(x[0]) * f + np.exp(x[1]), floor)) - ly

    d0 = max(float(np.median(np.maximum(y, floor))), floor)
    peak = float(np.max(y) / np.max(f))
    best = None
    for s0 in (peak, 1e-2 * peak, 1e2 * peak):
        res = least_squares(r, [math.log(s0), math.log(d0)], method="trf", xtol=1e-10)
        if best is None or res.cost < best.cost:
            best = res
    return math.exp(best.x[0]), math.exp(best.x[1])


def run_fit(exe, fit, init):
    """(cost, params) of one goniofit fit, or None when it gave no finite cost."""
    args = [exe, *FIT, *(["--init", init] if init else []), *fit.select]
    out = subprocess.run(args, capture_output=True, text=True)
    if not out.stdout.strip():
        return None
    d = json.loads(out.stdout)
    cost = d.get("cost")
    if cost is None or not math.isfinite(cost):
        return None
    return cost, {k: v["value"] for k, v in d["params"].items()}


def edge(p, lam):
    """Why a point is at an edge of KBS's physical domain, or "none"."""
    s, t = p["sigma"], p["T"]
    if not (s > 0 and t > 0 and p["scale"] > 0):
        return "scale" if s > 0 and t > 0 else "sigma"
    if s / lam < MIN_SIGMA_OVER_LAMBDA:
        return "sigma"
    if t / s < MIN_T_OVER_SIGMA:
        return "T/sigma"
    if 2 * math.pi * t / lam < MIN_KT:
        return "kT"
    return "none"


def runs_of(exe, fit):
    """Every run of one fit: the default start, then the grid of starts (a) and (b)."""
    results = [run_fit(exe, fit, None)]
    for so in SIGMA_OVER_LAMBDA:
        for tos in T_OVER_SIGMA:
            sigma, t = so * fit.lam, so * tos * fit.lam
            results.append(run_fit(exe, fit, f"sigma={sigma:.6g},T={t:.6g}"))
            col = kbs_column(exe, fit, sigma, t)
            amp = amplitudes(*col) if col else None
            if amp:
                init = f"sigma={sigma:.6g},T={t:.6g},scale={amp[0]:.6g},scale_d={amp[1]:.6g}"
                results.append(run_fit(exe, fit, init))
    return [r for r in results if r is not None]


def row(fit, runs):
    best = min(runs, key=lambda r: r[0])
    inside = [r for r in runs if edge(r[1], fit.lam) == "none"]
    cost_in, p = min(inside, key=lambda r: r[0]) if inside else (math.inf, None)
    vals = ["nan"] * 5 if p is None else [
        f"{p['sigma']:.6g}", f"{p['T']:.6g}", f"{p['scale']:.6g}", f"{p['scale_d']:.6g}",
        f"{p['T'] / p['sigma']:.6g}"]
    return [fit.corpus, fit.file, fit.group, f"{fit.lam:g}", str(len(runs)),
            f"{best[0]:.10g}", edge(best[1], fit.lam),
            "inf" if math.isinf(cost_in) else f"{cost_in:.10g}", *vals]


def main(exe, only=None):
    todo = [f for f in fits() if only is None or f"{f.file}:{f.group}" in only]
    with cf.ThreadPoolExecutor(max_workers=2) as pool:
        rows = list(pool.map(lambda f: row(f, runs_of(exe, f)), todo))
    w = csv.writer(sys.stdout, lineterminator="\n")
    w.writerow(["corpus", "file", "group", "lambda_nm", "runs", "cost_best", "edge_best",
                "cost_inside", "sigma", "T", "scale", "scale_d", "T_over_sigma"])
    w.writerows(rows)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    # Optional further arguments FILE:GROUP restrict the table to those fits (for checks).
    main(sys.argv[1], set(sys.argv[2:]) or None)
