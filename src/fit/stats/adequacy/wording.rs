//! The adequacy verdict and its reasons in a physicist's words, with the numbers behind
//! them (docs/adequacy.md says what each reason means and what to do).

use super::{
    Adequacy, AdequacyVerdict, RegionTest, RunsTest, SpreadTest, ALPHA, FAR_DEG, GRAZING_DEG,
};
use crate::geometry::PerSample;

/// Whether a reason says the model does not describe the data (the others say the weights
/// do not match the noise).
pub(super) fn is_misfit(code: &str) -> bool {
    !matches!(code, "proportional_noise" | "chi2_low")
}

/// A p-value for the text: two significant digits, or "< 1e-300" at 0.
pub(super) fn p_text(p: f64) -> String {
    if p <= 0.0 {
        "p < 1e-300".into()
    } else if p >= 0.01 {
        format!("p = {p:.2}")
    } else {
        format!("p = {p:.1e}")
    }
}

/// The verdict in one line.
pub(super) fn headline(a: &Adequacy) -> String {
    let tests = format!(
        "{} test{}, family-wise α = {}",
        a.tests,
        if a.tests == 1 { "" } else { "s" },
        ALPHA
    );
    match a.verdict {
        AdequacyVerdict::Adequate => {
            format!("adequate: no test finds the model or its weights at odds with the data ({tests})")
        }
        AdequacyVerdict::Misfit if a.reasons.iter().any(|r| !is_misfit(&r.code)) => format!(
            "misfit: the model does not describe these data, and the weights do not match the noise; weigh the samples as measured first, since some of the misfit may follow from the weighting ({tests})"
        ),
        AdequacyVerdict::Misfit => {
            format!("misfit: the model does not describe these data ({tests})")
        }
        AdequacyVerdict::Noise => format!(
            "noise: the model follows the data, but the weights do not match the noise ({tests})"
        ),
        AdequacyVerdict::Exact => {
            "exact: the model meets every sample to rounding error, as values computed from the model would; there is no noise to test".into()
        }
        AdequacyVerdict::NotComputed => {
            "not computed: no residuals at the reported point, or too few samples for a test"
                .into()
        }
    }
}

/// The χ² reason: too large (`high`) or too small.
pub(super) fn chi2(reduced: f64, p: f64, high: bool) -> (&'static str, String) {
    if high {
        (
            "chi2_high",
            format!(
                "χ²/(n − p) = {reduced:.3} with the stated uncertainties ({}): the model does not describe these data within σ_L, or σ_L understates the noise",
                p_text(p)
            ),
        )
    } else {
        (
            "chi2_low",
            format!(
                "χ²/(n − p) = {reduced:.3} with the stated uncertainties ({}): the residuals are smaller than σ_L allows; σ_L overstates the noise, and the errors quoted here are too large",
                p_text(p)
            ),
        )
    }
}

/// The runs reason.
pub(super) fn runs(t: &RunsTest) -> (&'static str, String) {
    (
        "runs",
        format!(
            "the residuals keep their sign along the scans: {} runs of one sign where {:.0} ± {:.0} are expected ({} signs in {} scans, {}); the model's shape does not follow the data",
            t.runs,
            t.expected,
            t.sd,
            t.signs,
            t.scans,
            p_text(t.p)
        ),
    )
}

/// The spread reason (weights all equal, or not).
pub(super) fn spread(t: &SpreadTest, sqrt_w: &PerSample) -> (&'static str, String) {
    let slope = if t.slope.is_finite() {
        format!(
            ", ln spread rises {:.2} × ln L, 1 for proportional noise",
            t.slope
        )
    } else {
        String::new()
    };
    let stats = format!(
        "rank correlation {:.2} with L over {} triples of neighbours{slope}, {}",
        t.rho,
        t.triples,
        p_text(t.p)
    );
    let text = if matches!(sqrt_w, PerSample::One { .. }) {
        format!("the residual spread grows with L ({stats}): the noise looks proportional; --residual relative or log weighs the samples as measured, and the errors quoted here are too small")
    } else {
        format!("the weighted residual spread grows with L ({stats}): the weights do not follow the noise, which grows with L; --residual relative or log, or weights from the measured noise, weigh the samples as measured, and the errors quoted here are too small")
    };
    ("proportional_noise", text)
}

/// The reason of a region's sign test.
pub(super) fn region(t: &RegionTest, has_diffuse: bool) -> (&'static str, String) {
    let above = 2 * t.data_above > t.n;
    let count = |k: usize, side: &str| {
        format!(
            "{k} of {} samples there {side} the model, {}",
            t.n,
            p_text(t.p)
        )
    };
    let (a, b) = (
        count(t.data_above, "above"),
        count(t.n - t.data_above, "below"),
    );
    match (t.region.as_ref(), above) {
        ("grazing", true) => ("grazing_above", format!(
            "the measured values rise above the model beyond θ = {GRAZING_DEG:.0}° ({a}), as unmodelled Fresnel reflection would")),
        ("grazing", false) => ("grazing_below", format!(
            "the measured values fall below the model beyond θ = {GRAZING_DEG:.0}° ({b}), as unmodelled shadowing and masking would")),
        ("peak", false) => ("peak_below", format!(
            "the measured peak is lower and flatter than the model's where the model is above half its peak ({b}), as a saturated or clipped detector would")),
        ("peak", true) => ("peak_above", format!(
            "the measured values near the peak rise above the model ({a}), as a sharper specular component than the model's would (a coherent reflection, or a second, smoother scale of roughness)")),
        (_, true) if !has_diffuse => ("floor", format!(
            "a diffuse floor is missing: the measured values more than {FAR_DEG:.0}° from the mirror direction lie systematically above the model ({a}); try --model kbs+lambert")),
        (_, true) => ("far_above", format!(
            "the measured values more than {FAR_DEG:.0}° from the mirror direction lie above the model ({a}): neither its lobe nor its diffuse term reaches them")),
        (_, false) => ("far_below", format!(
            "the measured values more than {FAR_DEG:.0}° from the mirror direction lie below the model ({b}): its lobe or diffuse term is too broad for these data")),
    }
}
