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
            let copies = ((mf * wj).floor() as usize).min(m - k);
            ancestors[k..k + copies].fill(j);
            k += copies;
        }
        let r = m - k;
        if r == 0 {
            return;
        }
        let residual = |j: usize| {
            let x = mf * w[j];
            (x - x.floor()) / r as f64
        };
        let mut cdf = InverseCdf::new(w.len(), residual);
        let tail = &mut ancestors[k..];
        sorted_uniforms(r, rng, |i, u| tail[i] = cdf.locate(u));
    }
}
