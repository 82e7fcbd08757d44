//! Numbers read back from a JSON report. JSON has no NaN or infinity, and serde_json writes
//! a non-finite `f64` as `null`; these read `null` back as NaN, so that a statistic that
//! was not computable (a p-value of an empty test, a slope of a constant) survives the
//! round trip through a report's JSON as "not a number" rather than failing it.

use serde::{Deserialize, Deserializer};

/// An `f64` field: a number as it is, `null` as NaN.
pub(crate) fn nan_if_null<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

#[cfg(test)]
mod tests {
    #[derive(serde::Serialize, serde::Deserialize)]
    struct S {
        #[serde(deserialize_with = "super::nan_if_null")]
        x: f64,
    }

    #[test]
    fn non_finite_numbers_come_back_as_nan_and_finite_ones_exactly() {
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let text = serde_json::to_string(&S { x }).unwrap();
            assert_eq!(text, r#"{"x":null}"#);
            assert!(serde_json::from_str::<S>(&text).unwrap().x.is_nan());
        }
        for x in [0.0, -1.5e-300, 0.1, 1.7976931348623157e308] {
            let text = serde_json::to_string(&S { x }).unwrap();
            assert_eq!(serde_json::from_str::<S>(&text).unwrap().x, x);
        }
    }
}
