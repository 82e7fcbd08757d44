#!/usr/bin/env python3
"""Cross-check of rows of tests/ref/corpus_reference.csv with an independent model and solver.

corpus_reference.py finds each fit's best optimum with goniofit's own Levenberg-Marquardt
and model. Here a handful of its rows are re-fitted with none of goniofit's numerics:
  - the KBS model in numpy (benches/scipy_kbs_fit.py's: the series of eq. 37 summed in
    log space, here over the window m = g +- (10 sqrt(g) + 30) that holds all but ~1e-20
    of it), as a BRDF L / cos(theta_i), plus the Lambertian BRDF scale_d; sigma <= 10
    lambda (g <= 1.6e4) keeps the window small;
  - scipy.optimize.least_squares (trust-region reflective, bounded, 2-point finite
    differences) on the log residuals ln max(f, floor) - ln max(y, floor), in the
    parameters (ln sigma, ln T, ln scale, ln scale_d), from the table's point and from 12
    other starts (sigma/lambda x T/sigma grid, amplitudes from a log-space fit).
goniofit supplies only the samples and the floor: `fit --residuals` writes the angles and
measured values it read, and `--json` the floor it used (the readers are tested elsewhere).

For each row it prints the cost of the table's point under the numpy model (must equal
cost_inside: the two models agree), and the lowest cost scipy reaches (must not be below
cost_best: no better optimum exists that goniofit's multi-start missed).

Usage (numpy, scipy; ~3 minutes on one core):
  python3 tests/ref/corpus_crosscheck.py target/release/goniofit > tests/ref/corpus_crosscheck.csv
"""
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.optimize import least_squares

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "benches"))
from scipy_kbs_fit import geometry, ln_kbs  # noqa: E402  (the benchmark's numpy model)

# (corpus file, group): regimes from smooth paints to rough CUReT samples.
ROWS = [
    ("krylon_blue.astm", "640nm"),
    ("garnet_red.astm", "550nm"),
    ("cayman.astm", "550nm"),
    ("acryl_blue.astm", "630nm"),
    ("acryl_blue.astm", "550nm"),
    ("curet.csv", "1"),
    ("curet.csv", "4"),
    ("curet.csv", "6"),
    ("curet.csv", "13"),
]
MAX_SIGMA_OVER_LAMBDA = 10.0
SIGMA_OVER_LAMBDA = [0.01, 0.1, 1.0]
T_OVER_SIGMA = [1.5, 5.0, 20.0, 100.0]


def select(file, group):
    if file == "curet.csv":
        return ["--wavelength", "550", "--channel", group, "data/curet/curet.csv"]
    return ["--channel", group, f"data/cornell/{file}"]


def samples(binary, file, group):
    """(theta_i, theta_r, phi_r) in radians, the measured BRDF, and the floor."""
    with tempfile.TemporaryDirectory() as tmp:
        res = os.path.join(tmp, "res.csv")
        out = subprocess.run(
            [binary, "fit", "--model", "kbs+lambert", "--quantity", "brdf", "--residual",
             "log", "--no-intervals", "--json", "--residuals", res, *select(file, group)],
            capture_output=True, text=True)
        report = json.loads(out.stdout)
        rows = list(csv.DictReader(open(res)))
    floor = report["setting"]["floor"]["value"]
    col = lambda name: np.array([float(r[name]) for r in rows])
    if "phi_i" in rows[0]:  # ASTM: (theta_i, phi_i, theta_s, phi_s), radians
        ti, tr = col("theta_i"), col("theta_s")
        pr = np.angle(np.exp(1j * (col("phi_s") - col("phi_i") - math.pi)))
        y = col("BRDF")
    else:  # goniofit's convention, degrees
        ti, tr, pr = (np.radians(col(c)) for c in ("theta_i", "theta_r", "phi_r"))
        y = col("L")  # the value column (a BRDF here: --quantity brdf)
    return ti, tr, pr, y, floor


def kbs(sigma, t, s, ti, tr, pr, lam):
    """KBS radiance (no coherent term, A = lambda^2), the series over the window of terms
    m = g +- (10 sqrt(g) + 30) around its peak."""
    k = 2 * np.pi / lam
    c, h, vxy2 = geometry(ti, tr, pr)
    g = (k * sigma * c) ** 2
    a = vxy2 * (k * t) ** 2 / 4
    half = 10 * np.sqrt(g) + 30
    m0 = np.maximum(1.0, np.floor(g - half))
    width = int(np.ceil(2 * half.max())) + 1
    m = m0[None, :] + np.arange(width)[:, None]
    return np.exp(ln_kbs(s, t, lam, g, a, c, h, m))


def brdf(q, ti, tr, pr, lam):
    sigma, t, s, sd = np.exp(q)
    return kbs(sigma, t, s, ti, tr, pr, lam) / np.cos(ti) + sd


def residual(q, ti, tr, pr, y, floor, lam):
    f = brdf(q, ti, tr, pr, lam)
    f = np.where(np.isfinite(f), f, 1e300)
    return np.log(np.maximum(f, floor)) - np.log(np.maximum(y, floor))


def cost(q, *data):
    r = residual(q, *data)
    return 0.5 * float(r @ r)


def amplitudes(sigma, t, data):
    """ln scale, ln scale_d at (sigma, T) from a bounded fit of the two amplitudes."""
    ti, tr, pr, y, floor, lam = data
    fun = lambda a: residual([math.log(sigma), math.log(t), *a], *data)
    a0 = [0.0, math.log(max(np.median(y), 1e-12))]
    return least_squares(fun, a0, bounds=([-60, -60], [60, 10]), method="trf").x


def refit(q0, data):
    lam = data[-1]
    lo = [math.log(1e-6 * lam), math.log(0.1 * lam / (2 * math.pi)), -60, -60]
    hi = [math.log(MAX_SIGMA_OVER_LAMBDA * lam), math.log(1e6 * lam), 60, 10]
    q0 = np.clip(q0, np.array(lo) + 1e-9, np.array(hi) - 1e-9)
    r = least_squares(residual, q0, args=data, bounds=(lo, hi), method="trf",
                      x_scale="jac", xtol=1e-14, ftol=1e-14, gtol=1e-14, max_nfev=4000)
    return cost(r.x, *data), r.x


def main():
    binary = sys.argv[1]
    ref = {(r["file"], r["group"]): r
           for r in csv.DictReader(l for l in open("tests/ref/corpus_reference.csv")
                                   if not l.startswith("#"))}
    w = csv.writer(sys.stdout, lineterminator="\n")
    print("# Generated by tests/ref/corpus_crosscheck.py; see that script for the method.")
    w.writerow(["file", "group", "cost_best", "cost_inside", "numpy_cost_at_table_point",
                "scipy_best_cost", "scipy_starts", "scipy_sigma", "scipy_T"])
    for file, group in ROWS:
        r = ref[(file, group)]
        lam = float(r["lambda_nm"])
        ti, tr, pr, y, floor = samples(binary, file, group)
        data = (ti, tr, pr, y, floor, lam)
        point = [math.log(float(r[k])) for k in ("sigma", "T", "scale", "scale_d")]
        at_table = cost(point, *data)
        starts = [point]
        for so in SIGMA_OVER_LAMBDA:
            for ts in T_OVER_SIGMA:
                sigma, t = so * lam, ts * so * lam
                starts.append([math.log(sigma), math.log(t), *amplitudes(sigma, t, data)])
        best, bx = min((refit(q, data) for q in starts), key=lambda c: c[0])
        w.writerow([file, group, r["cost_best"], r["cost_inside"], f"{at_table:.10g}",
                    f"{best:.10g}", len(starts), f"{math.exp(bx[0]):.6g}",
                    f"{math.exp(bx[1]):.6g}"])
        sys.stdout.flush()


if __name__ == "__main__":
    main()
