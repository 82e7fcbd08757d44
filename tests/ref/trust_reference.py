#!/usr/bin/env python3
"""The trust matrix's reference: the best optimum of every (model, residual, dataset) case
a user may try at goniofit's defaults, found by an independent multi-start.

Models kbs, kbs+lambert, lambert-specular, lambert, kbs-rough x residuals absolute,
relative, log x the bundled data (datasets(): the synthetic files, eleven CUReT surfaces
(read as the BRDF the file states), the NIST PTFE file at 633 nm, nine Cornell channels:
550 nm of every paint, 450 and 650 nm of three).

Nothing of goniofit's numerics is used. goniofit supplies only the samples it read
(`fit --residuals` writes each row as read; the angle conventions are those of
docs/conventions.md and data/README.md, applied here). Written from the equations
(docs/conventions.md, "Models"; Peters 2000, eq. 34-37, 43):
  - KBS radiance L = s pi (T/lam)^2 (h/c)^2 e^{-g} S(g, a), S = sum_{m>=1} g^m/(m! m)
    e^{-a/m}, with c = cos ti + cos tr, h = 1 + cos ti cos tr - sin ti sin tr cos pr
    (cos^2 ti F^2 = h^2/c^2), g = (k sigma c)^2, a = vxy2 (k T)^2/4, k = 2 pi/lam. The sum
    is taken in log space over m* +- (8 sqrt(m*) + 16), m* the peak of its terms (all but
    ~e^-30 of it); kbs-rough replaces e^{-g} S by e^{-a/g}/g (eq. 43) and holds sigma at
    the median wavelength (as `fit` does: T carries T/sigma);
  - kbs+lambert adds s_d cos ti; lambert is s cos ti; lambert-specular is s cos ti +
    B/(w sqrt(2 pi)) exp(-1/2 [((tr - ti)/w)^2 + (pr/(2w))^2]);
  - a BRDF is the radiance / cos ti;
  - residuals f - y, (f - y)/max(|y|, floor), ln max(f, floor) - ln max(y, floor), floor
    = 1e-6 max |y|; weights 1, or from a sigma_L column 1/sigma_L^2 (absolute) and
    max(|y|, floor)^2/sigma_L^2 (relative, log); cost = 1/2 sum w r^2.
Solver: scipy.optimize.least_squares (trust-region reflective, bounded, analytic Jacobian)
in (ln sigma, ln T, ln w) and the amplitudes themselves (bounded below by 0), from at least
20 starts log-spaced over the domain (KBS: sigma/lam x T/sigma, 4 x 5; kbs-rough: T/sigma,
20; lambert-specular: w, 20; lambert: scale, 20 from 1e-7 to 10 x the largest value;
kbs+lambert and lambert-specular also at and from their special cases' best points,
nested_seeds), the
amplitudes of each start fitted at its other parameters (non-negative least squares; for
log residuals, least squares in their logarithms), each run for at most 30 evaluations, then the two best
distinct ends (and the best inside the domain) polished (up to 500 evaluations each).

Each row gives the best cost and its point, whether that point is at an edge of the
model's physical domain (as goniofit's README states it: T/sigma < 0.1, 2 pi T/lam < 0.1,
a KBS or Gaussian lobe narrower than the angular sampling, a lobe amplitude at 0; or
`sigma-cap`, the reference's own bound sigma <= 10 lam, on the rough ridge), and the best
cost and point of the runs that ended inside the domain.

Usage (numpy, scipy; ~15 minutes on one core):
  python3 tests/ref/trust_reference.py target/release/goniofit > tests/ref/trust_reference.csv
  python3 tests/ref/trust_reference.py target/release/goniofit --skip DATASET,... >> TABLE
    (continue a table: the datasets not yet in it)
  python3 tests/ref/trust_reference.py --nest target/release/goniofit TABLE
    (a table made without the nested start: add it, rewriting TABLE)
  python3 tests/ref/trust_reference.py --check target/release/goniofit [CASE-FILTER]
    (this script's cost at goniofit's fitted point against goniofit's reported cost)
"""
import csv
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.optimize import least_squares, nnls
from scipy.special import gammaln

# In this order: a model's special cases come first (their best points seed it, NESTED).
MODELS = ["lambert", "kbs", "kbs+lambert", "lambert-specular", "kbs-rough"]
RESIDUALS = ["absolute", "relative", "log"]
# Cornell channels: 550 nm of every paint, and 450 / 650 nm of three of them.
CORNELL = [("acryl_blue", "550nm"), ("acryl_blue", "650nm"), ("cayman", "450nm"),
           ("cayman", "550nm"), ("cayman", "650nm"), ("garnet_red", "450nm"),
           ("garnet_red", "550nm"), ("garnet_red", "650nm"), ("krylon_blue", "550nm")]
CURET_SURFACES = ["1", "4", "6", "7", "8", "13", "15", "25", "33", "41", "55"]


def datasets():
    """(name, goniofit arguments selecting the data, as a user types them)."""
    out = [(f"synthetic/{f}", ["--wavelength", "1", f"data/synthetic/{f}.csv"])
           for f in ("kbs_hemisphere", "kbs_inplane", "kbs_rough", "lambert_specular")]
    out += [(f"curet/{s}", ["--wavelength", "550nm", "--channel", s, "data/curet/curet.csv"])
            for s in CURET_SURFACES]
    out += [("nist-ptfe/633nm", ["--channel", "0.633", "data/nist-ptfe/PTFE.data.csv"])]
    out += [(f"cornell/{p}/{c}", ["--channel", c, f"data/cornell/{p}.astm"]) for p, c in CORNELL]
    return out


# ---------------------------------------------------------------- samples


class Data:
    """One dataset: angles (rad), wavelength per sample, measured values y, sqrt of the
    weights (per residual kind), BRDF or radiance."""

    def __init__(self, ti, tr, pr, lam, y, sigma_l, brdf):
        self.ti, self.tr, self.pr, self.lam, self.y = ti, tr, pr, lam, y
        self.sigma_l, self.brdf = sigma_l, brdf
        self.floor = 1e-6 * float(np.max(np.abs(y)))
        self.cos_i = np.cos(ti)
        self.factor = 1 / self.cos_i if brdf else np.ones_like(ti)
        ci, cr, si, sr = np.cos(ti), np.cos(tr), np.sin(ti), np.sin(tr)
        self.c = ci + cr
        self.h = 1 + ci * cr - si * sr * np.cos(pr)
        self.vxy2 = (si - sr * np.cos(pr)) ** 2 + (sr * np.sin(pr)) ** 2
        self.lam_med = float(np.median(lam))
        self.offset = np.sqrt((tr - ti) ** 2 + 0.25 * pr ** 2)  # from the mirror, eq. 34

    def sqrt_w(self, kind):
        if self.sigma_l is None:
            return np.ones_like(self.y)
        if kind == "absolute":
            return 1 / self.sigma_l
        return np.maximum(np.abs(self.y) if kind == "relative" else self.y,
                          self.floor) / self.sigma_l


def wrap(a):
    """Wrap radians into (-pi, pi]."""
    return -((-a + np.pi) % (2 * np.pi) - np.pi)


def load(binary, args):
    """The dataset goniofit reads for these arguments, via its --residuals file."""
    with tempfile.TemporaryDirectory() as tmp:
        res = os.path.join(tmp, "res.csv")
        out = subprocess.run([binary, "fit", "--model", "lambert", "--no-intervals", "--json",
                              "--residuals", res, *args], capture_output=True, text=True)
        if not out.stdout.strip():
            sys.exit(f"{args}: {out.stderr}")
        setting = json.loads(out.stdout)["setting"]
        rows = list(csv.DictReader(open(res)))
    col = lambda name: np.array([float(r[name]) for r in rows])
    head = rows[0].keys()
    brdf = setting["quantity"] == "brdf"
    sigma_l = col("sigma_L") if "sigma_L" in head else None
    if "phi_i" in head:  # ASTM: radians, outward azimuths; lambda from the channel name
        ti, tr = col("theta_i"), col("theta_s")
        pr = wrap(col("phi_s") - col("phi_i") - math.pi)
        y = col(rows[0]["channel"]) if rows[0]["channel"] in head else col("BRDF")
        lam = np.full_like(ti, float(rows[0]["channel"][:-2]))
    elif "thetai" in head:  # NIST: degrees, outward azimuths, thetai < 0 = source at phi+180
        ti_s = col("thetai")
        phi_src = col("phi") + np.where(ti_s < 0, 180.0, 0.0)
        ti, tr = np.radians(np.abs(ti_s)), np.radians(col("thetar"))
        pr = wrap(np.radians(col("phir") - phi_src - 180.0))
        y, lam = col("f_r11"), col("lambda")
    else:  # goniofit's convention, degrees
        ti, tr, pr = (np.radians(col(c)) for c in ("theta_i", "theta_r", "phi_r"))
        pr = wrap(pr)
        y = col("L")
        lam = np.full_like(ti, setting["wavelength"]["values"][0])
    d = Data(ti, tr, pr, lam, y, sigma_l, brdf)
    d.floor_goniofit = setting["floor"]["value"]
    return d


# ---------------------------------------------------------------- models


_LGAMMA = np.zeros(1)


def lgamma_int(m):
    """ln Gamma(m + 1) for integer arrays m >= 1 (a growing table)."""
    global _LGAMMA
    top = int(m.max()) + 2
    if top > len(_LGAMMA):
        _LGAMMA = gammaln(np.arange(max(top, 2 * len(_LGAMMA))) + 1.0)
    return _LGAMMA[m]


def peak_m(g, a):
    """The m >= 1 where ln t_m = m ln g - ln m! - ln m - a/m peaks (stationary point of
    ln g - ln m + a/m^2, which falls in m), by bisection in ln m."""
    lo, hi = np.zeros_like(g), np.full_like(g, 40.0)
    for _ in range(70):
        mid = 0.5 * (lo + hi)
        m = np.exp(mid)
        up = np.log(g) - mid + a / (m * m) > 0
        lo, hi = np.where(up, mid, lo), np.where(up, hi, mid)
    return np.maximum(1.0, np.exp(lo))


def ln_s(g, a):
    """ln S(g, a), <m> and <1/m> under the terms t_m (for the derivatives)."""
    n = len(g)
    out, mean_m, mean_inv = np.empty(n), np.empty(n), np.empty(n)
    mstar = peak_m(g, a)
    half = 8 * np.sqrt(mstar) + 16
    order = np.argsort(half)
    lng = np.log(g)
    for chunk in np.array_split(order, max(1, n // 384)):
        if len(chunk) == 0:
            continue
        m0 = np.maximum(1, np.floor(mstar[chunk] - half[chunk])).astype(np.int64)
        width = int(np.ceil(2 * half[chunk].max())) + 2
        m = m0[None, :] + np.arange(width)[:, None]
        mf = m.astype(float)
        lnt = mf * lng[chunk][None, :] - lgamma_int(m) - np.log(mf) - a[chunk][None, :] / mf
        peak = lnt.max(axis=0)
        t = np.exp(lnt - peak)
        tot = t.sum(axis=0)
        out[chunk] = peak + np.log(tot)
        mean_m[chunk] = (t * mf).sum(axis=0) / tot
        mean_inv[chunk] = (t / mf).sum(axis=0) / tot
    return out, mean_m, mean_inv


def kbs_unit(d, sigma, t, rough=False):
    """KBS values at scale 1 in the dataset's quantity, and d ln f/d ln sigma, d ln T."""
    k = 2 * np.pi / d.lam
    g = (k * sigma * d.c) ** 2
    a = d.vxy2 * (k * t) ** 2 / 4
    pre = np.log(np.pi * (t / d.lam) ** 2) + 2 * np.log(d.h) - 2 * np.log(d.c)
    if rough:
        lnq = -a / g - np.log(g)
        ds, dt = 2 * a / g - 2, 2 - 2 * a / g
    else:
        ls, mm, mi = ln_s(g, a)
        lnq = -g + ls
        ds, dt = 2 * mm - 2 * g, 2 - 2 * a * mi
    f = np.exp(pre + lnq) * d.factor
    return f, ds, dt


class Model:
    """A model in the solver's variables x: values f(x) and df/dx."""

    def __init__(self, name, d):
        self.name, self.d = name, d
        lam = d.lam_med
        if name in ("kbs", "kbs+lambert"):
            self.names = ["sigma", "T", "scale"] + (["scale_d"] if name == "kbs+lambert" else [])
            self.lo = [math.log(1e-6 * lam), math.log(1e-5 * lam), 0.0, 0.0][:len(self.names)]
            self.hi = [math.log(10 * lam), math.log(1e3 * lam), np.inf, np.inf][:len(self.names)]
        elif name == "kbs-rough":
            self.names = ["T", "scale"]
            self.lo, self.hi = [math.log(1e-4 * lam), 0.0], [math.log(1e4 * lam), np.inf]
        elif name == "lambert-specular":
            self.names = ["scale", "B", "w"]
            self.w_floor = width_floor(d)
            self.lo = [0.0, 0.0, math.log(self.w_floor)]
            self.hi = [np.inf, np.inf, math.log(10.0)]
        else:
            self.names = ["scale"]
            self.lo, self.hi = [0.0], [np.inf]

    def params(self, x):
        """goniofit's parameters (name -> value) of solver point x."""
        if self.name in ("kbs", "kbs+lambert"):
            p = {"sigma": math.exp(x[0]), "T": math.exp(x[1]), "scale": x[2]}
            if self.name == "kbs+lambert":
                p["scale_d"] = x[3]
            return p
        if self.name == "kbs-rough":
            return {"sigma": self.d.lam_med, "T": math.exp(x[0]), "scale": x[1]}
        if self.name == "lambert-specular":
            return {"scale": x[0], "B": x[1], "w": math.exp(x[2])}
        return {"scale": x[0]}

    def to_x(self, p):
        if self.name in ("kbs", "kbs+lambert"):
            x = [math.log(p["sigma"]), math.log(p["T"]), p["scale"]]
            return x + ([p["scale_d"]] if self.name == "kbs+lambert" else [])
        if self.name == "kbs-rough":
            # the fit holds sigma; at another sigma the same T/sigma is the same model
            return [math.log(p["T"] / p["sigma"] * self.d.lam_med), p["scale"]]
        if self.name == "lambert-specular":
            return [p["scale"], p["B"], math.log(p["w"])]
        return [p["scale"]]

    def columns(self, x):
        """(f, J): values and derivatives with respect to x."""
        d = self.d
        diffuse = d.cos_i * d.factor
        if self.name in ("kbs", "kbs+lambert", "kbs-rough"):
            rough = self.name == "kbs-rough"
            sigma, t = (d.lam_med, math.exp(x[0])) if rough else (math.exp(x[0]), math.exp(x[1]))
            s = x[1] if rough else x[2]
            f1, ds, dt = kbs_unit(d, sigma, t, rough)
            f = s * f1
            cols = [f * dt, f1] if rough else [f * ds, f * dt, f1]
            if self.name == "kbs+lambert":
                f = f + x[3] * diffuse
                cols.append(diffuse)
            return f, np.column_stack(cols)
        if self.name == "lambert-specular":
            s, b, w = x[0], x[1], math.exp(x[2])
            q = d.offset ** 2
            lobe1 = np.exp(-0.5 * q / w ** 2) / (w * math.sqrt(2 * math.pi)) * d.factor
            # d lobe/d ln w = lobe (q/w^2 - 1)
            return (s * diffuse + b * lobe1,
                    np.column_stack([diffuse, lobe1, b * lobe1 * (q / w ** 2 - 1)]))
        return x[0] * diffuse, diffuse[:, None]

    def edge(self, x):
        """Why point x is at an edge of the physical domain, or 'none'."""
        d, p = self.d, self.params(x)
        if "sigma" in p:
            sigma, t = p["sigma"], p["T"]
            if t / sigma < 0.1:
                return "T/sigma"
            if 2 * math.pi * t / d.lam_med < 0.1:
                return "kT"
            if narrow_kbs_lobe(d, sigma, t):
                return "narrow"
            f1, _, _ = kbs_unit(d, sigma, t, self.name == "kbs-rough")
            if p["scale"] * f1.max() <= 1e-9 * np.abs(d.y).max():
                return "scale"
            if self.name != "kbs-rough" and x[0] >= self.hi[0] - 1e-6:
                return "sigma-cap"
            return "none"
        if "w" in p:
            if flank(d, p["w"]) < 3:
                return "w"
            if p["B"] * d.factor.max() / p["w"] <= 1e-9 * np.abs(d.y).max():
                return "B"
        if p["scale"] * (d.cos_i * d.factor).max() <= 1e-9 * np.abs(d.y).max():
            return "scale"
        return "none"


def flank(d, w):
    """Samples on a Gaussian lobe's flank: offset from the mirror in [w/2, 4w]."""
    return int(np.count_nonzero((d.offset >= 0.5 * w) & (d.offset <= 4 * w)))


def width_floor(d):
    """Half the narrowest w with three samples on its flank (the fit's lower bound)."""
    o = np.sort(d.offset[(d.offset > 0) & np.isfinite(d.offset)])
    ok = o[2:] <= 8 * o[:-2]
    return 0.5 * float((0.25 * o[2:][ok]).min())


def narrow_kbs_lobe(d, sigma, t):
    """Fewer than 3 samples on the KBS lobe's flank (e^-8 <= e^{-a/max(g,1)} <= e^-1/8) and
    more beyond it than inside."""
    k = 2 * np.pi / d.lam
    lnf = -(d.vxy2 * (k * t) ** 2 / 4) / np.maximum((k * sigma * d.c) ** 2, 1.0)
    inside = np.count_nonzero(lnf > -0.125)
    fl = np.count_nonzero((lnf <= -0.125) & (lnf >= -8))
    return fl < 3 and len(lnf) - inside - fl > inside


# ---------------------------------------------------------------- residuals, cost


class Problem:
    def __init__(self, model, kind):
        self.m, self.kind, self.d = model, kind, model.d
        self.sw = self.d.sqrt_w(kind)
        y, fl = self.d.y, self.d.floor
        self.den = np.maximum(np.abs(y), fl)
        self.lny = np.log(np.maximum(y, fl))
        self._key, self._cols = None, None

    def r_of_f(self, f):
        if self.kind == "absolute":
            return f - self.d.y
        if self.kind == "relative":
            return (f - self.d.y) / self.den
        return np.log(np.maximum(f, self.d.floor)) - self.lny

    def columns(self, x):
        """The model's (f, J) at x (the last point's kept: the solver asks for both)."""
        key = np.asarray(x, float).tobytes()
        if self._key != key:
            self._key, self._cols = key, self.m.columns(x)
        return self._cols

    def fun(self, x):
        f, _ = self.columns(x)
        r = self.sw * self.r_of_f(f)
        return np.where(np.isfinite(r), r, 1e150)

    def jac(self, x):
        f, j = self.columns(x)
        if self.kind == "absolute":
            drdf = np.ones_like(f)
        elif self.kind == "relative":
            drdf = 1 / self.den
        else:
            drdf = np.where(f > self.d.floor, 1 / np.maximum(f, self.d.floor), 0.0)
        out = (self.sw * drdf)[:, None] * j
        return np.where(np.isfinite(out), out, 0.0)

    def cost(self, x):
        r = self.fun(x)
        return 0.5 * float(r @ r)

    def amplitudes(self, x, amp_idx):
        """x with its amplitudes (indices amp_idx) fitted at the other parameters: by
        non-negative least squares on the residuals as linear in f (absolute, relative),
        or for log residuals by least squares in the amplitudes' logarithms."""
        x = np.array(x, dtype=float)
        x[amp_idx] = 1.0
        f, j = self.m.columns(x)
        cols = j[:, amp_idx]
        good = np.all(np.isfinite(cols), axis=1)
        if self.kind == "log":
            x[amp_idx] = np.exp(self.log_amplitudes(cols[good], good))
            return x
        scale = self.sw / (np.ones_like(f) if self.kind == "absolute" else self.den)
        sol, _ = nnls(cols[good] * scale[good][:, None], (self.d.y * scale)[good])
        x[amp_idx] = np.where(sol > 0, sol, 1e-12 * max(sol.max(), 1e-300))
        return x

    def log_amplitudes(self, cols, good):
        """ln of the amplitudes a >= 0 minimising the log residuals of cols @ a: from each
        column's geometric-mean level (the others e^-7 below it), the best refined."""
        lny, sw = self.lny[good], self.sw[good]
        fl = self.d.floor

        def res(la):
            return sw * (np.log(np.maximum(cols @ np.exp(la), fl)) - lny)

        k = cols.shape[1]
        tries = []
        for i in range(k):
            pos = cols[:, i] > 0
            level = np.average(lny[pos] - np.log(cols[pos, i]), weights=sw[pos] ** 2 + 1e-300) \
                if pos.any() else 0.0
            la = np.full(k, level - 7.0)
            la[i] = level
            tries.append(la)
        best = min(tries, key=lambda la: float(res(la) @ res(la)))
        r = least_squares(res, best, method="trf", max_nfev=60, x_scale="jac")
        return r.x if r.cost <= 0.5 * float(res(best) @ res(best)) else best

def starts(model, prob):
    """At least 20 starts, log-spaced over the domain, amplitudes by NNLS."""
    d, lam = model.d, model.d.lam_med
    out = []
    if model.name in ("kbs", "kbs+lambert"):
        amp = [2, 3][: len(model.names) - 2]
        for so in np.logspace(-3, 0.3, 4):
            for ts in np.logspace(-0.7, 2.3, 5):
                x = [math.log(so * lam), min(math.log(ts * so * lam), model.hi[1] - 1e-3), 1, 1]
                out.append(prob.amplitudes(x[: len(model.names)], amp))
    elif model.name == "kbs-rough":
        for ts in np.logspace(-0.9, 2.5, 20):
            out.append(prob.amplitudes([math.log(ts * lam), 1.0], [1]))
    elif model.name == "lambert-specular":
        for w in np.logspace(math.log10(model.w_floor * 1.01), math.log10(1.5), 20):
            out.append(prob.amplitudes([1.0, 1.0, math.log(w)], [0, 1]))
    else:
        # the levels from the smallest to the largest measured value (as a BRDF)
        top = float(np.abs(d.y).max() / (d.cos_i * d.factor).min())
        out = [[top * f] for f in np.logspace(-7, 1, 20)]
    return out


def solve(prob, x0, tight=False):
    """(cost, x) of a bounded least-squares run from x0: a short exploring one, or
    (tight) one to convergence."""
    lo, hi = np.array(prob.m.lo, float), np.array(prob.m.hi, float)
    span = np.where(np.isfinite(hi - lo), 1e-9 * (hi - lo), 0.0)
    x0 = np.clip(np.asarray(x0, float), lo + span, np.where(np.isfinite(hi), hi - span, np.inf))
    tol = 1e-15 if tight else 1e-12
    r = least_squares(prob.fun, x0, jac=prob.jac, bounds=(lo, hi), method="trf",
                      x_scale="jac", ftol=tol, xtol=tol, gtol=tol,
                      max_nfev=500 if tight else 30)
    return prob.cost(r.x), r.x


def reference(model, prob, seeds=()):
    """(starts, best (cost, x), best inside the domain or None) from starts() and the
    extra `seeds`."""
    runs = [solve(prob, x0) for x0 in [*starts(model, prob), *seeds]]
    # a seed is a point of the model too (the solver moves an amplitude at its bound 0 off
    # it before the first step, which sigma_L weights of 1e27 punish)
    runs += [(prob.cost(np.array(x, float)), np.array(x, float)) for x in seeds]
    n_starts = len(runs) - len(seeds)
    runs = sorted([(c, x) for c, x in runs if math.isfinite(c)], key=lambda r: r[0])
    distinct = []
    for c, x in runs:
        if all(abs(c / c2 - 1) > 1e-6 or np.abs(x - x2).max() > 1e-3 * (1 + np.abs(x2).max())
               for c2, x2 in distinct):
            distinct.append((c, x))
        if len(distinct) == 2:
            break
    polished = [solve(prob, x, tight=True) for _, x in distinct]
    runs += polished
    best = min(runs, key=lambda r: r[0])
    inside = [r for r in runs if model.edge(r[1]) == "none"]
    best_in = min(inside, key=lambda r: r[0]) if inside else None
    if best_in is not None:
        best_in = min([best_in, solve(prob, best_in[1], tight=True)], key=lambda r: r[0])
        if model.edge(best_in[1]) != "none":
            best_in = None
    return n_starts, best, best_in


def nested_seeds(model, best, x_own):
    """Points of `model` that are its special cases' best points (`best`: model name ->
    best x, same residual): kbs+lambert at kbs's (s_d = 0) and at lambert's (s = 0, sigma
    and T of `x_own`); lambert-specular at lambert's (B = 0)."""
    out = []
    if model.name == "kbs+lambert":
        if "kbs" in best:
            out.append([*best["kbs"], 0.0])
        if "lambert" in best:
            out.append([x_own[0], x_own[1], 0.0, best["lambert"][0]])
    if model.name == "lambert-specular" and "lambert" in best:
        out.append([best["lambert"][0], 0.0, max(model.lo[2], math.log(0.1))])
    return out


def nest(binary, path):
    """Rewrite table `path` with the kbs+lambert and lambert-specular rows also taken at and
    polished from their special cases' best points (nested_seeds), where that is lower."""
    lines = open(path).read().splitlines()
    comments = [l for l in lines if l.startswith("#")]
    rows = list(csv.DictReader(l for l in lines if not l.startswith("#")))
    data = {}
    for row in rows:
        if row["model"] not in ("kbs+lambert", "lambert-specular"):
            continue
        if row["dataset"] not in data:
            data[row["dataset"]] = load(binary, row["args"].split())
        d = data[row["dataset"]]
        model = Model(row["model"], d)
        prob = Problem(model, row["residual"])
        best = {}
        for sub in ("kbs", "lambert"):
            r = next((r for r in rows if r["dataset"] == row["dataset"] and r["model"] == sub
                      and r["residual"] == row["residual"]), None)
            if r is None:
                continue
            p = dict(kv.split("=") for kv in r["params_best"].split(";"))
            best[sub] = Model(sub, d).to_x({k: float(v) for k, v in p.items()})
        p = dict(kv.split("=") for kv in row["params_best"].split(";"))
        own = model.to_x({k: float(v) for k, v in p.items()})
        for x0 in nested_seeds(model, best, own):
            x0 = np.array(x0, float)
            c, x = min([(prob.cost(x0), x0), solve(prob, x0, tight=True)], key=lambda r: r[0])
            edge = model.edge(x)
            if c < float(row["cost_best"]):
                row.update(cost_best=f"{c:.12g}", edge_best=edge, params_best=fmt_params(model, x))
            if edge == "none" and c < float(row["cost_inside"]):
                row.update(cost_inside=f"{c:.12g}", params_inside=fmt_params(model, x))
    with open(path, "w") as f:
        f.write("\n".join(comments) + "\n")
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def fmt_params(model, x):
    return ";".join(f"{k}={v:.10g}" for k, v in model.params(x).items())


def main_table(binary, skip=()):
    """The table on standard output; `skip`: datasets left out (header too when any)."""
    w = csv.writer(sys.stdout, lineterminator="\n")
    if not skip:
        print("# Generated by tests/ref/trust_reference.py; see that script for the method.")
        w.writerow(["dataset", "model", "residual", "args", "n", "starts", "cost_best",
                    "edge_best", "params_best", "cost_inside", "params_inside"])
    t0 = time.time()
    for name, args in datasets():
        if name in skip:
            continue
        d = load(binary, args)
        assert abs(d.floor / d.floor_goniofit - 1) < 1e-12, (name, d.floor, d.floor_goniofit)
        bests = {kind: {} for kind in RESIDUALS}
        for mname in MODELS:
            model = Model(mname, d)
            for kind in RESIDUALS:
                prob = Problem(model, kind)
                own = starts(model, prob)[0]
                runs, (cb, xb), inside = reference(model, prob,
                                                   nested_seeds(model, bests[kind], own))
                bests[kind][mname] = xb
                w.writerow([name, mname, kind, " ".join(args), len(d.y), runs, f"{cb:.12g}",
                            model.edge(xb), fmt_params(model, xb),
                            f"{inside[0]:.12g}" if inside else "inf",
                            fmt_params(model, inside[1]) if inside else ""])
                sys.stdout.flush()
        print(f"{name}: {time.time() - t0:.0f} s", file=sys.stderr)


def check(binary, pattern=""):
    """This script's cost at goniofit's fitted point against goniofit's reported cost."""
    worst = 0.0
    for name, args in datasets():
        if pattern not in name:
            continue
        d = load(binary, args)
        for mname in MODELS:
            model = Model(mname, d)
            for kind in RESIDUALS:
                out = subprocess.run([binary, "fit", "--model", mname, "--residual", kind,
                                      "--no-intervals", "--json", *args],
                                     capture_output=True, text=True)
                rep = json.loads(out.stdout)
                p = {k: v["value"] for k, v in rep["params"].items()}
                mine = Problem(model, kind).cost(model.to_x(p))
                rel = abs(mine / rep["cost"] - 1)
                worst = max(worst, rel)
                print(f"{name:24s} {mname:17s} {kind:9s} goniofit {rep['cost']:.12g} "
                      f"here {mine:.12g} rel {rel:.1e}")
    print(f"worst relative difference {worst:.1e}")


if __name__ == "__main__":
    np.seterr(all="ignore")  # overflowing trial points are residuals of 1e150, not errors
    if sys.argv[1] == "--check":
        check(sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else "")
    elif sys.argv[1] == "--nest":
        nest(sys.argv[2], sys.argv[3])
    elif len(sys.argv) > 3 and sys.argv[2] == "--skip":
        main_table(sys.argv[1], sys.argv[3].split(","))
    else:
        main_table(sys.argv[1])
