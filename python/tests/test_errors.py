"""Bad input raises ValueError with its location, as the CLI's messages locate it; a
missing file is FileNotFoundError; unknown options are TypeError. Never a panic."""

import numpy as np
import pytest

import goniofit
from conftest import DATA

TI, TR, PR, L = [10.0, 20.0, 30.0, 40.0], [5.0] * 4, [0.0] * 4, [1.0, 2.0, 3.0, 4.0]


def test_angle_out_of_domain_names_array_and_index():
    with pytest.raises(ValueError, match=r"^theta_i\[2\]: theta_i = 95° is outside \[0, 90°\)"):
        goniofit.fit(TI[:2] + [95.0] + TI[3:], TR, PR, L, model="lambert")
    with pytest.raises(ValueError, match=r"^theta_r\[0\]: .*signed_theta_r=True"):
        goniofit.fit(TI, [-5.0] + TR[1:], PR, L, model="lambert")


def test_non_finite_and_non_positive_values():
    with pytest.raises(ValueError, match=r"^L\[1\]: NaN is not a finite number"):
        goniofit.fit(TI, TR, PR, [1.0, float("nan"), 3.0, 4.0], model="lambert")
    with pytest.raises(ValueError, match=r"^sigma_L\[3\]: 0 must be finite and positive"):
        goniofit.fit(TI, TR, PR, L, model="lambert", sigma_L=[1.0, 1.0, 1.0, 0.0])
    with pytest.raises(ValueError, match="both weights and sigma_L"):
        goniofit.fit(TI, TR, PR, L, model="lambert", sigma_L=[1.0] * 4, weights=[1.0] * 4)


def test_shapes_models_and_options():
    with pytest.raises(ValueError, match="theta_r has 3 elements, theta_i has 4"):
        goniofit.fit(TI, TR[:3], PR, L, model="lambert")
    with pytest.raises(ValueError, match="unknown model 'kbz'"):
        goniofit.fit(TI, TR, PR, L, model="kbz")
    with pytest.raises(ValueError, match="KBS models need a wavelength"):
        goniofit.fit(TI, TR, PR, L, model="kbs")
    with pytest.raises(ValueError, match="residual 'squared'"):
        goniofit.fit(TI, TR, PR, L, model="lambert", residual="squared")
    with pytest.raises(TypeError, match="unexpected keyword argument 'tolerance'"):
        goniofit.fit(TI, TR, PR, L, model="lambert", tolerance=1e-3)
    with pytest.raises(ValueError, match="parameter scale_x: not a parameter of this fit"):
        goniofit.fit(TI, TR, PR, L, model="lambert", fix={"scale_x": 1.0})
    with pytest.raises(ValueError, match="parameter T: missing"):
        goniofit.evaluate("kbs", {"sigma": 1.0, "scale": 1.0}, TI, TR, PR)


def test_values_the_fit_cannot_square_name_array_and_index():
    # The CLI's check_magnitudes: |L| beyond 1e100 would overflow the cost ½Σw r².
    with pytest.raises(ValueError, match=r"^L\[2\]: value 1e150 is beyond ±1e100"):
        goniofit.fit(TI, TR, PR, [1.0, 2.0, 1e150, 4.0], model="lambert")
    with pytest.raises(ValueError, match=r"^weights\[0\]: weight 1e-120 .* outside what the fit"):
        goniofit.fit(TI, TR, PR, L, model="lambert", weights=[1e-120, 1.0, 1.0, 1.0])


def test_loss_and_f_scale_are_checked():
    with pytest.raises(ValueError, match="loss 'hubber': expected one of linear, soft_l1, huber"):
        goniofit.fit(TI, TR, PR, L, model="lambert", loss="hubber")
    with pytest.raises(ValueError, match="f_scale -1"):
        goniofit.fit(TI, TR, PR, L, model="lambert", f_scale=-1.0)


def test_read_errors_carry_file_line_column(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("theta_i,theta_r,phi_r,L\n10,5,0,1\n20,5,abc,2\n")
    with pytest.raises(ValueError, match=r"bad\.csv:3: column phi_r: 'abc' is not a number"):
        goniofit.read(bad)
    with pytest.raises(FileNotFoundError, match="no_such.csv"):
        goniofit.read(tmp_path / "no_such.csv")
    with pytest.raises(ValueError, match="channel"):
        goniofit.read(DATA / "cornell" / "garnet_red.astm", channel="551nm")


def test_read_layouts():
    ptfe = goniofit.read(DATA / "nist-ptfe" / "PTFE.data.csv")
    assert len(ptfe["theta_i"]) == 7296 and "L" in ptfe
    d = goniofit.read(DATA / "synthetic" / "kbs_hemisphere.csv")
    assert set(d) == {"theta_i", "theta_r", "phi_r", "L", "sigma_L"}
    assert d["theta_i"][0] == pytest.approx(9.0, rel=1e-15)
    # phi_r in goniofit's convention: -180 in the file is the back side, 180.
    assert abs(d["phi_r"][0]) == pytest.approx(180.0, rel=1e-15)


def test_messages_speak_python_and_the_namespace_is_clean():
    with pytest.raises(ValueError, match=r"^KBS models need a wavelength: give wavelength=") as e:
        goniofit.fit(TI, TR, PR, L, model="kbs")
    assert "--" not in str(e.value) and "arrays:" not in str(e.value)
    public = [n for n in dir(goniofit) if not n.startswith("_")]
    assert sorted(public) == sorted([n for n in goniofit.__all__ if not n.startswith("_")] + ["dask"])
    assert "np" not in dir(goniofit) and "List" not in dir(goniofit)
