//! Stratified resampling: `u_i = (i + U_i)/M` with independent `U_i ~ U[0, 1)`.

use super::{InverseCdf, Resample};
use rand::{Rng, RngExt};

/// Stratified resampling (Kitagawa 1996).
#[derive(Debug, Clone, Copy, Default)]
pub struct Stratified;

impl Resample for Stratified {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        let m = ancestors.len() as f64;
        let mut cdf = InverseCdf::new(w.len(), |j| w[j]);
        for (i, a) in ancestors.iter_mut().enumerate() {
            let u: f64 = rng.random();
            *a = cdf.locate((i as f64 + u) / m);
        }
    }
}
