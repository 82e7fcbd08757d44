"""The boundary at run time: Ctrl-C interrupts a long fit (KeyboardInterrupt, Python's own
SIGINT handler kept), and fits run with the GIL released."""

import csv
import os
import signal
import threading

import numpy as np
import pytest

import goniofit
from conftest import DATA


def long_fit_arrays(repeat):
    rows = list(csv.DictReader(open(DATA / "synthetic" / "kbs_hemisphere.csv")))
    return [np.tile([float(r[k]) for r in rows], repeat) for k in ("theta_i", "theta_r", "phi_r", "L")]


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signals reach the main thread only")
def test_ctrl_c_interrupts_a_long_fit(python_sigint):
    # 864,000 samples in series mode: several seconds of fitting (timeout is the safety net).
    arrays = long_fit_arrays(600)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            goniofit.fit(*arrays, wavelength=1.0, mode="series", timeout=60.0)
    finally:
        timer.cancel()
    # The interpreter's handler is still in place, and the next fit runs normally.
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    small = long_fit_arrays(1)
    assert goniofit.fit(*small, wavelength=1.0).converged


def test_fit_releases_the_gil():
    arrays = long_fit_arrays(100)
    done = threading.Event()
    result = {}

    def work():
        result["r"] = goniofit.fit(*arrays, wavelength=1.0, mode="series", timeout=1.0)
        done.set()

    t = threading.Thread(target=work)
    t.start()
    ticks = 0
    while not done.is_set():
        ticks += 1  # pure Python: runs only while the fit does not hold the GIL
    t.join()
    assert result["r"].n == 144000
    assert ticks > 100_000, ticks
