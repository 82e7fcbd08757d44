"""Type stubs of the native module ``goniofit._goniofit`` (the PyO3 binding).

The public functions live in ``goniofit`` (``goniofit/__init__.py``), which converts
array-likes to contiguous float64 arrays and calls these. Conventions: angles in degrees
unless ``radians=True`` (φr = 0 the forward, specular side); σ and T in the unit of the
wavelength; cost = ½ Σ wᵢ rᵢ².
"""

from os import PathLike
from typing import (
    Any,
    Dict,
    List,
    Literal,
    Mapping,
    Optional,
    Sequence,
    Tuple,
    TypedDict,
    Union,
    overload,
)

import numpy as np
import numpy.typing as npt

__version__: str
AUTO_CANDIDATES: List[str]

F64Array = npt.NDArray[np.float64]

class _Intervals(TypedDict, total=False):
    """Profile-likelihood intervals [lo, hi] (None for a side the data does not bound),
    present where the CLI reports one (a single fit with at most 8 free parameters)."""

    interval68: List[Optional[float]]
    interval95: List[Optional[float]]

class ParamReport(_Intervals):
    """One fitted parameter, as in the CLI's JSON ``params``."""

    value: Optional[float]
    stderr: Optional[float]  # None when fixed or not determined by the data
    determined: bool
    fixed: bool
    unit: str  # "λ unit" for sigma and T (the unit of the wavelength), "rad" for w

class DerivedReport(_Intervals):
    """One derived quantity (T/sigma, beckmann_alpha, amplitude, ...), as in the CLI's JSON."""

    value: Optional[float]
    stderr: Optional[float]
    determined: bool
    doc: str

Termination = Literal[
    "ftol", "xtol", "ftolxtol", "predicted", "gtol",  # converged
    "maxiterations", "maxevaluations", "timeout", "interrupted",
    "nonfinitestart", "nonfinitejacobian", "noprogress",
]
Verdict = Literal["full", "rough", "smooth", "partial"]
Fresnel = Literal["none", "dielectric", "conductor", "schlick"]
"""The Fresnel factor on a KBS lobe (``--fresnel``): parameters ``n`` (and ``kappa``)."""
Shadowing = Literal["none", "smith", "smith-correlated"]
"""Smith shadowing–masking on a KBS lobe (``--shadowing``), through T/σ: no parameter."""
AdequacyVerdict = Literal["adequate", "misfit", "noise", "not_computed", "exact"]

class AdequacyReason(TypedDict):
    """One reason of a flagged adequacy verdict (docs/adequacy.md explains each code)."""

    code: Literal[
        "chi2_high", "chi2_low", "runs", "proportional_noise", "grazing_above",
        "grazing_below", "peak_below", "peak_above", "floor", "far_above", "far_below",
    ]
    text: str
    p: Optional[float]  # the test's p-value

class Adequacy(TypedDict):
    """Whether the model describes the data and the weights match the noise, from the
    residuals: the CLI's JSON ``adequacy``. Each test is held to ``alpha / tests``."""

    verdict: AdequacyVerdict
    headline: str
    reasons: List[AdequacyReason]
    alpha: float
    tests: int
    r2: Optional[float]
    reduced_chi2: Optional[float]  # with stated sigma_L only
    chi2_p: Optional[float]
    runs: Optional[Dict[str, Any]]  # runs, expected, sd, signs, scans, p
    spread: Optional[Dict[str, Any]]  # triples, rho, slope, p (absolute residuals only)
    regions: List[Dict[str, Any]]  # region (grazing, peak, far), n, data_above, p

class FitResult:
    """A finished fit (converged or not). Every field comes from the CLI's JSON report."""

    @property
    def model(self) -> str: ...
    @property
    def factors(self) -> str:
        """The lobe's factors as CLI options (``"--fresnel dielectric --shadowing smith"``),
        empty for the paper's model."""
    @property
    def params(self) -> Dict[str, ParamReport]: ...
    @property
    def derived(self) -> Dict[str, DerivedReport]: ...
    @property
    def cost(self) -> float:
        """½ Σ wᵢ rᵢ² at the optimum."""
    @property
    def converged(self) -> bool: ...
    @property
    def termination(self) -> Termination: ...
    @property
    def verdict(self) -> Verdict: ...
    @property
    def adequacy(self) -> Adequacy:
        """Whether the model describes the data (a verdict beside ``converged``)."""
    @property
    def notes(self) -> List[str]: ...
    @property
    def L_fit(self) -> F64Array:
        """Fitted radiance or BRDF per sample."""
    @property
    def residuals(self) -> F64Array:
        """fitted − measured per sample, in the chosen residual form, unweighted."""
    @property
    def std_residuals(self) -> F64Array: ...
    @property
    def n(self) -> int: ...
    def report(self) -> str:
        """The CLI's text report."""
    def to_dict(self) -> Dict[str, Any]:
        """The CLI's JSON report (``goniofit fit --json``), key for key."""
    @overload
    def figures(self, format: Literal["svg"] = "svg") -> Dict[str, str]: ...
    @overload
    def figures(self, format: Literal["png"]) -> Dict[str, bytes]: ...
    @overload
    def figures(self, format: Literal["matplotlib"]) -> Dict[str, Any]:
        """The report's pictures by name (``fit_log``, ``fit_linear``, ``residuals_theta``,
        ``residuals_phi``, ``polar``, ``contour``, ``hemisphere_1`` …): SVG documents,
        PNG bytes, or matplotlib figures (needs matplotlib)."""
    def to_json(self) -> str: ...
    def _repr_html_(self) -> str: ...

def _fit(
    theta_i: F64Array, theta_r: F64Array, phi_r: F64Array, L: F64Array, **options: Any
) -> FitResult: ...
def _fit_codes(
    theta_i: F64Array,
    theta_r: F64Array,
    phi_r: F64Array,
    L: F64Array,
    codes: npt.NDArray[np.int64],
    labels: List[str],
    summary: bool,
    **options: Any,
) -> Union[List[FitResult], Dict[str, Any]]: ...
def evaluate(
    model: str,
    params: Union[Mapping[str, float], Sequence[float]],
    theta_i: F64Array,
    theta_r: F64Array,
    phi_r: F64Array,
    *,
    wavelength: Union[float, F64Array, None] = ...,
    quantity: str = ...,
    mode: str = ...,
    tol: float = ...,
    patch: Optional[Tuple[float, float]] = ...,
    jacobian: bool = ...,
    radians: bool = ...,
    fresnel: Fresnel = ...,
    shadowing: Shadowing = ...,
) -> Union[F64Array, Tuple[F64Array, F64Array]]:
    """The values, or with ``jacobian=True`` (values, J) with J of shape (n, p)."""
def read(
    path: Union[str, PathLike[str]],
    channel: Optional[str] = None,
    *,
    radians: bool = False,
    csv_radians: bool = False,
    columns: Optional[str] = None,
    signed_theta_r: bool = False,
    require_value: bool = False,
    subsample: int = 1,
) -> Dict[str, Any]:
    """The file's columns: theta_i, theta_r, phi_r (degrees unless radians), and where
    present L, weights or sigma_L, wavelength (float arrays) and channel (list of str).
    ``subsample=k`` keeps every k-th θd and φd cell of a MERL table."""
def models() -> Dict[str, List[Tuple[str, str, str]]]:
    """Model name → [(parameter, unit, meaning), ...]."""
def _json_roundtrip(text: str) -> Any: ...

def _design(
    model: str,
    params: Union[Mapping[str, float], Sequence[float]],
    existing: Optional[Tuple[F64Array, F64Array, F64Array]],
    candidates: Optional[Tuple[F64Array, F64Array, F64Array]],
    *,
    noise: float,
    residual: str = "relative",
    wavelength: float = 1.0,
    unit: Optional[str] = None,
    quantity: str = "radiance",
    theta_max: float = 85.0,
    step: float = 2.5,
    in_plane: bool = False,
    n: int = 20,
    target: str = "all",
    dynamic_range: float = 1e4,
    wavelengths: Sequence[float] = ...,
    simulate: int = 0,
    seed: int = 1,
) -> Dict[str, Any]:
    """The engine of ``goniofit.design``: the JSON report as a dict, plus
    ``candidate_table`` (arrays ``theta_i``, ``theta_r``, ``phi_r``, ``value``, ``gain``,
    ``reachable``, ``chosen``)."""
    ...
