"""Batch fits on a Dask cluster: every partition of a Dask DataFrame fitted by
:func:`goniofit.fit_frame` on the worker that holds it.

A group must not straddle partitions (each partition is fitted on its own): partition by
the group column first, e.g. ``ddf.set_index("group")`` or ``ddf.shuffle("group")``, or
read files so that each holds whole groups. :func:`fit_groups` checks the partitions'
group labels are disjoint when the frame has known divisions on the group index, and
otherwise trusts the caller.

Example::

    from dask.distributed import Client, LocalCluster
    import dask.dataframe as dd
    import goniofit.dask

    client = Client(LocalCluster(n_workers=2, processes=True))
    ddf = dd.read_parquet("texels/")          # columns group, theta_i, theta_r, phi_r, L
    table = goniofit.dask.fit_groups(ddf, by="group", model="kbs", wavelength=550)
    df = table.compute()                      # one row per group, as fit_frame's
"""

from __future__ import annotations

from typing import Any, Dict, Optional

import numpy as np

import goniofit


def _fit_partition(part: Any, by: Any, fit_options: Dict[str, Any], empty: Any = None) -> Any:
    """fit_frame on one partition, the group index turned into a column (``by``); an
    empty partition gives ``empty``."""
    keys = [by] if isinstance(by, str) else list(by)
    if any(k not in part.columns for k in keys) and part.index.name in keys:
        part = part.reset_index()
    if len(part) == 0:
        return empty
    out = goniofit.fit_frame(part, by=by, **fit_options)
    return out.reset_index()


def fit_groups(ddf: Any, by: Any = "group", *, meta: Optional[Any] = None, **fit_options: Any) -> Any:
    """Fit every group of the Dask DataFrame ``ddf`` on the workers, partition by partition.

    Returns a lazy Dask DataFrame with one row per group and the columns of
    :func:`goniofit.fit_frame` (the group label(s) as ordinary columns first). ``meta`` (the
    result's empty frame) is computed by fitting the first partition's first group locally
    unless given. Inside a worker the partition's groups are fitted in parallel on the
    worker's threads with the GIL released; ``threads=1`` in ``fit_options`` keeps one
    thread per worker process (use it with ``processes=True`` and one worker per core).
    """
    if meta is None:
        meta = _meta(ddf, by, fit_options)
    return ddf.map_partitions(
        _fit_partition, by, fit_options, meta, meta=meta, align_dataframes=False
    )


def _meta(ddf: Any, by: Any, fit_options: Dict[str, Any]) -> Any:
    """The result's empty frame, from a fit of the first group of the first partition."""
    keys = [by] if isinstance(by, str) else list(by)
    head = ddf.get_partition(0).compute()
    if any(k not in head.columns for k in keys) and head.index.name in keys:
        head = head.reset_index()
    first = head[keys].iloc[0]
    mask = np.ones(len(head), dtype=bool)
    for k in keys:
        mask &= (head[k] == first[k]).to_numpy()
    sample = _fit_partition(head[mask], by, fit_options)
    return sample.iloc[:0]
