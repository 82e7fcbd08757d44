//! The Levenberg parameter (MINPACK `lmpar`): Moré's safeguarded Newton iteration for the
//! `λ` at which the damped step has the trust radius as its scaled length.

use nalgebra::DVector;

use super::norm::enorm;
use super::qr::{qrsolv, QrState};

/// MINPACK `lmpar`: find `λ ≥ 0` and the step `x` (the negative of the LM step) with
/// `(JᵀJ + λDD) x = Jᵀ f`, such that either `λ = 0` and `‖D x‖ ≤ 1.1 Δ`, or
/// `|‖D x‖ − Δ| ≤ 0.1 Δ` (at most 10 Newton iterations, as MINPACK). `par` is the initial
/// estimate on entry and the result on exit. `qr`'s strict lower triangle is overwritten
/// (workspace of `qrsolv`); its upper triangle, pivots and `Qᵀ f` are kept.
pub(super) fn lmpar(
    qr: &mut QrState,
    diag: &DVector<f64>,
    delta: f64,
    par: &mut f64,
    x: &mut DVector<f64>,
) {
    let n = qr.r.ncols();
    let dwarf = f64::MIN_POSITIVE;
    let mut sdiag = DVector::zeros(n);

    let nsing = gauss_newton_step(qr, x);
    let mut wa2 = diag.component_mul(x);
    let mut dxnorm = enorm(wa2.as_slice());
    let mut fp = dxnorm - delta;
    if fp <= 0.1 * delta {
        *par = 0.0;
        return;
    }

    // Lower bound parl (only when R is non-singular: then the Newton step is defined).
    let mut parl = if nsing >= n {
        lower_bound(qr, diag, &wa2, dxnorm, fp, delta)
    } else {
        0.0
    };
    let (gnorm, mut paru) = upper_bound(qr, diag, delta);

    *par = par.max(parl).min(paru);
    if *par == 0.0 {
        *par = gnorm / dxnorm;
    }

    let mut iter = 0;
    loop {
        iter += 1;
        if *par == 0.0 {
            *par = dwarf.max(0.001 * paru);
        }
        let s = par.sqrt();
        let d = diag * s;
        qrsolv(&mut qr.r, &qr.ipvt, &d, &qr.qtf, x, &mut sdiag);
        wa2 = diag.component_mul(x);
        dxnorm = enorm(wa2.as_slice());
        let temp = fp;
        fp = dxnorm - delta;
        if fp.abs() <= 0.1 * delta || (parl == 0.0 && fp <= temp && temp < 0.0) || iter == 10 {
            break;
        }
        let parc = newton_correction(qr, &sdiag, diag, &wa2, dxnorm, fp, delta);
        if fp > 0.0 {
            parl = parl.max(*par);
        }
        if fp < 0.0 {
            paru = paru.min(*par);
        }
        *par = parl.max(*par + parc);
        if !par.is_finite() {
            *par = paru;
        }
    }
}

/// The Gauss–Newton direction `x` with `R Pᵀ x = Qᵀ f` (minimum-length on the non-singular
/// part when `R` has zero pivots). Returns the rank used: the index of the first zero pivot,
/// or `n`.
fn gauss_newton_step(qr: &QrState, x: &mut DVector<f64>) -> usize {
    let n = qr.r.ncols();
    let r = &qr.r;
    let mut wa1 = qr.qtf.clone();
    let mut nsing = n;
    for j in 0..n {
        if r[(j, j)] == 0.0 && nsing == n {
            nsing = j;
        }
        if nsing < n {
            wa1[j] = 0.0;
        }
    }
    for j in (0..nsing).rev() {
        wa1[j] /= r[(j, j)];
        let t = wa1[j];
        for i in 0..j {
            wa1[i] -= r[(i, j)] * t;
        }
    }
    for j in 0..n {
        x[qr.ipvt[j]] = wa1[j];
    }
    nsing
}

/// Moré's lower bound on `λ` from the Newton step of `φ(λ) = ‖D x(λ)‖ − Δ` at `λ = 0`
/// (`wa2 = D x`, `fp = φ(0)`); 0 when it is not finite.
fn lower_bound(
    qr: &QrState,
    diag: &DVector<f64>,
    wa2: &DVector<f64>,
    dxnorm: f64,
    fp: f64,
    delta: f64,
) -> f64 {
    let n = qr.r.ncols();
    let r = &qr.r;
    let mut wa1 = pivoted_direction(qr, diag, wa2, dxnorm);
    for j in 0..n {
        let mut sum = 0.0;
        for i in 0..j {
            sum += r[(i, j)] * wa1[i];
        }
        wa1[j] = (wa1[j] - sum) / r[(j, j)];
    }
    let t = enorm(wa1.as_slice());
    let parl = ((fp / delta) / t) / t;
    if parl.is_finite() {
        parl
    } else {
        0.0
    }
}

/// The scaled gradient norm `‖D⁻¹ Jᵀ f‖` and Moré's upper bound on `λ` (`gnorm / Δ`, or a
/// tiny positive value when the gradient is zero).
fn upper_bound(qr: &QrState, diag: &DVector<f64>, delta: f64) -> (f64, f64) {
    let n = qr.r.ncols();
    let r = &qr.r;
    let mut wa1 = DVector::zeros(n);
    for j in 0..n {
        let mut sum = 0.0;
        for i in 0..=j {
            sum += r[(i, j)] * qr.qtf[i];
        }
        wa1[j] = sum / diag[qr.ipvt[j]];
    }
    let gnorm = enorm(wa1.as_slice());
    let mut paru = gnorm / delta;
    if paru == 0.0 {
        paru = f64::MIN_POSITIVE / delta.min(0.1);
    }
    (gnorm, paru)
}

/// Newton's correction to `λ` for `φ(λ) = ‖D x(λ)‖ − Δ`, from the factor `S` that
/// `qrsolv` left in `qr`'s strict lower triangle and `sdiag` (`wa2 = D x`, `fp = φ(λ)`).
fn newton_correction(
    qr: &QrState,
    sdiag: &DVector<f64>,
    diag: &DVector<f64>,
    wa2: &DVector<f64>,
    dxnorm: f64,
    fp: f64,
    delta: f64,
) -> f64 {
    let n = qr.r.ncols();
    let r = &qr.r;
    let mut wa1 = pivoted_direction(qr, diag, wa2, dxnorm);
    for j in 0..n {
        wa1[j] /= sdiag[j];
        let t = wa1[j];
        for i in j + 1..n {
            wa1[i] -= r[(i, j)] * t;
        }
    }
    let t = enorm(wa1.as_slice());
    ((fp / delta) / t) / t
}

/// `Pᵀ D (D x)/‖D x‖` (with `wa2 = D x`): the right-hand side of both Newton corrections.
fn pivoted_direction(
    qr: &QrState,
    diag: &DVector<f64>,
    wa2: &DVector<f64>,
    dxnorm: f64,
) -> DVector<f64> {
    DVector::from_iterator(
        qr.ipvt.len(),
        qr.ipvt.iter().map(|&l| diag[l] * (wa2[l] / dxnorm)),
    )
}
