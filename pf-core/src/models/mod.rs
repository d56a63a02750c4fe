//! Ready-made models shared by several papers and by the benchmarks.

mod ar1;

pub use ar1::NoisyAr1;
