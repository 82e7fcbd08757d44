"""Batch fits on a Dask cluster: every partition of a Dask DataFrame fitted by
:func:`goniofit.fit_frame` on the worker that holds it.

Each group is fitted whole: when the group is the frame's index with known divisions (e.g.
``ddf.set_index("group")``), each partition already holds whole groups and is fitted as it
is; otherwise :func:`fit_groups` first shuffles the frame by the group column(s)
(``ddf.shuffle(on=by)``), so that a group spread over several partitions (or files) is
still fitted once, on all its rows.

Every partition's table has the same columns, in the same order and with the same types:
the group label(s), the fit statistics, and for every parameter of every model the fit can
choose (the ``model`` option, or the four of ``model="auto"``) and every derived quantity
(``T/sigma``, ``beckmann_alpha``, ``amplitude`` for KBS models) its ``NAME``, ``NAME_stderr``,
``NAME_determined``; a quantity a group's fit does not report is NaN / False there. (A
joint fit over several channels reports per-channel names, ``scale[550nm]``: pass the
result's columns as ``meta`` for those.)

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

from typing import Any, Dict, List, Optional, Tuple

import numpy as np

import goniofit

#: The derived quantities of a model with parameters ``sigma`` and ``T`` (KBS models).
KBS_DERIVED = ("T/sigma", "beckmann_alpha", "amplitude")


def _keys(by: Any) -> List[str]:
    return [by] if isinstance(by, str) else list(by)


def _fit_partition(part: Any, by: Any, fit_options: Dict[str, Any], meta: Any,
                   shuffled: bool = False) -> Any:
    """fit_frame on one partition (the group index turned into a column), conformed to
    ``meta``'s columns and types; an empty partition gives ``meta``. ``shuffled``: the
    partition comes from a shuffle, which does not keep the rows' order: they are put back
    in the order of the frame's index (stable) first."""
    keys = _keys(by)
    if shuffled:
        part = part.sort_index(kind="stable")
    if any(k not in part.columns for k in keys) and part.index.name in keys:
        part = part.reset_index()
    if len(part) == 0:
        return meta
    out = goniofit.fit_frame(part, by=by, **fit_options).reset_index()
    return _conform(out, meta)


def _conform(out: Any, meta: Any) -> Any:
    """``out`` with ``meta``'s columns in its order and types: a quantity no fit of the
    partition reported is NaN (its ``_determined`` False). A column ``meta`` lacks is an
    error naming it."""
    extra = [c for c in out.columns if c not in meta.columns]
    if extra:
        raise ValueError(
            f"goniofit.dask.fit_groups: the fits report {extra}, which the result's columns "
            f"do not have; pass meta= with them (e.g. the columns of fit_frame on one group)"
        )
    for c in meta.columns:
        if c not in out.columns:
            out[c] = False if meta[c].dtype == bool else np.nan
    return out[list(meta.columns)].astype(meta.dtypes.to_dict())


def fit_groups(ddf: Any, by: Any = "group", *, meta: Optional[Any] = None, **fit_options: Any) -> Any:
    """Fit every group of the Dask DataFrame ``ddf`` on the workers, partition by partition.

    Returns a lazy Dask DataFrame with one row per group: the group label(s) as ordinary
    columns first, then the columns described in the module doc (those of
    :func:`goniofit.fit_frame`, for every quantity any group's fit can report). Unless the
    group is ``ddf``'s index with known divisions, the frame is shuffled by the group
    first, so that a group is never split between two fits (its rows are then fitted in
    the order of ``ddf``'s index, which gives fit_frame's bits when the index orders the
    rows, e.g. a RangeIndex), and the result's rows come in no particular order (sort by
    the group). ``meta``: the result's empty frame, built from
    the options unless given. Inside a worker the partition's groups are fitted in parallel
    on the worker's threads with the GIL released; ``threads=1`` in ``fit_options`` keeps
    one thread per worker process (use it with ``processes=True`` and one worker per core).
    """
    keys = _keys(by)
    indexed = [ddf.index.name] == keys
    shuffled = not (indexed and ddf.known_divisions)
    if shuffled:
        if indexed:
            ddf = ddf.reset_index()
        ddf = ddf.shuffle(on=keys)
    if meta is None:
        meta = _meta(ddf, keys, fit_options)
    return ddf.map_partitions(
        _fit_partition, by, fit_options, meta, shuffled, meta=meta, align_dataframes=False
    )


def _quantities(fit_options: Dict[str, Any]) -> List[str]:
    """Every parameter and derived quantity a fit with these options can report, in a fixed
    order: each candidate model's parameters (and the Fresnel factor's), then the KBS
    derived quantities and, for a BRDF with a Lambertian term, its reflectance factor."""
    model = str(fit_options.get("model", "kbs")).lower()
    fresnel = str(fit_options.get("fresnel", "none")).lower()
    # Each candidate as (model, Fresnel factor): auto's own list names its factors.
    if model == "auto":
        candidates = [_model_and_fresnel(c) for c in goniofit.AUTO_CANDIDATES]
    else:
        candidates = [(model, fresnel)]
    models = goniofit.models()
    names: List[str] = []
    kbs = False
    for m, factor in candidates:
        params = [p[0] for p in models.get(m, [])]
        if "sigma" in params and "T" in params:
            kbs = True
            if factor != "none":
                params += ["n", "kappa"] if factor == "conductor" else ["n"]
        names += [p for p in params if p not in names]
    derived = list(KBS_DERIVED) if kbs else []
    # A BRDF's Lambertian term is also reported as a reflectance factor (π times it).
    lambertian = {"lambert", "lambert-specular", "kbs+lambert"} & {m for m, _ in candidates}
    if lambertian and str(fit_options.get("quantity", "radiance")).lower() == "brdf":
        derived.append("reflectance_factor")
    return names + derived


def _model_and_fresnel(candidate: str) -> Tuple[str, str]:
    """``"kbs+lambert --fresnel dielectric --shadowing smith"`` → (``"kbs+lambert"``,
    ``"dielectric"``); a candidate without the factor → (its name, ``"none"``)."""
    words = candidate.split()
    fresnel = words[words.index("--fresnel") + 1] if "--fresnel" in words[:-1] else "none"
    return words[0], fresnel


def _meta(ddf: Any, keys: List[str], fit_options: Dict[str, Any]) -> Any:
    """The result's empty frame: the group columns with ``ddf``'s types, then fit_frame's
    columns for every quantity the options allow (see :func:`_quantities`)."""
    import pandas as pd

    head = ddf._meta
    if any(k not in head.columns for k in keys) and head.index.name in keys:
        head = head.reset_index()
    one = {k: head[k].iloc[:0].tolist() for k in keys}
    cols: Dict[str, Any] = {
        "model": ["kbs"],
        "samples": np.zeros(1, dtype=np.uint64),
        "converged": [True],
        "termination": ["converged"],
        "verdict": ["full"],
        "adequacy": ["adequate"],
        "adequacy_reasons": [""],
        "cost": [0.0],
        "reduced_chi2": [0.0],
        "r2": [0.0],
        "iterations": np.zeros(1, dtype=np.uint64),
        "start_from": ["search"],
    }
    for name in _quantities(fit_options):
        cols[name] = [0.0]
        cols[f"{name}_stderr"] = [0.0]
        cols[f"{name}_determined"] = [True]
    stats = pd.DataFrame(cols).iloc[:0]
    groups = pd.DataFrame(one).astype({k: head[k].dtype for k in keys})
    return pd.concat([groups, stats], axis=1)
