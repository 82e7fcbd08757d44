use super::*;
use crate::geometry::{Geometry, Quantity};
use crate::model::{by_name, ModelOptions};
use std::path::Path;

#[test]
fn default_sizes() {
    assert_eq!(Layout::inplane().angles().len(), 5 * 171);
    assert_eq!(Layout::hemisphere().angles().len(), 3240);
    assert_eq!(Layout::grazing().angles().len(), 3240);
}

#[test]
fn inplane_signed_theta_r() {
    let a = Layout::inplane().angles();
    // First scan, θi = 15: θr = −85 … 85.
    assert_eq!(
        a[0],
        AnglesDeg {
            theta_i: 15.0,
            theta_r: 85.0,
            phi_r: 180.0
        }
    );
    assert_eq!(
        a[85],
        AnglesDeg {
            theta_i: 15.0,
            theta_r: 0.0,
            phi_r: 0.0
        }
    );
    assert_eq!(
        a[170],
        AnglesDeg {
            theta_i: 15.0,
            theta_r: 85.0,
            phi_r: 0.0
        }
    );
    for x in &a {
        assert!(x.phi_r == 0.0 || x.phi_r == 180.0);
        assert!(x.theta_r >= 0.0 && x.theta_r <= 85.0);
        assert_eq!(x.theta_r.fract(), 0.0, "integer steps stay exact");
    }
    assert_eq!(a.iter().filter(|x| x.phi_r == 180.0).count(), 5 * 85);
}

#[test]
fn grids_cover_the_ranges() {
    let h = Layout::Hemisphere {
        n_theta_i: 3,
        n_theta_r: 4,
        n_phi_r: 8,
    }
    .angles();
    assert_eq!(h.len(), 96);
    let ti: Vec<f64> = h.iter().step_by(32).map(|a| a.theta_i).collect();
    assert_eq!(ti, vec![15.0, 45.0, 75.0]);
    let tr: Vec<f64> = h[..32].iter().step_by(8).map(|a| a.theta_r).collect();
    assert_eq!(tr, vec![11.25, 33.75, 56.25, 78.75]);
    let pr: Vec<f64> = h[..8].iter().map(|a| a.phi_r).collect();
    assert_eq!(
        pr,
        vec![-180.0, -135.0, -90.0, -45.0, 0.0, 45.0, 90.0, 135.0]
    );
    let g = Layout::Grazing {
        n_theta_i: 20,
        n_theta_r: 2,
        n_phi_r: 2,
    }
    .angles();
    let gi: Vec<f64> = g.iter().step_by(4).map(|a| a.theta_i).collect();
    assert_eq!(gi.len(), 20);
    assert_eq!(gi[0], 70.0);
    assert_eq!(gi[19], 89.0);
    for w in gi.windows(2) {
        assert!((w[1] - w[0] - 1.0).abs() < 1e-12);
    }
}

#[test]
fn subsample_spreads_over_the_layout() {
    let a = Layout::hemisphere().angles();
    let s = subsample(&a, 100).unwrap();
    assert_eq!(s.len(), 100);
    assert_eq!(s[0], a[0]);
    let mut ti: Vec<f64> = s.iter().map(|x| x.theta_i).collect();
    ti.dedup();
    assert_eq!(ti.len(), 5, "every θi is kept");
    assert!(subsample(&a, 0).is_err());
    assert!(subsample(&a, 3241).is_err());
    assert_eq!(subsample(&a, 3240).unwrap(), a);
}

#[test]
fn zero_noise_is_exact() {
    let exact = vec![1.0, 2.5, 1e-300, 0.0];
    let n = add_noise(&exact, &Noise::none()).unwrap();
    assert_eq!(n.value, exact);
    assert_eq!(n.sigma_l, vec![0.0; 4]);
}

#[test]
fn noise_kinds_have_the_documented_sigma() {
    let exact = vec![4.0, 1.0, 0.0];
    let mk = |kind| Noise {
        kind,
        level: 0.1,
        seed: 7,
    };
    let r = add_noise(&exact, &mk(NoiseKind::Relative)).unwrap();
    assert_eq!(r.sigma_l, vec![0.4, 0.1, 0.0]);
    assert_eq!(r.value[2], 0.0);
    let a = add_noise(&exact, &mk(NoiseKind::Absolute)).unwrap();
    assert_eq!(a.sigma_l, vec![0.4, 0.4, 0.4]);
    let p = add_noise(&exact, &mk(NoiseKind::Poisson)).unwrap();
    assert_eq!(p.sigma_l, vec![0.4, 0.2, 0.0]);
    // Same z stream for every kind: (value − L)/σ agrees.
    let z = (r.value[0] - 4.0) / 0.4;
    assert!(((a.value[0] - 4.0) / 0.4 - z).abs() < 1e-12);
    assert!(((p.value[1] - 1.0) / 0.2 - (a.value[1] - 1.0) / 0.4).abs() < 1e-12);
    assert!(add_noise(
        &exact,
        &Noise {
            level: -1.0,
            ..mk(NoiseKind::Relative)
        }
    )
    .is_err());
    assert!(add_noise(
        &exact,
        &Noise {
            level: f64::NAN,
            ..mk(NoiseKind::Relative)
        }
    )
    .is_err());
}

#[test]
fn relative_noise_statistics() {
    let exact: Vec<f64> = (1..=20_000).map(|i| i as f64).collect();
    let eps = 0.05;
    let n = add_noise(
        &exact,
        &Noise {
            kind: NoiseKind::Relative,
            level: eps,
            seed: 3,
        },
    )
    .unwrap();
    let r: Vec<f64> = n
        .value
        .iter()
        .zip(&exact)
        .map(|(v, l)| v / l - 1.0)
        .collect();
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    let sd = (r.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (r.len() - 1) as f64).sqrt();
    // Standard error of the mean is ε/√n ≈ 3.5e-4; of the sd about 0.5 %.
    assert!(
        mean.abs() < 4.0 * eps / (r.len() as f64).sqrt(),
        "mean {mean}"
    );
    assert!((sd / eps - 1.0).abs() < 0.03, "sd {sd}");
}

#[test]
fn generate_matches_the_model() {
    let m = by_name("kbs", &ModelOptions::default()).unwrap();
    let p = [0.3, 2.0, 1.0];
    let layout = Layout::inplane();
    let d = generate(
        m.as_ref(),
        &p,
        &layout.angles(),
        1.0,
        Quantity::Radiance,
        &Noise::none(),
    )
    .unwrap();
    let geo = Geometry::new(&layout.samples(), &[1.0], Quantity::Radiance).unwrap();
    let mut want = vec![0.0; geo.len()];
    m.eval(&geo, &p, &mut want, None);
    assert_eq!(d.exact, want);
    assert_eq!(d.value, want);
    assert!(generate(
        m.as_ref(),
        &p[..2],
        &layout.angles(),
        1.0,
        Quantity::Radiance,
        &Noise::none()
    )
    .is_err());
    assert!(generate(
        m.as_ref(),
        &p,
        &layout.angles(),
        -1.0,
        Quantity::Radiance,
        &Noise::none()
    )
    .is_err());
}

#[test]
fn parse_reads_back_describe() {
    let layouts = [
        Layout::inplane(),
        Layout::hemisphere(),
        Layout::grazing(),
        Layout::Hemisphere {
            n_theta_i: 2,
            n_theta_r: 3,
            n_phi_r: 4,
        },
        Layout::Grazing {
            n_theta_i: 1,
            n_theta_r: 30,
            n_phi_r: 7,
        },
        Layout::InPlane {
            theta_i_deg: vec![0.0, 12.5, 89.0],
            step_deg: 0.1,
            theta_r_max_deg: 90.0,
        },
    ];
    for l in layouts {
        assert_eq!(Layout::parse(&l.describe()).unwrap(), l, "{}", l.describe());
    }
    assert_eq!(
        Layout::parse("InPlane max=10 step=5")
            .unwrap()
            .angles()
            .len(),
        5 * 5
    );
    for bad in [
        "hemisphere 5x18",
        "hemisphere 5x18x36 7",
        "inplane theta_r=80",
        "inplane foo=1",
        "inplane step=x",
        "inplane step=0",
        "grazing 0x1x1",
    ] {
        assert!(Layout::parse(bad).is_err(), "{bad}");
    }
}

#[test]
fn inplane_non_dividing_step_is_symmetric() {
    let a = Layout::parse("inplane theta_i=30 max=85 step=0.7")
        .unwrap()
        .angles();
    assert_eq!(a.len(), 2 * 121 + 1);
    assert_eq!((a[0].theta_r, a[0].phi_r), (121.0 * 0.7, 180.0));
    assert_eq!((a[242].theta_r, a[242].phi_r), (121.0 * 0.7, 0.0));
    assert_eq!((a[121].theta_r, a[121].phi_r), (0.0, 0.0));
    // 900 × 0.1 rounds above 90: kept at 90.
    let a = Layout::parse("inplane theta_i=30 max=90 step=0.1")
        .unwrap()
        .angles();
    assert_eq!(a.len(), 1801);
    assert_eq!(a[1800].theta_r, 90.0);
    assert!(a.iter().all(|x| x.sample().validate().is_ok()));
}

proptest::proptest! {
    #[test]
    fn every_generated_layout_is_valid_and_reads_back(
        ni in 1usize..9, nr in 1usize..9, np in 1usize..9, grazing: bool,
        step in 0.05f64..40.0, max in 0.0f64..=90.0,
        ti in proptest::collection::vec(0.0f64..89.999, 1..4),
    ) {
        let grid = if grazing {
            Layout::Grazing { n_theta_i: ni, n_theta_r: nr, n_phi_r: np }
        } else {
            Layout::Hemisphere { n_theta_i: ni, n_theta_r: nr, n_phi_r: np }
        };
        let inplane = Layout::InPlane { theta_i_deg: ti.clone(), step_deg: step, theta_r_max_deg: max };
        for l in [grid, inplane] {
            proptest::prop_assert!(l.validate().is_ok());
            let a = l.angles();
            proptest::prop_assert!(!a.is_empty());
            for x in &a {
                proptest::prop_assert!(x.sample().validate().is_ok(), "{:?}", x);
            }
            proptest::prop_assert_eq!(Layout::parse(&l.describe()).unwrap(), l.clone());
        }
        proptest::prop_assert_eq!(Layout::Hemisphere { n_theta_i: ni, n_theta_r: nr, n_phi_r: np }.angles().len(), ni * nr * np);
        let k = (max / step + 1e-9).floor() as usize;
        proptest::prop_assert_eq!(
            Layout::InPlane { theta_i_deg: ti.clone(), step_deg: step, theta_r_max_deg: max }.angles().len(),
            ti.len() * (2 * k + 1)
        );
    }
}

#[test]
fn truth_path_sits_beside_the_data() {
    assert_eq!(
        truth_path(Path::new("/tmp/x/data.csv")),
        Path::new("/tmp/x/data.truth.json")
    );
    assert_eq!(truth_path(Path::new("data")), Path::new("data.truth.json"));
}
