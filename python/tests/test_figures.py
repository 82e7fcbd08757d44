"""The report's pictures from Python: ``FitResult.figures()`` draws the pictures
``goniofit fit --plot DIR`` writes, byte for byte, as SVG, PNG or matplotlib figures; the
notebook view shows the fit's picture and, for ``auto``, the model comparison."""

import re
import subprocess
import sys

import pytest

import goniofit
from conftest import DATA
from test_fit import assert_same_report, read_csv


def fit_file(name, **options):
    d = read_csv(DATA / "synthetic" / name)
    return goniofit.fit(d["theta_i"], d["theta_r"], d["phi_r"], d["L"], wavelength=1,
                        sigma_L=d.get("sigma_L"), **options)


def test_svg_figures_are_the_cli_pictures(cli, cli_json, tmp_path):
    # A file with sigma_L: the residuals are standardized by the stated uncertainties.
    path = DATA / "synthetic" / "kbs_hemisphere.csv"
    code, _ = cli("fit", "--wavelength", "1", "--plot", tmp_path, path)
    assert code == 0
    r = fit_file("kbs_hemisphere.csv")
    assert_same_report(cli_json("--wavelength", "1", path), r.to_dict())
    figures = r.figures()
    written = sorted(p.stem for p in tmp_path.glob("*.svg"))
    assert sorted(figures) == written
    assert {"fit_log", "residuals_theta", "contour", "hemisphere_1"} <= set(figures)
    for name, svg in figures.items():
        assert svg == (tmp_path / f"{name}.svg").read_text(), name


def test_png_figures_have_the_size_of_their_svg_in_a_fresh_process():
    # PNG first in a new interpreter: a picture whose size depends on its legend's text
    # widths must be measured with the font the drawing uses.
    script = f"""
import csv, struct, re, goniofit
rows = list(csv.DictReader(l for l in open({str(DATA / "synthetic" / "lambert_specular.csv")!r}) if not l.startswith("#")))
col = lambda k: [float(r[k]) for r in rows]
r = goniofit.fit(col("theta_i"), col("theta_r"), col("phi_r"), col("L"), model="auto",
                 wavelength=1)
pngs = r.figures("png")
svgs = r.figures("svg")
for name, png in pngs.items():
    assert png[:8] == b"\\x89PNG\\r\\n\\x1a\\n", name
    w, h = struct.unpack(">II", png[16:24])
    sw, sh = map(int, re.search(r'width="(\\d+)" height="(\\d+)"', svgs[name]).groups())
    assert (w, h) == (sw, sh), (name, w, h, sw, sh)
print(len(pngs))
"""
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert int(out.stdout) >= 6


def test_notebook_view_shows_the_fit_and_the_comparison():
    r = fit_file("lambert_specular.csv", model="auto")
    html = r._repr_html_()
    assert "Model comparison" in html
    for model in goniofit.AUTO_CANDIDATES:
        assert f"<td>{model}</td>" in html, model
    # The chosen model's fit on a log scale, inline.
    assert html.count("<svg") == 1
    assert "measured vs fitted (log scale)" in html
    single = fit_file("kbs_inplane.csv")._repr_html_()
    assert "Model comparison" not in single and "<svg" in single


def test_matplotlib_figures_or_a_clear_error():
    r = fit_file("kbs_inplane.csv")
    try:
        import matplotlib
    except ImportError:
        with pytest.raises(ImportError, match="needs matplotlib"):
            r.figures("matplotlib")
        return
    matplotlib.use("Agg")
    figs = r.figures("matplotlib")
    pngs = r.figures("png")
    assert list(figs) == list(pngs)
    fig = figs["fit_log"]
    size = re.search(rb"IHDR(.{8})", pngs["fit_log"], re.S).group(1)
    width, height = int.from_bytes(size[:4], "big"), int.from_bytes(size[4:], "big")
    assert tuple(round(v) for v in fig.get_size_inches() * fig.dpi) == (width, height)


def test_unknown_format_is_a_value_error():
    with pytest.raises(ValueError, match='give "svg", "png" or "matplotlib"'):
        fit_file("kbs_inplane.csv").figures("pdf")
