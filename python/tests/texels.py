"""A deterministic per-texel capture: ``n`` small KBS scans (36 samples each: θi 15° and
45°, θr 0–80° in 10° steps, in-plane forward and back, plus two out-of-plane azimuths)
of a surface whose σ and T vary from texel to texel, with 1 % multiplicative noise from a
seeded generator. Used by the fit_frame, Dask and benchmark code."""

import numpy as np

import goniofit


def texel_frame(n, seed=14):
    import pandas as pd

    ti, tr, pr = np.meshgrid([15.0, 45.0], np.arange(0.0, 81.0, 10.0), [0.0, 60.0, 120.0, 180.0],
                             indexing="ij")
    ti, tr, pr = ti.ravel(), tr.ravel(), pr.ravel()
    rng = np.random.default_rng(seed)
    sigma = rng.uniform(0.15, 0.35, n)
    corr = rng.uniform(1.5, 4.0, n)
    m = len(ti)
    L = np.concatenate([
        goniofit.evaluate("kbs", {"sigma": sigma[k], "T": corr[k], "scale": 1.0}, ti, tr, pr)
        for k in range(n)
    ])
    L *= 1.0 + 0.01 * rng.standard_normal(L.shape)
    return pd.DataFrame({
        "group": np.repeat(np.arange(n), m),
        "theta_i": np.tile(ti, n),
        "theta_r": np.tile(tr, n),
        "phi_r": np.tile(pr, n),
        "L": L,
    })


def write_csv(df, path):
    """The frame as a CSV the CLI reads, every float written exactly (repr)."""
    with open(path, "w") as f:
        f.write("group,theta_i,theta_r,phi_r,L\n")
        for g, a, b, c, l in df[["group", "theta_i", "theta_r", "phi_r", "L"]].itertuples(index=False):
            f.write(f"{g},{a!r},{b!r},{c!r},{l!r}\n")
