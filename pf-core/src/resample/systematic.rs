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
pub(crate) fn systematic_from_uniform(w: &[f64], u: f64, ancestors: &mut [usize]) {
    let m = ancestors.len();
    let mf = m as f64;
    let last = w.len() - 1;
    let mut c = 0.0;
    let mut written = 0usize;
    for (j, &wj) in w.iter().enumerate() {
        c += wj;
        let k = if j == last {
            m
        } else {
            ((mf * c - u).ceil().max(0.0) as usize).min(m)
        };
        if k > written {
            ancestors[written..k].fill(j);
            written = k;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resample::InverseCdf;

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
