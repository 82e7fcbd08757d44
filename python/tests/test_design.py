"""goniofit.design: a closed form, the same design as ``goniofit design``, tables as
DataFrames, the simulation beside the linearised figures, errors in Python's terms."""

import json

import numpy as np
import pandas as pd
import pytest

import goniofit


def scan():
    """In plane, θi 15, 30, 45°, θr −60…60° in 5° steps (negative: the back side)."""
    rows = [(ti, abs(tr), 0.0 if tr >= 0 else 180.0) for ti in (15.0, 30.0, 45.0) for tr in range(-60, 61, 5)]
    return pd.DataFrame(rows, columns=["theta_i", "theta_r", "phi_r"])


ROUGH = dict(sigma=3.0, T=15.0, scale=1.0)


def test_lambert_scale_closed_form():
    # L = s cos θi, 2 % relative noise: every sample gives d ln L / d ln s = 1, so 25
    # samples give a standard error of ln s of 0.02/√25.
    d = goniofit.design("lambert", {"scale": 2.0}, noise=0.02, target="scale", n=25)
    assert d.target["after"] == pytest.approx(0.004, rel=1e-12)
    assert d.target["before"] is None
    assert d.after["scale"]["stderr"] == pytest.approx(0.008, rel=1e-12)


def test_same_design_as_the_cli(cli, tmp_path):
    existing = scan()
    path = tmp_path / "scan.csv"
    existing.to_csv(path, index=False)
    code, out = cli(
        "design", "--model", "kbs", "--params", "sigma=3,T=15,scale=1", "--noise", "0.05",
        "--existing", path, "--in-plane", "--target", "sigma", "--n", "15", "--json",
    )
    assert code == 0
    want = json.loads(out)
    d = goniofit.design("kbs", ROUGH, noise=0.05, existing=existing, in_plane=True, target="sigma", n=15)
    assert isinstance(d.chosen, pd.DataFrame) and list(d.chosen.columns) == ["theta_i", "theta_r", "phi_r"]
    got = d.chosen.to_dict("records")
    assert got == want["chosen"]
    assert d.target["after"] == want["target"]["after"]
    assert d.sentence == want["sentence"] and d.sentence.startswith("σ becomes determined to ±")
    cand = d.candidates
    assert int(cand["chosen"].sum()) == 15 and bool(cand.loc[cand["chosen"], "reachable"].all())
    assert len(cand) == want["candidates"]["count"]


def test_simulation_beside_the_linearised_figures():
    d = goniofit.design("kbs", ROUGH, noise=0.05, existing=scan(), in_plane=True, target="sigma", simulate=60)
    lin, sim = d.target["after"], d.target["simulated"]
    assert d.simulated["used"] >= 58
    assert sim == pytest.approx(lin, rel=0.3), (lin, sim)
    assert np.isfinite(d.simulated["spread"]["T/sigma"]["relative"])


def test_bad_input_is_a_value_error_in_python_terms():
    with pytest.raises(ValueError, match="target="):
        goniofit.design("kbs", ROUGH, noise=0.05, target="colour")
    with pytest.raises(ValueError, match="existing"):
        goniofit.design("kbs", ROUGH, noise=0.05, existing={"theta_i": [10.0]})
    with pytest.raises(ValueError, match="candidates, index 0"):
        goniofit.design("kbs", ROUGH, noise=0.05, candidates=([95.0], [10.0], [0.0]))
    with pytest.raises(ValueError):
        goniofit.design("kbs", ROUGH, noise=float("nan"))
