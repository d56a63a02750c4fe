//! Special functions for models' loops over particles: [`exp`], [`ln`], [`atan2`] and
//! [`hypot`], written so that LLVM vectorises a loop that calls them.
//!
//! The speeds quoted are one run of the bench on a shared 2-core AMD EPYC (Zen, AVX2),
//! 4096 values in L1.
//!
//! Each is an `#[inline(always)]` scalar `f64 → f64` function of plain IEEE-754 arithmetic
//! (`+ − × ÷`, `sqrt`, comparisons, bit operations): no call into the C library, no branch
//! on the data (the special cases are selects), no fused multiply-add, no table larger than
//! the 64 entries of `exp`'s `2^{j/64}`. So the same input gives the same bits on every
//! instruction set and every compiled copy (baseline x86-64, AVX2, AVX-512), and a loop over
//! a chunk of particles runs four or eight lanes at a time where std's `f64::atan2` and
//! friends, which are libm calls, run one. Where the caller is compiled for AVX2 (as the
//! batch filter's model calls are, see [`simd`](super)), a loop over them is several times
//! faster than over std's (measured in `pf-core/benches/components.rs`, group `special`:
//! the ratios are in each function's docs).
//!
//! Accuracy is stated in ulps against the platform's (glibc's) functions, which are within
//! one ulp of the exact value; the bounds below are the largest errors measured by this
//! module's tests (dense sweeps, random arguments over the whole range, and the special
//! values), which assert them.

// fdlibm's and Cephes' constants, digit for digit.
#![allow(clippy::excessive_precision)]

use super::math::{EXP2_64THS, LN2_HI, LN2_LO, ROUND_MAGIC};

/// `2⁵²` as a double: `from_bits(2⁵² bits | e) − 2⁵²` is the small integer `e` exactly.
const TWO52: f64 = 4_503_599_627_370_496.0;

/// `2^k` for `−1022 ≤ k ≤ 1023`, exactly.
const fn pow2(k: i64) -> f64 {
    f64::from_bits(((k + 1023) as u64) << 52)
}

/// `e^x` for every `x`, branch-free (Tang's table method of
/// [`exp_nonpositive`](super::math::exp_nonpositive), extended to the whole range).
///
/// `x = (64k + j)·ln 2/64 + r`, `|r| ≤ ln 2/128`, `e^x = 2^k · 2^{j/64} · e^r`, with
/// `e^r − 1` from its Taylor polynomial of degree 5 and `2^{j/64}` from the same table of
/// correctly rounded doubles. `2^k` is applied as two powers of two `2^{k₁}·2^{k₂}`, so
/// that results between `2⁻¹⁰⁷⁴` and `2⁻¹⁰²²` come out as correctly scaled subnormals
/// and `k = 1024` overflows to `+∞` in the product, not in the exponent field.
///
/// Accuracy: at most 1 ulp from glibc's `exp` over `[−708.39, 709.78]` (normal results), and
/// at most 1 ulp of the subnormal spacing `2⁻¹⁰⁷⁴` below (tested). Special values:
/// `exp(±0) = 1`, `exp(+∞) = +∞`, `exp(−∞) = 0`, `exp(NaN) = NaN`, `+∞` above
/// 709.782712893384 and `0` below −745.1332191019412, as glibc; a subnormal `x` gives 1.
///
/// Speed: a loop over it compiled for AVX2 is 3.2× glibc's `exp` (2.1 against 6.7 ns per
/// value, bench `special/exp`).
#[inline(always)]
pub fn exp(x: f64) -> f64 {
    // Clamp first so that the integer steps stay in range; NaN becomes −746 here and is
    // selected back at the end.
    let xc = x.clamp(-746.0, 710.0);
    let xc = if xc.is_nan() { -746.0 } else { xc };
    // n = round(64x/ln 2) by the magic-number trick (|n| < 2¹⁷, so n·LN2_HI/64 is exact).
    let t = xc * (64.0 / std::f64::consts::LN_2) + ROUND_MAGIC;
    let nf = t - ROUND_MAGIC;
    let r = (xc - nf * (LN2_HI / 64.0)) - nf * (LN2_LO / 64.0);
    let r2 = r * r;
    let a = 0.5 + r * (1.0 / 6.0);
    let b = 1.0 / 24.0 + r * (1.0 / 120.0);
    let p = r + r2 * (a + r2 * b);
    let bits = t.to_bits();
    // k ∈ [−1077, 1024]: k₁ = ⌊k/2⌋ and k₂ = k − k₁ both in [−539, 512], normal powers.
    let k = (bits.wrapping_sub(ROUND_MAGIC.to_bits()) as i64) >> 6;
    let k1 = k >> 1;
    let k2 = k - k1;
    let s1 = f64::from_bits(((k1 + 1023) as u64) << 52);
    let s2 = f64::from_bits(((k2 + 1023) as u64) << 52);
    let tj = f64::from_bits(EXP2_64THS[(bits & 63) as usize]);
    let y = (tj + tj * p) * s1 * s2;
    if x.is_nan() { x } else { y }
}

/// `ln x` for every `x`, branch-free (fdlibm's `__ieee754_log`, with selects for its special
/// cases).
///
/// `x = 2^k·m` with `√2/2 ≤ m < √2`, `f = m − 1`, `s = f/(2 + f)`, and
/// `ln m = f − f²/2 + s(f²/2 + R(s²))` with fdlibm's polynomial `R` of degree 14 in `s`
/// (error below 2⁻⁵⁸·⁴⁵); `k·ln 2` in fdlibm's two parts. Subnormal `x` are first scaled
/// by `2⁵⁴`.
///
/// Accuracy: at most 1 ulp from glibc's `log` over all positive doubles, subnormals
/// included (tested). Special values: `ln(±0) = −∞`, `ln(+∞) = +∞`, `ln(x < 0) = NaN`
/// (`−∞` included), `ln(NaN) = NaN`, `ln 1 = +0`.
///
/// Speed: a loop over it compiled for AVX2 is only 1.3× glibc's `log` (4.4 against 5.5 ns
/// per value, bench `special/ln`; glibc's table-driven `log` is fast, and the division
/// here is on the critical path); what it buys is that the loop around it vectorises.
#[inline(always)]
pub fn ln(x: f64) -> f64 {
    const LG1: f64 = 6.666666666666735130e-01;
    const LG2: f64 = 3.999999999940941908e-01;
    const LG3: f64 = 2.857142874366239149e-01;
    const LG4: f64 = 2.222219843214978396e-01;
    const LG5: f64 = 1.818357216161805012e-01;
    const LG6: f64 = 1.531383769920937332e-01;
    const LG7: f64 = 1.479819860511658591e-01;
    const TWO54: f64 = 18_014_398_509_481_984.0;
    let tiny = x < f64::MIN_POSITIVE;
    let xs = if tiny { x * TWO54 } else { x };
    let bits = xs.to_bits();
    // Move m into [√2/2, √2): add the offset of √2/2's high word so that the exponent field
    // carries over exactly when m ≥ √2, then put the high word of m back.
    let hx = (bits >> 32).wrapping_add(0x3ff0_0000 - 0x3fe6_a09e);
    let e = (hx >> 20) & 0x7ff;
    let kf = (f64::from_bits(TWO52.to_bits() | e) - TWO52) - 1023.0 - if tiny { 54.0 } else { 0.0 };
    let m = f64::from_bits((((hx & 0x000f_ffff) + 0x3fe6_a09e) << 32) | (bits & 0xffff_ffff));
    let f = m - 1.0;
    let hfsq = 0.5 * f * f;
    let s = f / (2.0 + f);
    let z = s * s;
    let w = z * z;
    let t1 = w * (LG2 + w * (LG4 + w * LG6));
    let t2 = z * (LG1 + w * (LG3 + w * (LG5 + w * LG7)));
    let r = t2 + t1;
    let y = s * (hfsq + r) + kf * LN2_LO - hfsq + f + kf * LN2_HI;
    let y = if x == f64::INFINITY { x } else { y };
    let y = if x == 0.0 { f64::NEG_INFINITY } else { y };
    if x < 0.0 || x.is_nan() { f64::NAN } else { y }
}

/// `atan2(y, x)`, the angle of the point `(x, y)` in `[−π, π]`, branch-free (Cephes'
/// `atan` rational approximation after a reduction to `|t| ≤ 0.66` done with one division).
///
/// With `n = min(|x|, |y|)` and `d = max(|x|, |y|)`, `atan(n/d)` is `atan t` with `t = n/d`
/// when `n ≤ 0.66 d`, else `π/4 + atan t` with `t = (n − d)/(n + d)`; `atan t = t + t·z·P(z)/Q(z)`,
/// `z = t²` (Cephes' coefficients, relative error 2·10⁻¹⁶). The quadrant then gives the
/// angle as `k·π/4 ± atan t` for an integer `k ∈ [0, 4]`, with π/4 in two parts so that
/// `k·π/4` carries no rounding error (the high part times 3 is exact).
///
/// Accuracy: at most 2 ulp from glibc's `atan2` over all finite arguments, subnormals and
/// huge ones included (tested). Special values as IEEE 754 and C99: `atan2(±0, +0) = ±0`,
/// `atan2(±0, −0) = ±π`, `atan2(±0, x < 0) = ±π`, `atan2(y ≠ 0, ±0) = ±π/2`,
/// `atan2(±y, +∞) = ±0`, `atan2(±y, −∞) = ±π`, `atan2(±∞, x finite) = ±π/2`,
/// `atan2(±∞, +∞) = ±π/4`, `atan2(±∞, −∞) = ±3π/4`, NaN if either is NaN.
///
/// Speed: a loop over it compiled for AVX2 is 3.8× glibc's `atan2` (4.6 against 17.5 ns
/// per value, bench `special/atan2`).
#[inline(always)]
pub fn atan2(y: f64, x: f64) -> f64 {
    const P: [f64; 5] = [
        -8.750608600031904122785e-1,
        -1.615753718733365076637e1,
        -7.500855792314704667340e1,
        -1.228866684490136173410e2,
        -6.485021904942025371773e1,
    ];
    const Q: [f64; 5] = [
        2.485846490142306297962e1,
        1.650270098316988542046e2,
        4.328810604912902668951e2,
        4.853903996359136964868e2,
        1.945506571482613964425e2,
    ];
    // π/4 = PIO4_HI + PIO4_LO; PIO4_HI's significand ends in three zero bits, so k·PIO4_HI
    // is exact for k ≤ 4.
    const PIO4_HI: f64 = std::f64::consts::FRAC_PI_4;
    const PIO4_LO: f64 = 3.061616997868382943065e-17;
    const TWO100: f64 = pow2(100);
    let (ax, ay) = (x.abs(), y.abs());
    let swap = ay > ax;
    let (n, d) = if swap { (ax, ay) } else { (ay, ax) };
    // Above 2⁹⁹⁶ n + d could overflow, and below 2⁻⁹⁶³ a subnormal 0.66·d loses the
    // reduction's threshold: a power-of-two scale is exact (or loses only bits of an n too
    // small to matter against d).
    let sc = if d > 1e300 {
        0.25
    } else if d < 1e-290 {
        TWO100
    } else {
        1.0
    };
    let (n, d) = (n * sc, d * sc);
    let both_inf = n == f64::INFINITY;
    let red = n > 0.66 * d || both_inf;
    let num = if red { n - d } else { n };
    let den = if red { n + d } else { d };
    let t = num / den;
    let t = if d == 0.0 || both_inf { 0.0 } else { t };
    let z = t * t;
    let p = (((P[0] * z + P[1]) * z + P[2]) * z + P[3]) * z + P[4];
    let q = ((((z + Q[0]) * z + Q[1]) * z + Q[2]) * z + Q[3]) * z + Q[4];
    let r = t + t * (z * p / q);
    // The angle of (|x|, |y|) is k·π/4 + s·r: k = 0 (+r), 1 (reduced: π/4 + r), 2 (swapped:
    // π/2 − r), 1 (both: π/4 − r); for x < 0 (−0 included), π minus that: 4 − k, −s.
    let k = (if red { 1.0 } else { 0.0 }) + (if swap && !red { 2.0 } else { 0.0 });
    let neg_r = swap;
    let xneg = x.is_sign_negative();
    let k = if xneg { 4.0 - k } else { k };
    let neg_r = neg_r != xneg;
    let sr = if neg_r { -r } else { r };
    let a = k * PIO4_HI + (k * PIO4_LO + sr);
    let a = a.copysign(y);
    if x.is_nan() || y.is_nan() { x + y } else { a }
}

/// `√(x² + y²)` without undue overflow or underflow, branch-free.
///
/// `x` and `y` are scaled by a power of two chosen from the larger magnitude (`2⁻⁶⁰⁰` above
/// `2⁵¹⁰`, `2⁶⁰⁰` below `2⁻⁵¹⁰`, exact), `√(x² + y²)` is taken in plain arithmetic and
/// scaled back.
///
/// Accuracy: at most 1 ulp from glibc's `hypot` over all finite arguments, subnormals and
/// huge ones included (tested). Special values: `hypot(±∞, y) = +∞` even for a NaN `y`
/// (IEEE 754), otherwise NaN if either is NaN; `hypot(±0, ±0) = +0`; `hypot(x, ±0) = |x|`.
///
/// Speed: a loop over it compiled for AVX2 is 7.5× glibc's `hypot` (1.0 against 7.4 ns per
/// value, bench `special/hypot`).
#[inline(always)]
pub fn hypot(x: f64, y: f64) -> f64 {
    const BIG: f64 = pow2(510);
    const SMALL: f64 = pow2(-510);
    const DOWN: f64 = pow2(-600);
    const UP: f64 = pow2(600);
    let (ax, ay) = (x.abs(), y.abs());
    let d = if ay > ax { ay } else { ax };
    let (s, back) = if d > BIG {
        (DOWN, UP)
    } else if d < SMALL {
        (UP, DOWN)
    } else {
        (1.0, 1.0)
    };
    let (sx, sy) = (ax * s, ay * s);
    let h = (sx * sx + sy * sy).sqrt() * back;
    if ax == f64::INFINITY || ay == f64::INFINITY {
        f64::INFINITY
    } else {
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mc::{PfRng, stream_rng};
    use rand::RngExt;

    /// The distance in ulps between `a` and `b`: the number of doubles between them (0 when
    /// equal, both NaN, or ±0); `u64::MAX` when one is NaN and the other not.
    fn ulps(a: f64, b: f64) -> u64 {
        if a.is_nan() || b.is_nan() {
            return if a.is_nan() && b.is_nan() {
                0
            } else {
                u64::MAX
            };
        }
        // Map to integers ordered as the doubles are.
        let key = |v: f64| {
            let b = v.to_bits() as i64;
            if b < 0 { i64::MIN - b } else { b }
        };
        key(a).abs_diff(key(b))
    }

    /// The largest error in ulps of `f` against `g` over `xs`, with its argument.
    fn worst1(
        f: impl Fn(f64) -> f64,
        g: impl Fn(f64) -> f64,
        xs: impl IntoIterator<Item = f64>,
    ) -> (u64, f64) {
        xs.into_iter()
            .map(|x| (ulps(f(x), g(x)), x))
            .fold((0, f64::NAN), |a, b| if b.0 > a.0 { b } else { a })
    }

    /// As [`worst1`], for functions of two arguments.
    fn worst2(
        f: impl Fn(f64, f64) -> f64,
        g: impl Fn(f64, f64) -> f64,
        xs: impl IntoIterator<Item = (f64, f64)>,
    ) -> (u64, (f64, f64)) {
        xs.into_iter()
            .map(|p| (ulps(f(p.0, p.1), g(p.0, p.1)), p))
            .fold(
                (0, (f64::NAN, f64::NAN)),
                |a, b| if b.0 > a.0 { b } else { a },
            )
    }

    /// A double with a uniform random exponent over the whole range (subnormals through the
    /// largest) and a random significand and sign.
    fn any_double(rng: &mut PfRng, signed: bool) -> f64 {
        let e: u64 = rng.random_range(0..2047);
        let m: u64 = rng.random::<u64>() >> 12;
        let s = if signed && rng.random::<bool>() {
            1u64 << 63
        } else {
            0
        };
        f64::from_bits(s | (e << 52) | m)
    }

    fn rng() -> PfRng {
        stream_rng(48, 0)
    }

    /// Values at which special functions go wrong: zeros, subnormals, the ends of the normal
    /// range, infinities, NaN, and ordinary numbers near 1.
    const SPECIAL: [f64; 20] = [
        0.0,
        -0.0,
        5e-324,
        -5e-324,
        2.2250738585072009e-308,
        f64::MIN_POSITIVE,
        -f64::MIN_POSITIVE,
        1e-300,
        0.5,
        1.0,
        -1.0,
        std::f64::consts::SQRT_2,
        2.0,
        1e300,
        -1e300,
        f64::MAX,
        f64::MIN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
    ];

    #[test]
    fn exp_is_within_one_ulp_of_std() {
        let sweep = (0..=4_000_000).map(|i| -746.0 + 1456.0 * f64::from(i) / 4e6);
        let steps = (-68_900..65_600).flat_map(|n| {
            let x = f64::from(n) * std::f64::consts::LN_2 / 64.0;
            [x.next_down(), x, x.next_up()]
        });
        let mut g = rng();
        let random: Vec<f64> = (0..1_000_000)
            .map(|_| g.random_range(-746.0..710.0))
            .collect();
        let small: Vec<f64> = (0..100_000)
            .map(|_| any_double(&mut g, true) * 1e-300)
            .collect();
        let (w, at) = worst1(
            exp,
            f64::exp,
            sweep.chain(steps).chain(random).chain(small).chain(SPECIAL),
        );
        assert!(w <= 1, "exp: {w} ulp at {at:e}");
        for (x, want) in [
            (0.0, 1.0),
            (-0.0, 1.0),
            (f64::INFINITY, f64::INFINITY),
            (f64::NEG_INFINITY, 0.0),
            (709.79, f64::INFINITY),
            (1e300, f64::INFINITY),
            (-745.2, 0.0),
            (-1e300, 0.0),
            (5e-324, 1.0),
        ] {
            assert_eq!(exp(x).to_bits(), want.to_bits(), "exp({x})");
        }
        assert!(exp(f64::NAN).is_nan());
        // The subnormal range, where glibc rounds 2^k·… once.
        assert_eq!(exp(-745.0), (-745.0f64).exp());
        assert!(exp(-744.5).to_bits().abs_diff((-744.5f64).exp().to_bits()) <= 1);
    }

    #[test]
    fn ln_is_within_one_ulp_of_std() {
        let sweep = (1..=4_000_000).map(|i| f64::from(i) / 1e6);
        let near_one = (-100_000..100_000).map(|i| 1.0 + f64::from(i) * 1e-9);
        let mut g = rng();
        let random: Vec<f64> = (0..2_000_000).map(|_| any_double(&mut g, false)).collect();
        let (w, at) = worst1(
            ln,
            f64::ln,
            sweep.chain(near_one).chain(random).chain(SPECIAL),
        );
        assert!(w <= 1, "ln: {w} ulp at {at:e}");
        assert_eq!(ln(1.0).to_bits(), 0.0f64.to_bits());
        assert_eq!(ln(0.0), f64::NEG_INFINITY);
        assert_eq!(ln(-0.0), f64::NEG_INFINITY);
        assert_eq!(ln(f64::INFINITY), f64::INFINITY);
        for x in [-1.0, -5e-324, f64::NEG_INFINITY, f64::NAN] {
            assert!(ln(x).is_nan(), "ln({x})");
        }
    }

    #[test]
    fn atan2_is_within_two_ulp_of_std() {
        let mut g = rng();
        // The unit circle densely, at radii that scale the arguments exactly.
        let circle = (0..2_000_000).flat_map(|i| {
            let a = -3.2 + 6.4 * f64::from(i) / 2e6;
            let (s, c) = a.sin_cos();
            [(s, c), (s * 1e-310, c * 1e-310), (s * 1e305, c * 1e305)]
        });
        // The reduction's boundaries, n/d ∈ {0.66, 1} and their neighbours.
        let edges = (0..100_000).flat_map(|i| {
            let d = 1.0 + f64::from(i) * 1e-5;
            [
                (0.66 * d, d),
                ((0.66 * d).next_up(), d),
                (d, d.next_up()),
                (d.next_up(), d),
            ]
        });
        let random: Vec<(f64, f64)> = (0..2_000_000)
            .map(|_| (any_double(&mut g, true), any_double(&mut g, true)))
            .collect();
        let special = SPECIAL
            .iter()
            .flat_map(|&y| SPECIAL.iter().map(move |&x| (y, x)));
        let (w, at) = worst2(
            atan2,
            f64::atan2,
            circle.chain(edges).chain(random).chain(special),
        );
        assert!(w <= 2, "atan2: {w} ulp at {at:?}");
        use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
        let inf = f64::INFINITY;
        for (y, x, want) in [
            (0.0, 0.0, 0.0),
            (-0.0, 0.0, -0.0),
            (0.0, -0.0, PI),
            (-0.0, -0.0, -PI),
            (0.0, -3.0, PI),
            (-0.0, -3.0, -PI),
            (2.0, 0.0, FRAC_PI_2),
            (-2.0, -0.0, -FRAC_PI_2),
            (2.0, inf, 0.0),
            (-2.0, inf, -0.0),
            (2.0, -inf, PI),
            (-2.0, -inf, -PI),
            (inf, 5.0, FRAC_PI_2),
            (-inf, -5.0, -FRAC_PI_2),
            (inf, inf, FRAC_PI_4),
            (-inf, inf, -FRAC_PI_4),
            (inf, -inf, 3.0 * FRAC_PI_4),
            (-inf, -inf, -3.0 * FRAC_PI_4),
            (1.0, 1.0, FRAC_PI_4),
        ] {
            assert_eq!(atan2(y, x).to_bits(), want.to_bits(), "atan2({y}, {x})");
        }
        assert!(atan2(f64::NAN, 1.0).is_nan() && atan2(1.0, f64::NAN).is_nan());
    }

    #[test]
    fn hypot_is_within_one_ulp_of_std() {
        let mut g = rng();
        let sweep = (0..2_000_000).map(|i| {
            let a = f64::from(i) / 2e6;
            (a * 3.0, 1.0 - a)
        });
        let random: Vec<(f64, f64)> = (0..2_000_000)
            .map(|_| (any_double(&mut g, true), any_double(&mut g, true)))
            .collect();
        // Comparable magnitudes, where both squares count, at every scale.
        let close: Vec<(f64, f64)> = (0..1_000_000)
            .map(|_| {
                let x = any_double(&mut g, true);
                (x, x * g.random_range(-3.0..3.0))
            })
            .collect();
        let special = SPECIAL
            .iter()
            .flat_map(|&y| SPECIAL.iter().map(move |&x| (y, x)));
        let (w, at) = worst2(
            hypot,
            f64::hypot,
            sweep.chain(random).chain(close).chain(special),
        );
        assert!(w <= 1, "hypot: {w} ulp at {at:?}");
        assert_eq!(hypot(3.0, 4.0), 5.0);
        assert_eq!(hypot(f64::INFINITY, f64::NAN), f64::INFINITY);
        assert_eq!(hypot(f64::NAN, f64::NEG_INFINITY), f64::INFINITY);
        assert!(hypot(f64::NAN, 1.0).is_nan());
        assert_eq!(hypot(-0.0, 0.0).to_bits(), 0.0f64.to_bits());
        assert_eq!(hypot(f64::MAX, f64::MAX), f64::INFINITY);
        assert_eq!(hypot(f64::MAX, 1.0), f64::MAX);
        assert_eq!(hypot(5e-324, 0.0), 5e-324);
    }
}
