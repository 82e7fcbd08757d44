"""The Fresnel and shadowing factors through the Python API: ``evaluate`` against the
textbook Fresnel reflectance (numpy, written here from r_s and r_p), and a fit of a file
``goniofit synth --fresnel dielectric --shadowing smith`` wrote, which must recover the
index n within its reported standard error and name the factors as the CLI does."""

import numpy as np
import pytest

import goniofit


def textbook_ratio(theta_deg, n):
    """R(θ)/R(0) of a dielectric of index n: Snell's law and the amplitudes r_s, r_p."""
    ti = np.radians(theta_deg)
    tt = np.arcsin(np.sin(ti) / n)
    rs = (np.cos(ti) - n * np.cos(tt)) / (np.cos(ti) + n * np.cos(tt))
    rp = (n * np.cos(ti) - np.cos(tt)) / (n * np.cos(ti) + np.cos(tt))
    r0 = ((n - 1) / (n + 1)) ** 2
    return (rs**2 + rp**2) / 2 / r0


def test_evaluate_with_a_dielectric_factor_is_the_textbook_ratio_at_the_mirror():
    # In the mirror direction (θr = θi, φr = 0) the local incidence angle is θi.
    theta = np.array([0.0, 20.0, 45.0, 56.31, 70.0, 80.0, 85.0])
    zeros = np.zeros_like(theta)
    p = {"sigma": 0.3, "T": 2.0, "scale": 1.0}
    plain = goniofit.evaluate("kbs", p, theta, theta, zeros)
    for n in (1.33, 1.5, 2.4):
        ext = goniofit.evaluate("kbs", dict(p, n=n), theta, theta, zeros, fresnel="dielectric")
        np.testing.assert_allclose(ext / plain, textbook_ratio(theta, n), rtol=1e-12)


def test_shadowing_only_lowers_the_lobe_and_vanishes_at_normal_incidence():
    ti = np.array([0.0, 30.0, 60.0, 80.0])
    p = {"sigma": 0.3, "T": 1.5, "scale": 1.0}
    plain = goniofit.evaluate("kbs", p, ti, ti, np.zeros(4))
    g = goniofit.evaluate("kbs", p, ti, ti, np.zeros(4), shadowing="smith") / plain
    assert g[0] == pytest.approx(1.0, abs=1e-15)
    assert np.all(np.diff(g) < 0) and g[-1] < 0.9


def test_a_fit_of_a_synthetic_dielectric_file_recovers_n(cli, tmp_path):
    csv = tmp_path / "glossy.csv"
    code, _ = cli("synth", "--model", "kbs", "--params", "sigma=0.3,T=2.0,scale=1.0,n=1.6",
                  "--fresnel", "dielectric", "--shadowing", "smith", "--layout", "hemisphere",
                  "--grid", "5x18x24", "--noise", "0.01", "--seed", "7", "--write-sigma",
                  "-o", csv)
    assert code == 0
    d = goniofit.read(csv)
    r = goniofit.fit(d["theta_i"], d["theta_r"], d["phi_r"], d["L"], model="kbs",
                     wavelength=1.0, sigma_L=d["sigma_L"], fresnel="dielectric",
                     shadowing="smith", intervals=False)
    assert r.converged
    assert r.factors == "--fresnel dielectric --shadowing smith"
    n = r.params["n"]
    assert n["determined"] and n["stderr"] > 0
    assert abs(n["value"] - 1.6) <= 3 * n["stderr"], n
    assert "--fresnel dielectric --shadowing smith" in r.to_dict()["command"]
    # The CLI fits the same file to the same index.
    code, out = cli("fit", "--model", "kbs", "--fresnel", "dielectric", "--shadowing",
                    "smith", "--no-intervals", "--json", csv)
    import json
    assert code == 0
    assert json.loads(out)["params"]["n"]["value"] == pytest.approx(n["value"], rel=1e-6)
    # fit_frame's columns keep the index `n` apart from the sample count `samples`.
    import pandas as pd
    df = pd.DataFrame({k: d[k] for k in ("theta_i", "theta_r", "phi_r", "L", "sigma_L")})
    row = goniofit.fit_frame(df.assign(g=0), by="g", model="kbs", wavelength=1.0,
                             fresnel="dielectric", shadowing="smith", intervals=False).iloc[0]
    assert row["samples"] == len(df) == r.n
    assert row["n"] == pytest.approx(n["value"], rel=1e-12)


def test_an_unknown_factor_is_a_value_error():
    with pytest.raises(ValueError, match="fresnel 'glass'"):
        goniofit.fit([10.0], [10.0], [0.0], [1.0], model="kbs", wavelength=1.0, fresnel="glass")
    with pytest.raises(ValueError, match="shadowing 'torrance'"):
        goniofit.evaluate("kbs", [0.3, 2.0, 1.0], [10.0], [10.0], [0.0], shadowing="torrance")
