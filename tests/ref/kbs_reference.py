#!/usr/bin/env python3
"""High-precision reference values for the KBS series (goniofit, tests/lib/kbs_reference.rs).

    S(g, a) = sum_{m>=1} g^m / (m! m) exp(-a/m)        Q(g, a) = exp(-g) S(g, a) / g

Output (written next to this script):
  kbs_reference_q.csv   g, a, ln Q, d lnQ/dg, d lnQ/da, and at a = 0 the closed form
                        ln Q from S(g, 0) = Ei(g) - gamma - ln g (empty otherwise)
  kbs_reference_l.csv   full-model radiance L = s pi (T/lam)^2 h^2 (k sigma)^2 Q (A = lam^2,
                        no coherent term) with d ln L / d ln sigma and d ln L / d ln T, for
                        angles in degrees, sigma/lam, T/lam, s = 1.

Method: mpmath at 60 significant digits. The series is summed directly, term by term,
outward from its largest term m* (the first m with ratio t_{m+1}/t_m < 1; the ratio
r_m = g m/(m+1)^2 exp(a/(m(m+1))) decreases in m, so the terms rise up to m* and fall
after it). The summation window around the peak is not fixed in advance; it ends where a
rigorous bound on everything left out is below 1e-50 of the sum:
  upward:   sum_{j>m} t_j <= t_m r_m/(1 - r_m)   (geometric, since r_j <= r_m for j > m)
  downward: sum_{j<m} t_j <= (m-1) t_{m-1}       (terms fall monotonically below the peak)
so for large g the window is about +-15 sqrt(m*) terms wide (where a Gaussian-like peak of
width ~ sqrt(m*) falls below 1e-50) and the omitted terms cannot matter at 40+ digits. The
derivative sums sum (m-1-g) t_m and sum t_m/m use the same window (their weights grow at
most linearly, which the 1e-50 margin covers many times over).

Inputs are exactly the binary64 numbers the Rust test uses (g, a printed with repr; angles
converted to radians in binary64 as Rust's f64::to_radians does) so that the reference and
the code see identical arguments. Rerun: python3 tests/ref/kbs_reference.py (takes a few
minutes); requires mpmath.
"""
import math
import os
import sys

import mpmath as mp

mp.mp.dps = 60
HERE = os.path.dirname(os.path.abspath(__file__))
CUT = mp.mpf(10) ** -50


def ratio(m, g, a):
    """t_{m+1}/t_m."""
    m = mp.mpf(m)
    return g * m / (m + 1) ** 2 * mp.exp(a / (m * (m + 1)))


def peak(g, a):
    """Smallest m >= 1 with t_{m+1}/t_m < 1 (the index of the largest term)."""
    if ratio(1, g, a) < 1:
        return 1
    lo, hi = 1, 2
    while ratio(hi, g, a) >= 1:
        lo, hi = hi, hi * 2
    while hi - lo > 1:  # ratio(lo) >= 1 > ratio(hi)
        mid = (lo + hi) // 2
        if ratio(mid, g, a) >= 1:
            lo = mid
        else:
            hi = mid
    return hi


def ln_q(g_f, a_f):
    """ln Q, d ln Q/dg, d ln Q/da at binary64 inputs g_f > 0, a_f >= 0."""
    g = mp.mpf(g_f)
    a = mp.mpf(a_f)
    m0 = peak(g, a)
    ln_t0 = m0 * mp.log(g) - mp.loggamma(m0 + 1) - mp.log(m0) - a / m0
    s0 = mp.mpf(1)
    s_c = (m0 - 1 - g)
    s_inv = mp.mpf(1) / m0
    # upward
    m, rel = m0, mp.mpf(1)
    while True:
        r = ratio(m, g, a)
        rel *= r
        m += 1
        s0 += rel
        s_c += (m - 1 - g) * rel
        s_inv += rel / m
        r_next = ratio(m, g, a)
        if r_next < 1 and rel * r_next / (1 - r_next) < CUT * s0:
            break
    # downward
    m, rel = m0, mp.mpf(1)
    while m > 1:
        rel /= ratio(m - 1, g, a)
        m -= 1
        s0 += rel
        s_c += (m - 1 - g) * rel
        s_inv += rel / m
        if (m - 1) * rel < CUT * s0:
            break
    lnq = -g + ln_t0 + mp.log(s0) - mp.log(g)
    return lnq, s_c / (g * s0), -s_inv / s0


def ln_q_closed(g_f):
    """ln Q at a = 0 from S(g, 0) = Ei(g) - gamma - ln g."""
    g = mp.mpf(g_f)
    s = mp.ei(g) - mp.euler - mp.log(g)
    return -g + mp.log(s) - mp.log(g)


def f64_radians(deg):
    return float(deg) * (math.pi / 180.0)


def model(ti_deg, tr_deg, pr_deg, sigma, corr):
    """KBS radiance with lam = 1, s = 1, A = lam^2, no coherent term."""
    ti, tr, pr = (mp.mpf(f64_radians(x)) for x in (ti_deg, tr_deg, pr_deg))
    k = 2 * mp.pi
    ci, cr = mp.cos(ti), mp.cos(tr)
    si, sr = mp.sin(ti), mp.sin(tr)
    c = ci + cr
    h = 1 + ci * cr - si * sr * mp.cos(pr)
    vxy2 = (si - sr * mp.cos(pr)) ** 2 + (sr * mp.sin(pr)) ** 2
    ks = k * mp.mpf(sigma)
    t = mp.mpf(corr)
    g = (ks * c) ** 2
    a = vxy2 * (k * t) ** 2 / 4
    # Here g, a are exact functions of the binary64 angles, not binary64 numbers.
    lnq, dg, da = ln_q_exact(g, a)
    ln_l = mp.log(mp.pi * t * t) + 2 * mp.log(h) + 2 * mp.log(ks) + lnq
    return ln_l, 2 + 2 * g * dg, 2 + 2 * a * da, g, a


def ln_q_exact(g, a):
    # ln_q converts through mp.mpf, which keeps an mpf argument exact.
    return ln_q(g, a)


def fmt(x):
    return mp.nstr(x, 45, min_fixed=1, max_fixed=0)


def main():
    gs = [1e-12, 1e-8, 1e-4, 0.01, 0.1, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 30.0, 45.0, 70.0,
          100.0, 150.0, 300.0, 1e3, 3e3, 1e4, 1e5, 1e6]
    a_abs = [0.0, 1e-8, 1e-3, 0.1, 1.0, 5.0, 20.0, 100.0, 1e3, 1e4, 1e6, 1e8]
    b_rel = [0.01, 0.3, 1.0, 3.0, 10.0, 30.0]
    rows = []
    for g in gs:
        a_list = sorted(set(a_abs + [b * g for b in b_rel] + [b * g ** 1.5 for b in (0.01, 0.1)]))
        for a in a_list:
            rows.append((g, a))
    with open(os.path.join(HERE, "kbs_reference_q.csv"), "w") as f:
        f.write("g,a,ln_q,d_g,d_a,ln_q_closed\n")
        for i, (g, a) in enumerate(rows):
            lnq, dg, da = ln_q(g, a)
            closed = ""
            if a == 0.0:
                cl = ln_q_closed(g)
                assert abs(cl - lnq) < mp.mpf(10) ** -40 * max(1, abs(lnq)), (g, cl, lnq)
                closed = fmt(cl)
            f.write(f"{g!r},{a!r},{fmt(lnq)},{fmt(dg)},{fmt(da)},{closed}\n")
            print(f"q {i + 1}/{len(rows)}", file=sys.stderr, end="\r")
    print(file=sys.stderr)

    # Full model at the extreme geometries.
    geoms = [
        (0.0, 0.0, 0.0),        # normal incidence and view: mirror and backscatter at once
        (30.0, 30.0, 0.0),      # mirror
        (30.0, 30.0, 180.0),    # backscatter
        (45.0, 45.0, 0.0),
        (45.0, 0.0, 0.0),
        (45.0, 60.0, 90.0),
        (45.0, 20.0, 135.0),
        (70.0, 10.0, 30.0),
        (89.99, 89.99, 0.0),    # grazing mirror
        (89.99, 90.0, 0.0),     # grazing in and out: c -> 0, h -> 0
        (89.99, 90.0, 180.0),   # grazing backscatter
        (89.99, 0.0, 0.0),
        (10.0, 90.0, 45.0),
        (60.0, 60.0, 180.0),
        (80.0, 85.0, 5.0),
    ]
    params = [(1e-7, 1e-3), (1e-7, 1e3), (1e-3, 1.0), (1e-3, 1e5), (0.05, 0.3), (0.05, 30.0),
              (0.2, 1.0), (1.0, 5.0), (1.0, 1e3), (5.0, 25.0), (20.0, 100.0), (80.0, 400.0),
              (80.0, 1e5), (0.3, 1e-3)]
    with open(os.path.join(HERE, "kbs_reference_l.csv"), "w") as f:
        f.write("theta_i,theta_r,phi_r,sigma,T,ln_l,dlnl_dlnsigma,dlnl_dlnt,g,a\n")
        n = len(geoms) * len(params)
        i = 0
        for (ti, tr, pr) in geoms:
            for (sig, corr) in params:
                i += 1
                ln_l, ds, dt, g, a = model(ti, tr, pr, sig, corr)
                f.write(f"{ti!r},{tr!r},{pr!r},{sig!r},{corr!r},{fmt(ln_l)},{fmt(ds)},"
                        f"{fmt(dt)},{mp.nstr(g, 17)},{mp.nstr(a, 17)}\n")
                print(f"l {i}/{n}", file=sys.stderr, end="\r")
    print(file=sys.stderr)


if __name__ == "__main__":
    main()
