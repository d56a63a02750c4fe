//! Multinomial resampling in O(N): a Poisson process of points, conditioned on its size.

use super::Resample;
use super::offspring::walk;
use super::poisson::{Thresholds, distinct_sorted};
use crate::simd::LANES;
use crate::simd::math::{floor_index, unit_from_bits};
use crate::simd::{LaneRng, Simd, dispatch};
use rand::{Rng, RngExt};
use std::cell::RefCell;

/// Multinomial resampling: `M` independent draws from the weights.
///
/// Drawing `M` independent uniforms and matching each with the cumulative weights needs
/// the uniforms in order; sorting them costs O(M log M). Instead the points come already
/// grouped in `M` equal cells of [0, 1):
///
/// 1. **Poissonisation.** Each cell gets an independent Poisson(1) number of points; the
///    total `T` is then Poisson(M) and, given `T`, the points of a Poisson process are
///    `T` independent uniforms.
/// 2. **Conditioning on `M`.** If `T > M`, a uniformly chosen subset of `T − M` points is
///    removed; if `T < M`, `M − T` cells drawn uniformly each get one more point. Removing a
///    random subset of independent uniforms, or adding independent uniforms, leaves
///    independent uniforms, so exactly `M` independent uniforms remain. (Points within a
///    cell are exchangeable, so removing one of a cell's points is removing its last.)
///    `|T − M|` is of order `√M`, drawn from the caller's generator.
/// 3. **Offsets.** Point `g` of cell `f` sits at `f + u_g` (in units of `1/M`) with `u_g`
///    uniform on [0, 1), drawn after the counts are final; a cell's points are not sorted,
///    only counted, and only their offsets `u_g` are stored.
///
/// Particle `j`'s boundary, the number of points below its cumulative weight `C_j`, is
/// with `x = M·C_j` and `f = ⌊x⌋`: every point of the cells before `f` (from a table of
/// the cells' first points), plus the points of cell `f` with `u_g < x − f` (one on
/// average, compared four at a time; `x − f` is exact, so this is the exact comparison of
/// the point with `x`). The counts and offsets come from a [`LaneRng`] seeded from
/// the caller's generator. The
/// ancestors are exactly those of the textbook merge of the same points with the same
/// cumulative weights (tested), and the joint law of the offspring counts is multinomial
/// (tested by a chi-square over every outcome of a small case).
#[derive(Debug, Clone, Copy, Default)]
pub struct Multinomial;

impl Resample for Multinomial {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        multinomial_draws(Simd::Auto, w, rng, ancestors);
    }
}

/// Offsets read past a cell's start without checking its count.
const PAD: usize = 4;

/// Thresholds compared in the vectorised pass; counts of `QUICK` or more (probability
/// 6·10⁻⁴) are finished against the rest.
const QUICK: usize = 6;

thread_local! {
    /// Scratch of [`multinomial_draws`], reused from call to call on each thread (no
    /// allocation once grown; every call overwrites what it reads).
    static SCRATCH: RefCell<Points> = const { RefCell::new(Points::new()) };
}

/// `M` uniform points grouped in `M` cells.
#[derive(Debug)]
pub(crate) struct Points {
    /// `first[f]`: index of cell `f`'s first point (`first[M] = first[M + 1] = M`).
    first: Vec<usize>,
    /// Offsets `u_g` in cell order (cell `f`'s from `first[f]`), then `PAD` zeros read
    /// past the last cell and masked off.
    offset: Vec<f64>,
    /// The conditioning step's sorted removals (point indices) or additions (cells).
    fix: Vec<usize>,
}

impl Points {
    const fn new() -> Self {
        Points {
            first: Vec::new(),
            offset: Vec::new(),
            fix: Vec::new(),
        }
    }

    /// Draw `m ≥ 1` points: counts and offsets from `lanes`, the conditioning from `rng`.
    #[inline(always)]
    fn draw<R: Rng + ?Sized>(&mut self, m: usize, lanes: &mut LaneRng, rng: &mut R) {
        let Points { first, offset, fix } = self;
        let poisson1 = Thresholds::new(1.0);
        first.resize(m + 2, 0);
        offset.resize(m + PAD, 0.0);
        // Poisson(1) counts, 64 cells per lane step, into first[..m].
        let mut t = 0usize;
        let mut bits = [0u64; LANES];
        for cells in first[..m].chunks_mut(LANES) {
            lanes.step(&mut bits);
            let mut tail = false;
            for (c, &b) in cells.iter_mut().zip(bits.iter()) {
                let k = poisson1.count_quick::<QUICK>(b >> 11);
                tail |= k == QUICK;
                *c = k;
            }
            if tail {
                for (c, &b) in cells.iter_mut().zip(bits.iter()) {
                    if *c == QUICK {
                        *c = poisson1.count_from(b >> 11, QUICK);
                    }
                }
            }
            t += cells.iter().sum::<usize>();
        }
        // Conditioning on M points: a uniform subset of T − M points to remove, or M − T
        // cells, with replacement, to add to.
        if t > m {
            distinct_sorted(t, t - m, rng, fix);
        } else {
            fix.clear();
            fix.extend((t..m).map(|_| rng.random_range(0..m)));
            fix.sort_unstable();
            fix.push(usize::MAX);
        }
        // Counts into starts, removals and additions applied on the way.
        let (mut start, mut orig, mut p) = (0usize, 0usize, 0usize);
        for (f, c) in first[..m].iter_mut().enumerate() {
            let mut nf = *c;
            orig += *c;
            if t > m {
                while fix[p] < orig {
                    nf -= 1;
                    p += 1;
                }
            } else {
                while fix[p] == f {
                    nf += 1;
                    p += 1;
                }
            }
            *c = start;
            start += nf;
        }
        first[m] = start;
        first[m + 1] = start;
        debug_assert_eq!(start, m);
        // Offsets, in cell order.
        for u in offset[..m].chunks_mut(LANES) {
            lanes.step(&mut bits);
            for (u, &b) in u.iter_mut().zip(bits.iter()) {
                *u = unit_from_bits(b);
            }
        }
        offset[m..].fill(0.0);
    }

    /// Boundary of the cumulative weight `c`: with `x = M·c` and `f = ⌊x⌋`, every point of
    /// the cells before `f`, plus the points of cell `f` whose offset is below `x − f`, four
    /// compared at a time (a cell's points are unsorted, so all of them are compared; reads
    /// past the cell's end are masked off).
    #[inline(always)]
    fn below(&self, mf: f64, c: f64) -> usize {
        let m = self.first.len() - 2;
        let x = mf * c;
        let cell = floor_index(x).0;
        // `⌊x⌋` back from the integer (exact below 2⁵¹): taking `floor_index`'s double
        // instead compiled to a branch on its rounding, mispredicted half the time.
        let t = x - (cell as i64) as f64;
        let cell = cell.min(m);
        let (mut i, end) = (self.first[cell], self.first[cell + 1]);
        let mut k = i;
        loop {
            let u: &[f64; PAD] = self.offset[i..i + PAD].try_into().expect("PAD offsets");
            let left = end.saturating_sub(i);
            k += usize::from((u[0] < t) & (0 < left))
                + usize::from((u[1] < t) & (1 < left))
                + usize::from((u[2] < t) & (2 < left))
                + usize::from((u[3] < t) & (3 < left));
            i += PAD;
            if i >= end {
                return k;
            }
        }
    }
}

/// `out` ← `M = out.len()` independent draws from the weights `w` (summing to 1 up to
/// rounding), in increasing order, in O(M + N): see [`Multinomial`].
pub(crate) fn multinomial_draws<R: Rng + ?Sized>(
    simd: Simd,
    w: &[f64],
    rng: &mut R,
    out: &mut [usize],
) {
    let m = out.len();
    if m == 0 || w.is_empty() {
        return;
    }
    let mut lanes = LaneRng::from_rng(rng);
    let mf = m as f64;
    SCRATCH.with(|cell| {
        let mut points = cell.borrow_mut();
        dispatch(
            simd,
            #[inline(always)]
            || {
                points.draw(m, &mut lanes, rng);
                let points = &*points;
                walk(
                    w,
                    #[inline(always)]
                    |c, k| {
                        for (k, &c) in k.iter_mut().zip(c) {
                            *k = points.below(mf, c);
                        }
                    },
                    out,
                );
            },
        );
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mc::stream_rng;
    use crate::resample::offspring::cumulative;
    use crate::testing::{binomial_pmf, chi2_quantile_999, multinomial_pmf, pearson_pooled};

    fn weights(n: usize, skew: i32) -> Vec<f64> {
        let raw: Vec<f64> = (1..=n)
            .map(|i| (((i * 17) % 11) as f64 + 0.3).powi(skew))
            .collect();
        let s: f64 = raw.iter().sum();
        raw.iter().map(|x| x / s).collect()
    }

    /// The same points as `multinomial_draws(…, stream_rng(seed, r), …)` draws.
    fn points(m: usize, seed: u64, r: u64) -> Points {
        let mut rng = stream_rng(seed, r);
        let mut lanes = LaneRng::from_rng(&mut rng);
        let mut p = Points::new();
        p.draw(m, &mut lanes, &mut rng);
        p
    }

    /// The cell search gives the ancestors of the plain merge of the same points with the
    /// same cumulative weights, on both kernels, for M below, at and above N.
    #[test]
    fn cell_search_equals_the_plain_merge_of_the_same_points() {
        for (n, skew) in [(23usize, 1), (300, 4), (1, 1)] {
            let w = weights(n, skew);
            let c = cumulative(&w);
            for &m in &[1usize, 5, 23, 200, 301, 1000] {
                let p = points(m, 9, m as u64);
                assert_eq!(p.first[m], m);
                // Every point as (cell, offset), in cell order; point (f, u) lies
                // below the key x when f < ⌊x⌋, or f = ⌊x⌋ and u < x − f.
                let pts: Vec<(usize, f64)> = (0..m)
                    .flat_map(|f| (p.first[f]..p.first[f + 1]).map(move |g| (f, g)))
                    .map(|(f, g)| (f, p.offset[g]))
                    .collect();
                assert_eq!(pts.len(), m);
                let below = |(f, u): (usize, f64), x: f64| {
                    let fx = x.floor();
                    (f as f64) < fx || ((f as f64) == fx && u < x - fx)
                };
                let mut sorted = pts.clone();
                sorted.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
                let mut j = 0;
                let plain: Vec<usize> = sorted
                    .iter()
                    .map(|&pt| {
                        // First j whose key M·C_j is above the point.
                        while j + 1 < n && !below(pt, m as f64 * c[j]) {
                            j += 1;
                        }
                        j
                    })
                    .collect();
                for simd in [Simd::Auto, Simd::Portable] {
                    let mut fast = vec![0; m];
                    multinomial_draws(simd, &w, &mut stream_rng(9, m as u64), &mut fast);
                    assert_eq!(fast, plain, "N = {n}, M = {m}, {simd:?}");
                }
            }
        }
    }

    /// Whatever the size of the Poisson process, exactly M points come out, each offset
    /// within its cell.
    #[test]
    fn conditioning_gives_exactly_m_points() {
        for m in [1usize, 2, 3, 64, 65, 1000, 4097] {
            for r in 0..20 {
                let p = points(m, 5, r);
                assert_eq!(p.first[0], 0);
                assert_eq!(p.first[m], m);
                assert!(p.first.windows(2).all(|w| w[0] <= w[1]));
                for f in 0..m {
                    for g in p.first[f]..p.first[f + 1] {
                        assert!((0.0..1.0).contains(&p.offset[g]), "{f}");
                    }
                }
                assert_eq!(p.offset.len(), m + PAD);
            }
        }
    }

    /// The joint law of the offspring counts of 3 particles from M = 4 draws is
    /// Multinomial(4; W): chi-square over all 15 outcomes from 60 000 seeded draws (the
    /// conditioning step acts in most of them, since T ~ Poisson(4)). With 14 degrees of
    /// freedom, P(χ² > 36.1) = 0.001.
    #[test]
    fn offspring_counts_are_jointly_multinomial() {
        let w = [0.5, 0.3, 0.2];
        let m = 4usize;
        let reps = 60_000;
        let mut seen = std::collections::HashMap::new();
        let mut rng = stream_rng(11, 0);
        let mut out = [0usize; 4];
        for _ in 0..reps {
            multinomial_draws(Simd::Auto, &w, &mut rng, &mut out);
            let mut k = [0usize; 3];
            for &a in &out {
                k[a] += 1;
            }
            *seen.entry(k).or_insert(0usize) += 1;
        }
        let mut chi2 = 0.0;
        let mut outcomes = 0;
        for a in 0..=m {
            for b in 0..=m - a {
                let c = m - a - b;
                let e = multinomial_pmf(&[a, b, c], &w) * reps as f64;
                let o = seen.get(&[a, b, c]).copied().unwrap_or(0) as f64;
                chi2 += (o - e).powi(2) / e;
                outcomes += 1;
            }
        }
        assert_eq!(outcomes, 15);
        assert_eq!(seen.values().sum::<usize>(), reps);
        assert!(chi2 < 36.1, "chi-square {chi2}");
    }

    /// With one heavy particle (its cumulative weight spans many cells) and two light ones,
    /// each particle's count is Binomial(M, W_j): chi-square per particle over 20 000 draws.
    #[test]
    fn marginals_are_binomial_when_one_weight_dominates() {
        let w = [0.05, 0.9, 0.05];
        let m = 40usize;
        let mut hist = [[0usize; 41]; 3];
        let mut rng = stream_rng(12, 0);
        let mut out = vec![0usize; m];
        for _ in 0..20_000 {
            multinomial_draws(Simd::Auto, &w, &mut rng, &mut out);
            let mut k = [0usize; 3];
            for &a in &out {
                k[a] += 1;
            }
            for (h, &kj) in hist.iter_mut().zip(&k) {
                h[kj] += 1;
            }
        }
        for (j, h) in hist.iter().enumerate() {
            let (stat, df) = pearson_pooled(h, |k| binomial_pmf(m, w[j], k));
            assert!(
                stat < chi2_quantile_999(df),
                "particle {j}: χ² {stat} on {df} df"
            );
        }
    }

    /// Weights with no mass give every draw to the last particle, as the cumulative-weight
    /// schemes do, and never hang.
    #[test]
    fn zero_weights_go_to_the_last_particle() {
        let mut out = vec![7usize; 10];
        multinomial_draws(Simd::Auto, &[0.0; 3], &mut stream_rng(1, 0), &mut out);
        assert!(out.iter().all(|&a| a == 2));
    }
}
