"""goniofit.dask.fit_groups on a real two-process LocalCluster (loopback only) gives the
serial fit_frame's table bit for bit."""

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
    out = out.sort_index()
    assert list(out.columns) == list(serial.columns)
    for name in serial.columns:
        a, b = serial[name].to_numpy(), out[name].to_numpy()
        if a.dtype.kind == "f":
            assert np.array_equal(a.view(np.uint64), b.astype(np.float64).view(np.uint64)), name
        else:
            assert list(a) == list(b), name
