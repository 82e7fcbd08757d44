"""Hostile parameter values at the Python boundary: every evaluation ends (a correlation
length of 1e17 λ, a fit held at T = 1e20), every parameter of every model at NaN, ±inf,
-1, 0, 1e-300, 1e300, 1e19 either raises ValueError or returns finite numbers, and Ctrl-C
interrupts a long evaluation (KeyboardInterrupt)."""

import csv
import os
import signal
import threading
import time

import numpy as np
import pytest

import goniofit
from conftest import DATA

HOSTILE = [float("nan"), float("inf"), float("-inf"), -1.0, 0.0, 1e-300, 1e300, 1e19]

#: A usable value of each parameter (by name), for those not under test.
USABLE = {"sigma": 0.3, "T": 2.0}


def hemisphere(repeat=1):
    rows = list(csv.DictReader(open(DATA / "synthetic" / "kbs_hemisphere.csv")))
    return [np.tile([float(r[k]) for r in rows], repeat) for k in ("theta_i", "theta_r", "phi_r", "L")]


def test_a_huge_correlation_length_evaluates_to_the_flat_limit():
    # Off the specular direction Q < e^-999999 at T = 1e17 λ: the radiance is 0, at once.
    t0 = time.monotonic()
    for t in (1e16, 1e17, 1e19, 1e100):
        v = goniofit.evaluate("kbs", {"sigma": 0.3, "T": t, "scale": 1.0}, [9.0], [2.5], [-180.0])
        assert v.tolist() == [0.0], t
    assert time.monotonic() - t0 < 10.0


def test_a_fit_held_at_a_huge_correlation_length_ends():
    ti, tr, pr, L = hemisphere()
    t0 = time.monotonic()
    r = goniofit.fit(ti, tr, pr, L, wavelength=1.0, fix={"T": 1e20}, timeout=30.0)
    assert time.monotonic() - t0 < 10.0
    assert np.isfinite(r.cost)
    assert not r.converged  # nothing off the specular direction can be fitted at T = 1e20 λ


def test_every_parameter_of_every_model_at_hostile_values():
    ti, tr, pr, _ = hemisphere()
    bad = []
    for model, specs in goniofit.models().items():
        names = [s[0] for s in specs]
        for name in names:
            for v in HOSTILE:
                params = {n: (v if n == name else USABLE.get(n, 0.5)) for n in names}
                t0 = time.monotonic()
                try:
                    out = goniofit.evaluate(model, params, ti, tr, pr, wavelength=1.0, jacobian=True)
                except ValueError:
                    continue
                finally:
                    if time.monotonic() - t0 > 10.0:
                        bad.append(f"{model} {name}={v}: over 10 s")
                values, jac = out
                if not (np.isfinite(values).all() and np.isfinite(jac).all()):
                    bad.append(f"{model} {name}={v}: non-finite values or Jacobian")
    assert not bad, "\n".join(bad)


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signals reach the main thread only")
def test_ctrl_c_interrupts_a_long_evaluation(python_sigint):
    # 864,000 samples of a rough surface summed term by term (mode="series", g ~ 1e5):
    # ~10 s of work; Ctrl-C after 0.5 s ends it within one block of 4096 samples.
    ti, tr, pr, _ = hemisphere(600)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    t0 = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            goniofit.evaluate("kbs", {"sigma": 25.0, "T": 60.0, "scale": 1.0}, ti, tr, pr,
                              wavelength=1.0, mode="series")
    finally:
        timer.cancel()
    assert time.monotonic() - t0 < 5.0
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    small = goniofit.evaluate("kbs", {"sigma": 0.3, "T": 2.0, "scale": 1.0}, [30.0], [30.0], [0.0])
    assert np.isfinite(small).all()
