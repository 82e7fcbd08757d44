#!/usr/bin/env python3
"""Peer baseline for the `goniofit fit` speed benchmark (benches/fit_vs_scipy.sh).

What a lab writes today: a vectorised numpy KBS model (the full series of eq. 37, summed in
log space so it does not overflow) fitted with scipy.optimize.least_squares(method='lm')
(MINPACK, finite-difference Jacobian), in log-parameters (ln sigma, ln T, ln scale) like
goniofit, from the same starting values.

Usage: scipy_kbs_fit.py DATA.csv --wavelength 1 --init sigma=..,T=..,scale=.. [--repeats 5]
Prints one JSON object: median seconds, final cost (1/2 sum r^2), nfev, parameters.
"""
import argparse
import json
import sys
import time

import numpy as np
from scipy.optimize import least_squares
from scipy.special import gammaln


def load(path):
    data = np.genfromtxt(path, delimiter=",", names=True, comments="#")
    ti = np.radians(data["theta_i"])
    tr = np.radians(data["theta_r"])
    pr = np.radians(data["phi_r"])
    return ti, tr, pr, np.asarray(data["L"], dtype=float)


def geometry(ti, tr, pr):
    """(c, h, vxy2) of eq. 36: c = cos ti + cos tr, h = 1 + cos ti cos tr - sin ti sin tr cos pr
    (cos^2 F^2 = h^2 / c^2), vxy2 = |v_xy|^2 / k^2."""
    ci, cr = np.cos(ti), np.cos(tr)
    si, sr = np.sin(ti), np.sin(tr)
    c = ci + cr
    h = 1 + ci * cr - si * sr * np.cos(pr)
    vxy2 = (si - sr * np.cos(pr)) ** 2 + (sr * np.sin(pr)) ** 2
    return c, h, vxy2


def ln_kbs(s, T, lam, g, a, c, h, m):
    """ln L = ln[s cos^2(ti) F^2 (pi T^2/lam^2) e^{-g} S], S = sum over the terms m (one
    column per sample) of g^m/(m! m) e^{-a/m}, summed in log space."""
    lnt = m * np.log(g)[None, :] - gammaln(m + 1) - np.log(m) - a[None, :] / m
    peak = lnt.max(axis=0)
    ln_s = peak + np.log(np.exp(lnt - peak).sum(axis=0))
    return np.log(s) + np.log(np.pi * (T / lam) ** 2) + 2 * np.log(h) - 2 * np.log(c) - g + ln_s


def kbs(params, ti, tr, pr, lam):
    sigma, T, s = params
    k = 2 * np.pi / lam
    c, h, vxy2 = geometry(ti, tr, pr)
    g = (k * sigma * c) ** 2
    a = vxy2 * (k * T) ** 2 / 4
    gmax = float(g.max())
    mmax = int(gmax + 12 * np.sqrt(gmax) + 30)
    m = np.arange(1, mmax + 1)[:, None]
    return np.exp(ln_kbs(s, T, lam, g, a, c, h, m))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("data")
    ap.add_argument("--wavelength", type=float, default=1.0)
    ap.add_argument("--init", required=True)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--also", help="sigma=..,T=..,scale=..: also report the cost of these "
                    "parameters under this script's model (to compare final costs on one model)")
    args = ap.parse_args()
    init = dict(kv.split("=") for kv in args.init.split(","))
    x0 = np.log([float(init["sigma"]), float(init["T"]), float(init["scale"])])
    ti, tr, pr, y = load(args.data)

    def resid(x):
        return kbs(np.exp(x), ti, tr, pr, args.wavelength) - y

    times = []
    res = None
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        res = least_squares(resid, x0, method="lm", xtol=1e-10, ftol=1e-10)
        times.append(time.perf_counter() - t0)
    p = np.exp(res.x)
    also_cost = None
    if args.also:
        q = dict(kv.split("=") for kv in args.also.split(","))
        x = np.log([float(q["sigma"]), float(q["T"]), float(q["scale"])])
        also_cost = float(0.5 * np.sum(resid(x) ** 2))
    json.dump(
        {
            "seconds_median": float(np.median(times)),
            "seconds": times,
            "cost": float(res.cost),
            "nfev": int(res.nfev),
            "status": int(res.status),
            "params": {"sigma": p[0], "T": p[1], "scale": p[2]},
            "n": int(len(y)),
            "also_cost": also_cost,
        },
        sys.stdout,
    )
    print()


if __name__ == "__main__":
    main()
