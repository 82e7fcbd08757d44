//! Quantiles of the normal and Student-t distributions, and the regularised incomplete
//! beta function under them: the thresholds of the profile intervals
//! ([`super::profile::threshold`]).

/// The standard normal quantile: Φ⁻¹(q) for q ∈ (0, 1), by bisection and Newton on
/// Φ(z) = erfc(−z/√2)/2 (to 1e-14 absolute).
pub(crate) fn normal_quantile(q: f64) -> f64 {
    let cdf = |z: f64| 0.5 * libm::erfc(-z / std::f64::consts::SQRT_2);
    let (mut lo, mut hi) = (-40.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if cdf(mid) < q {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-15 {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// The Student-t quantile t_q(ν) for q ∈ (0.5, 1) and ν > 0 degrees of freedom: the root of
/// F(t) = q with F(t) = 1 − ½ I_{ν/(ν+t²)}(ν/2, ½), by bisection; accurate to about 1e-9
/// relative (the incomplete beta's 1e-10 in F), far below what an interval needs.
pub fn student_t_quantile(q: f64, nu: f64) -> f64 {
    if nu > 1e7 {
        return normal_quantile(q);
    }
    let cdf = |t: f64| 1.0 - 0.5 * incomplete_beta(0.5 * nu, 0.5, nu / (nu + t * t));
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    while cdf(hi) < q && hi < 1e12 {
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if cdf(mid) < q {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-13 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// The regularised incomplete beta function I_x(a, b), by its continued fraction (Lentz),
/// accurate to about 1e-10 for the a, b of the t distribution (lgamma's rounding in the
/// prefactor dominates).
pub(crate) fn incomplete_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front =
        libm::lgamma(a + b) - libm::lgamma(a) - libm::lgamma(b) + a * x.ln() + b * (1.0 - x).ln();
    let front = ln_front.exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_cf(a, b, x) / a
    } else {
        1.0 - front * beta_cf(b, a, 1.0 - x) / b
    }
}

/// The continued fraction of the incomplete beta function (modified Lentz).
fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    let tiny = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < tiny {
        d = tiny;
    }
    d = 1.0 / d;
    let mut h = d;
    // One Lentz step with coefficient aa: the new d, c and their product.
    let step = |aa: f64, d: &mut f64, c: &mut f64| -> f64 {
        *d = 1.0 + aa * *d;
        if d.abs() < tiny {
            *d = tiny;
        }
        *c = 1.0 + aa / *c;
        if c.abs() < tiny {
            *c = tiny;
        }
        *d = 1.0 / *d;
        *d * *c
    };
    for m in 1..10_000 {
        let m = m as f64;
        let m2 = 2.0 * m;
        h *= step(m * (b - m) * x / ((qam + m2) * (a + m2)), &mut d, &mut c);
        let del = step(
            -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
            &mut d,
            &mut c,
        );
        h *= del;
        if (del - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_match_tables() {
        // Tables (scipy.stats t.ppf / norm.ppf): t_0.975(10), t_0.975(1), t_0.95(5) (also
        // checked by Simpson integration of the t density: F = 0.95 to 1e-10), z_0.975.
        assert!((student_t_quantile(0.975, 10.0) - 2.228_138_851_986_273_5).abs() < 1e-8);
        assert!((student_t_quantile(0.975, 1.0) - 12.706_204_736_174_698).abs() < 1e-8);
        assert!((student_t_quantile(0.95, 5.0) - 2.015_048_372_669_157_5).abs() < 1e-8);
        assert!((normal_quantile(0.975) - 1.959_963_984_540_054).abs() < 1e-12);
        assert!((normal_quantile(0.841_344_746_068_542_9) - 1.0).abs() < 1e-12);
    }
}
