"""Every numeric keyword of fit and evaluate, over values a careless caller may give: a
ValueError naming the keyword (the CLI refuses the same values with exit 2, through the
same checks), or a result without NaN or inf; never a PanicException (a BaseException
that `except Exception` misses). Group labels that are missing are refused."""

import math
import re
import warnings

import numpy as np
import pytest

import goniofit

VALUES = [float("nan"), float("inf"), float("-inf"), -1.0, 0.0, 1e-300, 1e300, 1e19]

# A small KBS measurement: 3 incidence angles × 12 view angles in the plane.
TI = np.repeat([20.0, 40.0, 60.0], 12)
TR = np.tile(np.linspace(2.0, 80.0, 12), 3)
PR = np.zeros_like(TI)
L = goniofit.evaluate("kbs", {"sigma": 0.3, "T": 2.0, "scale": 1.0}, TI, TR, PR, wavelength=1.0)

# keyword → the options it needs beside it.
FIT_KEYWORDS = {
    "wavelength": {},
    "tol": {},
    "patch": {},
    "floor": {"residual": "log"},
    "timeout": {},
    "threads": {},
    "f_scale": {"loss": "soft_l1"},
    "max_iter": {},
}


def _no_non_finite_words(text):
    words = re.findall(r"[A-Za-z]+", text)
    bad = [w for w in words if w in ("NaN", "nan", "inf", "Inf", "infinity")]
    assert not bad, text


@pytest.mark.parametrize("keyword", sorted(FIT_KEYWORDS))
def test_fit_keywords_refuse_or_report_finite_numbers(keyword):
    for v in VALUES:
        value = (v, v) if keyword == "patch" else v
        if keyword in ("threads", "max_iter") and math.isfinite(v) and v == int(v) and v < 1e18:
            value = int(v)
        opts = dict(model="kbs", wavelength=1.0, intervals=False, **FIT_KEYWORDS[keyword])
        opts[keyword] = value
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                result = goniofit.fit(TI, TR, PR, L, **opts)
        except (ValueError, TypeError, OverflowError, TimeoutError) as e:
            if isinstance(e, ValueError) and keyword not in ("max_iter",):
                assert keyword in str(e) or "length" in str(e), f"{keyword}={v}: {e}"
            continue
        _no_non_finite_words(result.report())


def test_a_huge_timeout_is_a_value_error_not_a_panic():
    for t in (1e300, 1e19, float("inf"), float("nan"), -1.0):
        with pytest.raises(ValueError, match="timeout"):
            goniofit.fit(TI, TR, PR, L, model="kbs", wavelength=1.0, timeout=t)


def test_f_scale_and_floor_whose_cost_would_overflow_are_refused():
    with pytest.raises(ValueError, match="f_scale 1e160"):
        goniofit.fit(TI, TR, PR, L, model="kbs", wavelength=1.0, loss="soft_l1", f_scale=1e160)
    for f in (float("nan"), -1.0):
        with pytest.raises(ValueError, match="floor"):
            goniofit.fit(TI, TR, PR, L, model="kbs", wavelength=1.0, residual="log", floor=f)
    with pytest.raises(ValueError, match="not below the largest measured value"):
        goniofit.fit(TI, TR, PR, L, model="kbs", wavelength=1.0, residual="log", floor=1e19)


def test_threads_beyond_the_machine_are_capped_with_a_warning():
    with pytest.warns(RuntimeWarning, match="cores"):
        r = goniofit.fit(TI, TR, PR, L, model="kbs", wavelength=1.0, threads=100000,
                         intervals=False)
    assert r.converged


def test_evaluate_refuses_what_the_cli_refuses(cli, tmp_path):
    kbs = {"sigma": 0.3, "T": 2.0, "scale": 1.0}
    cases = [
        ("kbs", kbs, dict(wavelength=1e-300), ["--wavelength", "1e-300"]),
        ("kbs", kbs, dict(wavelength=1.0, patch=(1e-300, 1e-300)),
         ["--wavelength", "1", "--patch", "1e-300,1e-300"]),
        ("lambert-specular", {"scale": 1.0, "B": 1.0, "w": 1e-300}, {}, []),
        ("lambert-specular", {"scale": 1.0, "B": 1e308, "w": 0.1}, {}, []),
    ]
    # The scan with its specular samples (θr = θi), where a narrow lobe peaks.
    ti, tr = np.append(TI, [20.0, 40.0]), np.append(TR, [20.0, 40.0])
    pr = np.zeros_like(ti)
    angles = tmp_path / "angles.csv"
    angles.write_text("theta_i,theta_r,phi_r\n" + "".join(
        f"{a},{b},{c}\n" for a, b, c in zip(ti, tr, pr)))
    for model, params, opts, flags in cases:
        with pytest.raises(ValueError):
            goniofit.evaluate(model, params, ti, tr, pr, **opts)
        text = ",".join(f"{k}={v!r}" for k, v in params.items())
        code, _ = cli("eval", "--model", model, "--params", text, *flags, angles)
        assert code == 2, (model, params, opts)


def test_missing_group_labels_are_refused_as_fit_frame_does():
    group = ["a"] * 18 + [float("nan")] * 18
    with pytest.raises(ValueError, match="missing group label"):
        goniofit.fit(TI, TR, PR, L, model="kbs", wavelength=1.0, group=group)
    with pytest.raises(ValueError, match="missing group label"):
        goniofit.fit(TI, TR, PR, L, model="kbs", wavelength=1.0, group=["a"] * 35 + [None])
