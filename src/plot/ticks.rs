//! Tick positions chosen from an axis' range, so that every axis shows at least a few
//! labelled ticks: plotters' logarithmic axis labels only powers of ten (none at all for a
//! range under a decade, as the NIST PTFE BRDF's 0.02–0.4 sr⁻¹), and its linear axis can
//! leave a log-scaled run-time axis with two ticks.

/// A "nice" step (1, 2, 2.5 or 5 × 10ᵏ) near `raw` (> 0).
pub(crate) fn nice_step(raw: f64) -> f64 {
    let k = raw.log10().floor();
    let base = 10f64.powf(k);
    let m = raw / base;
    let nice = if m <= 1.0 {
        1.0
    } else if m <= 2.0 {
        2.0
    } else if m <= 2.5 {
        2.5
    } else if m <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * base
}

/// Linear ticks on [lo, hi]: multiples of a nice step, about `target` of them (at least 2
/// for any lo < hi). Empty for an empty or non-finite range.
pub(crate) fn linear_ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Vec::new();
    }
    let mut n = target.max(2);
    loop {
        let step = nice_step((hi - lo) / n as f64);
        let first = (lo / step).ceil() as i64;
        let last = (hi / step).floor() as i64;
        let ticks: Vec<f64> = (first..=last)
            .map(|k| {
                let v = k as f64 * step;
                // 0.30000000000000004 → 0.3: round to the step's decimals.
                let d = (-step.log10().floor()).max(0.0) as i32 + 2;
                let p = 10f64.powi(d);
                (v * p).round() / p
            })
            .collect();
        if ticks.len() >= 2 || n > 64 {
            return ticks;
        }
        n *= 2;
    }
}

/// m × 10ᵏ as the double nearest to the decimal (2e-3, not 2 × 0.0010000000000000002).
fn decimal(m: f64, k: i32) -> f64 {
    format!("{m}e{k}").parse().unwrap_or(f64::NAN)
}

/// Ticks for a logarithmic axis on [lo, hi] (0 < lo < hi): powers of ten when the range
/// spans enough decades (every k-th decade so that at most 10 remain), else 1-2-5, then
/// 1-2-3-5, then 1…9 per decade, whichever first gives at least 4 ticks; a range too narrow
/// for any of these (under a factor of about 2) gets linear nice ticks. Always at least 2
/// ticks inside [lo, hi] for a valid range; empty otherwise.
pub(crate) fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
        return Vec::new();
    }
    let (a, b) = (lo.log10(), hi.log10());
    let inside = |v: &f64| *v >= lo * (1.0 - 1e-12) && *v <= hi * (1.0 + 1e-12);
    let decades: Vec<i32> = ((a.ceil() as i32)..=(b.floor() as i32)).collect();
    if decades.len() >= 4 {
        let every = decades.len().div_ceil(10);
        return decades
            .iter()
            .filter(|k| k.rem_euclid(every as i32) == 0)
            .map(|&k| decimal(1.0, k))
            .collect();
    }
    let per_decade: [&[f64]; 3] = [
        &[1.0, 2.0, 5.0],
        &[1.0, 2.0, 3.0, 5.0],
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
    ];
    for mantissas in per_decade {
        let ticks: Vec<f64> = ((a.floor() as i32)..=(b.floor() as i32))
            .flat_map(|k| mantissas.iter().map(move |&m| decimal(m, k)))
            .filter(inside)
            .collect();
        if ticks.len() >= 4 {
            return ticks;
        }
    }
    linear_ticks(lo, hi, 6)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_under_a_decade_are_labelled() {
        // The PTFE fit_log range (0.02–0.4 sr⁻¹): 1-2-5 gives 0.02, 0.05, 0.1, 0.2.
        assert_eq!(log_ticks(0.018, 0.45), vec![0.02, 0.05, 0.1, 0.2]);
        // Less than a factor 4: every integer mantissa.
        assert_eq!(
            log_ticks(0.25, 0.95),
            vec![0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]
        );
        // Under a factor 2: linear nice ticks, still inside the range.
        let t = log_ticks(0.29, 0.41);
        assert_eq!(t, vec![0.3, 0.32, 0.34, 0.36, 0.38, 0.4]);
    }

    #[test]
    fn log_ticks_over_many_decades_are_powers_of_ten() {
        assert_eq!(log_ticks(3e-5, 2e0), vec![1e-4, 1e-3, 1e-2, 1e-1, 1.0]);
        // 24 decades: every third, at most 10.
        let t = log_ticks(1e-17, 1e7);
        assert!(t.len() <= 10 && t.len() >= 4, "{t:?}");
        assert!(t.iter().all(|v| (v.log10().round() as i32) % 3 == 0));
        // Two decades: 1-2-5.
        assert_eq!(log_ticks(1.5e-3, 3e-2), vec![2e-3, 5e-3, 1e-2, 2e-2]);
    }

    #[test]
    fn linear_ticks_are_nice() {
        assert_eq!(
            linear_ticks(0.0, 1.0, 5),
            vec![0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
        );
        assert_eq!(linear_ticks(-3.0, 7.0, 4), vec![-2.5, 0.0, 2.5, 5.0]);
        assert!(linear_ticks(1.0, 1.0, 5).is_empty());
        assert!(log_ticks(-1.0, 1.0).is_empty());
    }
}
