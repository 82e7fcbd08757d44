"""goniofit.dask.fit_groups on a real two-process LocalCluster (loopback only) gives the
serial fit_frame's table bit for bit, whatever regime a partition's groups are in, with an
empty first partition, and with groups split across partitions."""

import numpy as np
import pandas as pd
import pytest

import goniofit
import goniofit.dask
from texels import texel_frame

import dask.dataframe as dd  # noqa: E402  (a missing Dask is a failure, not a skip)
import dask.distributed as distributed  # noqa: E402


def test_dask_fit_groups_matches_fit_frame_bit_for_bit():
    df = texel_frame(2000)
    serial = goniofit.fit_frame(df, by="group", wavelength=1.0)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        with distributed.Client(cluster):
            # Whole groups per partition: the frame is sorted by group, cut at group edges.
            ddf = dd.from_pandas(df.set_index("group"), npartitions=8, sort=True)
            table = goniofit.dask.fit_groups(ddf, by="group", wavelength=1.0, threads=1)
            out = table.compute().set_index("group")
    assert len(out) == 2000
    same_table(serial, out)


def rough_texel(group, sigma=6.0, corr=40.0, seed=3):
    """One texel of a rough surface (σ = 6 λ: the fit's verdict is rough, and it reports
    the rough regime's lobe amplitude, a column the smooth-ish texels do not have)."""
    base = texel_frame(1)
    rng = np.random.default_rng(seed)
    L = goniofit.evaluate("kbs", {"sigma": sigma, "T": corr, "scale": 1.0},
                          base["theta_i"], base["theta_r"], base["phi_r"])
    base["L"] = L * (1.0 + 0.01 * rng.standard_normal(L.shape))
    base["group"] = group
    return base


def same_table(serial, out):
    """``out`` (the Dask result, indexed by group) has every column of ``serial`` with the
    same bits, and its other columns are NaN / False (quantities no fit reported)."""
    out = out.sort_index()
    assert list(out.index) == list(serial.index)
    for name in serial.columns:
        a, b = serial[name].to_numpy(), out[name].to_numpy()
        if a.dtype.kind == "f":
            assert np.array_equal(a.view(np.uint64), b.astype(np.float64).view(np.uint64)), name
        else:
            assert list(a) == list(b), name
    for name in set(out.columns) - set(serial.columns):
        col = out[name].to_numpy()
        assert (col == False).all() if col.dtype == bool else np.isnan(col).all(), name  # noqa: E712


def test_dask_conforms_partitions_whatever_regime_their_groups_are_in():
    # The rough group is in the last partition: its amplitude columns, which the first
    # partition's fits do not have, are in every partition's table (NaN elsewhere).
    df = pd.concat([texel_frame(6), rough_texel(6)], ignore_index=True)
    serial = goniofit.fit_frame(df, by="group", wavelength=1.0)
    assert "amplitude" in serial.columns and serial["verdict"].iloc[-1] == "rough"
    ddf = dd.from_pandas(df.set_index("group"), npartitions=3, sort=True)
    out = goniofit.dask.fit_groups(ddf, by="group", wavelength=1.0, threads=1)
    same_table(serial, out.compute(scheduler="sync").set_index("group"))


def test_dask_fits_a_frame_whose_first_partition_is_empty():
    df = texel_frame(4)
    serial = goniofit.fit_frame(df, by="group", wavelength=1.0)
    # Known divisions on the group index (no shuffle), the first one below every group.
    ddf = dd.from_pandas(df.set_index("group"), npartitions=2, sort=True)
    ddf = ddf.repartition(divisions=[-10, -5, 0, 2, 3], force=True)
    assert len(ddf.get_partition(0).compute()) == 0
    out = goniofit.dask.fit_groups(ddf, by="group", wavelength=1.0, threads=1)
    same_table(serial, out.compute(scheduler="sync").set_index("group"))


def test_dask_fits_a_group_split_across_partitions_once():
    # Rows in group order cut into 7 partitions that split groups: after the shuffle by
    # group each group is fitted once on all its rows, as fit_frame fits it.
    df = texel_frame(10)
    serial = goniofit.fit_frame(df, by="group", wavelength=1.0)
    ddf = dd.from_pandas(df, npartitions=7, sort=False)
    out = goniofit.dask.fit_groups(ddf, by="group", wavelength=1.0, threads=1)
    table = out.compute(scheduler="sync").set_index("group")
    assert len(table) == 10
    same_table(serial, table)


def test_dask_reports_the_reflectance_factor_of_a_brdf_and_every_model_s_columns():
    """A BRDF fitted with a Lambertian term also reports π·scale (the reflectance factor):
    the result's columns announce it, and it equals π times the fitted scale."""
    df = pd.read_csv(goniofit_data("curet/curet.csv"), comment="#")
    df = df[df["group"].isin([2, 3, 7])]
    ddf = dd.from_pandas(df, npartitions=2)
    for model in ("lambert", "lambert-specular", "auto"):
        extra = {"wavelength": 0.55} if model == "auto" else {}
        out = goniofit.dask.fit_groups(ddf, by="group", model=model, quantity="brdf",
                                       residual="log", **extra).compute(scheduler="synchronous")
        assert sorted(out["group"]) == [2, 3, 7]
        # The Lambertian term is `scale` alone, `scale_d` beside a KBS lobe.
        kbs = out["model"].str.startswith("kbs+lambert")
        plain = out["model"].isin(["lambert", "lambert-specular"])
        assert (kbs | plain).all(), (model, list(out["model"]))
        term = np.where(kbs, out.get("scale_d", np.nan), out["scale"])
        np.testing.assert_allclose(out["reflectance_factor"], np.pi * term, rtol=1e-14)


def goniofit_data(name):
    import os
    return os.path.join(os.path.dirname(__file__), "..", "..", "data", name)
