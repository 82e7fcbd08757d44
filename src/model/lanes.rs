//! Four f64 lanes with the handful of operations the asymptotic KBS expansion needs
//! ([`super::series`]): fused multiply-add, lane shifts across two vectors, comparisons to
//! bit masks, and a fixed-order horizontal sum.
//!
//! Two implementations: on x86-64, [`Avx`] (AVX2 + FMA intrinsics, chosen at run time), and
//! [`Portable`] (plain arrays) everywhere. `Portable<true>` fuses its multiply-adds
//! (`f64::mul_add`) and gives the bits `Avx` gives (unit-tested op by op);
//! `Portable<false>` rounds the product and the sum separately, for CPUs without FMA,
//! where `f64::mul_add` is a slow library call. [`PortableNative`] is the one this build
//! runs when `Avx` cannot: fused where the target always has FMA (aarch64, or x86-64 built
//! with it), unfused otherwise. The compiler's own vectorisation of the same array code
//! picked 128-bit registers and spent most of its instructions shuffling lanes; written
//! against these types the expansion runs in 256-bit registers.
//!
//! Code written against these types must compile into the AVX2 + FMA function that runs
//! it (`with_lanes` in `series.rs`): `#[inline(always)]` functions, no closures. A closure
//! or a function that is not inlined is compiled without those features, and there every
//! fused multiply-add becomes a call to the `fma` library routine (correct, but it made
//! the series' fallback samples 4× slower once).

/// Four f64 lanes. Every operation is lane by lane unless it says otherwise; `shift1`,
/// `shift2`, `prefix_sum` and `hsum` fix their order of operations, so that both
/// implementations round alike.
pub(crate) trait F64x4: Copy {
    /// a · b + c on scalars, fused exactly when [`F64x4::mul_add`] is (so that the scalar
    /// code beside the lanes also rounds alike in both implementations).
    fn fma1(a: f64, b: f64, c: f64) -> f64;
    fn splat(x: f64) -> Self;
    fn from_array(a: [f64; 4]) -> Self;
    fn to_array(self) -> [f64; 4];
    /// self · m + c lane by lane, with [`F64x4::fma1`].
    fn mul_add(self, m: Self, c: Self) -> Self;
    fn mul(self, o: Self) -> Self;
    fn add(self, o: Self) -> Self;
    fn abs(self) -> Self;
    /// The larger of the two (the second when they are unordered).
    fn max(self, o: Self) -> Self;
    /// The smaller of the two (the second when they are unordered).
    fn min(self, o: Self) -> Self;
    /// self / o, correctly rounded.
    fn div(self, o: Self) -> Self;
    /// √self, correctly rounded.
    fn sqrt(self) -> Self;
    /// `if_ge` where self ≥ o (ordered), `otherwise` elsewhere.
    fn select_ge(self, o: Self, if_ge: Self, otherwise: Self) -> Self;
    /// 2^k for lanes that hold k + 1.5·2⁵² exactly (k an integer in [−1022, 1023]; what
    /// x + 1.5·2⁵² rounds x to): the low bits of the sum are k in two's complement.
    fn pow2_of_rounded(self) -> Self;
    /// [prev₃, cur₀, cur₁, cur₂]: the lanes of `cur` moved up one, `prev`'s last below.
    fn shift1(prev: Self, cur: Self) -> Self;
    /// [prev₂, prev₃, cur₀, cur₁].
    fn shift2(prev: Self, cur: Self) -> Self;
    /// Bit i set where self_i < o_i (false when unordered); likewise `le`, `gt`, `ge`.
    fn lt(self, o: Self) -> u32;
    fn le(self, o: Self) -> u32;
    fn gt(self, o: Self) -> u32;
    fn ge(self, o: Self) -> u32;
    /// (x₀ + x₂) + (x₁ + x₃).
    fn hsum(self) -> f64;
    /// Inclusive prefix sums: [x₀, x₀+x₁, x₀+(x₁+x₂), (x₀+x₁)+(x₂+x₃)].
    #[inline(always)]
    fn prefix_sum(self) -> Self {
        let zero = Self::splat(0.0);
        let s = self.add(Self::shift1(zero, self));
        s.add(Self::shift2(zero, s))
    }
}

/// The constants of the table-free e^x ([`exp`] lane by lane, the series' `exp_poly` one
/// value at a time): x = k ln 2 + r with ln 2 split into a high part (k·LN2_HI exact for
/// |k| ≤ 1010) and a low part, k rounded by adding MAGIC, and the Taylor coefficients
/// C[i] = 1/i! of e^r to degree 13.
pub(crate) mod exp_parts {
    /// 1/ln 2.
    pub(crate) const INV_LN2: f64 = std::f64::consts::LOG2_E;
    /// ln 2 to 32 bits.
    #[allow(clippy::excessive_precision, clippy::unreadable_literal)]
    pub(crate) const LN2_HI: f64 = 0.6931471803691238;
    /// ln 2 − LN2_HI.
    #[allow(clippy::excessive_precision, clippy::unreadable_literal)]
    pub(crate) const LN2_LO: f64 = 1.9082149292705877e-10;
    /// 1.5 · 2^52: adding it rounds to an integer.
    pub(crate) const MAGIC: f64 = 6_755_399_441_055_744.0;
    /// 1/i! for i = 0..=13.
    pub(crate) const C: [f64; 14] = {
        let mut c = [1.0f64; 14];
        let mut i = 2;
        while i < 14 {
            c[i] = c[i - 1] / i as f64;
            i += 1;
        }
        c
    };
}

/// e^x lane by lane for x ∈ [−700, 700] (clamped there; NaN gives NaN), without a table:
/// x = k ln 2 + r with |r| ≤ ln 2/2, e^r by its degree-13 Taylor polynomial (truncation
/// < 4e-18) in multiply-adds by Estrin's scheme, times 2^k through the exponent bits.
/// Relative error ≤ 2ε (ε = 2⁻⁵²) fused and unfused, asserted against std's `exp` at 2·10⁶
/// points of a grid over the whole domain, its ends and the clamp beyond them (measured
/// worst 1.94ε).
#[inline(always)]
pub(crate) fn exp<V: F64x4>(x: V) -> V {
    use exp_parts::{C, INV_LN2, LN2_HI, LN2_LO, MAGIC};
    let s = V::splat; // a function item, not a closure
    let x = s(700.0).min(s(-700.0).max(x));
    let kd = x.mul_add(s(INV_LN2), s(MAGIC));
    let k = kd.add(s(-MAGIC));
    let r = k.mul_add(s(-LN2_LO), k.mul_add(s(-LN2_HI), x));
    let r2 = r.mul(r);
    let r4 = r2.mul(r2);
    let r8 = r4.mul(r4);
    let q0 = r2.mul_add(r.mul_add(s(C[3]), s(C[2])), r.mul_add(s(C[1]), s(C[0])));
    let q1 = r2.mul_add(r.mul_add(s(C[7]), s(C[6])), r.mul_add(s(C[5]), s(C[4])));
    let q2 = r2.mul_add(r.mul_add(s(C[11]), s(C[10])), r.mul_add(s(C[9]), s(C[8])));
    let lo = r4.mul_add(q1, q0);
    let hi = r4.mul_add(r.mul_add(s(C[13]), s(C[12])), q2);
    r8.mul_add(hi, lo).mul(kd.pow2_of_rounded())
}

/// Plain arrays: runs everywhere; multiply-adds fused when `FUSED`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Portable<const FUSED: bool>([f64; 4]);

/// The portable lanes this build runs: fused where the target always has FMA.
pub(crate) type PortableNative =
    Portable<{ cfg!(any(target_feature = "fma", target_arch = "aarch64")) }>;

/// Bit i set where `holds(a_i, b_i)`.
#[inline(always)]
fn bits<const F: bool>(a: Portable<F>, b: Portable<F>, holds: impl Fn(f64, f64) -> bool) -> u32 {
    (0..4).fold(0, |m, i| m | (holds(a.0[i], b.0[i]) as u32) << i)
}

impl<const FUSED: bool> F64x4 for Portable<FUSED> {
    #[inline(always)]
    fn fma1(a: f64, b: f64, c: f64) -> f64 {
        if FUSED {
            a.mul_add(b, c)
        } else {
            a * b + c
        }
    }
    #[inline(always)]
    fn splat(x: f64) -> Self {
        Portable([x; 4])
    }
    #[inline(always)]
    fn from_array(a: [f64; 4]) -> Self {
        Portable(a)
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 4] {
        self.0
    }
    #[inline(always)]
    fn mul_add(self, m: Self, c: Self) -> Self {
        Portable(std::array::from_fn(|i| {
            Self::fma1(self.0[i], m.0[i], c.0[i])
        }))
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Portable(std::array::from_fn(|i| self.0[i] * o.0[i]))
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Portable(std::array::from_fn(|i| self.0[i] + o.0[i]))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Portable(self.0.map(f64::abs))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Portable(std::array::from_fn(|i| {
            if self.0[i] > o.0[i] {
                self.0[i]
            } else {
                o.0[i]
            }
        }))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Portable(std::array::from_fn(|i| {
            if self.0[i] < o.0[i] {
                self.0[i]
            } else {
                o.0[i]
            }
        }))
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        Portable(std::array::from_fn(|i| self.0[i] / o.0[i]))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Portable(self.0.map(f64::sqrt))
    }
    #[inline(always)]
    fn select_ge(self, o: Self, if_ge: Self, otherwise: Self) -> Self {
        Portable(std::array::from_fn(|i| {
            if self.0[i] >= o.0[i] {
                if_ge.0[i]
            } else {
                otherwise.0[i]
            }
        }))
    }
    #[inline(always)]
    fn pow2_of_rounded(self) -> Self {
        Portable(
            self.0
                .map(|k| f64::from_bits(k.to_bits().wrapping_add(1023) << 52)),
        )
    }
    #[inline(always)]
    fn shift1(prev: Self, cur: Self) -> Self {
        Portable([prev.0[3], cur.0[0], cur.0[1], cur.0[2]])
    }
    #[inline(always)]
    fn shift2(prev: Self, cur: Self) -> Self {
        Portable([prev.0[2], prev.0[3], cur.0[0], cur.0[1]])
    }
    #[inline(always)]
    fn lt(self, o: Self) -> u32 {
        bits(self, o, |x, y| x < y)
    }
    #[inline(always)]
    fn le(self, o: Self) -> u32 {
        bits(self, o, |x, y| x <= y)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> u32 {
        bits(self, o, |x, y| x > y)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> u32 {
        bits(self, o, |x, y| x >= y)
    }
    #[inline(always)]
    fn hsum(self) -> f64 {
        (self.0[0] + self.0[2]) + (self.0[1] + self.0[3])
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx::{has_avx2_fma, Avx};

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::F64x4;
    use std::arch::x86_64::*;

    /// AVX2 + FMA registers. Only ever created inside functions compiled with
    /// `#[target_feature(enable = "avx2,fma")]` that run after the CPU was checked for
    /// both (`has_avx2_fma`); the methods are `#[inline(always)]` so that they compile
    /// into those functions.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Avx(__m256d);

    /// Whether this CPU runs [`Avx`].
    pub(crate) fn has_avx2_fma() -> bool {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }

    /// Bit i set where the comparison `P` (an `_CMP_*` predicate) holds in lane i.
    #[inline(always)]
    fn mask<const P: i32>(a: Avx, b: Avx) -> u32 {
        // SAFETY: as for the methods below.
        unsafe { _mm256_movemask_pd(_mm256_cmp_pd::<P>(a.0, b.0)) as u32 }
    }

    // SAFETY (every `unsafe` block below): the intrinsics need AVX2/FMA, which the CPU has
    // whenever an `Avx` value exists (see the type's doc); they touch no memory except
    // through the references passed in.
    impl F64x4 for Avx {
        #[inline(always)]
        fn fma1(a: f64, b: f64, c: f64) -> f64 {
            // One vfmadd in the AVX2 + FMA functions these methods compile into.
            a.mul_add(b, c)
        }
        #[inline(always)]
        fn splat(x: f64) -> Self {
            unsafe { Avx(_mm256_set1_pd(x)) }
        }
        #[inline(always)]
        fn from_array(a: [f64; 4]) -> Self {
            unsafe { Avx(_mm256_loadu_pd(a.as_ptr())) }
        }
        #[inline(always)]
        fn to_array(self) -> [f64; 4] {
            let mut a = [0.0; 4];
            unsafe { _mm256_storeu_pd(a.as_mut_ptr(), self.0) };
            a
        }
        #[inline(always)]
        fn mul_add(self, m: Self, c: Self) -> Self {
            unsafe { Avx(_mm256_fmadd_pd(self.0, m.0, c.0)) }
        }
        #[inline(always)]
        fn mul(self, o: Self) -> Self {
            unsafe { Avx(_mm256_mul_pd(self.0, o.0)) }
        }
        #[inline(always)]
        fn add(self, o: Self) -> Self {
            unsafe { Avx(_mm256_add_pd(self.0, o.0)) }
        }
        #[inline(always)]
        fn abs(self) -> Self {
            unsafe { Avx(_mm256_andnot_pd(_mm256_set1_pd(-0.0), self.0)) }
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            // vmaxpd returns its second operand when unordered.
            unsafe { Avx(_mm256_max_pd(self.0, o.0)) }
        }
        #[inline(always)]
        fn min(self, o: Self) -> Self {
            // vminpd returns its second operand when unordered.
            unsafe { Avx(_mm256_min_pd(self.0, o.0)) }
        }
        #[inline(always)]
        fn div(self, o: Self) -> Self {
            unsafe { Avx(_mm256_div_pd(self.0, o.0)) }
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            unsafe { Avx(_mm256_sqrt_pd(self.0)) }
        }
        #[inline(always)]
        fn select_ge(self, o: Self, if_ge: Self, otherwise: Self) -> Self {
            unsafe {
                let m = _mm256_cmp_pd::<_CMP_GE_OQ>(self.0, o.0);
                Avx(_mm256_blendv_pd(otherwise.0, if_ge.0, m))
            }
        }
        #[inline(always)]
        fn pow2_of_rounded(self) -> Self {
            unsafe {
                let k = _mm256_add_epi64(_mm256_castpd_si256(self.0), _mm256_set1_epi64x(1023));
                Avx(_mm256_castsi256_pd(_mm256_slli_epi64::<52>(k)))
            }
        }
        #[inline(always)]
        fn shift1(prev: Self, cur: Self) -> Self {
            unsafe {
                // [p2, p3, c0, c1], then lanes (p3, c0, c1, c2).
                let mid = _mm256_permute2f128_pd::<0x21>(prev.0, cur.0);
                Avx(_mm256_shuffle_pd::<0b0101>(mid, cur.0))
            }
        }
        #[inline(always)]
        fn shift2(prev: Self, cur: Self) -> Self {
            unsafe { Avx(_mm256_permute2f128_pd::<0x21>(prev.0, cur.0)) }
        }
        #[inline(always)]
        fn lt(self, o: Self) -> u32 {
            mask::<_CMP_LT_OQ>(self, o)
        }
        #[inline(always)]
        fn le(self, o: Self) -> u32 {
            mask::<_CMP_LE_OQ>(self, o)
        }
        #[inline(always)]
        fn gt(self, o: Self) -> u32 {
            mask::<_CMP_GT_OQ>(self, o)
        }
        #[inline(always)]
        fn ge(self, o: Self) -> u32 {
            mask::<_CMP_GE_OQ>(self, o)
        }
        #[inline(always)]
        fn hsum(self) -> f64 {
            unsafe {
                let s = _mm_add_pd(
                    _mm256_castpd256_pd128(self.0),
                    _mm256_extractf128_pd::<1>(self.0),
                );
                _mm_cvtsd_f64(_mm_add_sd(s, _mm_unpackhi_pd(s, s)))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A repeatable stream of test values: a third of them zeros of both signs,
    /// infinities, NaN, the smallest subnormal, 1e308 and repeated values (ties), the rest
    /// spread over forty decades.
    #[cfg(target_arch = "x86_64")]
    fn test_values() -> impl FnMut() -> f64 {
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.5,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            5e-324,
            1e308,
            0.1,
            0.1,
            3.0,
        ];
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            if state % 3 == 0 {
                special[(state >> 8) as usize % special.len()]
            } else {
                (((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5)
                    * 10f64.powi((state % 40) as i32 - 20)
            }
        }
    }

    /// Equal bits lane by lane, or NaN in both (the compiler may commute an addition, which
    /// changes which of two NaN operands' payloads the sum carries).
    #[cfg(target_arch = "x86_64")]
    fn same(p: [f64; 4], q: [f64; 4]) -> bool {
        (p.iter().zip(&q)).all(|(x, y)| x.to_bits() == y.to_bits() || x.is_nan() && y.is_nan())
    }

    /// Every operation of [`Avx`] gives the bits fused [`Portable`] lanes give, on values
    /// that include zeros of both signs, infinities, NaN, subnormals and ties.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx_matches_portable_bit_for_bit() {
        if !avx::has_avx2_fma() {
            return;
        }
        #[target_feature(enable = "avx2,fma")]
        unsafe fn run() {
            type P = Portable<true>;
            let mut next = test_values();
            for _ in 0..20_000 {
                let (x, y, z) = (
                    [next(), next(), next(), next()],
                    [next(), next(), next(), next()],
                    [next(), next(), next(), next()],
                );
                let (px, py, pz) = (P::from_array(x), P::from_array(y), P::from_array(z));
                let (ax, ay, az) = (Avx::from_array(x), Avx::from_array(y), Avx::from_array(z));
                let rounded = |v: [f64; 4]| {
                    v.map(|x| (x * 1e3).clamp(-1022.0, 1023.0).round() + 6_755_399_441_055_744.0)
                };
                let (pk, ak) = (P::from_array(rounded(x)), Avx::from_array(rounded(x)));
                let pairs: [([f64; 4], [f64; 4]); 14] = [
                    (px.div(py).to_array(), ax.div(ay).to_array()),
                    (px.sqrt().to_array(), ax.sqrt().to_array()),
                    (
                        px.select_ge(py, pz, px).to_array(),
                        ax.select_ge(ay, az, ax).to_array(),
                    ),
                    (px.min(py).to_array(), ax.min(ay).to_array()),
                    (
                        pk.pow2_of_rounded().to_array(),
                        ak.pow2_of_rounded().to_array(),
                    ),
                    (px.mul_add(py, pz).to_array(), ax.mul_add(ay, az).to_array()),
                    (px.mul(py).to_array(), ax.mul(ay).to_array()),
                    (px.add(py).to_array(), ax.add(ay).to_array()),
                    (px.abs().to_array(), ax.abs().to_array()),
                    (px.max(py).to_array(), ax.max(ay).to_array()),
                    (P::shift1(px, py).to_array(), Avx::shift1(ax, ay).to_array()),
                    (P::shift2(px, py).to_array(), Avx::shift2(ax, ay).to_array()),
                    (px.prefix_sum().to_array(), ax.prefix_sum().to_array()),
                    (
                        [P::splat(x[1]).hsum(), px.hsum(), 0.0, 0.0],
                        [Avx::splat(x[1]).hsum(), ax.hsum(), 0.0, 0.0],
                    ),
                ];
                for (i, (p, a)) in pairs.iter().enumerate() {
                    assert!(same(*p, *a), "op {i}: {x:?} {y:?} {z:?}: {p:?} != {a:?}");
                }
                assert_eq!(px.lt(py), ax.lt(ay));
                assert_eq!(px.le(py), ax.le(ay));
                assert_eq!(px.gt(py), ax.gt(ay));
                assert_eq!(px.ge(py), ax.ge(ay));
                assert_eq!(
                    P::fma1(x[0], y[0], z[0]).to_bits(),
                    Avx::fma1(x[0], y[0], z[0]).to_bits()
                );
            }
        }
        // SAFETY: the CPU has AVX2 and FMA (checked above).
        unsafe { run() };
    }

    #[test]
    fn portable_lane_order() {
        type P = Portable<false>;
        let x = P::from_array([1.0, 2.0, 4.0, 8.0]);
        let p = P::from_array([-1.0, -2.0, -3.0, -4.0]);
        assert_eq!(P::shift1(p, x).to_array(), [-4.0, 1.0, 2.0, 4.0]);
        assert_eq!(P::shift2(p, x).to_array(), [-3.0, -4.0, 1.0, 2.0]);
        assert_eq!(x.prefix_sum().to_array(), [1.0, 3.0, 7.0, 15.0]);
        assert_eq!(x.hsum(), 15.0);
        assert_eq!(x.lt(P::splat(3.0)), 0b0011);
        assert_eq!(x.ge(P::splat(4.0)), 0b1100);
    }

    /// [`exp`] against std's over its whole domain (a dense grid, its ends, and the clamp
    /// beyond them), fused and unfused: relative error at most 2ε.
    #[test]
    fn exp_matches_std_over_its_domain() {
        fn worst<V: F64x4>() -> f64 {
            let mut worst = 0.0f64;
            let mut check = |x: [f64; 4]| {
                let got = exp(V::from_array(x)).to_array();
                for (g, x) in got.iter().zip(x) {
                    let want = x.clamp(-700.0, 700.0).exp();
                    worst = worst.max((g - want).abs() / (want * f64::EPSILON));
                }
            };
            let n = 2_000_000;
            for i in (0..=n).step_by(4) {
                check(std::array::from_fn(|l| {
                    -700.0 + 1400.0 * (i + l) as f64 / n as f64
                }));
            }
            check([-700.0, 700.0, 0.0, -0.0]);
            check([-800.0, 800.0, f64::MIN_POSITIVE, -1e-300]);
            check([
                0.5 * std::f64::consts::LN_2,
                -0.5 * std::f64::consts::LN_2,
                1e-17,
                -50.0,
            ]);
            worst
        }
        for w in [worst::<Portable<true>>(), worst::<Portable<false>>()] {
            println!("lanes exp: worst relative error {w:.2} ε");
            assert!(w <= 2.0, "worst relative error {w} ε");
        }
        assert_eq!(exp(Portable::<true>::splat(0.0)).to_array(), [1.0; 4]);
        assert!(exp(Portable::<true>::splat(f64::NAN)).to_array()[0].is_nan());
    }

    #[test]
    fn pow2_of_rounded_is_exact() {
        for k in -1022..=1023 {
            let v = Portable::<false>::splat(k as f64 + 6_755_399_441_055_744.0);
            assert_eq!(v.pow2_of_rounded().to_array(), [2f64.powi(k); 4], "k={k}");
        }
    }

    #[test]
    fn fused_rounds_once_unfused_twice() {
        // (1 + 2^−30)(1 − 2^−30) − 1 = −2^−60 exactly; the product alone rounds to 1.
        let e = 2f64.powi(-30);
        let (a, b, c) = (1.0 + e, 1.0 - e, -1.0);
        assert_eq!(Portable::<true>::fma1(a, b, c), -e * e);
        assert_eq!(Portable::<false>::fma1(a, b, c), 0.0);
        let v = |x| Portable::<true>::splat(x);
        assert_eq!(v(a).mul_add(v(b), v(c)).to_array(), [-e * e; 4]);
    }
}
