//! The KBS series for small g and moderate a (g < 60, a < 600), summed upward from m = 1
//! eight terms at a time from tabulated constants (see the parent module's doc for the
//! sum, its tail bounds and its accuracy).

use super::super::lanes::F64x4;
use super::super::Mode;
use super::terms::{exp_poly, ratio_parts, LnQ};

/// Below these g and a the series is summed upward from m = 1 ([`series_from_one`]).
pub(super) const SMALL_G_MAX: f64 = 60.0;
pub(super) const SMALL_A_MAX: f64 = 600.0;

/// Number of terms the small-g path tabulates its per-term constants for.
const SMALL_M: usize = 168;

/// 1/(m! m) for m = 1..SMALL_M (index m − 1), correctly rounded (generated with Python's
/// exact `fractions`).
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
static SMALL_COEF: [f64; SMALL_M] = [
    1.0,
    0.25,
    0.05555555555555555,
    0.010416666666666666,
    0.0016666666666666668,
    0.0002314814814814815,
    2.834467120181406e-05,
    3.1001984126984127e-06,
    3.0619243582206544e-07,
    2.755731922398589e-08,
    2.27746439867652e-09,
    1.7397297489890083e-10,
    1.2353110643708935e-11,
    8.193389712664089e-13,
    5.0981091545465446e-14,
    2.9871733327421158e-15,
    1.6537983849091297e-16,
    8.677337204770125e-18,
    4.326650129802279e-19,
    2.0551588116560825e-20,
    9.32044812542441e-22,
    4.0439960874775335e-23,
    1.6818131176655147e-24,
    6.715573212900493e-26,
    2.5787801137537893e-27,
    9.53690870471076e-29,
    3.401366616220572e-30,
    1.1713890132392279e-31,
    3.8999872022233505e-33,
    1.2566625429386353e-34,
    3.922984005011348e-36,
    1.1876221108921073e-37,
    3.489798672961197e-39,
    9.962228045650476e-41,
    2.7650265596091116e-42,
    7.467278517462879e-44,
    1.9636378862575867e-45,
    5.031482118527058e-47,
    1.257043527311165e-48,
    3.0640435978209645e-50,
    7.291002017420499e-52,
    1.6946206503074855e-53,
    3.849327599400454e-55,
    8.549642911891504e-57,
    1.8577001882628452e-58,
    3.9506856555684327e-60,
    8.22686917863956e-62,
    1.6782241814065079e-63,
    3.3550504251358757e-65,
    6.575898833266316e-67,
    1.264109733422975e-68,
    2.3842306362637474e-70,
    4.4136700991710524e-72,
    8.022102717972078e-74,
    1.432044782712371e-75,
    2.5115581329458033e-77,
    4.328939841334718e-79,
    7.335005081928625e-81,
    1.2221496545586332e-82,
    2.0029674894155379e-84,
    3.2297245193478165e-86,
    5.125213207081603e-88,
    8.006127962687312e-90,
    1.231411283323488e-91,
    1.865333068229662e-93,
    2.783440069672361e-95,
    4.092382370202179e-97,
    5.9297062890040225e-99,
    8.46922973434727e-101,
    1.1926058197346155e-102,
    1.6560683868562405e-104,
    2.2681492181094343e-106,
    3.0644913436644638e-108,
    4.085242295242985e-110,
    5.374363197297438e-112,
    6.978484068512948e-114,
    8.945265461409749e-116,
    1.1321259706254943e-117,
    1.414930711565271e-119,
    1.746555097088381e-121,
    2.1296206030646317e-123,
    2.565426365976133e-125,
    3.053635680215458e-127,
    3.592003422022151e-129,
    4.176170068510183e-131,
    4.799546455156376e-133,
    5.453309487956775e-135,
    6.126522797678712e-137,
    6.806388160531835e-139,
    7.478624028238683e-141,
    8.127957523746909e-143,
    8.738706694954734e-145,
    9.295421620254775e-147,
    9.78354697469097e-149,
    1.019006554704655e-150,
    1.050408232388696e-152,
    1.0717312180817815e-154,
    1.0824440665757268e-156,
    1.0823336243691585e-158,
    1.0715102881254669e-160,
    1.0503973023482667e-162,
    1.0197051858628887e-164,
    9.803933354511702e-167,
    9.336216119773533e-169,
    8.80695216740542e-171,
    8.230063880184844e-173,
    7.6197639208629e-175,
    6.990009769653037e-177,
    6.354019485923138e-179,
    5.723868793104315e-181,
    5.110182349171939e-183,
    4.521924750941368e-185,
    3.9662900157054837e-187,
    3.448682454406892e-189,
    2.9727773141957326e-191,
    2.5406464858242366e-193,
    2.1529329560640765e-195,
    1.8090574250179328e-197,
    1.5074413964558723e-199,
    1.2457328206822833e-201,
    1.0210227339790588e-203,
    8.300440124393047e-206,
    6.693460871015611e-208,
    5.3544204418244026e-210,
    4.249268062631846e-212,
    3.345669613435253e-214,
    2.613642329300278e-216,
    2.0259556629707965e-218,
    1.5583337831876809e-220,
    1.189497384800064e-222,
    9.010818718256997e-225,
    6.77466283340029e-227,
    5.0554327209499594e-229,
    3.7445564261881524e-231,
    2.7531992379106304e-233,
    2.0095258278435072e-235,
    1.4561005519032287e-237,
    1.0474993468322954e-239,
    7.481750937469943e-242,
    5.3059356138179694e-244,
    3.736386428924681e-246,
    2.612728062281194e-248,
    1.8143057599096755e-250,
    1.2511850099685745e-252,
    8.569352743661105e-255,
    5.829218182730625e-257,
    3.9384786648094377e-259,
    2.6431535962700296e-261,
    1.7620230271067266e-263,
    1.1668508046173434e-265,
    7.676313349967173e-268,
    5.016981110825152e-270,
    3.2576407742552995e-272,
    2.1016151056715335e-274,
    1.3471330958310766e-276,
    8.580112995308056e-279,
    5.430230951633157e-281,
    3.41510278563694e-283,
    2.1343548124308234e-285,
    1.3256344342832068e-287,
    8.182612919459631e-290,
    5.019816643930043e-292,
    3.06074860294579e-294,
    1.8549301839684852e-296,
    1.1173867774869847e-298,
    6.690695974936583e-301,
    3.982414327654175e-303,
    2.3563746907534265e-305,
];

/// 1/m for m = 1..SMALL_M (index m − 1).
static SMALL_INV: [f64; SMALL_M] = small_inv();

const fn small_inv() -> [f64; SMALL_M] {
    let mut t = [0.0f64; SMALL_M];
    let mut i = 0;
    while i < SMALL_M {
        t[i] = 1.0 / (i + 1) as f64;
        i += 1;
    }
    t
}

/// The series for small g and moderate a, summed upward from m = 1 with the same tail
/// bounds as [`series`]: t_m = g^{m−1}/(m! m) e^{−a/m} relative to g, eight terms at a time
/// in independent lanes (powers of g by lane, tabulated 1/(m! m) and 1/m, one `exp` per
/// term; no serial product of ratios), the bounds checked after each group of eight with
/// the ratio of its last two terms (one division). With a < 600 and g < 60 the sum is
/// ≥ e^{−600} and no relevant term under- or overflows, and the terms fall below 1e-17 of
/// the sum well before m = SMALL_M.
#[inline(always)]
pub(super) fn series_from_one<V: F64x4>(g: f64, a: f64, tol: f64) -> LnQ {
    const L: usize = 8;
    let eps = 0.1 * tol.max(1e-17);
    let (mut s0, mut s_c, mut s_inv) = ([0.0f64; L], [0.0f64; L], [0.0f64; L]);
    let g2 = g * g;
    let g4 = g2 * g2;
    let g3 = g2 * g;
    let mut gp = [1.0, g, g2, g3, g4, g4 * g, g4 * g2, g4 * g3];
    let g8 = g4 * g4;
    let mut m0 = 1.0f64;
    for (coef, inv) in SMALL_COEF.chunks_exact(L).zip(SMALL_INV.chunks_exact(L)) {
        let mut t = [0.0f64; L];
        for l in 0..L {
            t[l] = gp[l] * coef[l];
            if a != 0.0 {
                t[l] *= exp_poly::<V>(-a * inv[l]);
            }
            s0[l] += t[l];
            s_c[l] = V::fma1(m0 + (l as f64 - 1.0) - g, t[l], s_c[l]);
            s_inv[l] = V::fma1(t[l], inv[l], s_inv[l]);
            gp[l] *= g8;
        }
        // The last term added is t_m, m = m0 + L − 1. The ratios decrease, so r_{m−1} =
        // t_m/t_{m−1} ≥ r_m bounds every later one (a few % above r_m here; a division
        // instead of an `exp`); from the formula only where t_{m−1} is near underflow. The
        // tail bounds of the module doc with r, multiplied through by (1−r) or (1−r)², and
        // 1/m ≥ 1/(m+1) in the last.
        let m = m0 + (L - 1) as f64;
        let r = if t[L - 2] > 1e-290 {
            t[L - 1] / t[L - 2]
        } else {
            let (factor, exponent) = ratio_parts(g, a, m);
            factor * exp_poly::<V>(exponent)
        };
        if r < 1.0 {
            let (s0, s_c, s_inv) = (sum8(&s0), sum8(&s_c), sum8(&s_inv));
            let om = 1.0 - r;
            let tail_om = t[L - 1] * r; // tail · (1−r)
            if tail_om <= eps * s0 * om
                && tail_om * ((m + g) * om + 1.0) <= eps * (s0 + s_c.abs()) * om * om
                && a * tail_om * inv[L - 1] <= eps * (s0 + a * s_inv) * om
            {
                break;
            }
        }
        m0 += L as f64;
    }
    let (s0, s_c, s_inv) = (sum8(&s0), sum8(&s_c), sum8(&s_inv));
    LnQ {
        ln_q: -g + s0.ln(),
        d_g: s_c / (g * s0),
        d_a: -s_inv / s0,
        mode: Mode::Series,
    }
}

/// The sum of eight lanes, pairwise.
#[inline(always)]
fn sum8(v: &[f64; 8]) -> f64 {
    ((v[0] + v[1]) + (v[2] + v[3])) + ((v[4] + v[5]) + (v[6] + v[7]))
}
