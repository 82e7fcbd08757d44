"""goniofit: fit physical light-scattering models to gonioreflectometer data.

The Rust engine of the ``goniofit`` command line, called from Python: the same readers'
checks, the same fit (starting values, Levenberg-Marquardt, uncertainties, the verdict on
what the data determines) and the same reports, byte for byte.

Conventions (the project's docs/conventions.md):

- angles in **degrees** unless ``radians=True``; θ from the surface normal,
  ``theta_i`` in [0, 90), ``theta_r`` in [0, 90]; ``phi_r`` is the view azimuth with
  **φr = 0 the forward, specular side** (180 = back towards the source);
- ``L`` is a radiance (``quantity="radiance"``, eq. 28 of the paper) or a BRDF
  (``quantity="brdf"``, L / cos θi, in sr⁻¹); a Lambertian reflectance factor is BRDF × π;
- σ (``sigma``) and T (the correlation length) are in the unit of ``wavelength``
  (e.g. nm for ``wavelength=550``); the specular width ``w`` is in radians;
- cost = ½ Σ wᵢ rᵢ² (as MINPACK and scipy), weights ``weights`` or 1/``sigma_L``².

Example::

    import goniofit
    d = goniofit.read("data/cornell/garnet_red.astm", channel="550nm")
    r = goniofit.fit(d["theta_i"], d["theta_r"], d["phi_r"], d["L"], model="kbs+lambert",
                     quantity="brdf", residual="log", wavelength=d["wavelength"],
                     wavelength_unit=d["wavelength_unit"])
    print(r.report())
"""

from __future__ import annotations

import dataclasses
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Union

import numpy as np

from . import _goniofit
from ._goniofit import FitResult, models, read

__all__ = [
    "Design",
    "FitResult",
    "design",
    "evaluate",
    "fit",
    "fit_frame",
    "fit_many",
    "models",
    "read",
    "AUTO_CANDIDATES",
    "__version__",
]



def __dir__() -> List[str]:
    """The public names only (not the modules and typing names this module imports)."""
    return sorted(__all__ + ["dask"])


__version__: str = _goniofit.__version__
AUTO_CANDIDATES: List[str] = list(_goniofit.AUTO_CANDIDATES)

ArrayLike = Union[Sequence[float], np.ndarray]

# Per-sample options: arrays aligned with theta_i (wavelength may also be one number).
_PER_SAMPLE = ("weights", "sigma_L")


def _f64(name: str, x: Any) -> np.ndarray:
    """``x`` as a contiguous, aligned 1-D float64 array (buffers unpickled on a Dask worker
    can be misaligned views)."""
    try:
        a = np.require(np.asarray(x, dtype=np.float64), requirements=["C", "A"])
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name}: not an array of numbers ({e})") from None
    if a.ndim != 1:
        raise ValueError(f"{name}: expected a 1-D array, got shape {a.shape}")
    return a


def _labels(name: str, x: Any, n: int) -> List[str]:
    labels = [str(v) for v in (x.tolist() if hasattr(x, "tolist") else list(x))]
    if len(labels) != n:
        raise ValueError(
            f"{name} has {len(labels)} elements, theta_i has {n}: give one label per sample"
        )
    return labels


def _options(n: int, opts: Dict[str, Any]) -> Dict[str, Any]:
    """Fit options with per-sample arrays converted for the engine."""
    out = dict(opts)
    for key in _PER_SAMPLE:
        if out.get(key) is not None:
            out[key] = _f64(key, out[key])
    w = out.get("wavelength")
    if w is not None and not isinstance(w, (int, float, str, np.number)):
        out["wavelength"] = _f64("wavelength", w)
    if out.get("channel") is not None:
        out["channel"] = _labels("channel", out["channel"], n)
    return out


def _is_missing(v: Any) -> bool:
    """Whether a label is missing: None, NaN, NaT or pandas' NA (which is not equal to
    itself, or cannot say whether it is)."""
    if v is None:
        return True
    try:
        return bool(v != v)
    except (TypeError, ValueError):
        return True


def _factorize(group: Any, n: int):
    """Group codes in first-appearance order and the original label of each group; a
    missing label is an error, as in :func:`fit_frame`."""
    values = group.tolist() if hasattr(group, "tolist") else list(group)
    if len(values) != n:
        raise ValueError(
            f"group has {len(values)} elements, theta_i has {n}: give one label per sample"
        )
    index: Dict[Any, int] = {}
    codes = np.empty(n, dtype=np.int64)
    for i, v in enumerate(values):
        if _is_missing(v):
            raise ValueError(f"fit: missing group label (group[{i}])")
        codes[i] = index.setdefault(v, len(index))
    return codes, list(index)


def fit(
    theta_i: ArrayLike,
    theta_r: ArrayLike,
    phi_r: ArrayLike,
    L: ArrayLike,
    *,
    model: str = "kbs",
    wavelength: Union[float, ArrayLike, None] = None,
    quantity: str = "radiance",
    residual: str = "absolute",
    weights: Optional[ArrayLike] = None,
    sigma_L: Optional[ArrayLike] = None,
    loss: str = "linear",
    f_scale: float = 1.0,
    init: Union[Mapping[str, float], str, None] = None,
    fix: Union[Mapping[str, float], str, None] = None,
    channel: Optional[Sequence[Any]] = None,
    group: Optional[Sequence[Any]] = None,
    **options: Any,
) -> Union[FitResult, Dict[Any, FitResult]]:
    """Fit a light-scattering model to one measurement, as ``goniofit fit`` does.

    Parameters
    ----------
    theta_i, theta_r, phi_r : array-like of float, one value per sample
        Incidence angle, view angle (from the normal) and view azimuth (φr = 0 the
        forward, specular side); degrees unless ``radians=True``.
    L : array-like of float
        The measured radiance (``quantity="radiance"``) or BRDF (``"brdf"``, sr⁻¹).
    model : str
        ``kbs``, ``kbs-smooth``, ``kbs-rough``, ``kbs+lambert``, ``lambert``,
        ``lambert-specular``, or ``auto`` (fits lambert, lambert-specular, kbs, kbs+lambert
        and keeps the lowest BIC).
    wavelength : float, str or array-like, optional
        λ, the unit of σ and T (required for KBS models); one number, one per sample, or
        as the CLI's ``--wavelength`` a number with its unit (``"633nm"``, ``"0.633um"``).
        ``wavelength_unit="nm"`` (an option) names the unit of numbers; the report then
        gives σ and T in it.
    quantity : {"radiance", "brdf"}
    residual : {"absolute", "relative", "log"}
        f − y, (f − y)/|y|, or ln f − ln y (values below ``floor`` raised to it).
    weights, sigma_L : array-like, optional
        Weights w > 0, or standard uncertainties of L (weights 1/σ²); not both.
    loss : {"linear", "soft_l1", "huber", "cauchy", "arctan"}
        The robust loss on the weighted residuals f = √w r, as scipy's ``least_squares``
        and the CLI's ``--loss``: the fit minimises ½ Σ C² ρ(f²/C²) with C = ``f_scale``.
        ``"linear"`` (default) is plain least squares; the others weaken gross outliers.
    f_scale : float
        The loss scale C > 0, in the unit of the weighted residual (with
        ``residual="relative"`` and no weights, 0.03 = 3 %); unused with ``"linear"``.
    init, fix : dict name → value, or "name=value,..." text, optional
        Starting values; parameters held fixed (``scale[550nm]`` names one channel).
    channel : sequence of labels, optional
        A channel label per sample: a joint fit with shared σ, T and per-channel scales
        (as ``--channel all``).
    group : sequence of labels, optional
        A group label per sample: every group fitted on its own, in parallel (as
        ``--by-group``); returns a dict label → FitResult in first-appearance order. A
        missing label (None, NaN) is a ValueError, as in :func:`fit_frame`.
    **options
        ``radians`` (bool), ``signed_theta_r`` (bool: θr < 0 is the back side),
        ``fresnel`` (``none``/``dielectric``/``conductor``/``schlick``: the Fresnel factor
        on the KBS lobe, parameters ``n`` and with ``conductor`` ``kappa``), ``shadowing``
        (``none``/``smith``/``smith-correlated``: Smith's shadowing–masking through T/σ),
        ``mode``
        (``auto``/``series``/``smooth``/``rough``, the KBS evaluation), ``tol`` (its
        relative accuracy, default 1e-10), ``patch`` ((X, Y) half-sizes in the unit of λ:
        the coherent term), ``floor`` (for relative/log residuals; default 1e-6 × max |L|),
        ``max_iter`` (default 500), ``timeout`` (seconds, 0 < t ≤ 1e9), ``reduce``
        (default True: refit the reduced problem when only combinations are determined),
        ``threads`` (at most the machine's cores: more run on its cores, with a
        ``RuntimeWarning``),
        ``wavelength_unit``, ``absolute_sigma`` (standard errors from ``sigma_L`` as stated,
        as scipy's ``curve_fit(absolute_sigma=True)``), ``intervals`` (profile-likelihood
        intervals: default True for one fit, as the CLI's single-file report, False with
        ``group``; ``params[name]["interval68"]``/``["interval95"]`` hold them).

    Returns
    -------
    FitResult
        Also when the fit did not converge (``converged`` is False and ``termination``
        says why), as the CLI prints a report and exits 3.

    Raises
    ------
    ValueError
        Bad input, with its location (``theta_i[17]: theta_i = 95° is outside [0, 90°)``),
        or inconsistent options.
    KeyboardInterrupt
        Ctrl-C (a notebook's interrupt) while fitting: the fit stops after its current step.
    TimeoutError
        ``timeout`` passed before the first model evaluation on the whole data finished
        (nothing was fitted); a later time limit returns the result with ``termination``
        ``"timeout"``.
    """
    ti = _f64("theta_i", theta_i)
    opts = _options(
        len(ti),
        dict(
            options,
            model=model,
            wavelength=wavelength,
            quantity=quantity,
            residual=residual,
            weights=weights,
            sigma_L=sigma_L,
            loss=loss,
            f_scale=f_scale,
            init=init,
            fix=fix,
            channel=channel,
        ),
    )
    tr, pr, y = _f64("theta_r", theta_r), _f64("phi_r", phi_r), _f64("L", L)
    if group is None:
        return _goniofit._fit(ti, tr, pr, y, **opts)
    codes, labels = _factorize(group, len(ti))
    results = _goniofit._fit_codes(
        ti, tr, pr, y, codes, [str(x) for x in labels], False, **opts
    )
    return dict(zip(labels, results))


def fit_many(scans: Iterable[Mapping[str, Any]], **fit_options: Any) -> List[FitResult]:
    """Fit many measurements in parallel (GIL released), one ``FitResult`` per scan.

    Every scan is a mapping with ``theta_i``, ``theta_r``, ``phi_r``, ``L`` and optionally
    ``weights`` or ``sigma_L`` and ``wavelength`` (a number or an array); ``fit_options``
    are those of :func:`fit` and apply to every scan.
    """
    scans = list(scans)
    if not scans:
        return []
    keys = ("theta_i", "theta_r", "phi_r", "L")
    cols = {k: [] for k in keys + _PER_SAMPLE + ("wavelength",)}
    sizes = []
    for k, scan in enumerate(scans):
        arrays = {key: _f64(f"scans[{k}].{key}", scan[key]) for key in keys}
        m = len(arrays["theta_i"])
        sizes.append(m)
        for key in keys:
            cols[key].append(arrays[key])
        for key in _PER_SAMPLE + ("wavelength",):
            v = scan.get(key)
            if v is not None:
                v = np.broadcast_to(np.asarray(v, dtype=np.float64), (m,))
            cols[key].append(v)
    per_sample = {}
    for key in _PER_SAMPLE + ("wavelength",):
        given = [v is not None for v in cols[key]]
        if any(given) and not all(given):
            raise ValueError(f"{key}: given for some scans but not all")
        if all(given):
            per_sample[key] = np.concatenate(cols[key])
    if "wavelength" in per_sample and fit_options.get("wavelength") is not None:
        raise ValueError("wavelength: given both per scan and as an option")
    codes = np.repeat(np.arange(len(scans), dtype=np.int64), sizes)
    columns = [np.concatenate(cols[key]) for key in keys]
    opts = _options(len(codes), dict(fit_options, **per_sample))
    labels = [f"scans[{k}]" for k in range(len(scans))]
    return _goniofit._fit_codes(*columns, codes, labels, False, **opts)


def fit_frame(
    df: Any,
    by: Union[str, Sequence[str]] = "group",
    *,
    columns: Optional[Mapping[str, str]] = None,
    **fit_options: Any,
) -> Any:
    """Fit every group of a pandas DataFrame on its own, in parallel; one row per group.

    ``df`` has columns ``theta_i``, ``theta_r``, ``phi_r``, ``L`` (``columns`` maps other
    names: ``{"L": "brdf"}``) and optionally ``weights``/``weight``, ``sigma_L``,
    ``wavelength``; ``by`` names the group column(s). ``fit_options`` are those of
    :func:`fit`.

    The result (indexed by the group labels, sorted as ``df.groupby(by)`` sorts them) has
    columns ``model``, ``samples``, ``converged``, ``termination``, ``verdict``, ``adequacy``
    (``adequate``, ``misfit``, ``noise`` or ``not_computed``), ``adequacy_reasons`` (the
    reason codes, comma-separated), ``cost``, ``reduced_chi2``, ``r2``, ``iterations``,
    ``start_from`` (``search``, or ``neighbour``) and for every parameter and derived
    quantity ``NAME``, ``NAME_stderr`` (NaN when not determined or fixed) and
    ``NAME_determined``.
    Deterministic: the same frame gives the same bits on any machine and thread count.

    ``warm_start=True`` (the CLI's ``--warm-start``) starts each group's fit at the
    optimum of the group before it in that order (a neighbouring texel), keeping it when
    it converges to an optimum that describes the data as well as the neighbour's did, and
    searching as usual otherwise: much faster on many similar small fits. The groups then
    run in a few chains per thread, so the results depend on the thread count to the
    solver's tolerance (the same optima, not the same bits).
    """
    import pandas as pd

    roles = {"theta_i": "theta_i", "theta_r": "theta_r", "phi_r": "phi_r", "L": "L"}
    roles.update(columns or {})
    missing = [c for c in roles.values() if c not in df.columns]
    if missing:
        raise ValueError(f"fit_frame: no column {missing[0]!r} (columns: {list(df.columns)})")
    keys = [by] if isinstance(by, str) else list(by)
    for k in keys:
        if k not in df.columns:
            raise ValueError(f"fit_frame: no group column {k!r}")
    if len(keys) == 1:
        codes, uniques = pd.factorize(df[keys[0]], sort=True)
        index = pd.Index(uniques, name=keys[0])
    else:
        mi = pd.MultiIndex.from_frame(df[keys])
        codes, uniques = pd.factorize(mi, sort=True)
        index = pd.MultiIndex.from_tuples(list(uniques), names=keys)
    if len(codes) and codes.min() < 0:
        raise ValueError(f"fit_frame: missing group label in {keys} (row {int(np.argmin(codes))})")
    opts = dict(fit_options)
    for key, name in (("weights", "weights"), ("weights", "weight"), ("sigma_L", "sigma_L"),
                      ("wavelength", "wavelength")):
        if name in df.columns and opts.get(key) is None:
            opts[key] = df[name].to_numpy()
    opts = _options(len(df), opts)
    arrays = [_f64(role, df[roles[role]].to_numpy()) for role in ("theta_i", "theta_r", "phi_r", "L")]
    labels = [str(u) for u in index]
    codes = np.require(codes, dtype=np.int64, requirements=["C", "A"])
    cols = _goniofit._fit_codes(*arrays, codes, labels, True, **opts)
    return pd.DataFrame(cols, index=index)


def evaluate(
    model: str,
    params: Union[Mapping[str, float], Sequence[float]],
    theta_i: ArrayLike,
    theta_r: ArrayLike,
    phi_r: ArrayLike,
    *,
    wavelength: Union[float, ArrayLike] = 1.0,
    quantity: str = "radiance",
    mode: str = "auto",
    tol: float = 1e-10,
    patch: Optional[Sequence[float]] = None,
    jacobian: bool = False,
    radians: bool = False,
    fresnel: str = "none",
    shadowing: str = "none",
):
    """Evaluate a model at sample angles, as ``goniofit eval`` does.

    ``params``: a dict name → value (``models()`` lists the names) or values in the model's
    order; σ, T in the unit of ``wavelength``. Angles in degrees unless ``radians=True``.
    Returns the values (radiance, or BRDF with ``quantity="brdf"``), and with
    ``jacobian=True`` the pair (values, J) with J[i, j] = ∂value_i/∂p_j (shape n × p). The
    KBS sum meets relative accuracy ``tol`` in ``mode="auto"`` and ``"series"``.
    ``fresnel`` and ``shadowing`` put the CLI's ``--fresnel``/``--shadowing`` factors on a
    KBS lobe (``n``, ``kappa`` then follow ``scale`` among the parameters).
    """
    ti = _f64("theta_i", theta_i)
    w = wavelength
    if not isinstance(w, (int, float, np.number)):
        w = _f64("wavelength", w)
    return _goniofit.evaluate(
        model,
        params,
        ti,
        _f64("theta_r", theta_r),
        _f64("phi_r", phi_r),
        wavelength=w,
        quantity=quantity,
        mode=mode,
        tol=tol,
        patch=None if patch is None else tuple(float(x) for x in patch),
        jacobian=jacobian,
        radians=radians,
        fresnel=fresnel,
        shadowing=shadowing,
    )


Angles = Union[Mapping[str, ArrayLike], Sequence[ArrayLike]]


def _angle_arrays(name: str, x: Optional[Angles]):
    """(theta_i, theta_r, phi_r) float64 arrays from a DataFrame/mapping with those columns
    or a sequence of three arrays (degrees); None stays None."""
    if x is None:
        return None
    if hasattr(x, "keys"):
        missing = [k for k in ("theta_i", "theta_r", "phi_r") if k not in x.keys()]
        if missing:
            raise ValueError(f"{name}: no column {', '.join(missing)} (needs theta_i, theta_r, phi_r in degrees)")
        cols = [x["theta_i"], x["theta_r"], x["phi_r"]]
    else:
        cols = list(x)
        if len(cols) != 3:
            raise ValueError(f"{name}: expected three arrays theta_i, theta_r, phi_r (degrees)")
    return tuple(_f64(f"{name}.{k}", c) for k, c in zip(("theta_i", "theta_r", "phi_r"), cols))


def _table(columns: Dict[str, Any]):
    """A pandas DataFrame of the columns when pandas is installed, else the dict of arrays."""
    try:
        import pandas as pd
    except ImportError:
        return {k: np.asarray(v) for k, v in columns.items()}
    return pd.DataFrame(columns)


@dataclasses.dataclass
class Design:
    """A design: the proposed geometries and the standard errors they give.

    ``chosen``: the proposed geometries (``theta_i``, ``theta_r``, ``phi_r`` in degrees, in
    the order chosen), a pandas DataFrame when pandas is installed, else a dict of numpy
    arrays; ``candidates`` likewise, every candidate with its predicted ``value``, its
    ``gain`` (what it alone would add), ``reachable`` and ``chosen``. ``before`` and
    ``after``: every parameter and derived quantity, name → dict (``value``, ``stderr``,
    ``relative``, ``determined``), linearised, with the measured geometries alone and with
    the proposed ones added; ``simulated``: the scatter of fits of simulated measurements
    (``simulate=N``), else None; ``target``: its name, criterion and relative standard
    error before, after and simulated; ``alternatives``: the design at each other
    wavelength offered; ``sentence``: what to do, in words. ``to_dict()`` gives the CLI's
    JSON report.
    """

    chosen: Any
    candidates: Any
    before: Dict[str, Dict[str, Any]]
    after: Dict[str, Dict[str, Any]]
    simulated: Optional[Dict[str, Any]]
    target: Dict[str, Any]
    alternatives: List[Dict[str, Any]]
    sentence: str
    report: Dict[str, Any] = dataclasses.field(repr=False)

    def to_dict(self) -> Dict[str, Any]:
        """The design as ``goniofit design --json`` prints it."""
        return dict(self.report)


def design(
    model: str,
    params: Union[Mapping[str, float], Sequence[float]],
    *,
    noise: float,
    residual: str = "relative",
    wavelength: float = 1.0,
    wavelength_unit: Optional[str] = None,
    quantity: str = "radiance",
    existing: Optional[Angles] = None,
    candidates: Optional[Angles] = None,
    theta_max: float = 85.0,
    step: float = 2.5,
    in_plane: bool = False,
    n: int = 20,
    target: str = "all",
    dynamic_range: float = 1e4,
    wavelengths: Optional[Sequence[float]] = None,
    simulate: int = 0,
    seed: int = 1,
) -> Design:
    """The next ``n`` geometries to measure, as ``goniofit design`` chooses them.

    ``model`` at ``params`` (σ, T in the unit of ``wavelength``), the noise of one sample
    (``residual="relative"``: ``noise`` a fraction of L; ``"log"``: in ln L;
    ``"absolute"``: in the unit of L), the geometries already measured (``existing``: a
    DataFrame or mapping with ``theta_i``, ``theta_r``, ``phi_r`` in degrees, or three
    arrays) and the candidates (``candidates``, the same; default a grid up to
    ``theta_max`` in steps of ``step``, ``in_plane`` for φr = 0 and 180° only). ``target``:
    a parameter (``"sigma"``), a derived quantity (``"T/sigma"``) or ``"all"``
    (D-optimal). ``wavelengths``: other wavelengths to plan for (same unit).
    ``simulate=N`` fits N simulated measurements at the measured and proposed geometries.
    Bad input raises ``ValueError``.
    """
    raw = _goniofit._design(
        model,
        params,
        _angle_arrays("existing", existing),
        _angle_arrays("candidates", candidates),
        noise=float(noise),
        residual=residual,
        wavelength=float(wavelength),
        unit=wavelength_unit,
        quantity=quantity,
        theta_max=float(theta_max),
        step=float(step),
        in_plane=bool(in_plane),
        n=int(n),
        target=target,
        dynamic_range=float(dynamic_range),
        wavelengths=[float(w) for w in (wavelengths or [])],
        simulate=int(simulate),
        seed=int(seed),
    )
    table = raw.pop("candidate_table")
    chosen = raw["chosen"]
    return Design(
        chosen=_table({k: np.array([c[k] for c in chosen], dtype=float) for k in ("theta_i", "theta_r", "phi_r")}),
        candidates=_table(table),
        before=raw["before"],
        after=raw["after"],
        simulated=raw["simulated"],
        target=raw["target"],
        alternatives=raw["alternatives"],
        sentence=raw["sentence"],
        report=raw,
    )
