//! Residual resampling: deterministic copies, then multinomial on what is left.

use super::multinomial::sorted_uniforms;
use super::{InverseCdf, Resample};
use rand::Rng;

/// Residual resampling (Liu & Chen 1998): particle `j` first gets `⌊M·W_j⌋` copies; the
/// remaining `R = M − Σ⌊M·W_j⌋` are drawn multinomially from the residual weights
/// `(M·W_j − ⌊M·W_j⌋)/R`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Residual;

impl Resample for Residual {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        let m = ancestors.len();
        let mf = m as f64;
        let mut k = 0;
        for (j, &wj) in w.iter().enumerate() {
            // M·w ≥ 0, so the cast is the floor (without a libm call on baseline x86-64).
            let copies = ((mf * wj) as usize).min(m - k);
            ancestors[k..k + copies].fill(j);
            k += copies;
        }
        let r = m - k;
        if r == 0 {
            return;
        }
        // A multiplication, not a division, on the merge's dependency chain.
        let inv_r = 1.0 / r as f64;
        let residual = |j: usize| {
            let x = mf * w[j];
            (x - (x as usize) as f64) * inv_r
        };
        // The residual draws are about half as many as the particles, so the merge mostly
        // skips particles: a branching merge predicts that well (measured faster here than
        // the select-based merge multinomial resampling uses).
        let mut cdf = InverseCdf::new(w.len(), residual);
        let tail = &mut ancestors[k..];
        sorted_uniforms(r, rng, |i, u| tail[i] = cdf.locate(u));
    }
}
