//! Systematic resampling: `u_i = (i + U)/M` with a single `U ~ U[0, 1)`.

use super::{InverseCdf, Resample};
use rand::{Rng, RngExt};

/// Systematic resampling (Kitagawa 1996; Carpenter, Clifford & Fearnhead 1999).
#[derive(Debug, Clone, Copy, Default)]
pub struct Systematic;

impl Resample for Systematic {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        let m = ancestors.len() as f64;
        let u0: f64 = rng.random();
        let mut cdf = InverseCdf::new(w.len(), |j| w[j]);
        for (i, a) in ancestors.iter_mut().enumerate() {
            *a = cdf.locate((i as f64 + u0) / m);
        }
    }
}
