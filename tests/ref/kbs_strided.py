#!/usr/bin/env python3
"""How exact the strided sum of the KBS series is (goniofit, src/model/series/strided.rs).

    S(g, a) = sum_{m>=1} g^m / (m! m) exp(-a/m)

Where the terms' peak is wide (width W from the curvature of ln t_m at the peak m0),
`auto` sums every h-th term only, h = floor(W / 1.5), and multiplies by h. Poisson
summation predicts a relative error of about 2 exp(-2 pi^2 (W/h)^2): 5e-20 at W/h = 1.5,
2.6e-9 at W/h = 1. This script measures it in 30-digit arithmetic: for random (g, a) with
g in [1e2, 1e6] and a in [0, 3e3 g^1.5] it sums every term outward from the peak (until a
term is below 1e-25 of the peak) and every h-th term (until below 1e-20), for W/h = 1.5
(what goniofit uses) and 1.0 (to show the predicted law), and writes the errors of ln S
and of the derivative sum g dlnS/dg = sum (m-1-g) t_m / sum t_m to kbs_strided.csv.

Rerun: python3 tests/ref/kbs_strided.py (a few minutes; requires mpmath).
"""
import math
import os
import random

import mpmath as mp

mp.mp.dps = 30
HERE = os.path.dirname(os.path.abspath(__file__))


def ln_term(m, g, a):
    m = mp.mpf(m)
    return m * mp.log(g) - g - mp.loggamma(m + 1) - mp.log(m) - a / m


def peak(g, a):
    """Smallest m >= 1 with t_{m+1}/t_m < 1."""
    def ln_ratio(m):
        return math.log(g) + math.log(m) - 2 * math.log(m + 1) + a / (m * (m + 1))
    if ln_ratio(1) < 0:
        return 1
    lo, hi = 1, max(2, int(g))
    while ln_ratio(hi) >= 0:
        lo, hi = hi, hi * 2
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if ln_ratio(mid) >= 0:
            lo = mid
        else:
            hi = mid
    return hi


def sums(g, a, m0, step, cut):
    """ln(step * sum t) and sum (m-1-g) t / sum t over m = m0 + j step, j in Z, m >= 1."""
    l0 = ln_term(m0, g, a)
    s0, sc = mp.mpf(1), mp.mpf(m0 - 1) - g
    for d in (step, -step):
        m = m0 + d
        while m >= 1:
            t = mp.exp(ln_term(m, g, a) - l0)
            s0 += t
            sc += (m - 1 - g) * t
            if t < cut:
                break
            m += d
    return l0 + mp.log(s0 * step), sc / s0


def main():
    random.seed(20261202)
    rows = []
    for _ in range(16):
        g = mp.mpf(10 ** random.uniform(2, 6))
        s = 0.0 if random.random() < 0.15 else 10 ** random.uniform(-3, math.log10(3e3))
        a = mp.mpf(s) * g ** 1.5
        m0 = peak(float(g), float(a))
        w = 1 / math.sqrt(1 / (m0 + 0.5) - 1 / m0**2 + 2 * float(a) / m0**3)
        exact = sums(g, a, m0, 1, mp.mpf(10) ** -25)
        for c in (1.5, 1.0):
            h = max(1, int(w / c))
            ln_s, d = sums(g, a, m0, h, mp.mpf(10) ** -20)
            rows.append((float(g), s, c, h, float(abs(ln_s - exact[0])),
                         float(abs(d - exact[1]) / (1 + abs(exact[1])))))
            print(*rows[-1], flush=True)
    with open(os.path.join(HERE, "kbs_strided.csv"), "w") as f:
        f.write("# python3 tests/ref/kbs_strided.py: errors of the strided KBS sum (30 digits)\n")
        f.write("g,a_over_g15,width_per_stride,stride,err_ln_s,err_g_dlns_dg\n")
        for r in rows:
            f.write("%.6g,%.4g,%g,%d,%.2e,%.2e\n" % r)
    for c in (1.5, 1.0):
        worst = max(max(r[4], r[5]) for r in rows if r[2] == c)
        print(f"W/h = {c}: worst error {worst:.2e} (predicted {2 * math.exp(-2 * math.pi**2 * c * c):.1e})")


if __name__ == "__main__":
    main()
