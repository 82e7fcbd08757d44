"""Arrays in, the CLI's numbers out: goniofit.fit on the bundled data against
``goniofit fit --json`` on the same files (the same engine, so the numbers agree to 1e-12;
in practice they are identical), and the report pieces key for key."""

import csv
import math

import numpy as np
import pytest

import goniofit
from conftest import DATA

# Fields that describe the run, not the fit: wall times, where the samples came from, and
# the command line (the CLI's argv; the Python report writes the equivalent CLI options).
RUN_FIELDS = {"seconds", "init_seconds", "start_seconds", "interval_seconds", "input", "command"}
# Where the setting's choices came from: a file and flags for the CLI, arrays and keywords
# for Python (the values themselves, floor, weights, residual, quantity, units, agree).
PROVENANCE = {".setting.input", ".setting.wavelength.source", ".setting.quantity_source",
              ".setting.channel"}
# The replay's settings of how a file is read, which arrays do not have, and those a file
# can state instead (null in the CLI's settings then).
READING = {"channel", "radians", "signed_theta_r", "columns", "subsample", "by_group"}
STATED = {"quantity", "wavelength_unit"}


def assert_same_report(cli, py, rtol=1e-12, path=""):
    """Every key of the CLI's JSON is in the Python report and vice versa; numbers agree
    to ``rtol`` (relative), everything else exactly. The replay's settings agree but for
    how a file is read and what the CLI left to the file to state."""
    if isinstance(cli, dict):
        assert sorted(cli) == sorted(py), f"{path}: keys {sorted(cli)} vs {sorted(py)}"
        for k in cli:
            if path == "" and k in RUN_FIELDS:
                continue
            if path == ".replay.settings" and (k in READING or k in STATED and cli[k] is None):
                continue
            if f"{path}.{k}" in PROVENANCE:
                continue
            assert_same_report(cli[k], py[k], rtol, f"{path}.{k}")
    elif isinstance(cli, list):
        assert len(cli) == len(py), path
        for i, (a, b) in enumerate(zip(cli, py)):
            assert_same_report(a, b, rtol, f"{path}[{i}]")
    elif isinstance(cli, float) or isinstance(py, float):
        assert math.isclose(cli, py, rel_tol=rtol, abs_tol=0.0), f"{path}: {cli} vs {py}"
    else:
        assert cli == py, f"{path}: {cli!r} vs {py!r}"


def read_csv(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(line for line in f if not line.startswith("#"))]
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def test_garnet_matches_cli_json(cli_json):
    # The README's first command, from arrays (radians: exactly the file's values).
    cli = cli_json("--model", "kbs+lambert", "--quantity", "brdf", "--channel", "550nm",
                   "--residual", "log", DATA / "cornell" / "garnet_red.astm")
    d = goniofit.read(DATA / "cornell" / "garnet_red.astm", channel="550nm", radians=True)
    r = goniofit.fit(d["theta_i"], d["theta_r"], d["phi_r"], d["L"], model="kbs+lambert",
                     quantity="brdf", residual="log", wavelength=d["wavelength"],
                     wavelength_unit=d["wavelength_unit"], channel=d["channel"], radians=True)
    assert_same_report(cli, r.to_dict())
    assert r.verdict == "rough" and r.converged and r.termination == cli["termination"]
    assert r.cost == cli["cost"]
    assert r.params["scale_d"]["value"] == cli["params"]["scale_d"]["value"]
    assert r.derived["T/sigma"]["stderr"] == cli["derived"]["T/sigma"]["stderr"]
    # The profile-likelihood intervals of a single fit, as the CLI's (σ bounded loosely).
    lo, hi = r.params["sigma"]["interval95"]
    assert lo < r.params["sigma"]["value"] < hi
    assert r.params["sigma"]["interval95"] == cli["params"]["sigma"]["interval95"]
    assert r.L_fit.shape == (1439,) and r.residuals.shape == (1439,)


def test_cli_and_python_ask_for_equal_settings_and_report_alike(cli_json):
    # Every setting both front ends have, away from its default, as flags and as keywords.
    path = DATA / "synthetic" / "kbs_hemisphere.csv"
    cli = cli_json("--model", "kbs", "--quantity", "radiance", "--wavelength", "1nm",
                   "--residual", "relative", "--loss", "huber", "--f-scale", "0.5",
                   "--floor", "1e-9", "--init", "sigma=0.3,T=2", "--fix", "scale=1",
                   "--mode", "series", "--tol", "1e-9", "--patch", "50,60", "--max-iter", "300",
                   "--timeout", "600", "--no-reduce", "--absolute-sigma", "--no-intervals",
                   "--threads", "1", "--warm-start", path)
    d = read_csv(path)
    r = goniofit.fit(d["theta_i"], d["theta_r"], d["phi_r"], d["L"], sigma_L=d["sigma_L"],
                     model="kbs", quantity="radiance", wavelength="1nm", residual="relative",
                     loss="huber", f_scale=0.5, floor=1e-9, init={"sigma": 0.3, "T": 2},
                     fix="scale=1", mode="series", tol=1e-9, patch=(50, 60), max_iter=300,
                     timeout=600, reduce=False, absolute_sigma=True, intervals=False,
                     threads=1, warm_start=True)
    settings = r.to_dict()["replay"]["settings"]
    assert settings == cli["replay"]["settings"]
    assert settings["wavelength_unit"] == "nm" and settings["patch"] == [50.0, 60.0]
    assert_same_report(cli, r.to_dict())
    # The report's command asks for the same settings.
    assert r.to_dict()["command"].startswith(
        "goniofit fit --model kbs --quantity radiance --residual relative --mode series "
        "--tol 1e-9 --max-iter 300 --loss huber --f-scale 0.5 --wavelength 1nm "
        "--init sigma=0.3,T=2 --fix scale=1 --patch 50,60 --floor 0.000000001 --timeout 600 "
        "--threads 1 --no-reduce --absolute-sigma --no-intervals --warm-start (arrays)")


def test_adequacy_flags_the_garnet_fresnel_rise_as_the_cli_does(cli_json):
    cli = cli_json("--model", "kbs+lambert", "--quantity", "brdf", "--channel", "550nm",
                   "--residual", "log", "--no-intervals", DATA / "cornell" / "garnet_red.astm")
    d = goniofit.read(DATA / "cornell" / "garnet_red.astm", channel="550nm", radians=True)
    r = goniofit.fit(d["theta_i"], d["theta_r"], d["phi_r"], d["L"], model="kbs+lambert",
                     quantity="brdf", residual="log", wavelength=d["wavelength"],
                     wavelength_unit=d["wavelength_unit"], radians=True, intervals=False)
    a = r.adequacy
    assert a == cli["adequacy"]
    assert a["verdict"] == "misfit" and a["alpha"] == 0.001
    assert "grazing_above" in [x["code"] for x in a["reasons"]]
    assert all(0.0 <= x["p"] < a["alpha"] / a["tests"] for x in a["reasons"])
    assert r.converged  # a misfit is information, not a failure


def test_csv_with_uncertainties_matches_cli_json(cli_json):
    path = DATA / "synthetic" / "kbs_hemisphere.csv"
    cli = cli_json("--wavelength", "1", path)
    d = read_csv(path)
    r = goniofit.fit(d["theta_i"], d["theta_r"], d["phi_r"], d["L"], wavelength=1.0,
                     sigma_L=d["sigma_L"])
    assert_same_report(cli, r.to_dict())
    assert r.verdict == "full" and r.params["sigma"]["determined"]


def test_robust_loss_matches_cli_json(cli_json):
    # A robust fit (scipy's soft_l1 on relative residuals, C = 2 %) as `--loss --f-scale`.
    path = DATA / "synthetic" / "kbs_inplane.csv"
    cli = cli_json("--wavelength", "1", "--residual", "relative", "--loss", "soft_l1",
                   "--f-scale", "0.02", path)
    d = read_csv(path)
    r = goniofit.fit(d["theta_i"], d["theta_r"], d["phi_r"], d["L"], wavelength=1,
                     residual="relative", loss="soft_l1", f_scale=0.02)
    assert_same_report(cli, r.to_dict())
    assert r.to_dict()["setting"]["loss"] == "soft_l1"
    assert r.to_dict()["setting"]["f_scale"] == 0.02
    linear = goniofit.fit(d["theta_i"], d["theta_r"], d["phi_r"], d["L"], wavelength=1,
                          residual="relative", intervals=False)
    assert r.cost != linear.cost


def test_auto_model_comparison_matches_cli(cli_json):
    path = DATA / "synthetic" / "lambert_specular.csv"
    cli = cli_json("--model", "auto", "--wavelength", "1", path)
    d = read_csv(path)
    r = goniofit.fit(d["theta_i"], d["theta_r"], d["phi_r"], d["L"], model="auto", wavelength=1)
    assert_same_report(cli, r.to_dict())
    assert [c["model"] for c in r.to_dict()["comparison"]] == goniofit.AUTO_CANDIDATES


def test_text_report_is_the_cli_report(cli):
    path = DATA / "synthetic" / "kbs_inplane.csv"
    code, text = cli("fit", "--wavelength", "1", path)
    assert code == 0
    d = read_csv(path)
    r = goniofit.fit(d["theta_i"], d["theta_r"], d["phi_r"], d["L"], wavelength=1)
    # Run lines, and where λ and the quantity came from (flags vs keywords).
    skip = ("input ", "command ", "run time ", "wavelength ", "quantity ")
    keep = lambda s: [l for l in s.splitlines() if not l.strip().startswith(skip)]
    assert keep(r.report()) == keep(text)
    assert "wavelength      = 1 unit of λ (from the wavelength keyword" in r.report()
    html = r._repr_html_()
    assert "<table>" in html and "sigma" in html and r.model in html


def test_by_group_matches_cli(cli_json):
    # Every channel of a Cornell paint on its own, as `--by-group`.
    path = DATA / "cornell" / "krylon_blue.astm"
    cli = cli_json("--model", "kbs+lambert", "--quantity", "brdf", "--residual", "log",
                   "--channel", "all", "--by-group", path)
    d = goniofit.read(path, channel="all", radians=True)
    fits = goniofit.fit(d["theta_i"], d["theta_r"], d["phi_r"], d["L"], model="kbs+lambert",
                        quantity="brdf", residual="log", wavelength=d["wavelength"],
                        wavelength_unit="nm", group=d["channel"], radians=True)
    assert len(fits) == cli["datasets"] == 31
    for (label, r), c in zip(fits.items(), cli["fits"]):
        assert c["input"].endswith(f"[{label}]")
        assert_same_report(c, r.to_dict())


def test_fit_many_is_fit_one_by_one():
    d = read_csv(DATA / "synthetic" / "kbs_rough.csv")
    scans = [{k: v[i::3] for k, v in d.items()} for i in range(3)]
    many = goniofit.fit_many(scans, wavelength=1.0)
    for scan, r in zip(scans, many):
        # Fits of many datasets carry no profile intervals (as the CLI's --by-group).
        one = goniofit.fit(scan["theta_i"], scan["theta_r"], scan["phi_r"], scan["L"],
                           wavelength=1.0, intervals=False)
        assert r.cost == one.cost
        assert r.params == one.params
        assert "interval95" not in r.params["sigma"]


def test_evaluate_closed_forms_and_jacobian():
    ti = np.array([0.0, 30.0, 60.0])
    # Lambert: L = s cos θi, the BRDF is s.
    v = goniofit.evaluate("lambert", {"scale": 0.5}, ti, np.full(3, 10.0), np.zeros(3))
    np.testing.assert_allclose(v, 0.5 * np.cos(np.radians(ti)), rtol=1e-15)
    b = goniofit.evaluate("lambert", [0.5], ti, np.full(3, 10.0), np.zeros(3), quantity="brdf")
    np.testing.assert_allclose(b, 0.5, rtol=1e-15)
    # KBS: the analytic Jacobian against central differences in each parameter.
    p = {"sigma": 0.2, "T": 2.0, "scale": 1.0}
    tr, pr = np.array([10.0, 30.0, 50.0]), np.array([0.0, 90.0, 180.0])
    f, J = goniofit.evaluate("kbs", p, ti, tr, pr, wavelength=1.0, jacobian=True)
    assert J.shape == (3, 3)
    for j, name in enumerate(["sigma", "T", "scale"]):
        h = 1e-6 * p[name]
        up = goniofit.evaluate("kbs", dict(p, **{name: p[name] + h}), ti, tr, pr)
        dn = goniofit.evaluate("kbs", dict(p, **{name: p[name] - h}), ti, tr, pr)
        np.testing.assert_allclose(J[:, j], (up - dn) / (2 * h), rtol=1e-6)


def test_evaluate_matches_cli_eval(cli, tmp_path):
    code, out = cli("eval", "--model", "kbs", "--params", "sigma=0.3,T=3,scale=2",
                    "--wavelength", "1", DATA / "angles_inplane.csv")
    assert code == 0
    rows = list(csv.DictReader(out.splitlines()))
    got = goniofit.evaluate("kbs", {"sigma": 0.3, "T": 3, "scale": 2},
                            [float(r["theta_i"]) for r in rows],
                            [float(r["theta_r"]) for r in rows],
                            [float(r["phi_r"]) for r in rows])
    np.testing.assert_allclose(got, [float(r["L_model"]) for r in rows], rtol=1e-12)
