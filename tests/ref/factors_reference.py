#!/usr/bin/env python3
"""The trust matrix's reference for the lobe with its factors: the best optimum of
`fit --model kbs+lambert --fresnel dielectric --shadowing smith` on bundled data, found by
an independent multi-start.

Built on tests/ref/trust_reference.py (its samples, KBS sum, residuals, weights, solver and
domain edges; nothing of goniofit's numerics), with the factors written from the
equations (docs/conventions.md, "Factors on the KBS lobe"; He et al. 1991; Smith 1967):
  - F = R(θ_loc; n)/R(0; n), cos θ_loc = sqrt(h/2), R = (r_s² + r_p²)/2 with the textbook
    r_s = (c − w)/(c + w), r_p = (n²c − w)/(n²c + w), w = sqrt(n² − 1 + c²), R(0) =
    ((n − 1)/(n + 1))²; ∂F/∂n by a complex step (F is analytic in n > 1);
  - G = 1/((1 + Λ(ν_i))(1 + Λ(ν_r))), ν = T/(2σ tan θ), Λ(ν) = e^{−ν²}(1/(ν√π) −
    erfcx ν)/2 (Λ = 0 at θ = 0), ∂Λ/∂ln ν = −e^{−ν²}/(2ν√π), so ∂ln G/∂ln T = −∂ln G/∂ln σ
    = −Σ ν Λ'(ν)/(1 + Λ(ν));
  - L = (KBS lobe) F G + s_d cos θi, solver variables ln σ, ln T, s, s_d, ln(n − 1).
Starts: trust_reference's 20 KBS starts at each n of 1.2, 1.5, 2.2, 3.2, and the plain
kbs+lambert's best point (its own multi-start) at each of those n, amplitudes fitted at
each start; the two best distinct ends polished. A point is at an edge of the domain
where trust_reference says so, or where n < 1.001 (`n`: the factor's strongest rise).

Each row: the case, the best cost and point and its edge, the best inside the domain, and
this script's cost at goniofit's fitted point beside goniofit's own cost (they agree to
1e-9 or the reference's model is not goniofit's; where goniofit's n is 1 to double
precision the textbook F is 0/0 and the cost here is the 1e150 residuals' 1e302).
tests/trust/factors_trust.rs classes goniofit's fits against it.

Usage (numpy, scipy; a few minutes on one core):
  python3 tests/ref/factors_reference.py target/release/goniofit > tests/ref/factors_reference.csv
"""
import csv
import math
import os
import subprocess
import json
import sys

import numpy as np
from scipy.special import erfcx

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import trust_reference as tr  # noqa: E402

FACTORS = ["--fresnel", "dielectric", "--shadowing", "smith"]
N_STARTS = [1.2, 1.5, 2.2, 3.2]
RESIDUALS = ["log", "relative"]


def datasets():
    """The Cornell channels, CUReT surfaces and the synthetic hemisphere of the matrix."""
    return [d for d in tr.datasets() if d[0].startswith(("cornell", "curet/1", "curet/4",
                                                          "curet/6", "synthetic/kbs_hemi"))]


def fresnel(c, n):
    w = np.sqrt(n * n - 1 + c * c)
    rs = (c - w) / (c + w)
    rp = (n * n * c - w) / (n * n * c + w)
    r0 = ((n - 1) / (n + 1)) ** 2
    return 0.5 * (rs * rs + rp * rp) / r0


def smith(theta, t_over_sigma):
    """Λ and ν ∂Λ/∂ν per sample (0 at θ = 0)."""
    tan = np.tan(theta)
    with np.errstate(divide="ignore"):
        nu = np.where(tan > 0, t_over_sigma / (2 * tan), np.inf)
    big = nu > 27
    v = np.where(big, 1.0, nu)
    e = np.exp(-v * v)
    lam = np.where(big, 0.0, 0.5 * e * (1 / (v * math.sqrt(math.pi)) - erfcx(v)))
    dlam = np.where(big, 0.0, -0.5 * e / (v * math.sqrt(math.pi)))
    return lam, dlam


class FactorModel(tr.Model):
    def __init__(self, d):
        super().__init__("kbs+lambert", d)
        self.names = self.names + ["n"]
        self.lo = self.lo + [math.log(1e-6)]
        self.hi = self.hi + [math.log(1e3)]
        self.cos_loc = np.minimum(np.sqrt(0.5 * d.h), 1.0)

    def params(self, x):
        p = super().params(x[:4])
        if len(x) > 4:
            p["n"] = 1 + math.exp(x[4])
        return p

    def to_x(self, p):
        return super().to_x(p) + [math.log(max(p["n"] - 1, 1e-300))]

    def columns(self, x):
        d = self.d
        sigma, t, s, sd, n = math.exp(x[0]), math.exp(x[1]), x[2], x[3], 1 + math.exp(x[4])
        f1, ds, dt = tr.kbs_unit(d, sigma, t)
        fr = fresnel(self.cos_loc, n)
        h = 1e-30
        dfr = fresnel(self.cos_loc.astype(complex), complex(n, h)).imag / h
        li, dli = smith(d.ti, t / sigma)
        lr, dlr = smith(d.tr, t / sigma)
        g = 1 / ((1 + li) * (1 + lr))
        dlng = -(dli / (1 + li) + dlr / (1 + lr))
        unit = f1 * fr * g
        lobe = s * unit
        diffuse = d.cos_i * d.factor
        f = lobe + sd * diffuse
        cols = [lobe * (ds - dlng), lobe * (dt + dlng), unit, diffuse,
                s * f1 * g * dfr * (n - 1)]
        return f, np.column_stack(cols)

    def edge(self, x):
        e = super().edge(x)
        return e if e != "none" else ("n" if self.params(x)["n"] < 1.001 else "none")


def reference(d, kind):
    plain = tr.Model("kbs+lambert", d)
    pprob = tr.Problem(plain, kind)
    _, (_, xp), _ = tr.reference(plain, pprob, tr.nested_seeds(plain, {}, None))
    model = FactorModel(d)
    prob = tr.Problem(model, kind)
    seeds = []
    for n in N_STARTS:
        ln = math.log(n - 1)
        seeds += [prob.amplitudes([*x[:2], 1.0, 1.0, ln], [2, 3])
                  for x in tr.starts(plain, pprob)]
        seeds.append(prob.amplitudes([*xp[:2], 1.0, 1.0, ln], [2, 3]))
    runs = [tr.solve(prob, x0) for x0 in seeds]
    runs = sorted([(c, x) for c, x in runs if math.isfinite(c)], key=lambda r: r[0])
    distinct = []
    for c, x in runs:
        if all(abs(c / c2 - 1) > 1e-6 or np.abs(x - x2).max() > 1e-3 * (1 + np.abs(x2).max())
               for c2, x2 in distinct):
            distinct.append((c, x))
        if len(distinct) == 2:
            break
    runs += [tr.solve(prob, x, tight=True) for _, x in distinct]
    best = min(runs, key=lambda r: r[0])
    inside = [r for r in runs if model.edge(r[1]) == "none"]
    return model, prob, len(seeds), best, min(inside, key=lambda r: r[0]) if inside else None


def goniofit(binary, args, kind):
    out = subprocess.run([binary, "fit", "--model", "kbs+lambert", *FACTORS, "--residual", kind,
                          "--no-intervals", "--json", *args], capture_output=True, text=True)
    rep = json.loads(out.stdout)
    return {k: v["value"] for k, v in rep["params"].items()}, rep["cost"]


def main(binary, pattern=""):
    w = csv.writer(sys.stdout, lineterminator="\n")
    print("# Generated by tests/ref/factors_reference.py; see that script for the method.")
    w.writerow(["dataset", "residual", "args", "starts", "cost_best", "edge_best",
                "params_best", "cost_inside", "cost_here_at_goniofit", "cost_goniofit"])
    worst = 0.0
    for name, args in datasets():
        if pattern not in name:
            continue
        d = tr.load(binary, args)
        for kind in RESIDUALS:
            model, prob, n, (cb, xb), inside = reference(d, kind)
            p, cg = goniofit(binary, args, kind)
            here = prob.cost(np.array(model.to_x(p)))
            worst = max(worst, abs(here / cg - 1))
            w.writerow([name, kind, " ".join(args), n, f"{cb:.12g}", model.edge(xb),
                        tr.fmt_params(model, xb), f"{inside[0]:.12g}" if inside else "inf",
                        f"{here:.12g}", f"{cg:.12g}"])
            sys.stdout.flush()
        print(f"{name}: done", file=sys.stderr)
    print(f"worst relative difference of the costs at goniofit's point {worst:.1e}",
          file=sys.stderr)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main(*sys.argv[1:3])
