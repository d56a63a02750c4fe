//! The machinery the fast schemes share: cumulative weights four at a time, offspring
//! boundaries computed a block at a time, and ancestors written as runs of copies.
//!
//! Every scheme here resamples by **offspring counting**: particle `j` has a boundary `k_j`,
//! the number of outputs whose point lies below its cumulative weight `C_j` (non-decreasing
//! in `j`, and `k_{N−1} = M`, the clamp), so it fills outputs `k_{j−1} … k_j − 1`. Nothing
//! merges two sorted sequences with a data-dependent branch (which the CPU mispredicts about
//! once per particle). The ancestors are exactly those of the textbook inverse-CDF merge on
//! the same cumulative weights and the same points (tested per scheme).
//!
//! The cumulative weights are summed in blocks of four with a fixed tree of additions
//! (see [`prefix4`]), so only one addition per block waits for the previous block. They can
//! therefore differ from a left-to-right sum by rounding (a few ulp), which moves an
//! ancestor only when a point falls within those few ulp of a cumulative weight.

use crate::simd::{Simd, dispatch};

/// Particles per block of boundaries.
pub(crate) const SCAN: usize = 64;

/// Cumulative sums of `w`, continuing from `carry`, into `out`; returns the last one.
///
/// In each block of four, `w₀, w₀+w₁, (w₀+w₁)+w₂, (w₀+w₁)+(w₂+w₃)` are added to the carry:
/// the sums are non-decreasing for non-negative `w`, and the last one carries on.
#[inline(always)]
pub(crate) fn prefix4(w: &[f64], carry: f64, out: &mut [f64]) -> f64 {
    prefix4_each(w, carry, out, |_| {})
}

/// [`prefix4`], calling `visit` on each block of (up to) four weights as it is summed, so
/// that another reduction over the weights needs no pass of its own.
#[inline(always)]
pub(crate) fn prefix4_each(
    w: &[f64],
    mut carry: f64,
    out: &mut [f64],
    mut visit: impl FnMut(&[f64]),
) -> f64 {
    let mut o4 = out.chunks_exact_mut(4);
    let mut w4 = w.chunks_exact(4);
    for (o, w) in (&mut o4).zip(&mut w4) {
        let s01 = w[0] + w[1];
        let s23 = w[2] + w[3];
        o[0] = carry + w[0];
        o[1] = carry + s01;
        o[2] = carry + (s01 + w[2]);
        o[3] = carry + (s01 + s23);
        carry = o[3];
        visit(w);
    }
    let rest = w4.remainder();
    for (o, &w) in o4.into_remainder().iter_mut().zip(rest) {
        carry += w;
        *o = carry;
    }
    visit(rest);
    carry
}

/// Where the next run of copies starts in an output buffer, and the writing of runs, `W`
/// copies at a time.
///
/// `W` is 8 (two vector stores) for multinomial resampling, whose Poisson counts spread
/// widely: with 4, the branch to the loop for longer runs was mispredicted on about 2 % of
/// the particles, and 8 is 8–15 % faster. The other schemes keep 4
/// (one vector store): their counts stay within one or two of `M·W_j`, and with 8
/// systematic ran 3 % slower and residual 5 % slower at N = 10⁴.
pub(crate) struct Runs<const W: usize> {
    pos: usize,
}

impl<const W: usize> Runs<W> {
    pub(crate) fn new() -> Self {
        Runs { pos: 0 }
    }

    /// Write `value` (`W` copies of one index) into `out[pos .. k]` (nothing when `k = pos`)
    /// and move to `k`. Callers keep the copies in a vector register and add 1 to them per
    /// particle, instead of broadcasting each particle's index: 2–4 % fewer instructions
    /// for every scheme. The `W`
    /// copies go out with unconditional vector stores whatever the count; the next run
    /// overwrites the surplus. Once `out` is full, further (ordered) runs write nothing, so
    /// callers check [`is_full`](Self::is_full) once per block rather than after every run
    /// (a branch per particle that cost systematic resampling 5–9 %).
    ///
    /// Boundaries never decrease (they count points below non-decreasing cumulative
    /// weights), so the next run starts at `k` itself: taking `max(pos, k)` instead put a
    /// compare-and-select on the loop's critical path, which cost systematic resampling
    /// 9 %. Should NaN weights break the order, each run
    /// still starts where the previous one ended and the last ends at `M`, so every output
    /// is written and in range (tested).
    ///
    /// With `SMALL` (for `out.len() < 2³²`, so the position too) the position is read as 32
    /// bits, which tells the compiler that `pos + W` cannot overflow and drops one of the
    /// bound checks per run: 2.5 % fewer instructions for multinomial and residual, 7 % for
    /// systematic and 4 % for stratified in their fitting blocks.
    ///
    /// With `FIT` (only after [`fits`](Self::fits), which implies `SMALL`), `k` needs no
    /// clamp and the `W` copies no test for the end of `out`.
    #[inline(always)]
    fn push<T: Copy, const SMALL: bool, const FIT: bool>(
        &mut self,
        out: &mut [T],
        value: [T; W],
        k: usize,
    ) {
        let m = out.len();
        debug_assert!(!SMALL || u32::try_from(m).is_ok());
        debug_assert!(!FIT || (SMALL && self.pos.max(k) + W <= m));
        let pos = if SMALL {
            self.pos as u32 as usize
        } else {
            self.pos
        };
        let k = if FIT { k } else { k.min(m) };
        if FIT || pos + W <= m {
            out[pos..pos + W].copy_from_slice(&value);
            if k > pos + W {
                out[pos + W..k].fill(value[0]);
            }
        } else if k > pos {
            out[pos..k].fill(value[0]);
        }
        self.pos = k;
    }

    /// One run per particle, for particles `j0, j0 + 1, …` with boundaries `ks`, their
    /// copies advanced as a vector (see [`push`](Self::push), also for `SMALL` and `FIT`).
    #[inline(always)]
    pub(crate) fn push_each<const SMALL: bool, const FIT: bool>(
        &mut self,
        out: &mut [usize],
        j0: usize,
        ks: &[usize],
    ) {
        let mut v = [j0; W];
        for &k in ks {
            self.push::<_, SMALL, FIT>(out, v, k);
            v = v.map(|a| a + 1);
        }
    }

    /// Whether the runs of boundaries `ks` may all take `FIT`: `M < 2³²`, and the current
    /// position and every boundary leave room for `W` copies. The maximum, not the last
    /// boundary: bad weights (NaN, negative) can leave boundaries out of order, within a
    /// block and across blocks, or near `usize::MAX`.
    #[inline(always)]
    pub(crate) fn fits(&self, ks: &[usize], m: usize) -> bool {
        u32::try_from(m).is_ok()
            && ks.iter().fold(self.pos, |a, &k| a.max(k)).saturating_add(W) <= m
    }

    /// Continue from output `k`, the runs up to it written by the caller.
    #[inline(always)]
    pub(crate) fn skip_to(&mut self, k: usize) {
        self.pos = k;
    }

    /// Whether every one of the `m` outputs is written.
    #[inline(always)]
    pub(crate) fn is_full(&self, m: usize) -> bool {
        self.pos >= m
    }
}

/// Offspring counting over the weights `w` into `out` (length `M`): blocks of [`SCAN`]
/// particles get their cumulative weights ([`prefix4`]), then `boundaries(C, k)` turns the
/// block's `C` into its boundaries `k` (a vectorisable loop for the arithmetic schemes),
/// then the runs are written. The last particle's boundary is forced to `M`.
///
/// A full block that [`Runs::fits`] writes its runs with no clamp and no end test per run,
/// in a loop whose length is the constant [`SCAN`]: systematic resampling 7 % faster,
/// stratified 5 %.
#[inline(always)]
pub(crate) fn walk<B>(w: &[f64], mut boundaries: B, out: &mut [usize])
where
    B: FnMut(&[f64], &mut [usize]),
{
    let m = out.len();
    let mut cb = [0.0f64; SCAN];
    let mut kb = [0usize; SCAN];
    let mut carry = 0.0;
    let mut runs = Runs::<4>::new();
    for (b, wb) in w.chunks(SCAN).enumerate() {
        let (j0, len) = (b * SCAN, wb.len());
        carry = prefix4(wb, carry, &mut cb[..len]);
        boundaries(&cb[..len], &mut kb[..len]);
        if j0 + len == w.len() {
            kb[len - 1] = m;
        }
        if len == SCAN && runs.fits(&kb, m) {
            runs.push_each::<true, true>(out, j0, &kb);
        } else {
            runs.push_each::<false, false>(out, j0, &kb[..len]);
        }
        if runs.is_full(m) {
            return;
        }
    }
}

/// [`walk`] over the weights `w` on the chosen kernels, for the schemes whose boundaries
/// need nothing but the cumulative weights (systematic and stratified).
#[inline(always)]
pub(crate) fn walk_weights<B>(simd: Simd, w: &[f64], boundaries: B, out: &mut [usize])
where
    B: FnMut(&[f64], &mut [usize]),
{
    dispatch(
        simd,
        #[inline(always)]
        || walk(w, boundaries, out),
    );
}

/// The cumulative weights [`walk`] uses, for tests and reference merges.
#[cfg(test)]
pub(crate) fn cumulative(w: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; w.len()];
    let mut carry = 0.0;
    for (wb, ob) in w.chunks(SCAN).zip(out.chunks_mut(SCAN)) {
        carry = prefix4(wb, carry, ob);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prefix4_is_monotone_and_close_to_the_plain_sum() {
        let w: Vec<f64> = (0..1001).map(|i| ((i * 37) % 101) as f64 / 7.0).collect();
        let c = cumulative(&w);
        let mut plain = 0.0;
        for (j, (&cj, &wj)) in c.iter().zip(&w).enumerate() {
            plain += wj;
            // Both sums carry at most a few roundings of magnitude ≤ the total per step.
            assert!((cj - plain).abs() <= 1e-12 * plain.max(1.0), "{j}");
            if j > 0 {
                assert!(cj >= c[j - 1]);
            }
        }
    }

    #[test]
    fn runs_fill_exactly() {
        fn check<const W: usize, const SMALL: bool>() {
            for m in 0..12 {
                let mut out = vec![usize::MAX; m];
                let mut runs = Runs::<W>::new();
                // Boundaries 0, 0, 3, 3, 7, … , capped at m.
                let ks = [0usize, 0, 3, 3, 7, 8, 8, 11, 20];
                for (j, &k) in ks.iter().enumerate() {
                    runs.push::<_, SMALL, false>(&mut out, [j; W], k.min(m));
                }
                let full = runs.is_full(m);
                let want: Vec<usize> = (0..m)
                    .map(|i| ks.iter().position(|&k| k > i).unwrap())
                    .collect();
                assert_eq!(out, want, "M = {m}, W = {W}, small {SMALL}");
                assert!(full || m == 0 || m > 20);
            }
        }
        check::<4, false>();
        check::<8, false>();
        check::<4, true>();
        check::<8, true>();
    }

    /// [`walk`], whose full blocks mostly take the fitting runs, writes exactly what the
    /// checked runs write particle by particle, for systematic boundaries over good and bad
    /// weights (so over blocks in and out of order).
    #[test]
    fn fitting_runs_write_what_checked_runs_write() {
        let skewed: Vec<f64> = (0..1000)
            .map(|i| (((i * 37) % 101) as f64 / 101.0).powi(4))
            .collect();
        let bad: Vec<f64> = (0..500)
            .map(|i| match i % 7 {
                3 => f64::NAN,
                5 => -0.5,
                _ => 1.0,
            })
            .collect();
        for w in [skewed, vec![1.0; 700], bad] {
            let total: f64 = w.iter().filter(|x| **x > 0.0).sum();
            let w: Vec<f64> = w.iter().map(|x| x / total).collect();
            let c = cumulative(&w);
            for m in [1usize, 3, 64, 68, 100, 500, 1000, 3000] {
                for u in [0.0, 0.37, 0.999] {
                    let mf = m as f64;
                    let k = |c: f64| crate::simd::math::ceil_index(mf * c - u);
                    let mut walked = vec![usize::MAX; m];
                    walk(
                        &w,
                        |c, kb| kb.iter_mut().zip(c).for_each(|(kj, &cj)| *kj = k(cj)),
                        &mut walked,
                    );
                    let mut checked = vec![usize::MAX; m];
                    let mut runs = Runs::<4>::new();
                    for (j, &cj) in c.iter().enumerate() {
                        let kj = if j + 1 == c.len() { m } else { k(cj) };
                        runs.push::<_, false, false>(&mut checked, [j; 4], kj);
                    }
                    assert_eq!(walked, checked, "N = {}, M = {m}, U = {u}", w.len());
                    assert!(walked.iter().all(|&a| a < w.len()));
                }
            }
        }
    }

    /// A block whose boundaries fall below where the previous block ended (bad weights)
    /// neither writes past the end nor leaves an output unwritten, whatever the blocks'
    /// boundaries.
    #[test]
    fn walk_survives_boundaries_out_of_order_across_blocks() {
        let n = 3 * SCAN;
        let w = vec![1.0 / n as f64; n];
        for m in [5usize, 64, 130, 200, 260] {
            for high in [
                m.saturating_sub(1),
                m.saturating_sub(2),
                m.saturating_sub(4),
                m / 2,
            ] {
                let mut block = 0;
                let mut out = vec![usize::MAX; m];
                walk(
                    &w,
                    |_, kb| {
                        // Block 0 ends near M, block 1 drops to 0, block 2 climbs again.
                        let k = [high, 0, 3][block];
                        kb.fill(k);
                        block += 1;
                    },
                    &mut out,
                );
                assert!(out.iter().all(|&a| a < n), "M = {m}, high {high}: {out:?}");
            }
        }
    }

    /// Boundaries out of order (what NaN weights can produce) still write every output.
    #[test]
    fn runs_out_of_order_still_fill_every_output() {
        fn check<const W: usize, const SMALL: bool>() {
            for m in 1..12 {
                let mut out = vec![usize::MAX; m];
                let mut runs = Runs::<W>::new();
                for (j, &k) in [5usize, 2, 9, 1, 0, 7, 30].iter().enumerate() {
                    runs.push::<_, SMALL, false>(&mut out, [j; W], k);
                }
                assert!(out.iter().all(|&a| a < 7), "M = {m}, W = {W}: {out:?}");
            }
        }
        check::<4, false>();
        check::<8, false>();
        check::<4, true>();
        check::<8, true>();
    }
}
