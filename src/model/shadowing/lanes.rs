//! Smith's Λ of many directions four at a time ([`directions`]): the table of erfcx
//! ([`super::E_PIECES`]) with each lane's piece loaded from a transposed copy of it, and
//! e^{−ν²} by the table-free [`exp`], in the lanes [`with_lanes`] picks (AVX2 + FMA where
//! the CPU has them). Branch-free: every direction costs the same whatever its ν.
//!
//! The same Λ and ν ∂Λ/∂ν as [`super::lambda`], up to rounding: the Taylor `exp`
//! (relative error ≤ 2ε) in place of std's and fused multiply-adds in the polynomial, so
//! to 1e-15 (1 + Λ) against the dense reference (unit-tested, worst 1.7e-16, with the bits
//! of the AVX2 lanes equal to those of the fused portable lanes).

use super::E_PIECES;
use crate::model::lanes::{exp, F64x4};
use crate::model::series::{with_lanes, LanesFn};

const INV_SQRT_PI: f64 = 0.564_189_583_547_756_3;

/// The rows of the lane table: per piece k (the column), whether it is in ν (row `IN_NU`,
/// 1 or 0) or in y (row `IN_Y`), −mid, 1/half-width, then the twelve coefficients.
const IN_NU: usize = 0;
const IN_Y: usize = 1;
const NEG_MID: usize = 2;
const INV_HALF: usize = 3;
const COEF: usize = 4;
const PIECES: usize = E_PIECES.len();

/// [`super::E_PIECES`] transposed: `TABLE[row][piece]`.
const TABLE: [[f64; PIECES]; COEF + 12] = {
    let mut t = [[0.0; PIECES]; COEF + 12];
    let mut k = 0;
    while k < PIECES {
        let p = &E_PIECES[k];
        t[IN_NU][k] = if p.in_y { 0.0 } else { 1.0 };
        t[IN_Y][k] = if p.in_y { 1.0 } else { 0.0 };
        t[NEG_MID][k] = -p.mid;
        t[INV_HALF][k] = p.inv_half;
        let mut j = 0;
        while j < 12 {
            t[COEF + j][k] = p.c[j];
            j += 1;
        }
        k += 1;
    }
    t
};

/// Λ and ν ∂Λ/∂ν ([`super::lambda`]) of every direction given by its (cot θ, tan θ)
/// ([`crate::geometry::cot_tan`]) at `(k, 1/k)`, k = T/(2σ) > 0, as
/// [`super::Shadowing::direction`] gives them (to rounding, module doc), into `out`.
/// Panics if the slices differ in length.
pub(crate) fn directions(cot_tan: &[(f64, f64)], k: (f64, f64), out: &mut [(f64, f64)]) {
    assert_eq!(cot_tan.len(), out.len());
    struct Call<'s>(&'s [(f64, f64)], (f64, f64), &'s mut [(f64, f64)]);
    impl LanesFn for Call<'_> {
        type Out = ();
        #[inline(always)]
        fn call<V: F64x4>(self) {
            let Call(cot_tan, (k, inv_k), out) = self;
            let (k, inv_k) = (V::splat(k), V::splat(inv_k));
            let mut chunks = cot_tan.chunks_exact(4);
            let mut outs = out.chunks_exact_mut(4);
            for (c, o) in (&mut chunks).zip(&mut outs) {
                let c: [(f64, f64); 4] = [c[0], c[1], c[2], c[3]];
                four::<V>(c, k, inv_k, o);
            }
            let (rest, o) = (chunks.remainder(), outs.into_remainder());
            if !rest.is_empty() {
                // The last few directions padded with normal incidence (Λ = 0).
                let mut c = [(f64::INFINITY, 0.0); 4];
                c[..rest.len()].copy_from_slice(rest);
                let mut tail = [(0.0, 0.0); 4];
                four::<V>(c, k, inv_k, &mut tail);
                o.copy_from_slice(&tail[..rest.len()]);
            }
        }
    }
    with_lanes(Call(cot_tan, k, out));
}

/// [`directions`] of four directions into `out[..4]`.
#[inline(always)]
fn four<V: F64x4>(c: [(f64, f64); 4], k: V, inv_k: V, out: &mut [(f64, f64)]) {
    let nu = V::from_array([c[0].0, c[1].0, c[2].0, c[3].0]).mul(k);
    let y = V::from_array([c[0].1, c[1].1, c[2].1, c[3].1]).mul(inv_k);
    let (l, d) = lambda_ny(nu, y);
    let (l, d) = (l.to_array(), d.to_array());
    for i in 0..4 {
        out[i] = (l[i], d[i]);
    }
}

/// The index of ν's piece in [`super::E_PIECES`] (0 for ν below the second, and NaN).
#[inline(always)]
fn piece(nu: f64) -> usize {
    let mut k = 0;
    for p in &E_PIECES[1..] {
        k += (nu >= p.nu_lo) as usize;
    }
    k
}

/// Row `r` of [`TABLE`] at each lane's piece.
#[inline(always)]
fn row<V: F64x4>(r: usize, at: [usize; 4]) -> V {
    let t = &TABLE[r];
    V::from_array([t[at[0]], t[at[1]], t[at[2]], t[at[3]]])
}

/// c_j + c_{j+1} t with the coefficients of each lane's piece.
#[inline(always)]
fn pair<V: F64x4>(t: V, j: usize, at: [usize; 4]) -> V {
    t.mul_add(row(COEF + j + 1, at), row(COEF + j, at))
}

/// Λ and ν ∂Λ/∂ν lane by lane from ν ≥ 0 and y = 1/ν (as `super::lambda_ny`: ν = 0,
/// y = ∞ gives Λ = ∞; ν = ∞, y = 0 gives 0).
#[inline(always)]
fn lambda_ny<V: F64x4>(nu: V, y: V) -> (V, V) {
    let s = V::splat;
    let at = nu.to_array().map(piece);
    // u = ν or y and the factor 1 or y as 0/1 weights: exact, and finite at both ends
    // (a piece in ν has ν < 1.25, one in y has y ≤ 0.8, below the caps).
    let (nu_c, y_c) = (nu.min(s(8.0)), y.min(s(1e3)));
    let (w_nu, w_y) = (row::<V>(IN_NU, at), row::<V>(IN_Y, at));
    let u = w_nu.mul_add(nu_c, w_y.mul(y_c));
    let factor = w_y.mul_add(y_c, w_nu);
    let t = u.add(row(NEG_MID, at)).mul(row(INV_HALF, at));
    let t2 = t.mul(t);
    let t4 = t2.mul(t2);
    let q0 = t2.mul_add(pair(t, 2, at), pair(t, 0, at));
    let q1 = t2.mul_add(pair(t, 6, at), pair(t, 4, at));
    let q2 = t2.mul_add(pair(t, 10, at), pair(t, 8, at));
    let erfcx = factor.mul(t4.mul(t4).mul_add(q2, t4.mul_add(q1, q0)));
    let e = exp(nu.mul(nu).min(s(50.0)).mul(s(-1.0)));
    let first = y.mul(s(INV_SQRT_PI));
    let half_e = e.mul(s(0.5));
    let lam = half_e.mul(erfcx.mul_add(s(-1.0), first)).max(s(0.0));
    (lam, half_e.mul(first).mul(s(-1.0)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::lanes::Portable;

    /// Λ and ν ∂Λ/∂ν of four ν in the lanes `V`.
    fn lambda4<V: F64x4>(nu: [f64; 4]) -> [(f64, f64); 4] {
        let (l, d) = lambda_ny(V::from_array(nu), V::from_array(nu.map(|v| 1.0 / v)));
        let (l, d) = (l.to_array(), d.to_array());
        std::array::from_fn(|i| (l[i], d[i]))
    }

    /// The dense 30-digit table of `tests/ref/smith_lambda.py`: (ν, Λ, ν ∂Λ/∂ν).
    fn reference() -> Vec<[f64; 3]> {
        let text = include_str!("../../../tests/ref/lambda_reference.csv");
        (text.lines().skip(1))
            .map(|l| {
                let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
                [v[0], v[1], v[2]]
            })
            .collect()
    }

    /// The lanes (fused and unfused portable, and through [`directions`] those this CPU
    /// runs) meet the module's accuracy against the dense reference: Λ to 1e-15 (1 + Λ),
    /// ν ∂Λ/∂ν to 1e-15 (1 + |·|).
    #[test]
    fn lanes_match_the_dense_reference() {
        let rows = reference();
        let cot_tan: Vec<(f64, f64)> = rows.iter().map(|r| (r[0], 1.0 / r[0])).collect();
        let mut dispatched = vec![(0.0, 0.0); rows.len()];
        directions(&cot_tan, (1.0, 1.0), &mut dispatched);
        let fused: Vec<(f64, f64)> = (rows.chunks(4))
            .flat_map(|c| lambda4::<Portable<true>>(std::array::from_fn(|i| c[i % c.len()][0])))
            .collect();
        let unfused: Vec<(f64, f64)> = (rows.chunks(4))
            .flat_map(|c| lambda4::<Portable<false>>(std::array::from_fn(|i| c[i % c.len()][0])))
            .collect();
        for (name, got) in [
            ("lanes", dispatched),
            ("fused", fused),
            ("unfused", unfused),
        ] {
            let (mut worst_l, mut worst_d) = (0.0f64, 0.0f64);
            for (r, &(l, d)) in rows.iter().zip(&got) {
                let el = (l - r[1]).abs() / (1.0 + r[1]);
                let ed = (d - r[2]).abs() / (1.0 + r[2].abs());
                assert!(
                    el < 1e-15 && ed < 1e-15,
                    "{name} ν={}: {l} {d} vs {r:?}",
                    r[0]
                );
                (worst_l, worst_d) = (worst_l.max(el), worst_d.max(ed));
            }
            println!("{name}: worst error of Λ {worst_l:.1e}, of ν∂Λ/∂ν {worst_d:.1e}");
        }
    }

    /// The ends: Λ = ∞ at grazing (ν = 0), 0 at normal incidence (ν = ∞) and beyond the
    /// clamp of e^{−ν²}; and [`directions`] gives every direction the same result whatever
    /// its place in the slice (the padded last lanes included).
    #[test]
    fn ends_and_padding() {
        let [g, n, far, edge] = lambda4::<Portable<true>>([0.0, f64::INFINITY, 30.0, 1.25]);
        assert_eq!(g.0, f64::INFINITY);
        assert_eq!(n, (0.0, -0.0));
        assert!(far.0 < 1e-22 && far.1.abs() < 1e-22);
        assert!(edge.0 > 0.0);
        let cot_tan: Vec<(f64, f64)> = (0..11)
            .map(|i| (0.37 * i as f64, 1.0 / (0.37 * i as f64)))
            .collect();
        let mut all = vec![(0.0, 0.0); 11];
        directions(&cot_tan, (1.3, 1.0 / 1.3), &mut all);
        for len in 0..11 {
            let mut part = vec![(0.0, 0.0); len];
            directions(&cot_tan[..len], (1.3, 1.0 / 1.3), &mut part);
            assert_eq!(part[..], all[..len]);
        }
        assert_eq!(all[0].0, f64::INFINITY);
    }

    /// The AVX2 + FMA lanes give the bits of the fused portable lanes, and the unfused
    /// portable lanes agree with both to 1e-15 (1 + |·|), at ν across every piece, its
    /// edges and both ends.
    #[test]
    fn lanes_agree_across_implementations() {
        let mut nus: Vec<f64> = (0..4000).map(|i| 1e-3 * 1.003f64.powi(i)).collect();
        for p in &E_PIECES {
            let x = p.nu_lo;
            nus.extend([x, x.next_up(), x.next_down(), x * (1.0 + 1e-9)]);
        }
        nus.extend([0.0, f64::INFINITY, 7.0, 7.1, 1e-300, 1e300]);
        nus.resize(nus.len().next_multiple_of(4), 1.0);
        for c in nus.chunks(4) {
            let c: [f64; 4] = [c[0], c[1], c[2], c[3]];
            let fused = lambda4::<Portable<true>>(c);
            let unfused = lambda4::<Portable<false>>(c);
            for (f, u) in fused.iter().zip(&unfused) {
                let close = |a: f64, b: f64| a == b || (a - b).abs() <= 1e-15 * (1.0 + a.abs());
                assert!(close(f.0, u.0) && close(f.1, u.1), "{c:?}: {f:?} {u:?}");
            }
            #[cfg(target_arch = "x86_64")]
            if crate::model::lanes::has_avx2_fma() {
                #[target_feature(enable = "avx2,fma")]
                unsafe fn avx(c: [f64; 4]) -> [(f64, f64); 4] {
                    lambda4::<crate::model::lanes::Avx>(c)
                }
                // SAFETY: the CPU has AVX2 and FMA (checked just above).
                let a = unsafe { avx(c) };
                let bits = |v: &[(f64, f64); 4]| v.map(|(l, d)| (l.to_bits(), d.to_bits()));
                assert_eq!(bits(&a), bits(&fused), "{c:?}");
            }
        }
    }
}
