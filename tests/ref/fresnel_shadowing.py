#!/usr/bin/env python3
"""Reference values for the Fresnel and Smith factors (goniofit, tests/lib/fresnel_shadowing.rs).

Independent of the Rust code's algebra: the textbook forms, evaluated with mpmath at 30
significant digits, derivatives by mpmath's numerical differentiation at that precision.

Fresnel (fresnel_reference.csv): c = cos(theta_loc) as a binary64 number, n, kappa;
  w = eta cos(theta_t) with sin(theta_t) = sin(theta)/eta (Snell), the root with
  Re w >= 0 (the wave decaying into the medium); r_s = (c - w)/(c + w),
  r_p = (eta^2 c - w)/(eta^2 c + w), R = (|r_s|^2 + |r_p|^2)/2, R0 = |(eta-1)/(eta+1)|^2;
  columns F = R/R0, dF/dn, dF/dkappa; and Schlick's
  S = (F0 + (1 - F0)(1 - c)^5)/F0, F0 = ((n-1)/(n+1))^2, with dS/dn (kappa = 0 rows only).
Smith (smith_reference.csv): cot(theta_i), cot(theta_r) as binary64 numbers, T/sigma;
  Lambda(nu) = (erf(nu) - 1)/2 + exp(-nu^2)/(2 nu sqrt(pi)), nu = (T/sigma) cot/2;
  G = 1/((1 + Li)(1 + Lr)) and Gc = 1/(1 + Li + Lr), with d ln G/d ln T and
  d ln Gc/d ln T (T varied at fixed sigma).

Angles: theta_loc and theta_i, theta_r in degrees up to 89.9; n from 1.01 to 4, kappa up
to 10; T/sigma from 0.5 to 200. Rerun: python3 tests/ref/fresnel_shadowing.py (seconds;
requires mpmath).
"""
import csv
import math
import os

import mpmath as mp

mp.mp.dps = 30
HERE = os.path.dirname(os.path.abspath(__file__))


def fresnel_ratio(c, n, kappa):
    c = mp.mpf(c)
    eta = mp.mpc(n, kappa)
    sin2 = 1 - c * c
    cos_t = mp.sqrt(1 - sin2 / (eta * eta))
    w = eta * cos_t
    if mp.re(w) < 0:
        w = -w
    rs = (c - w) / (c + w)
    rp = (eta * eta * c - w) / (eta * eta * c + w)
    r = (abs(rs) ** 2 + abs(rp) ** 2) / 2
    r0 = abs((eta - 1) / (eta + 1)) ** 2
    return r / r0


def schlick_ratio(c, n):
    c = mp.mpf(c)
    f0 = ((n - 1) / (n + 1)) ** 2
    return (f0 + (1 - f0) * (1 - c) ** 5) / f0


def smith_lambda(nu):
    if nu == 0:
        return mp.inf
    return (mp.erf(nu) - 1) / 2 + mp.exp(-nu * nu) / (2 * nu * mp.sqrt(mp.pi))


def smith(cot_i, cot_r, t, correlated):
    li = smith_lambda(t * mp.mpf(cot_i) / 2)
    lr = smith_lambda(t * mp.mpf(cot_r) / 2)
    return 1 / (1 + li + lr) if correlated else 1 / ((1 + li) * (1 + lr))


def g(x):
    return mp.nstr(x, 20, min_fixed=-1, max_fixed=-1) if mp.isfinite(x) else "inf"


def fresnel_rows():
    angles = [0.0, 10.0, 30.0, 45.0, 56.3, 60.0, 75.0, 85.0, 89.0, 89.9]
    indices = [(1.01, 0.0), (1.33, 0.0), (1.5, 0.0), (2.4, 0.0), (4.0, 0.0),
               (0.2, 3.0), (1.5, 0.5), (2.5, 10.0), (1.01, 10.0), (4.0, 1e-3)]
    for th in angles:
        c = math.cos(math.radians(th))
        for n, k in indices:
            n_, k_ = mp.mpf(n), mp.mpf(k)
            f = fresnel_ratio(c, n_, k_)
            dn = mp.diff(lambda x: fresnel_ratio(c, x, k_), n_)
            dk = mp.diff(lambda x: fresnel_ratio(c, n_, x), k_)
            if k == 0.0:
                s = schlick_ratio(c, n_)
                ds = mp.diff(lambda x: schlick_ratio(c, x), n_)
            else:
                s, ds = None, None
            yield [repr(c), repr(n), repr(k), g(f), g(dn), g(dk),
                   "" if s is None else g(s), "" if ds is None else g(ds)]


def smith_rows():
    angles = [0.0, 20.0, 45.0, 70.0, 80.0, 85.0, 89.0, 89.9]
    ratios = [0.5, 2.0, 5.0, 20.0, 200.0]
    for ti in angles:
        for tr in angles:
            ci = math.cos(math.radians(ti)) / math.sin(math.radians(ti)) if ti else math.inf
            cr = math.cos(math.radians(tr)) / math.sin(math.radians(tr)) if tr else math.inf
            for t in ratios:
                row = [repr(ci), repr(cr), repr(t)]
                for corr in (False, True):
                    if math.isinf(ci) and math.isinf(cr):
                        val, d = mp.mpf(1), mp.mpf(0)
                    else:
                        fi = ci if math.isfinite(ci) else 1e300
                        fr = cr if math.isfinite(cr) else 1e300
                        val = smith(fi, fr, mp.mpf(t), corr)
                        d = mp.diff(lambda x: mp.log(smith(fi, fr, mp.exp(x), corr)),
                                    mp.log(t))
                    row += [g(val), g(d)]
                yield row


def main():
    with open(os.path.join(HERE, "fresnel_reference.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["c", "n", "kappa", "F", "dF_dn", "dF_dkappa", "schlick", "dschlick_dn"])
        w.writerows(fresnel_rows())
    with open(os.path.join(HERE, "smith_reference.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["cot_i", "cot_r", "t_over_sigma", "G", "dlnG_dlnT", "Gc", "dlnGc_dlnT"])
        w.writerows(smith_rows())


if __name__ == "__main__":
    main()
