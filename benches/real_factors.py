#!/usr/bin/env python3
"""The Fresnel factor and Smith shadowing on the bundled real data.

Fits every Cornell channel (4 paints x 31 channels, `--channel all --by-group`), every
CUReT surface (61, `--by-group --wavelength 550`) and every channel of the 7 RGL files
(`--channel all --by-group`) with `--model kbs+lambert`, and again with `--model
kbs+lambert --fresnel dielectric --shadowing smith`; BRDF values, log residuals (as the
README fits them), so R² is that of ln L. Prints per dataset: fits (converged of each
model), median and worst R² without and with the factors, the median BIC change
(extended − plain; negative prefers the factors) and how many fits prefer them by more
than 10, how many extended fits end at a higher cost than the plain one (the factors do
not nest the plain lobe: F → 1 only as n → ∞ and G → 1 only as T/σ → ∞, so a plain fit
at T/σ → 0, where Smith's G shadows everything, has no extended counterpart), how many
extended fits the adequacy tests still call a misfit, how many end with n at its domain
edge 1 (n < 1.01: a grazing rise steeper than any index gives), and the fitted index n:
median and range over the fits, and for each Cornell paint at 550 nm the profile-likelihood
95 % interval from a single fit.

Usage: nice python3 benches/real_factors.py [BINARY] > docs/real_factors.txt
(BINARY defaults to $CARGO_TARGET_DIR or target, /release/goniofit; build it first with
`cargo build --release`). Runs with --threads 1.
"""
import glob
import json
import os
import statistics
import subprocess
import sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
FACTORS = ["--fresnel", "dielectric", "--shadowing", "smith"]
COMMON = ["fit", "--model", "kbs+lambert", "--residual", "log", "--json", "--threads", "1"]


def datasets():
    """(name, extra arguments, files) of each dataset row."""
    rows = []
    for f in sorted(glob.glob(os.path.join(ROOT, "data/cornell/*.astm"))):
        name = "Cornell " + os.path.basename(f)[:-5]
        rows.append((name, ["--quantity", "brdf", "--channel", "all", "--by-group"], [f]))
    rows.append(("CUReT (61 surfaces)", ["--wavelength", "550", "--by-group"],
                 [os.path.join(ROOT, "data/curet/curet.csv")]))
    rgl = sorted(glob.glob(os.path.join(ROOT, "data/rgl-epfl/*_rgb.bsdf")))
    rows.append((f"RGL ({len(rgl)} files x r,g,b)", ["--channel", "all", "--by-group"], rgl))
    return rows


def run(binary, args):
    out = subprocess.run([binary] + args, capture_output=True, text=True, cwd=ROOT)
    if out.returncode not in (0, 3):
        sys.exit(f"{' '.join(args)}: exit {out.returncode}\n{out.stderr}")
    return json.loads(out.stdout)


def fits(binary, extra, files, factors):
    """{fit name: fit report} of one model on one dataset."""
    out = {}
    for f in files:
        d = run(binary, COMMON + factors + extra + [f])
        for fit in d.get("fits", [d]):
            out[fit["input"]] = fit
    return out


def index_interval(binary, f):
    """n and its 95 % profile interval at 550 nm from a single fit of file f."""
    d = run(binary, COMMON + FACTORS + ["--quantity", "brdf", "--channel", "550nm", f])
    n = d["params"]["n"]
    iv = n.get("interval95")
    text = "[open]" if iv is None or None in iv else f"[{iv[0]:.2f}, {iv[1]:.2f}]"
    return f"{n['value']:.2f} {text}"


def row(name, plain, ext, interval):
    keys = sorted(set(plain) & set(ext))
    r2p = [plain[k]["r2"] for k in keys]
    r2e = [ext[k]["r2"] for k in keys]
    dbic = [ext[k]["bic"] - plain[k]["bic"] for k in keys]
    worse = sum(ext[k]["cost"] > plain[k]["cost"] * (1 + 1e-6) for k in keys)
    ns = [ext[k]["params"]["n"]["value"] for k in keys]
    conv = (sum(plain[k]["converged"] for k in keys), sum(ext[k]["converged"] for k in keys))
    misfit = sum(ext[k]["adequacy"]["verdict"] == "misfit" for k in keys)
    edge = sum(n < 1.01 for n in ns)
    n_text = f"{statistics.median(ns):.2f} ({min(ns):.2f}-{max(ns):.2f})"
    if interval:
        n_text += f"; 550 nm: {interval}"
    return (f"{name:<22} {len(keys):>4} {conv[0]:>3}/{conv[1]:<3} "
            f"{statistics.median(r2p):>6.3f} {min(r2p):>6.3f} "
            f"{statistics.median(r2e):>6.3f} {min(r2e):>6.3f} "
            f"{statistics.median(dbic):>9.1f} {sum(d < -10 for d in dbic):>4} {worse:>5} "
            f"{misfit:>6} {edge:>4}  {n_text}")


def main():
    default = os.path.join(os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")),
                           "release", "goniofit")
    binary = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else default)
    print("kbs+lambert without and with --fresnel dielectric --shadowing smith; BRDF, log "
          "residuals; R² of ln L")
    print("conv: converged fits plain/extended; ΔBIC: extended − plain (median), "
          "<-10: fits preferring the factors; worse: extended fits at a higher cost than plain;\n"
          "misfit: extended fits the adequacy tests reject; n→1: extended fits with n < 1.01")
    print(f"{'dataset':<22} {'fits':>4} {'conv':>7} {'R² plain med/worst':>13} "
          f"{'R² ext med/worst':>13} {'ΔBIC':>9} {'<-10':>4} {'worse':>5} {'misfit':>6} {'n→1':>4}"
          "  n median (range)")
    for name, extra, files in datasets():
        plain = fits(binary, extra, files, [])
        ext = fits(binary, extra, files, FACTORS)
        interval = index_interval(binary, files[0]) if name.startswith("Cornell") else None
        print(row(name, plain, ext, interval), flush=True)


if __name__ == "__main__":
    main()
