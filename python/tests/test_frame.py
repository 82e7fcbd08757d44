"""fit_frame: one row per group, the same numbers as ``goniofit fit --by-group --json`` on
the same samples written to a CSV."""

import numpy as np
import pandas as pd

import goniofit
from texels import texel_frame, write_csv


def test_fit_frame_matches_cli_by_group(cli_json, tmp_path):
    df = texel_frame(40)
    path = tmp_path / "texels.csv"
    write_csv(df, path)
    cli = cli_json("--wavelength", "1", "--by-group", path)
    table = goniofit.fit_frame(df, by="group", wavelength=1.0)
    assert list(table.index) == list(range(40)) and table.index.name == "group"
    assert cli["datasets"] == 40
    for k, c in enumerate(cli["fits"]):
        row = table.loc[k]
        assert c["input"].endswith(f"[{k}]")
        assert row["cost"] == c["cost"]
        assert row["converged"] == c["converged"] and row["verdict"] == c["verdict"]
        assert row["termination"] == c["termination"] and row["samples"] == c["n"] == 72
        assert row["adequacy"] == c["adequacy"]["verdict"]
        assert row["adequacy_reasons"] == ",".join(x["code"] for x in c["adequacy"]["reasons"])
        for name, p in {**c["params"], **c["derived"]}.items():
            assert row[name] == p["value"]
            se = p["stderr"]
            assert (np.isnan(row[f"{name}_stderr"]) if se is None else row[f"{name}_stderr"] == se)
            assert row[f"{name}_determined"] == p["determined"]


def test_fit_frame_columns_and_group_labels():
    df = texel_frame(3)
    df["group"] = df["group"].map({0: "c", 1: "a", 2: "b"})
    df = df.rename(columns={"L": "brdf"})
    table = goniofit.fit_frame(df, by="group", columns={"L": "brdf"}, wavelength=1.0)
    assert list(table.index) == ["a", "b", "c"]
    # Each row is the fit of that group's samples alone.
    sub = df[df["group"] == "b"]
    one = goniofit.fit(sub["theta_i"], sub["theta_r"], sub["phi_r"], sub["brdf"], wavelength=1.0)
    assert table.loc["b", "cost"] == one.cost
    assert table.loc["b", "sigma"] == one.params["sigma"]["value"]
    assert {"model", "samples", "converged", "termination", "verdict", "adequacy", "adequacy_reasons",
            "cost", "reduced_chi2", "r2",
            "iterations", "sigma", "sigma_stderr", "sigma_determined", "T/sigma"} <= set(table.columns)


def test_fit_frame_warm_start_ends_at_the_searched_optima_as_the_cli_does(cli_json, tmp_path):
    df = texel_frame(40)
    path = tmp_path / "texels.csv"
    write_csv(df, path)
    cold = goniofit.fit_frame(df, by="group", wavelength=1.0, threads=2)
    warm = goniofit.fit_frame(df, by="group", wavelength=1.0, threads=2, warm_start=True)
    cli = cli_json("--wavelength", "1", "--by-group", "--warm-start", "--threads", "2", path)
    assert set(cold["start_from"]) == {"search"}
    assert (warm["start_from"] == "neighbour").sum() >= 20
    assert (warm["converged"] == cold["converged"]).all()
    assert (warm["cost"] <= cold["cost"] * (1 + 1e-6)).all()
    assert np.allclose(warm["T/sigma"], cold["T/sigma"], rtol=1e-4)
    for k, c in enumerate(cli["fits"]):
        assert c["start_from"] == warm.loc[k, "start_from"]
        assert c["cost"] == warm.loc[k, "cost"]
