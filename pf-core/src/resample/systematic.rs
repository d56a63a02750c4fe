//! Systematic resampling: `u_i = (i + U)/M` with a single `U ~ U[0, 1)`.

use super::Resample;
use super::offspring::walk_weights;
use crate::simd::Simd;
use crate::simd::math::ceil_index;
use rand::{Rng, RngExt};

/// Systematic resampling (Kitagawa 1996; Carpenter, Clifford & Fearnhead 1999).
///
/// Instead of merging the `u_i` against the cumulative weights (a loop whose branch is
/// mispredicted about once per particle), it counts each particle's offspring directly:
/// `#{i : u_i < C_j} = ⌈M·C_j − U⌉`, so particle `j` gets `⌈M·C_j − U⌉ − ⌈M·C_{j−1} − U⌉`
/// copies, written as one run of copies. The last count is
/// forced so that the total is exactly `M`, which is the clamp that keeps rounding from
/// running past the end.
#[derive(Debug, Clone, Copy, Default)]
pub struct Systematic;

impl Resample for Systematic {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        let u: f64 = rng.random();
        systematic_from_uniform(Simd::Auto, w, u, ancestors);
    }
}

/// Systematic resampling with a given `U ∈ [0, 1)`.
pub(crate) fn systematic_from_uniform(simd: Simd, w: &[f64], u: f64, ancestors: &mut [usize]) {
    let mf = ancestors.len() as f64;
    walk_weights(
        simd,
        w,
        |c, k| {
            for (k, &c) in k.iter_mut().zip(c) {
                *k = ceil_index(mf * c - u);
            }
        },
        ancestors,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resample::offspring::cumulative;

    /// The direct count gives the same ancestors as the textbook merge of the points
    /// `(i + U)/M` with the same cumulative weights, on both kernels.
    #[test]
    fn counting_equals_the_merge() {
        let w: Vec<f64> = {
            let raw: Vec<f64> = (1..=337).map(|i| ((i * 31) % 17) as f64 + 0.5).collect();
            let s: f64 = raw.iter().sum();
            raw.iter().map(|x| x / s).collect()
        };
        let c = cumulative(&w);
        for &m in &[1usize, 3, 10, 37, 100, 337, 1000] {
            for &u in &[0.0, 0.123, 0.5, 0.999_999] {
                let mut j = 0;
                let merge: Vec<usize> = (0..m)
                    .map(|i| {
                        // First j with i < M·C_j − U (the boundary's own arithmetic).
                        while j + 1 < w.len() && (i as f64) >= m as f64 * c[j] - u {
                            j += 1;
                        }
                        j
                    })
                    .collect();
                for simd in [Simd::Auto, Simd::Portable] {
                    let mut fast = vec![0; m];
                    systematic_from_uniform(simd, &w, u, &mut fast);
                    assert_eq!(fast, merge, "M = {m}, U = {u}, {simd:?}");
                }
            }
        }
    }
}
