//! Ziggurat tables for the standard normal and the unit exponential: 256 layers of equal
//! area (Marsaglia & Tsang 2000, with Doornik's 2005 layout of `rand_distr`), built once, at
//! first use, from the two numbers that define them: the tail's start `R` and the common
//! area `V` of a layer, `V = R f(R) + ∫_R^∞ f`.
//!
//! `x[i]` is the right edge of layer `i` (`x[0] = V / f(R)` the base layer's virtual edge,
//! which makes its rectangle hold the tail's area too; `x[1] = R`; `x[256] = 0`), built by
//! `x[i+1] = f⁻¹(f(x[i]) + V / x[i])`; `f[i] = f(x[i])` the (unnormalised) density there.
//! In double precision the edges agree with `rand_distr`'s tables (generated at higher
//! precision) to 3·10⁻¹⁰ relative at worst, near the top layer: a bias of that order in a
//! layer's probability, far below what any sample could detect.

use std::sync::LazyLock;

/// One ziggurat: layer edges and the density at them.
pub(crate) struct Ziggurat {
    /// The tail's start `R`.
    pub(crate) r: f64,
    /// Layer edges `x[0] > x[1] = R > … > x[256] = 0`.
    pub(crate) x: [f64; 257],
    /// `f(x[i])`, rising to `f(0) = 1`.
    pub(crate) f: [f64; 257],
}

impl Ziggurat {
    fn build(r: f64, v: f64, f: impl Fn(f64) -> f64, f_inv: impl Fn(f64) -> f64) -> Self {
        let mut x = [0.0; 257];
        x[0] = v / f(r);
        x[1] = r;
        for i in 1..255 {
            x[i + 1] = f_inv(f(x[i]) + v / x[i]);
        }
        Ziggurat { r, x, f: x.map(&f) }
    }
}

/// `R` for 256 normal layers (Marsaglia & Tsang 2000, to the digits of Doornik 2005).
const NORMAL_R: f64 = 3.654_152_885_361_009;

/// `R` for 256 exponential layers (Marsaglia & Tsang 2000).
const EXP_R: f64 = 7.697_117_470_131_05;

/// `∫_a^∞ e^{−x²/2} dx` by composite Simpson over `[a, a + 12]` (the rest is below
/// `e^{−(a+12)²/2}`, ~10⁻⁸⁰ of the integral for a ≈ 3.65); 2¹⁴ intervals make the error
/// ~10⁻¹⁷ relative, below a double's resolution.
fn normal_tail(a: f64) -> f64 {
    const N: usize = 1 << 14;
    let h = 12.0 / N as f64;
    let g = |t: f64| (-0.5 * t * t).exp();
    let inner: f64 = (1..N)
        .map(|k| if k % 2 == 1 { 4.0 } else { 2.0 } * g(a + k as f64 * h))
        .sum();
    h / 3.0 * (g(a) + inner + g(a + 12.0))
}

/// The standard normal's ziggurat, `f(x) = e^{−x²/2}`.
pub(crate) static NORMAL: LazyLock<Ziggurat> = LazyLock::new(|| {
    let f = |x: f64| (-0.5 * x * x).exp();
    let v = NORMAL_R * f(NORMAL_R) + normal_tail(NORMAL_R);
    Ziggurat::build(NORMAL_R, v, f, |y: f64| (-2.0 * y.ln()).sqrt())
});

/// The unit exponential's ziggurat, `f(x) = e^{−x}` (so `V = (R + 1) e^{−R}`).
pub(crate) static EXPONENTIAL: LazyLock<Ziggurat> = LazyLock::new(|| {
    let f = |x: f64| (-x).exp();
    let v = (EXP_R + 1.0) * f(EXP_R);
    Ziggurat::build(EXP_R, v, f, |y: f64| -y.ln())
});

#[cfg(test)]
mod tests {
    use super::*;

    /// Every layer has area V: the rectangles of layers 1…255 (`x[i] (f[i+1] − f[i])`) and
    /// the base (its rectangle plus the tail), to a relative 10⁻¹² (the recurrence loses a
    /// few ulp per layer); and the top edge reaches 0, i.e. R and V are consistent.
    #[test]
    fn layers_have_equal_areas_and_close_at_zero() {
        for (z, tail) in [
            (&*NORMAL, normal_tail(NORMAL_R)),
            (&*EXPONENTIAL, (-EXP_R).exp()),
        ] {
            let v = z.x[0] * z.f[1];
            assert!((z.r * z.f[1] + tail - v).abs() < 1e-15 * v);
            for i in 1..255 {
                let area = z.x[i] * (z.f[i + 1] - z.f[i]);
                assert!((area - v).abs() < 1e-12 * v, "layer {i}: {area} vs {v}");
            }
            // The top layer [0, x[255]] × [f(x[255]), 1] has area V as well.
            let top = z.x[255] * (1.0 - z.f[255]);
            assert!((top - v).abs() < 1e-9 * v, "top layer: {top} vs {v}");
            assert_eq!(z.x[256], 0.0);
            assert_eq!(z.f[256], 1.0);
        }
    }
}
