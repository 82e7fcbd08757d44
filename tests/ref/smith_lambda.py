#!/usr/bin/env python3
"""Smith's Lambda for the Beckmann distribution: the polynomial table of src/model/shadowing.rs
and a dense reference (goniofit, tests/lib/fresnel_shadowing.rs).

Lambda(nu) = (erf(nu) - 1)/2 + exp(-nu^2)/(2 nu sqrt(pi)). The code writes it as

    Lambda = exp(-nu^2) (y/sqrt(pi) - E(nu)) / 2,   y = 1/nu,   E = erfcx(nu) = exp(nu^2) erfc(nu),

with one exponential and E from a table of eight pieces: erfcx(nu) as a polynomial in nu on
[0, 0.3], [0.3, 0.65], [0.65, 0.95], [0.95, 1.25], and erfcx(nu) = y P(y) with P a polynomial
in y on nu in [1.25, 1.6], [1.6, 2.2], [2.2, 3.2], [3.2, inf) (y in [0, 1/3.2] for the last,
so no cut-off is needed: exp(-nu^2) underflows to 0 and takes Lambda with it). Each
polynomial is the N-point Chebyshev interpolant of its function (mpmath, 50 digits) rewritten
exactly in t = (u - mid)/half in [-1, 1] (u = nu or y; mid and half the piece's centre and
half-width), so the code sums it by Estrin's scheme without branches beyond the choice of
piece. The script prints the table as Rust (`E_PIECES`) with, per piece, the worst
|Lambda - reference|/(1 + Lambda) of the formula above in binary64 at 1500 points.

lambda_reference.csv: nu (a binary64 number), Lambda(nu) and nu dLambda/dnu =
-exp(-nu^2)/(2 sqrt(pi) nu), at 30 digits, nu from 1e-3 to 6.5 and a few beyond (the pieces'
edges included). Rerun: python3 tests/ref/smith_lambda.py (about a minute; requires mpmath).
"""
import csv
import math
import os

import mpmath as mp

mp.mp.dps = 50
HERE = os.path.dirname(os.path.abspath(__file__))
N = 12
# (in y, lowest nu, highest nu)
PIECES = [(False, 0.0, 0.3), (False, 0.3, 0.65), (False, 0.65, 0.95), (False, 0.95, 1.25),
          (True, 1.25, 1.6), (True, 1.6, 2.2), (True, 2.2, 3.2), (True, 3.2, math.inf)]


def erfcx(x):
    return mp.exp(x * x) * mp.erfc(x)


def x_erfcx(y):
    """nu erfcx(nu) as a function of y = 1/nu (1/sqrt(pi) at y = 0)."""
    return 1 / y * erfcx(1 / y) if y > 0 else 1 / mp.sqrt(mp.pi)


def cheb_coefficients(f, a, b, n):
    nodes = [mp.cos(mp.pi * (k + mp.mpf(1) / 2) / n) for k in range(n)]
    fs = [f((b - a) / 2 * t + (a + b) / 2) for t in nodes]
    c = [2 * sum(fs[k] * mp.cos(mp.pi * j * (k + mp.mpf(1) / 2) / n) for k in range(n)) / n
         for j in range(n)]
    c[0] /= 2
    return c


def to_monomial(c):
    """The Chebyshev sum sum c_k T_k(t) as monomial coefficients in t (exact, mpmath)."""
    t_polys = [[mp.mpf(1)], [mp.mpf(0), mp.mpf(1)]]
    for k in range(2, len(c)):
        a = [mp.mpf(0)] + [2 * x for x in t_polys[k - 1]]
        b = t_polys[k - 2] + [mp.mpf(0)] * (len(a) - len(t_polys[k - 2]))
        t_polys.append([x - y for x, y in zip(a, b)])
    m = [mp.mpf(0)] * len(c)
    for ck, poly in zip(c, t_polys):
        for i, x in enumerate(poly):
            m[i] += ck * x
    return m


def smith_lambda(nu):
    nu = mp.mpf(nu)
    return (mp.erf(nu) - 1) / 2 + mp.exp(-nu * nu) / (2 * nu * mp.sqrt(mp.pi))


def piece(in_y, lo, hi):
    if in_y:
        a, b, f = (mp.mpf(0) if math.isinf(hi) else 1 / mp.mpf(hi)), 1 / mp.mpf(lo), x_erfcx
    else:
        a, b, f = mp.mpf(lo), mp.mpf(hi), erfcx
    m = [float(x) for x in to_monomial(cheb_coefficients(f, a, b, N))]
    mid, half = float((a + b) / 2), float((b - a) / 2)
    worst = 0.0
    top = 12.0 if math.isinf(hi) else hi
    for i in range(1, 1501):
        nu = lo + (top - lo) * i / 1500
        y = 1 / nu
        t = ((y if in_y else nu) - mid) / half
        v = 0.0
        for ck in reversed(m):
            v = v * t + ck
        e = y * v if in_y else v
        lam = 0.5 * math.exp(-nu * nu) * (y / math.sqrt(math.pi) - e)
        ref = smith_lambda(nu)
        worst = max(worst, float(abs(lam - ref) / (1 + ref)))
    return m, mid, 1 / half, worst


def table():
    print(f"const E_PIECES: [EPiece; {len(PIECES)}] = [")
    for in_y, lo, hi in PIECES:
        m, mid, inv_half, worst = piece(in_y, lo, hi)
        print(f"    // nu in [{lo}, {hi}], in {'y' if in_y else 'nu'}: worst error of Lambda {worst:.1e}")
        print(f"    EPiece {{ nu_lo: {lo!r}, in_y: {str(in_y).lower()}, mid: {mid!r}, "
              f"inv_half: {inv_half!r}, c: [")
        for x in m:
            print(f"        {x!r},")
        print("    ] },")
    print("];")


def reference_rows():
    edges = [p[1] for p in PIECES]
    nus = sorted(set([1e-3, 0.01, 0.1, 0.5, 1.0, 6.0000000000000009, 6.5, 8.0, 27.0, 40.0]
                     + edges[1:] + [math.nextafter(e, 0.0) for e in edges[1:]]
                     + [0.02 * k for k in range(1, 326)]))
    for nu in nus:
        lam = smith_lambda(nu)
        d = -mp.exp(-mp.mpf(nu) ** 2) / (2 * mp.sqrt(mp.pi) * mp.mpf(nu))
        yield [repr(nu), mp.nstr(lam, 25), mp.nstr(d, 25)]


def main():
    table()
    mp.mp.dps = 30
    with open(os.path.join(HERE, "lambda_reference.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["nu", "Lambda", "nu_dLambda_dnu"])
        w.writerows(reference_rows())


if __name__ == "__main__":
    main()
