//! Residual resampling: deterministic copies, then multinomial on what is left.

use super::Resample;
use super::multinomial::multinomial_draws;
use super::offspring::{Runs, SCAN};
use crate::simd::math::floor_index;
use crate::simd::{Simd, dispatch};
use rand::Rng;

/// Residual resampling (Liu & Chen 1998): particle `j` first gets `⌊M·W_j⌋` copies; the
/// remaining `R = M − Σ⌊M·W_j⌋` are drawn multinomially from the residual weights
/// `(M·W_j − ⌊M·W_j⌋)/R`, with the O(N) multinomial of
/// [`Multinomial`](super::Multinomial).
#[derive(Debug, Clone, Copy, Default)]
pub struct Residual;

impl Resample for Residual {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        residual(Simd::Auto, w, rng, ancestors);
    }
}

fn residual<R: Rng + ?Sized>(simd: Simd, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
    let m = ancestors.len();
    let mf = m as f64;
    // Deterministic copies: the floors computed SCAN at a time (vectorised), the copies
    // written as runs.
    let k = dispatch(
        simd,
        #[inline(always)]
        || {
            let mut runs = Runs::new();
            let mut kb = [0usize; SCAN];
            let mut k = 0usize;
            for (j0, block) in w.chunks(SCAN).enumerate() {
                for (c, &wj) in kb.iter_mut().zip(block) {
                    *c = floor_index(mf * wj).0;
                }
                for (q, &c) in kb[..block.len()].iter().enumerate() {
                    k = (k + c).min(m);
                    runs.push(ancestors, j0 * SCAN + q, k);
                }
            }
            k
        },
    );
    let r = m - k;
    if r == 0 {
        return;
    }
    // A multiplication, not a division, per residual weight.
    let inv_r = 1.0 / r as f64;
    let residual = |j: usize| {
        let x = mf * w[j];
        (x - floor_index(x).1) * inv_r
    };
    multinomial_draws(simd, w.len(), residual, rng, &mut ancestors[k..]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mc::stream_rng;

    /// The fast residual scheme equals its definition: the floors in order, then the
    /// multinomial of the residual weights on the same generator; on both kernels.
    #[test]
    fn residual_is_floors_then_multinomial() {
        let w: Vec<f64> = {
            let raw: Vec<f64> = (1..=150).map(|i| ((i * 7) % 19) as f64 + 0.1).collect();
            let s: f64 = raw.iter().sum();
            raw.iter().map(|x| x / s).collect()
        };
        for &m in &[1usize, 10, 150, 1000] {
            let mut want = Vec::new();
            for (j, &wj) in w.iter().enumerate() {
                let c = (m as f64 * wj).floor() as usize;
                want.extend(std::iter::repeat_n(j, c));
            }
            let k = want.len();
            let mut tail = vec![0; m - k];
            let inv_r = 1.0 / (m - k) as f64;
            multinomial_draws(
                Simd::Portable,
                w.len(),
                |j| {
                    let x = m as f64 * w[j];
                    (x - x.floor()) * inv_r
                },
                &mut stream_rng(1, m as u64),
                &mut tail,
            );
            want.extend(tail);
            for simd in [Simd::Auto, Simd::Portable] {
                let mut fast = vec![0; m];
                residual(simd, &w, &mut stream_rng(1, m as u64), &mut fast);
                assert_eq!(fast, want, "M = {m}, {simd:?}");
            }
        }
    }
}
