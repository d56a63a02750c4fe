//! The Poisson machinery of the O(N) multinomial draws: counts by inversion of 53-bit
//! uniforms, and the uniformly chosen draws removed when conditioning a Poisson total.

use rand::{Rng, RngExt};

/// Outcomes with a threshold; for the rates this module is used with (at most 4:
/// `P(N ≥ 48) < 10⁻³⁴` there) the count stops well before the last.
const LEN: usize = 48;

/// `2⁵³`, above every 53-bit draw.
const TWO53: u64 = 1 << 53;

/// Inversion thresholds of a Poisson(`rate`) law: with `v` a uniform 53-bit integer,
/// `#{k : v ≥ T_k}` is a Poisson(`rate`) count (`T_k = ⌊2⁵³·P(N ≤ k)⌋`, exact to 2⁻⁵³ per
/// outcome; the last threshold is 2⁵³, above every draw, where the tail is below 2⁻⁵³).
#[derive(Debug, Clone)]
pub(crate) struct Thresholds {
    t: [u64; LEN],
}

impl Thresholds {
    /// The thresholds of Poisson(`rate`), `0 < rate ≤ 4`.
    pub(crate) fn new(rate: f64) -> Self {
        debug_assert!(rate > 0.0 && rate <= 4.0, "rate {rate}");
        let mut t = [TWO53; LEN];
        let (mut term, mut cdf) = ((-rate).exp(), 0.0f64);
        for (k, tk) in t.iter_mut().enumerate() {
            cdf += term;
            // Stop where the distribution function rounds to 1, or stalls just below it
            // with a tail `P(N > k) < 2·term < 2⁻⁵³` (past `2·rate` the terms more than
            // halve): the count then never passes `k`.
            if cdf >= 1.0 || (k as f64 >= 2.0 * rate && term < 1.0 / (2 * TWO53) as f64) {
                break;
            }
            *tk = (cdf * TWO53 as f64) as u64;
            term *= rate / (k + 1) as f64;
        }
        Thresholds { t }
    }

    /// The count of `v` against the first `Q` thresholds (branch-free; `Q` means "`Q` or
    /// more", finished by [`Thresholds::count_from`]).
    #[inline(always)]
    pub(crate) fn count_quick<const Q: usize>(&self, v: u64) -> usize {
        let mut k = 0;
        for &th in &self.t[..Q] {
            k += usize::from(v >= th);
        }
        k
    }

    /// The whole count of `v`, known to be at least `q`.
    pub(crate) fn count_from(&self, v: u64, q: usize) -> usize {
        q + self.t[q..].iter().take_while(|&&th| v >= th).count()
    }
}

/// `out` ← `d ≤ t` distinct indices among `0 … t − 1`, uniformly, sorted, then
/// `usize::MAX` (a sentinel for merges). Distinct draws are taken until `d` remain; the
/// procedure is invariant under relabelling, so every subset is equally likely. Expected
/// work O(d log d) for `d` well below `t`, as here (`d` of order `√t`).
pub(crate) fn distinct_sorted<R: Rng + ?Sized>(
    t: usize,
    d: usize,
    rng: &mut R,
    out: &mut Vec<usize>,
) {
    out.clear();
    while out.len() < d {
        for _ in out.len()..d {
            out.push(rng.random_range(0..t));
        }
        out.sort_unstable();
        out.dedup();
    }
    out.push(usize::MAX);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mc::stream_rng;

    /// The thresholds are the distribution function, to the 53-bit grid, and stop where it
    /// rounds to 1.
    #[test]
    fn thresholds_are_the_poisson_cdf() {
        for rate in [0.3, 1.0, 1.003, 2.5, 4.0] {
            let th = Thresholds::new(rate);
            let (mut cdf, mut ln_fact) = (0.0, 0.0);
            for (k, &t) in th.t.iter().enumerate() {
                if k > 0 {
                    ln_fact += (k as f64).ln();
                }
                cdf += (k as f64 * f64::ln(rate) - rate - ln_fact).exp();
                let want = cdf.min(1.0) * TWO53 as f64;
                assert!(
                    (t as f64 - want).abs() <= 64.0,
                    "rate {rate}, k = {k}: {t} against {want}"
                );
            }
            let last =
                th.t.iter()
                    .position(|&x| x == TWO53)
                    .expect("a last threshold");
            assert!(last < 40, "rate {rate}: {last}");
        }
    }

    /// The quick count and its continuation give the full count.
    #[test]
    fn quick_count_and_continuation_agree() {
        let th = Thresholds::new(2.5);
        let mut rng = stream_rng(4, 0);
        for _ in 0..10_000 {
            let v = rng.next_u64() >> 11;
            let full = th.t.iter().filter(|&&x| v >= x).count();
            let quick = th.count_quick::<3>(v);
            let got = if quick == 3 {
                th.count_from(v, 3)
            } else {
                quick
            };
            assert_eq!(got, full);
        }
    }

    /// Exactly `d` distinct sorted indices below `t`, then the sentinel; and every index is
    /// equally likely to be chosen (chi-square over 8 cells, 7 df, P(χ² > 24.3) = 0.001).
    #[test]
    fn distinct_sorted_is_a_uniform_subset() {
        let mut rng = stream_rng(8, 0);
        let mut out = Vec::new();
        let mut hits = [0usize; 8];
        for _ in 0..20_000 {
            distinct_sorted(8, 3, &mut rng, &mut out);
            assert_eq!(out.len(), 4);
            assert_eq!(out[3], usize::MAX);
            assert!(out[..3].windows(2).all(|p| p[0] < p[1]));
            for &i in &out[..3] {
                hits[i] += 1;
            }
        }
        let e = 20_000.0 * 3.0 / 8.0;
        let chi2: f64 = hits.iter().map(|&h| (h as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 24.3, "χ² {chi2}");
        distinct_sorted(5, 5, &mut rng, &mut out);
        assert_eq!(out, [0, 1, 2, 3, 4, usize::MAX]);
    }
}
