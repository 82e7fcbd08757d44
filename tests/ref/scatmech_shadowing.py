"""goniofit's Smith shadowing–masking against NIST SCATMECH's shadowed facet model.

What is compared, exactly. SCATMECH (pySCATMECH 0.1.10, `pip install pyscatmech`) has no
KBS series; its `Shadowed_Facet_BRDF_Model` is the facet (geometric-optics) model, the
rough limit of KBS, times a shadow function f(θi, θs, φs). This script evaluates that BRDF
with `Smith_Shadow_Function` (parameter w) and again with `Unit_Shadow_Function` at the
same geometry, slope distribution and substrate; their ratio is SCATMECH's shadow function
as its BRDF applies it, f = S(θi) S(θs). SCATMECH's S is Smith's (1967) form,
S(θ) = (1 − ½ erfc(a)) / (1 + Λ(a)), a = cot θ / (√2 w), w the rms slope per direction;
goniofit's G₁ = 1/(1 + Λ(a)) is the same Λ without the factor (1 − ½ erfc(a)) (Smith's
average over all facets, not only those facing the viewer, which the microfacet form
leaves to the slope distribution; it is 1 − 1e-9 or closer for a > 4.3). The comparable
quantity is therefore

    G_scatmech = f / ((1 − ½ erfc(a_i)) (1 − ½ erfc(a_s)))

against goniofit's `Shadowing::Smith` G = G₁(θi) G₁(θr) with a = T/(2σ tan θ), i.e.
w = √2 σ/T (the KBS rough limit's Beckmann α = 2σ/T = √2 w). The slope distribution is
SCATMECH's Gaussian one with s = α (it cancels in the ratio). SCATMECH has no
height-correlated form, so `smith-correlated` is not compared. Rows where the unshadowed
BRDF underflows (below 1e-200) are left out. The Rust test (tests/lib/fresnel_shadowing.rs)
holds goniofit's G to 1e-13 relative of G_scatmech (its stated accuracy of G; measured
worst 1e-15), and the table's own f to G_scatmech times the factor to 1e-15.

Usage: python3 -m venv /tmp/v && /tmp/v/bin/pip install pyscatmech numpy &&
       /tmp/v/bin/python tests/ref/scatmech_shadowing.py > tests/ref/scatmech_shadowing.csv
"""
import math

import pySCATMECH.brdf as brdf

THETAS = [0.0, 10.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0, 88.0, 89.5]
PHIS = [0.0, 90.0, 180.0]
T_OVER_SIGMA = [1.0, 2.0, 5.0, 20.0]


def model(shadow, w, alpha):
    m = brdf.BRDF_Model("Shadowed_Facet_BRDF_Model")
    params = {"lambda": 1.0, "substrate": complex(1.5, 0.0), "type": 0,
              "sdf": "Gaussian_Slope_Distribution_Function", "sdf.s": alpha,
              "stack": "No_StackModel", "shadow": shadow}
    if shadow == "Smith_Shadow_Function":
        params["shadow.w"] = w
    m.setParameters(params)
    return m


def illuminated(theta_deg, w):
    """Smith's factor 1 − ½ erfc(a), a = cot θ/(√2 w); 1 at normal incidence."""
    if theta_deg == 0.0:
        return 1.0
    a = 1.0 / math.tan(math.radians(theta_deg)) / (math.sqrt(2.0) * w)
    return 1.0 - 0.5 * math.erfc(a)


def main():
    print("theta_i_deg,theta_r_deg,phi_r_deg,t_over_sigma,f_scatmech,illuminated,G_scatmech")
    for ts in T_OVER_SIGMA:
        w = math.sqrt(2.0) / ts
        alpha = 2.0 / ts
        smith = model("Smith_Shadow_Function", w, alpha)
        unit = model("Unit_Shadow_Function", w, alpha)
        for ti in THETAS:
            for tr in THETAS:
                for ph in PHIS:
                    args = (math.radians(ti), math.radians(tr), math.radians(ph))
                    b1, b0 = smith.BRDF(*args), unit.BRDF(*args)
                    if not (b0 > 1e-200 and math.isfinite(b1)):
                        continue
                    f = b1 / b0
                    ill = illuminated(ti, w) * illuminated(tr, w)
                    print(f"{ti!r},{tr!r},{ph!r},{ts!r},{f!r},{ill!r},{f / ill!r}")


if __name__ == "__main__":
    main()
