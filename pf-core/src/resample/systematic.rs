//! Systematic resampling: `u_i = (i + U)/M` with a single `U ~ U[0, 1)`.

use super::Resample;
use rand::{Rng, RngExt};

/// Systematic resampling (Kitagawa 1996; Carpenter, Clifford & Fearnhead 1999).
///
/// Instead of merging the `u_i` against the cumulative weights (a loop whose branch is
/// mispredicted about once per particle), it counts each particle's offspring directly:
/// `#{i : u_i < C_j} = ⌈M·C_j − U⌉`, so particle `j` gets `⌈M·C_j − U⌉ − ⌈M·C_{j−1} − U⌉`
/// copies. The last count is forced so that the total is exactly `M`, which is the clamp
/// that keeps rounding from running past the end.
#[derive(Debug, Clone, Copy, Default)]
pub struct Systematic;

impl Resample for Systematic {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        let u: f64 = rng.random();
        systematic_from_uniform(w, u, ancestors);
    }
}

/// Systematic resampling with a given `U ∈ [0, 1)`.
///
/// Branch-free in two passes: scatter a +1 at each boundary `k_j = ⌈M·C_j − U⌉`, then a
/// prefix sum turns the marks into ancestors, since `A_i = #{j : k_j ≤ i}` is the smallest
/// `j` with `k_j > i` (`k` is non-decreasing in `j`).
pub(crate) fn systematic_from_uniform(w: &[f64], u: f64, ancestors: &mut [usize]) {
    let mf = ancestors.len() as f64;
    prefix_offspring(w, ancestors, |c| ceil_to_usize(mf * c - u));
}

/// Ancestors from offspring boundaries: `boundary(C_j)` is the number of outputs whose point
/// lies below the cumulative weight `C_j` (non-decreasing in `j`). Each boundary marks one
/// step of the ancestor index; a prefix sum over the marks gives `A_i = #{j : k_j ≤ i}`, the
/// first particle whose cumulative weight exceeds output `i`'s point, with no branch on the
/// data. Outputs beyond every boundary go to the last particle (the clamp).
pub(crate) fn prefix_offspring(
    w: &[f64],
    ancestors: &mut [usize],
    boundary: impl Fn(f64) -> usize,
) {
    let m = ancestors.len();
    ancestors.fill(0);
    let mut c = 0.0;
    // The last particle's boundary is M by definition (the clamp), so it marks nothing.
    for &wj in &w[..w.len() - 1] {
        c += wj;
        let k = boundary(c).min(m);
        if k < m {
            ancestors[k] += 1;
        }
    }
    let mut acc = 0;
    for a in ancestors.iter_mut() {
        acc += *a;
        *a = acc;
    }
}

/// `⌈x⌉` for `x > −1`, as an index, without a libm call (`ceil` is one on baseline x86-64).
/// The float-to-int cast saturates, so negative `x` gives 0, which is `⌈x⌉` on (−1, 0].
#[inline]
pub(crate) fn ceil_to_usize(x: f64) -> usize {
    let f = x as usize;
    f + usize::from((f as f64) < x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resample::InverseCdf;

    #[test]
    fn ceil_matches_std() {
        for &x in &[-0.999, -0.5, 0.0, 0.2, 1.0, 1.000_000_1, 41.5, 1e6] {
            assert_eq!(ceil_to_usize(x), x.ceil().max(0.0) as usize, "{x}");
        }
    }

    /// The direct count gives the same ancestors as the textbook merge.
    #[test]
    fn counting_equals_the_merge() {
        let w: Vec<f64> = {
            let raw: Vec<f64> = (1..=37).map(|i| ((i * 31) % 17) as f64 + 0.5).collect();
            let s: f64 = raw.iter().sum();
            raw.iter().map(|x| x / s).collect()
        };
        for &m in &[1usize, 10, 37, 100] {
            for &u in &[0.0, 0.123, 0.5, 0.999_999] {
                let mut fast = vec![0; m];
                systematic_from_uniform(&w, u, &mut fast);
                let mut cdf = InverseCdf::new(w.len(), |j| w[j]);
                let merge: Vec<usize> = (0..m)
                    .map(|i| cdf.locate((i as f64 + u) / m as f64))
                    .collect();
                assert_eq!(fast, merge, "M = {m}, U = {u}");
            }
        }
    }
}
