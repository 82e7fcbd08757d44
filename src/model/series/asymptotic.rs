//! The asymptotic completion of the rough approximation (eq. 43): e^{−g} S as
//! (e^{−a/g}/g) Σ_n P_n(b) g^{−n}, b = a/g, with the polynomials P_n built at compile time
//! and the orders evaluated four at a time in four-lane vectors. The derivation, the
//! acceptance rule and the checks are in the parent module's doc.

use super::super::lanes::F64x4;
use super::super::Mode;
use super::terms::LnQ;

/// Highest order of the asymptotic expansion tabulated.
pub(crate) const ASYM_ORDERS: usize = 18;
const ASYM_DEG: usize = 2 * ASYM_ORDERS + 4; // ≥ 2n + 1, padded to a multiple of 4
const ASYM_K: usize = 2 * ASYM_ORDERS + 1;

/// P_n(b) coefficients: `ASYM[n][i]` multiplies b^i g^{−n}.
#[cfg(test)]
pub(super) static ASYM: [[f64; ASYM_DEG]; ASYM_ORDERS + 1] = asym_table();

/// Orders in blocks of four for the Horner scheme on four vectors of four lanes:
/// `ASYM_BLK[k][j]` holds, for the orders n = 4k+1..4k+4 (lane l = n − 4k − 1), the
/// vectors [P_n[2j], P_n[2j+1], P_n'[2j], P_n'[2j+1]]: the coefficients of b^{2j} and
/// b^{2j+1}; j runs to 4k + 4 (degree 2n ≤ 8k + 8), orders beyond [`ASYM_ORDERS`] are zero.
static ASYM_BLK: [[[[f64; 4]; 4]; ASYM_J]; ASYM_BLOCKS] = asym_blocks();
const ASYM_BLOCKS: usize = ASYM_ORDERS.div_ceil(4);
const ASYM_J: usize = 4 * ASYM_BLOCKS + 1;

const fn asym_blocks() -> [[[[f64; 4]; 4]; ASYM_J]; ASYM_BLOCKS] {
    let p = asym_table();
    let d = asym_deriv_table();
    let mut t = [[[[0.0f64; 4]; 4]; ASYM_J]; ASYM_BLOCKS];
    let mut k = 0;
    while k < ASYM_BLOCKS {
        let mut l = 0;
        while l < 4 {
            let n = 4 * k + l + 1;
            let mut j = 0;
            while n <= ASYM_ORDERS && j < ASYM_J && 2 * j + 1 < ASYM_DEG {
                t[k][j][0][l] = p[n][2 * j];
                t[k][j][1][l] = p[n][2 * j + 1];
                t[k][j][2][l] = d[n][2 * j];
                t[k][j][3][l] = d[n][2 * j + 1];
                j += 1;
            }
            l += 1;
        }
        k += 1;
    }
    t
}

/// P_n'(b) coefficients: `[n][i] = (i+1) P_n[i+1]`.
const fn asym_deriv_table() -> [[f64; ASYM_DEG]; ASYM_ORDERS + 1] {
    let p = asym_table();
    let mut d = [[0.0f64; ASYM_DEG]; ASYM_ORDERS + 1];
    let mut n = 0;
    while n <= ASYM_ORDERS {
        let mut i = 0;
        while i + 1 < ASYM_DEG {
            d[n][i] = (i + 1) as f64 * p[n][i + 1];
            i += 1;
        }
        n += 1;
    }
    d
}

/// Build the table of P_n (see the module doc) at compile time.
const fn asym_table() -> [[f64; ASYM_DEG]; ASYM_ORDERS + 1] {
    let mu = poisson_moments();
    let c = damped_exp_coefficients(&exp_coefficients());
    // P_n(b) = Σ_{k=n+1}^{2n} c_k(b) mu[k][k−n], P_0 = 1.
    let mut p = [[0.0f64; ASYM_DEG]; ASYM_ORDERS + 1];
    p[0][0] = 1.0;
    let mut n = 1;
    while n <= ASYM_ORDERS {
        let mut k = n + 1;
        while k <= 2 * n {
            let w = mu[k][k - n];
            let mut i = 0;
            while i < ASYM_K {
                p[n][i] += c[k][i] * w;
                i += 1;
            }
            k += 1;
        }
        n += 1;
    }
    p
}

/// The Poisson central moments as polynomials in g (`mu[k][j]`, the coefficient of g^j in
/// μ_k), for k < `ASYM_K`.
const fn poisson_moments() -> [[f64; ASYM_K]; ASYM_K] {
    // Poisson central moments μ_k(g) = Σ_j mu[k][j] g^j: μ0 = 1, μ1 = 0,
    // μ_{k+1} = g (k μ_{k−1} + dμ_k/dg).
    let mut mu = [[0.0f64; ASYM_K]; ASYM_K];
    mu[0][0] = 1.0;
    let mut k = 1;
    while k < ASYM_K {
        let mut j = 0;
        while j < ASYM_K {
            let mut v = 0.0;
            if j >= 1 && k >= 2 {
                v += (k - 1) as f64 * mu[k - 2][j - 1];
            }
            v += j as f64 * mu[k - 1][j];
            mu[k][j] = v;
            j += 1;
        }
        k += 1;
    }
    mu
}

/// The coefficients in b of the series of exp(b x/(1+x)) in x (`e[k][i]`, the coefficient
/// of b^i in the x^k term), for k < `ASYM_K`.
const fn exp_coefficients() -> [[f64; ASYM_K]; ASYM_K] {
    // e_k(b): coefficients of exp(b x/(1+x)) = Σ_k e_k(b) x^k,
    // e_k[i] = (−1)^{k−i} C(k−1, i−1)/i! (k ≥ 1), e_0 = 1.
    let mut e = [[0.0f64; ASYM_K]; ASYM_K];
    e[0][0] = 1.0;
    let mut k = 1;
    while k < ASYM_K {
        let mut i = 1;
        while i <= k {
            // C(k−1, i−1)/i!
            let mut c = 1.0;
            let mut t = 1;
            while t < i {
                c = c * (k - t) as f64 / t as f64;
                t += 1;
            }
            let mut fact = 1.0;
            let mut t = 2;
            while t <= i {
                fact *= t as f64;
                t += 1;
            }
            let sign = if (k - i) % 2 == 0 { 1.0 } else { -1.0 };
            e[k][i] = sign * c / fact;
            i += 1;
        }
        k += 1;
    }
    e
}

/// The coefficients in b of the series of (1+x)^{−1} exp(b x/(1+x)) in x, from those of
/// exp(b x/(1+x)) ([`exp_coefficients`]).
const fn damped_exp_coefficients(e: &[[f64; ASYM_K]; ASYM_K]) -> [[f64; ASYM_K]; ASYM_K] {
    // c_k(b) = Σ_{j≤k} (−1)^{k−j} e_j(b): the coefficients of (1+x)^{−1} exp(b x/(1+x)).
    let mut c = [[0.0f64; ASYM_K]; ASYM_K];
    let mut k = 0;
    while k < ASYM_K {
        let mut j = 0;
        while j <= k {
            let sign = if (k - j) % 2 == 0 { 1.0 } else { -1.0 };
            let mut i = 0;
            while i < ASYM_K {
                c[k][i] += sign * e[j][i];
                i += 1;
            }
            j += 1;
        }
        k += 1;
    }
    c
}

/// Smallest g for which `auto` tries the asymptotic expansion.
pub(super) const ASYM_G_MIN: f64 = 40.0;

#[inline(always)]
pub(super) fn asymptotic_body<V: F64x4>(g: f64, a: f64, tol: f64) -> Option<LnQ> {
    let b = a / g;
    let x = 1.0 / g;
    let target = 0.5 * tol;
    let (bv, yv) = (V::splat(b), V::splat(b * b));
    let mut sums = AsymSums::<V>::start(target, x, b);
    // Where the first eight orders are needed anyway (the error of order 4 is ~ 5·4!/g^4
    // times a decay of ~5/g: above 0.15 tol while g^5 tol < 4e3), block 1's polynomials are
    // evaluated before block 0 is tested, so that the two Horner chains overlap.
    let paired = {
        let g2 = g * g;
        g2 * g2 * g * tol < 4e3
    };
    // Blocks 0 and 1 with constant k (their Horner loops unroll), the rest in a loop.
    let block1 = if paired {
        Some(block_polynomials::<V>(1, bv, yv))
    } else {
        None
    };
    let (p, dp) = block_polynomials::<V>(0, bv, yv);
    if let Some(done) = sums.add_block(0, p, dp) {
        return done.map(|s| asymptotic_result(b, x, s));
    }
    let (p, dp) = match block1 {
        Some(pd) => pd,
        None => block_polynomials::<V>(1, bv, yv),
    };
    if let Some(done) = sums.add_block(1, p, dp) {
        return done.map(|s| asymptotic_result(b, x, s));
    }
    for k in 2..ASYM_BLOCKS {
        let (p, dp) = block_polynomials::<V>(k, bv, yv);
        if let Some(done) = sums.add_block(k, p, dp) {
            return done.map(|s| asymptotic_result(b, x, s));
        }
    }
    None
}

/// P_n(b) and P_n'(b) of the orders n = 4k+1..4k+4, lane by lane: P_n(b) = E(b²) + b O(b²)
/// and P_n'(b) = E'(b²) + b O'(b²) (even/odd split), Horner in y = b² on four vectors
/// (E, O, E', O'; a lower order's leading coefficients are zero, which leaves its chain
/// exact) over the block's 4k + 5 rows of [`ASYM_BLK`].
#[inline(always)]
fn block_polynomials<V: F64x4>(k: usize, b: V, y: V) -> (V, V) {
    let rows = &ASYM_BLK[k][..4 * k + 5];
    let mut v = rows[4 * k + 4].map(V::from_array);
    for row in rows[..4 * k + 4].iter().rev() {
        for (vk, rk) in v.iter_mut().zip(row) {
            *vk = vk.mul_add(y, V::from_array(*rk));
        }
    }
    (v[1].mul_add(b, v[0]), v[3].mul_add(b, v[2]))
}

/// The asymptotic expansion's running state: R = Σ g^{−n} P_n(b), r_g = g ∂R/∂g|_b =
/// −Σ n g^{−n} P_n, r_b = ∂R/∂b over the orders added so far; the sizes and error
/// estimates of the last block's four orders; the next block's weights g^{−n}.
struct AsymSums<V> {
    r: f64,
    r_g: f64,
    r_b: f64,
    size: V,
    err: V,
    /// 0.3 × the target for the estimated error relative to R.
    accept: V,
    /// g^{−n} of the next block's four orders.
    weights: V,
    /// g^{−4}: from one block's weights to the next block's.
    g_4: V,
    b: V,
}

/// The expansion's result: R, r_g, r_b (see [`AsymSums`]).
struct AsymTotal {
    r: f64,
    r_g: f64,
    r_b: f64,
}

/// `LANES_UPTO[i]`: 1 in lanes 0..=i, 0 above.
const LANES_UPTO: [[f64; 4]; 4] = [
    [1.0, 0.0, 0.0, 0.0],
    [1.0, 1.0, 0.0, 0.0],
    [1.0, 1.0, 1.0, 0.0],
    [1.0, 1.0, 1.0, 1.0],
];

impl<V: F64x4> AsymSums<V> {
    #[inline(always)]
    fn start(target: f64, x: f64, b: f64) -> Self {
        let x2 = x * x;
        let x4 = x2 * x2;
        AsymSums {
            r: 1.0,
            r_g: 0.0,
            r_b: 0.0,
            size: V::splat(f64::INFINITY),
            err: V::splat(f64::INFINITY),
            accept: V::splat(0.3 * target),
            weights: V::from_array([x, x2, x2 * x, x4]),
            g_4: V::splat(x4),
            b: V::splat(b),
        }
    }

    /// Add the orders n = 4k+1..4k+4 (polynomial values `p`, derivatives `dp`) and test
    /// each, lowest first. `Some(Some(total))` when an order is
    /// accepted, `Some(None)` when the orders have started to grow (the expansion fails),
    /// `None` to go on.
    ///
    /// Order n (≥ 3) is accepted when its error estimate err_n = (n+1)|term| + b|term_b|
    /// predicts the first omitted order below 0.3 × target × R: err_n · max(q1, q2) with
    /// the last two decay ratios q1 = err_n/err_{n−1}, q2 = err_{n−1}/err_{n−2}, both < ½
    /// (the larger ratio, so that an order that happens to be small, P_n(b) near a root,
    /// cannot stop the expansion early), written without divisions; and R > 0. The orders
    /// have started to grow when |term_n| ≥ max(|term_{n−1}|, |term_{n−2}|). Unlike the
    /// series' tail bounds this estimate is not a proof; see the module doc for its checks.
    #[inline(always)]
    fn add_block(&mut self, k: usize, p: V, dp: V) -> Option<Option<AsymTotal>> {
        let (g_n, b) = (self.weights, self.b);
        self.weights = g_n.mul(self.g_4);
        let base = 4.0 * k as f64;
        let n = V::from_array([base + 1.0, base + 2.0, base + 3.0, base + 4.0]);
        let term = g_n.mul(p);
        let term_b = g_n.mul(dp);
        let size = term.abs();
        let err = size.mul_add(n.add(V::splat(1.0)), b.mul(term_b.abs()));
        let (err1, err2) = (V::shift1(self.err, err), V::shift2(self.err, err));
        let (size1, size2) = (V::shift1(self.size, size), V::shift2(self.size, size));
        let r = term.prefix_sum().add(V::splat(self.r));
        let t = self.accept.mul(r.abs());
        let half = V::splat(0.5);
        let accepted = err.lt(half.mul(err1))
            & err1.lt(half.mul(err2))
            & err.mul(err).le(t.mul(err1))
            & err.mul(err1).le(t.mul(err2))
            & r.gt(V::splat(0.0));
        let growing = size.ge(size1.max(size2));
        // Orders from 3 to ASYM_ORDERS take part.
        let first = if k == 0 { 2 } else { 0 };
        let last = (ASYM_ORDERS - 4 * k).min(4);
        let valid = (1u32 << last) - (1u32 << first);
        let decided = (accepted | growing) & valid;
        if decided != 0 {
            let at = decided.trailing_zeros() as usize;
            if accepted & (1 << at) == 0 {
                return Some(None);
            }
            let upto = V::from_array(LANES_UPTO[at]);
            return Some(Some(AsymTotal {
                r: r.to_array()[at],
                r_g: self.r_g - n.mul(term).mul(upto).hsum(),
                r_b: self.r_b + term_b.mul(upto).hsum(),
            }));
        }
        self.r = r.to_array()[3];
        self.r_g -= n.mul(term).hsum();
        self.r_b += term_b.hsum();
        self.size = size;
        self.err = err;
        None
    }
}

/// ln Q and its derivatives from the asymptotic sums: Q = e^{−b} R / g².
#[inline(always)]
fn asymptotic_result(b: f64, x: f64, s: AsymTotal) -> LnQ {
    let inv_r = 1.0 / s.r;
    LnQ {
        ln_q: -b + (s.r * x * x).ln(),
        d_g: (b - 2.0 + (s.r_g - b * s.r_b) * inv_r) * x,
        d_a: (-1.0 + s.r_b * inv_r) * x,
        mode: Mode::Rough,
    }
}
