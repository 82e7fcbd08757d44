//! The Fresnel factor of many samples four at a time ([`conductor`], [`dielectric`]):
//! [`super::complex_ratio`]'s and [`super::real_ratio`]'s formulas in the lanes
//! [`with_lanes`] picks (AVX2 + FMA where the CPU has them); for the conductor the branch
//! on the sign of Re w² as a lane select and U⁻¹, D⁻¹ as two divisions.
//!
//! The same F, ∂F/∂n and ∂F/∂κ as the scalar forms up to rounding (fused multiply-adds,
//! the divisions): within 1e-14 (|F| + |∂F|) of them (unit-tested over n 0.05–10,
//! κ 1e-3–10 and n 1.001–10 for the dielectric, cos θ_loc 0–1, with the bits of the AVX2
//! lanes equal to those of the fused portable lanes), so to the module's accuracy against
//! the reference.

use super::{complex_ratio, FresnelValue};
use crate::model::lanes::F64x4;
use crate::model::series::{with_lanes, LanesFn};

/// Which form [`each`] evaluates.
#[derive(Debug, Clone, Copy)]
enum Form {
    /// η = n + iκ with n > 0, κ > 0, 2nκ > 0 finite.
    Conductor(f64, f64),
    /// Real n > 1.
    Dielectric(f64),
}

/// F(θ_loc; n + iκ) with ∂F/∂n and ∂F/∂κ at every `cos_loc` (∈ [0, 1]) into `out`, for
/// n > 0, κ > 0 with 2nκ > 0 a finite double (elsewhere each sample by
/// [`super::complex_ratio`]). Panics if the slices differ in length.
pub(crate) fn conductor(cos_loc: &[f64], n: f64, kappa: f64, out: &mut [FresnelValue]) {
    assert_eq!(cos_loc.len(), out.len());
    let ei = 2.0 * n * kappa;
    if !(n > 0.0 && kappa > 0.0 && ei > 0.0 && ei.is_finite()) {
        for (o, &c) in out.iter_mut().zip(cos_loc) {
            *o = complex_ratio(c, n, kappa);
        }
        return;
    }
    each(cos_loc, Form::Conductor(n, kappa), out);
}

/// F(θ_loc; n) with ∂F/∂n (∂F/∂κ = 0) at every `cos_loc` (∈ [0, 1]) into `out`, for a
/// real index n > 1 ([`super::real_ratio`]'s domain; elsewhere each sample by
/// [`super::complex_ratio`] at κ = 0); F = 1, ∂F/∂n = 0 from [`super::FLAT_INDEX`] on, as
/// [`super::Fresnel::eval`] gives. Panics if the slices differ in length.
pub(crate) fn dielectric(cos_loc: &[f64], n: f64, out: &mut [FresnelValue]) {
    assert_eq!(cos_loc.len(), out.len());
    if n >= super::FLAT_INDEX {
        out.fill(FresnelValue::ONE);
        return;
    }
    if n.is_nan() || n <= 1.0 {
        for (o, &c) in out.iter_mut().zip(cos_loc) {
            *o = complex_ratio(c, n, 0.0);
        }
        return;
    }
    each(cos_loc, Form::Dielectric(n), out);
}

/// `form`'s F at every `cos_loc` into `out` (of the same length), four at a time; the last
/// few samples padded with normal incidence.
fn each(cos_loc: &[f64], form: Form, out: &mut [FresnelValue]) {
    struct Call<'s>(&'s [f64], Form, &'s mut [FresnelValue]);
    impl LanesFn for Call<'_> {
        type Out = ();
        #[inline(always)]
        fn call<V: F64x4>(self) {
            let Call(cos_loc, form, out) = self;
            let mut chunks = cos_loc.chunks_exact(4);
            let mut outs = out.chunks_exact_mut(4);
            for (c, o) in (&mut chunks).zip(&mut outs) {
                four::<V>([c[0], c[1], c[2], c[3]], form, o);
            }
            let (rest, o) = (chunks.remainder(), outs.into_remainder());
            if !rest.is_empty() {
                let mut c = [1.0; 4];
                c[..rest.len()].copy_from_slice(rest);
                let mut tail = [FresnelValue::ONE; 4];
                four::<V>(c, form, &mut tail);
                o.copy_from_slice(&tail[..rest.len()]);
            }
        }
    }
    with_lanes(Call(cos_loc, form, out));
}

/// [`each`] of four samples into `out[..4]`.
#[inline(always)]
fn four<V: F64x4>(c: [f64; 4], form: Form, out: &mut [FresnelValue]) {
    let (f, d_n, d_kappa) = match form {
        Form::Conductor(n, kappa) => ratio(V::from_array(c), (n, kappa)),
        Form::Dielectric(n) => {
            let (f, d_n) = real(V::from_array(c), n);
            (f, d_n, V::splat(0.0))
        }
    };
    let (f, d_n, d_kappa) = (f.to_array(), d_n.to_array(), d_kappa.to_array());
    for i in 0..4 {
        out[i] = FresnelValue {
            f: f[i],
            d_n: d_n[i],
            d_kappa: d_kappa[i],
        };
    }
}

/// −x.
#[inline(always)]
fn neg<V: F64x4>(x: V) -> V {
    x.mul(V::splat(-1.0))
}

/// The complex product (a + ib)(c + id) as (re, im).
#[inline(always)]
fn cmul<V: F64x4>((a, b): (V, V), (c, d): (V, V)) -> (V, V) {
    (a.mul_add(c, neg(b.mul(d))), a.mul_add(d, b.mul(c)))
}

/// w = a + ib = √(η² − 1 + c²) (principal root) with x = Re w² and |w²|, for
/// Im η² = `ei` > 0 ([`super::complex_ratio`]'s form without cancellation).
#[inline(always)]
fn root<V: F64x4>(c2: V, er: f64, ei: f64) -> (V, V, V) {
    let s = V::splat;
    let x = c2.mul_add(s(-1.0), s(1.0)).mul_add(s(-1.0), s(er));
    let w_abs2 = x.mul_add(x, s(ei * ei)).sqrt();
    let t = w_abs2.add(x.abs()).mul(s(0.5)).sqrt();
    let r = s(ei).div(t.add(t));
    let zero = s(0.0);
    (x.select_ge(zero, t, r), x.select_ge(zero, r, t), w_abs2)
}

/// F, ∂F/∂n, ∂F/∂κ lane by lane at cos θ_loc = `c` for η = n + iκ (module doc of
/// [`super`]: F = |1 + η|⁴ (|A_s|² + |A_p|²)/2).
#[inline(always)]
fn ratio<V: F64x4>(c: V, (n, kappa): (f64, f64)) -> (V, V, V) {
    let s = V::splat;
    let (er, ei) = (n * n - kappa * kappa, 2.0 * n * kappa);
    let c2 = c.mul(c);
    let (a, b, w_abs2) = root(c2, er, ei);
    let ca = c.add(a);
    let u = ca.mul_add(ca, b.mul(b));
    let (dr, di) = (c.mul_add(s(er), a), c.mul_add(s(ei), b));
    let d = dr.mul_add(dr, di.mul(di));
    let (nr, ni) = (c2.mul_add(s(er), c2.add(s(-1.0))), c2.mul(s(ei)));
    let np = nr.mul_add(nr, ni.mul(ni));
    let (u_inv, d_inv) = (s(1.0).div(u), s(1.0).div(d));
    let kn = d_inv.mul(d_inv);
    let m = u_inv.mul_add(u_inv, np.mul(kn)).mul(s(0.5));
    let q = (1.0 + n) * (1.0 + n) + kappa * kappa;
    let p = q * q;
    // ∂M/∂n = Re Z, ∂M/∂κ = −Im Z with Z = −2U⁻³ z_s + D⁻² z_n − 2|N|² D⁻³ z_d.
    let inv_w2 = s(1.0).div(w_abs2);
    let w1 = cmul((s(n), s(kappa)), (a.mul(inv_w2), neg(b.mul(inv_w2))));
    let zs = cmul((ca, neg(b)), w1);
    let c2x2 = c2.add(c2);
    let zn = cmul((nr, neg(ni)), (c2x2.mul(s(n)), c2x2.mul(s(kappa))));
    let cx2 = c.add(c);
    let zd = cmul(
        (dr, neg(di)),
        (cx2.mul_add(s(n), w1.0), cx2.mul_add(s(kappa), w1.1)),
    );
    let ks = u_inv.mul(u_inv).mul(u_inv).mul(s(-2.0));
    let kd = np.mul(kn).mul(d_inv).mul(s(-2.0));
    let z_re = ks.mul_add(zs.0, kn.mul_add(zn.0, kd.mul(zd.0)));
    let z_im = ks.mul_add(zs.1, kn.mul_add(zn.1, kd.mul(zd.1)));
    let f = m.mul(s(p));
    let d_n = m.mul_add(s(4.0 * q * (1.0 + n)), z_re.mul(s(p)));
    let d_kappa = m.mul_add(s(4.0 * q * kappa), neg(z_im.mul(s(p))));
    (f, d_n, d_kappa)
}

/// F and ∂F/∂n lane by lane at cos θ_loc = `c` for a real index n > 1
/// ([`super::real_ratio`]'s formulas: one division).
#[inline(always)]
fn real<V: F64x4>(c: V, n: f64) -> (V, V) {
    let s = V::splat;
    let n2 = n * n;
    let c2 = c.mul(c);
    let w = c2.add(s(n2 - 1.0)).sqrt();
    let (u, d) = (c.add(w), c.mul_add(s(n2), w));
    let ud = u.mul(d);
    let inv = s(1.0).div(w.mul(ud));
    let dw = ud.mul(inv).mul(s(n));
    let u_inv = w.mul(d).mul(inv);
    let a_s = u_inv.mul(u_inv);
    let da_s = a_s.mul(dw).mul(u_inv).mul(s(-2.0));
    let num = c2.mul_add(s(n2), c2.add(s(-1.0)));
    let d_inv = w.mul(u).mul(inv);
    let d_inv2 = d_inv.mul(d_inv);
    let a_p = num.mul(d_inv2);
    let da_p = d_inv2.mul(c2).mul(s(2.0 * n)).mul_add(
        s(1.0),
        a_p.mul(c.mul_add(s(2.0 * n), dw)).mul(d_inv).mul(s(-2.0)),
    );
    let m = a_s.mul_add(a_s, a_p.mul(a_p)).mul(s(0.5));
    let q = (1.0 + n) * (1.0 + n);
    let p = q * q;
    let d_n = m.mul_add(
        s(4.0 * q * (1.0 + n)),
        a_s.mul_add(da_s, a_p.mul(da_p)).mul(s(p)),
    );
    (m.mul(s(p)), d_n)
}

#[cfg(test)]
mod tests {
    use super::super::real_ratio;
    use super::*;
    use crate::model::lanes::Portable;

    #[inline(always)]
    fn ratio4<V: F64x4>(c: [f64; 4], (n, kappa): (f64, f64)) -> [FresnelValue; 4] {
        let mut out = [FresnelValue::ONE; 4];
        let form = if kappa == 0.0 {
            Form::Dielectric(n)
        } else {
            Form::Conductor(n, kappa)
        };
        four::<V>(c, form, &mut out);
        out
    }

    /// The indices and angles of the tests: n 0.05–10, κ 1e-3–10 (κ = 0: the dielectric,
    /// n 1.001–10), cos θ_loc 0–1 with both ends.
    fn grid() -> Vec<((f64, f64), [f64; 4])> {
        let mut v = Vec::new();
        for n in [0.05, 0.2, 0.5, 0.9, 1.0, 1.01, 1.5, 2.5, 4.0, 10.0] {
            for kappa in [1e-3, 0.05, 0.5, 1.0, 2.0, 3.7, 10.0] {
                for j in 0..64 {
                    let c: [f64; 4] = std::array::from_fn(|l| (4 * j + l) as f64 / 255.0);
                    v.push(((n, kappa), c));
                }
            }
        }
        for n in [1.001, 1.01, 1.2, 1.5, 2.5, 4.0, 10.0] {
            for j in 0..64 {
                let c: [f64; 4] = std::array::from_fn(|l| (4 * j + l) as f64 / 255.0);
                v.push(((n, 0.0), c));
            }
        }
        v
    }

    /// Within 1e-14 (|F| + |∂F|) of [`complex_ratio`] and [`real_ratio`], fused and
    /// unfused, and through [`conductor`] and [`dielectric`] (the lanes this CPU runs, and
    /// the remainder's padding).
    #[test]
    fn lanes_match_the_scalar_form() {
        let mut worst = 0.0f64;
        let mut check = |got: FresnelValue, c: f64, (n, k): (f64, f64)| {
            let want = if k == 0.0 {
                real_ratio(c, n)
            } else {
                complex_ratio(c, n, k)
            };
            let scale = want.f.abs() + want.d_n.abs() + want.d_kappa.abs();
            for (g, w) in [
                (got.f, want.f),
                (got.d_n, want.d_n),
                (got.d_kappa, want.d_kappa),
            ] {
                let e = (g - w).abs() / scale;
                assert!(e < 1e-14, "n={n} κ={k} c={c}: {got:?} vs {want:?}");
                worst = worst.max(e);
            }
        };
        for (eta, c) in grid() {
            let (fused, unfused) = (
                ratio4::<Portable<true>>(c, eta),
                ratio4::<Portable<false>>(c, eta),
            );
            for l in 0..4 {
                check(fused[l], c[l], eta);
                check(unfused[l], c[l], eta);
            }
        }
        let cs: Vec<f64> = (0..23).map(|i| i as f64 / 22.0).collect();
        let mut out = vec![FresnelValue::ONE; cs.len()];
        conductor(&cs, 0.3, 2.9, &mut out);
        for (o, &c) in out.iter().zip(&cs) {
            check(*o, c, (0.3, 2.9));
        }
        dielectric(&cs, 1.7, &mut out);
        for (o, &c) in out.iter().zip(&cs) {
            check(*o, c, (1.7, 0.0));
        }
        println!("Fresnel lanes: worst difference from the scalar form {worst:.1e}");
    }

    /// The AVX2 + FMA lanes give the bits of the fused portable lanes.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx_lanes_give_the_fused_bits() {
        if !crate::model::lanes::has_avx2_fma() {
            return;
        }
        #[target_feature(enable = "avx2,fma")]
        unsafe fn avx(c: [f64; 4], eta: (f64, f64)) -> [FresnelValue; 4] {
            ratio4::<crate::model::lanes::Avx>(c, eta)
        }
        for (eta, c) in grid() {
            // SAFETY: the CPU has AVX2 and FMA (checked above).
            let a = unsafe { avx(c, eta) };
            let p = ratio4::<Portable<true>>(c, eta);
            let bits = |v: [FresnelValue; 4]| v.map(|f| [f.f, f.d_n, f.d_kappa].map(f64::to_bits));
            assert_eq!(bits(a), bits(p), "{eta:?} {c:?}");
        }
    }
}
