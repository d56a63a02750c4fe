//! Branch-free elementary functions for the vectorised kernels.
//!
//! [`exp_nonpositive`] is fdlibm's `exp` (Sun Microsystems 1993, as in musl and the `libm`
//! crate) with its branches turned into selects for the range the filter needs, `x ≤ 0`:
//! the same argument reduction `x = k·ln 2 + r`, `|r| ≤ ½ ln 2` (with `ln 2` split in two
//! parts), the same rational approximation of `exp(r)`, and `2^k` applied to the exponent
//! bits. Its maximum relative error against the platform's `f64::exp` is below 2·2⁻⁵² on
//! `[−708, 0]` (tested). Below −708 it returns 0 (a weight `e^{−708}` times the largest
//! one, which no sum or resampling step can see), including at `−∞`.

// fdlibm's constants, digit for digit.
#![allow(clippy::excessive_precision)]

const LN2_HI: f64 = 6.931_471_803_691_238_164_90e-1;
const LN2_LO: f64 = 1.908_214_929_270_587_700_02e-10;
const P1: f64 = 1.666_666_666_666_660_190_37e-1;
const P2: f64 = -2.777_777_777_701_559_338_42e-3;
const P3: f64 = 6.613_756_321_437_934_361_17e-5;
const P4: f64 = -1.653_390_220_546_525_153_90e-6;
const P5: f64 = 4.138_136_797_057_238_460_39e-8;

/// `1.5·2⁵²`: adding it rounds a double of magnitude below 2⁵¹ to the nearest integer,
/// which then sits in the low bits of the sum's significand.
pub(crate) const ROUND_MAGIC: f64 = 6_755_399_441_055_744.0;

/// `e^x` for `x ≤ 0` (`−∞` included), branch-free; 0 below −708. See the module docs.
///
/// A NaN argument gives an unspecified value (the filter rejects NaN weights before).
#[inline(always)]
pub fn exp_nonpositive(x: f64) -> f64 {
    let [y] = exp_nonpositive_lanes([x]);
    y
}

/// [`exp_nonpositive`] of each of `L` values, each operation applied to every lane before
/// the next.
///
/// The evaluation is one long chain of dependent operations (about 80 cycles of latency
/// for 28 vector instructions, a division among them), and the CPU's scheduler holds only
/// a few loop iterations of it, so a plain vectorised loop waits on latency. Written a
/// step at a time over many lanes, the steps of different lanes are independent
/// instructions side by side: the filter, which calls this on 64 lanes, runs about 7 %
/// faster (criterion, 2026-11-24). Every lane performs the same operations as the one-lane
/// case, so the results are the same bits.
#[inline(always)]
pub fn exp_nonpositive_lanes<const L: usize>(x: [f64; L]) -> [f64; L] {
    // k = round(x / ln 2) by the magic-number trick (no `round`, which is a libm call on
    // baseline x86-64); kf is k as a double; t keeps k's two's complement in its low bits.
    let t = each::<L>(|i| x[i] * std::f64::consts::LOG2_E + ROUND_MAGIC);
    let kf = each::<L>(|i| t[i] - ROUND_MAGIC);
    let hi = each::<L>(|i| x[i] - kf[i] * LN2_HI);
    let lo = each::<L>(|i| kf[i] * LN2_LO);
    let r = each::<L>(|i| hi[i] - lo[i]);
    let rr = each::<L>(|i| r[i] * r[i]);
    let c = each::<L>(|i| {
        let rr = rr[i];
        r[i] - rr * (P1 + rr * (P2 + rr * (P3 + rr * (P4 + rr * P5))))
    });
    let y = each::<L>(|i| 1.0 + (r[i] * c[i] / (2.0 - c[i]) - lo[i] + hi[i]));
    each(|i| {
        let k_bits = t[i].to_bits().wrapping_sub(ROUND_MAGIC.to_bits());
        // y ∈ [½√2, √2] and k ≥ −1021 on [−708, 0], so adding k to the exponent stays
        // normal.
        let scaled = f64::from_bits(y[i].to_bits().wrapping_add(k_bits << 52));
        if x[i] >= -708.0 { scaled } else { 0.0 }
    })
}

/// `[f(0), …, f(L − 1)]`: one step of a computation over lanes.
#[inline(always)]
fn each<const L: usize>(f: impl FnMut(usize) -> f64) -> [f64; L] {
    std::array::from_fn(f)
}

/// `⌈x⌉` for `−1 < x < 2⁵¹`, as an index, in float and integer operations that vectorise
/// (no libm call, no float-to-integer conversion, which AVX2 lacks for 64-bit integers).
#[inline(always)]
pub(crate) fn ceil_index(x: f64) -> usize {
    // t = ROUND_MAGIC + round(x) exactly, and round(x) sits in t's low significand bits.
    let t = x + ROUND_MAGIC;
    let r = t - ROUND_MAGIC;
    ((t.to_bits().wrapping_sub(ROUND_MAGIC.to_bits()) as i64) + i64::from(r < x)) as usize
}

/// `⌈x⌉` clamped to `[lo, hi]`, minus `lo`, as an index, for integers `0 ≤ lo ≤ hi < 2⁵¹`
/// and `x < 2⁵¹` (the same as `ceil_index(x).clamp(lo, hi) − lo` for `x > −1`): the clamp in
/// two float compare-and-selects rather than unsigned 64-bit ones, which AVX2 lacks. In the
/// batch filter's boundaries: 19 instead of 26 instructions per four particles, 61.1 instead
/// of 62.7 per particle-step, and 1.7 % faster (fastest of interleaved runs: 5.46 against
/// 5.55 ns at N = 10⁴, 7.09 against 7.27 at 10⁶; 2026-11-24).
#[inline(always)]
pub(crate) fn ceil_index_in(x: f64, lo: f64, hi: f64) -> usize {
    let t = x + ROUND_MAGIC;
    let r = t - ROUND_MAGIC;
    index_in(if r < x { r + 1.0 } else { r }, lo, hi)
}

/// The integer `c` (a double, `|c| < 2⁵¹`) clamped to `[lo, hi]`, minus `lo`, as an index
/// (see [`ceil_index_in`]).
#[inline(always)]
pub(crate) fn index_in(c: f64, lo: f64, hi: f64) -> usize {
    let c = if c < lo { lo } else { c };
    let c = if c > hi { hi } else { c };
    ((c - lo) + ROUND_MAGIC)
        .to_bits()
        .wrapping_sub(ROUND_MAGIC.to_bits()) as usize
}

/// `⌊x⌋` for `0 ≤ x < 2⁵¹`, as an index and as a double, vectorisable like [`ceil_index`].
#[inline(always)]
pub(crate) fn floor_index(x: f64) -> (usize, f64) {
    let t = x + ROUND_MAGIC;
    let r = t - ROUND_MAGIC;
    let above = r > x;
    let k = (t.to_bits().wrapping_sub(ROUND_MAGIC.to_bits()) as i64) - i64::from(above);
    (k as usize, if above { r - 1.0 } else { r })
}

/// A uniform on [0, 1) from the top 52 bits of `b`, exactly `⌊b/2¹²⌋·2⁻⁵²`, by the exponent
/// trick (AVX2 has no integer-to-float conversion for 64-bit lanes).
#[inline(always)]
pub(crate) fn unit_from_bits(b: u64) -> f64 {
    f64::from_bits((b >> 12) | 0x3ff0_0000_0000_0000) - 1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative error against the platform's `exp` over the whole range, on a fine grid and
    /// at awkward points (exact multiples of ln 2, the ends).
    #[test]
    fn exp_is_accurate_to_two_ulp() {
        let mut worst: f64 = 0.0;
        let mut check = |x: f64| {
            let (got, want) = (exp_nonpositive(x), x.exp());
            worst = worst.max(((got - want) / want).abs());
        };
        for i in 0..=2_000_000 {
            check(-708.0 * f64::from(i) / 2e6);
        }
        for k in 0..1021 {
            let x = -f64::from(k) * std::f64::consts::LN_2;
            for d in [-1e-12, 0.0, 1e-12] {
                check((x + d).min(0.0));
            }
        }
        for x in [
            0.0,
            -0.0,
            -1e-300,
            -f64::MIN_POSITIVE,
            -708.0,
            -0.346,
            -0.347,
        ] {
            check(x);
        }
        assert!(worst <= 2.0 * f64::EPSILON, "max relative error {worst:e}");
    }

    #[test]
    fn ceil_and_floor_match_std() {
        for &x in &[
            -0.999,
            -0.5,
            -0.0,
            0.0,
            0.2,
            0.5,
            1.0,
            1.5,
            2.5,
            1.000_000_1,
            41.5,
            1e6,
            1e15,
        ] {
            assert_eq!(ceil_index(x), x.ceil().max(0.0) as usize, "ceil {x}");
            if x >= 0.0 {
                let (k, f) = floor_index(x);
                assert_eq!((k, f), (x.floor() as usize, x.floor()), "floor {x}");
            }
        }
        for i in 0..10_000 {
            let x = f64::from(i) * 0.37 - 0.9;
            assert_eq!(ceil_index(x), x.ceil().max(0.0) as usize, "ceil {x}");
        }
    }

    /// The clamped ceiling is `ceil_index(x).clamp(lo, hi) − lo`: at integers, a rounding
    /// step either side of them, below `lo`, above `hi` and near the range's ends.
    #[test]
    fn clamped_ceiling_matches_the_integer_clamp() {
        for (lo, hi) in [
            (0usize, 0usize),
            (0, 7),
            (5, 5),
            (3, 2051),
            (1 << 20, (1 << 20) + 64),
        ] {
            let (lof, hif) = (lo as f64, hi as f64);
            let mut xs = vec![-0.999, -0.0, 0.0, 1e-300, 2.0 * hif + 3.0, 1e15];
            let near_lo = lo.saturating_sub(3)..=(hi + 3).min(lo + 300);
            for i in (0..5).chain(near_lo).chain(hi.saturating_sub(3)..=hi + 3) {
                let k = i as f64;
                xs.extend([k, k.next_up(), k.next_down(), k + 0.5]);
            }
            for x in xs {
                let want = ceil_index(x).clamp(lo, hi) - lo;
                assert_eq!(ceil_index_in(x, lof, hif), want, "x = {x}, [{lo}, {hi}]");
            }
        }
    }

    /// The lane-wise form returns, lane by lane, the bits of the one-lane form (which is
    /// what the filter's AVX2 and portable kernels are each compared with).
    #[test]
    fn lanes_give_the_bits_of_one_lane() {
        let xs: [f64; 64] = std::array::from_fn(|i| match i {
            0 => f64::NEG_INFINITY,
            1 => -708.5,
            2 => -708.0,
            3 => -0.0,
            _ => -(i as f64).powf(1.7) * 0.37,
        });
        let lanes = exp_nonpositive_lanes(xs);
        for (x, y) in xs.iter().zip(lanes) {
            assert_eq!(y.to_bits(), exp_nonpositive(*x).to_bits(), "x = {x}");
        }
    }

    #[test]
    fn exp_underflows_to_zero() {
        assert_eq!(exp_nonpositive(-708.5), 0.0);
        assert_eq!(exp_nonpositive(-1e300), 0.0);
        assert_eq!(exp_nonpositive(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp_nonpositive(0.0), 1.0);
    }
}
