//! The binary readers (RGL `.bsdf`, MERL `.binary`) under mutation: random bytes changed,
//! files cut short, hostile values. Reading never panics or hangs; it returns a dataset of
//! finite numbers or an error that says where (a byte offset, a field) and what was
//! expected.

use crate::io::{merl, read_bytes, ReadOptions};
use proptest::prelude::*;
use std::path::Path;

fn rgl_file() -> &'static [u8] {
    static BYTES: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    BYTES.get_or_init(|| {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/rgl-epfl/paper_white_rgb.bsdf");
        std::fs::read(p).unwrap()
    })
}

/// Read `bytes` as `name`; Ok must hold only finite numbers, an error must be located.
fn check(name: &str, bytes: &[u8]) {
    let opts = ReadOptions {
        channel: Some("all".into()),
        require_value: true,
        ..Default::default()
    };
    match read_bytes(Path::new(name), bytes, &opts) {
        Ok(ds) => {
            assert!(!ds.is_empty());
            assert!(ds.value.as_ref().unwrap().iter().all(|v| v.is_finite()));
            for s in &ds.samples {
                assert!(s.theta_i.is_finite() && s.theta_r.is_finite() && s.phi_r.is_finite());
                assert!(
                    s.theta_i < std::f64::consts::FRAC_PI_2
                        && s.theta_r <= std::f64::consts::FRAC_PI_2
                );
            }
        }
        Err(e) => {
            let m = e.to_string();
            assert!(
                m.contains("byte")
                    || m.contains("field")
                    || m.contains("expected")
                    || m.contains("no measured"),
                "{m}"
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Bytes of the header (names, types, offsets, shapes) and of the tables changed.
    #[test]
    fn mutated_rgl_files_never_panic(edits in proptest::collection::vec((0usize..700, any::<u8>()), 1..6),
                                     data_edits in proptest::collection::vec((700usize..658_928, any::<u8>()), 0..40)) {
        let mut bytes = rgl_file().to_vec();
        for (at, b) in edits.into_iter().chain(data_edits) {
            bytes[at] = b;
        }
        check("m.bsdf", &bytes);
    }

    /// A file cut anywhere is refused with the byte where it ends.
    #[test]
    fn truncated_rgl_files_are_refused(len in 0usize..658_928) {
        check("t.bsdf", &rgl_file()[..len]);
    }

    /// Anything named `.binary`, or starting with MERL's dimensions, that is not a whole
    /// MERL file is refused.
    #[test]
    fn short_merl_files_are_refused(head in proptest::collection::vec(any::<u8>(), 0..64), merl_dims in any::<bool>()) {
        let mut bytes = Vec::new();
        if merl_dims {
            for d in [90i32, 90, 180] {
                bytes.extend_from_slice(&d.to_le_bytes());
            }
        }
        bytes.extend_from_slice(&head);
        check("s.binary", &bytes);
    }
}

/// A whole MERL file of hostile values (NaN, ±inf, negative, huge, tiny): the dataset
/// keeps the finite non-negative ones, scaled, and nothing else.
#[test]
fn hostile_merl_values_are_skipped_or_kept_finite() {
    let hostile = [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        -1.0,
        -0.0,
        1e308,
        5e-324,
        1500.0,
    ];
    let mut bytes = Vec::with_capacity(merl::FILE_BYTES as usize);
    for d in [90i32, 90, 180] {
        bytes.extend_from_slice(&d.to_le_bytes());
    }
    for k in 0..3 * merl::CELLS {
        bytes.extend_from_slice(&hostile[k % hostile.len()].to_le_bytes());
    }
    check("h.binary", &bytes);
    let opts = ReadOptions {
        channel: Some("r".into()),
        require_value: true,
        ..Default::default()
    };
    let ds = read_bytes(Path::new("h.binary"), &bytes, &opts).unwrap();
    let v = ds.value.unwrap();
    assert!(
        v.iter().all(|x| [1.0, 1e308 / 1500.0, 0.0].contains(x)),
        "only the finite non-negative values, scaled"
    );
}
