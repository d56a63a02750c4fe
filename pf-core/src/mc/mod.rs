//! Reproducible Monte Carlo replications.
//!
//! Replication `r` of a run with seed `s` draws from its own stream, derived from `(s, r)`
//! alone. Replications run in parallel with rayon and are collected in order of `r`, so the
//! results are bit-identical whatever the number of threads, and, for [`try_replicate`]
//! through [`dist`] (feature `mpi`), whatever the number of MPI ranks.

pub mod dist;

use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// The engine's generator: xoshiro256++ (Blackman & Vigna 2021), fast, 2²⁵⁶ − 1 period,
/// and seedable from 32 bytes.
pub type PfRng = Xoshiro256PlusPlus;

/// SplitMix64's output function (Steele, Lea & Flood 2014): a bijective 64-bit mixer.
#[inline(always)]
pub(crate) fn splitmix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(SPLITMIX_MULTIPLIERS[0]);
    z = (z ^ (z >> 27)).wrapping_mul(SPLITMIX_MULTIPLIERS[1]);
    z ^ (z >> 31)
}

/// The two multipliers of [`splitmix`], in order (its vector twins use them too).
pub(crate) const SPLITMIX_MULTIPLIERS: [u64; 2] = [0xbf58_476d_1ce4_e5b9, 0x94d0_49bb_1331_11eb];

/// SplitMix64's increment, the odd integer closest to `2⁶⁴/φ`.
pub(crate) const GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// The stream of replication `r` under seed `seed`.
///
/// The 256-bit state is four SplitMix64 outputs of a counter started at a mix of both
/// numbers, so nearby `(seed, r)` pairs give unrelated states. Seed 0 is a seed like any
/// other.
pub fn stream_rng(seed: u64, r: u64) -> PfRng {
    let mut state = splitmix(seed).wrapping_add(splitmix(r ^ 0x5851_f42d_4c95_7f2d));
    let mut bytes = [0u8; 32];
    for chunk in bytes.chunks_exact_mut(8) {
        state = state.wrapping_add(GAMMA);
        chunk.copy_from_slice(&splitmix(state).to_le_bytes());
    }
    PfRng::from_seed(bytes)
}

/// How much Monte Carlo work an experiment does. Each experiment maps it to its own sizes
/// (particles, replications, steps) and documents them; the paper crates and the report
/// share this one scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Scale {
    /// Seconds: few particles and runs, for tests and smoke checks; noisy figures.
    Quick,
    /// About a minute or less per experiment: the standard report.
    #[default]
    Default,
    /// The paper's own sizes and replication counts.
    Full,
}

impl Scale {
    /// Every preset, smallest first.
    pub const ALL: [Scale; 3] = [Scale::Quick, Scale::Default, Scale::Full];

    /// The lower-case name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Scale::Quick => "quick",
            Scale::Default => "default",
            Scale::Full => "full",
        }
    }
}

impl std::str::FromStr for Scale {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        crate::names::parse_name("scale", &Scale::ALL, Scale::name, s)
    }
}

impl std::fmt::Display for Scale {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Where replications run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Par {
    /// On the calling thread.
    Seq,
    /// On the current rayon pool (cap it with `rayon::ThreadPool::install`).
    #[default]
    Rayon,
}

/// Run `f(r, rng_r)` for `r = 0..n` and collect the results in order of `r`.
///
/// Always on this process, for results of any type; in an MPI run every rank that calls it
/// computes every replication. The studies that MPI ranks share go through
/// [`try_replicate`], whose results can be serialised to cross ranks ([`dist`]).
pub fn replicate<T, F>(seed: u64, n: usize, par: Par, f: F) -> Vec<T>
where
    T: Send,
    F: Fn(usize, &mut PfRng) -> T + Sync,
{
    let mut out = Vec::new();
    replicate_into(seed, n, par, f, &mut out);
    out
}

/// [`replicate`] into `out`, which is cleared first and keeps its capacity.
fn replicate_into<T, F>(seed: u64, n: usize, par: Par, f: F, out: &mut Vec<T>)
where
    T: Send,
    F: Fn(usize, &mut PfRng) -> T + Sync,
{
    let run = |r: usize| f(r, &mut stream_rng(seed, r as u64));
    match par {
        Par::Seq => {
            out.clear();
            out.extend((0..n).map(run));
        }
        Par::Rayon => (0..n).into_par_iter().map(run).collect_into_vec(out),
    }
}

/// [`replicate`] for fallible replications: the first error (in order of `r`) is returned.
///
/// # Errors
/// [`CoreError::TooLarge`](crate::CoreError::TooLarge) for more than
/// [`MAX_COUNT`](crate::limits::MAX_COUNT) replications (a count from user input), or
/// results that would not fit in the machine's memory, both checked before anything runs;
/// otherwise the error of the lowest-numbered failing replication. In an MPI run ([`dist`])
/// that error is [`CoreError::Replication`](crate::CoreError::Replication) with its index
/// and message, on every rank; ranks whose programs took different paths get
/// [`CoreError::Distributed`](crate::CoreError::Distributed).
pub fn try_replicate<T, E, F>(seed: u64, n: usize, par: Par, f: F) -> Result<Vec<T>, E>
where
    T: Send + Serialize + DeserializeOwned,
    E: Send + std::fmt::Display + From<crate::CoreError>,
    F: Fn(usize, &mut PfRng) -> Result<T, E> + Sync,
{
    const WHAT: &str = "the number of replications";
    crate::limits::check_count(WHAT, n)?;
    // Both result vectors, checked together and reserved before the first replication
    // runs, so that a count the machine cannot hold is an error rather than an aborted
    // allocation or a process killed half-way.
    let both = size_of::<Result<T, E>>() + size_of::<T>();
    crate::limits::check_memory(WHAT, n, n.saturating_mul(both))?;
    if let Some(study) = dist::Study::begin(seed, n) {
        return study.run(par, f);
    }
    let mut all: Vec<Result<T, E>> = crate::limits::try_with_capacity(WHAT, n)?;
    let mut ok: Vec<T> = crate::limits::try_with_capacity(WHAT, n)?;
    replicate_into(seed, n, par, f, &mut all);
    for result in all {
        ok.push(result?);
    }
    Ok(ok)
}

/// Sample mean and standard error `σ̂/√R` of replicated values.
pub fn mean_and_se(x: &[f64]) -> (f64, f64) {
    let (mean, var) = mean_and_var(x);
    (mean, (var / x.len() as f64).sqrt())
}

/// Sample mean and standard deviation `σ̂` of replicated values (divisor `R − 1`; the
/// deviation is 0 below two values): the spread of one estimator across replications.
pub fn mean_and_sd(x: &[f64]) -> (f64, f64) {
    let (mean, var) = mean_and_var(x);
    (mean, var.sqrt())
}

/// Sample mean and variance (divisor `R − 1`, 0 below two values).
fn mean_and_var(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var)
}

/// Root mean square of replicated errors, from their squares, and its standard error by the
/// delta method: the squares' mean's standard error through the square root, `se/(2·RMS)`
/// (0 when the RMS is 0).
pub fn rms_and_se(squared: &[f64]) -> (f64, f64) {
    let (mean, se) = mean_and_se(squared);
    let rms = mean.sqrt();
    (rms, if rms > 0.0 { se / (2.0 * rms) } else { 0.0 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CoreError;
    use rand::RngExt;

    /// The report's manifest, the experiments' JSON and the command line all name the
    /// scale in lower case, the same way.
    #[test]
    fn scale_names_round_trip() {
        for s in Scale::ALL {
            let quoted = format!("\"{}\"", s.name());
            assert_eq!(serde_json::to_string(&s).unwrap(), quoted);
            assert_eq!(serde_json::from_str::<Scale>(&quoted).unwrap(), s);
            assert_eq!(s.to_string().parse::<Scale>(), Ok(s));
        }
        assert!("huge".parse::<Scale>().unwrap_err().contains("huge"));
        assert_eq!(Scale::default(), Scale::Default);
    }

    #[test]
    fn streams_differ_and_repeat() {
        let a: u64 = stream_rng(1, 0).random();
        let b: u64 = stream_rng(1, 1).random();
        let c: u64 = stream_rng(2, 0).random();
        let again: u64 = stream_rng(1, 0).random();
        assert_ne!(a, b);
        assert_ne!(a, c);
        assert_eq!(a, again);
        let zero: u64 = stream_rng(0, 0).random();
        assert_ne!(zero, 0);
    }

    #[test]
    fn results_do_not_depend_on_thread_count() {
        let work = |_r: usize, rng: &mut PfRng| (0..1000).map(|_| rng.random::<f64>()).sum::<f64>();
        let pool = |t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
        };
        let one = pool(1).install(|| replicate(42, 64, Par::Rayon, work));
        let two = pool(2).install(|| replicate(42, 64, Par::Rayon, work));
        let seq = replicate(42, 64, Par::Seq, work);
        assert_eq!(one, two);
        assert_eq!(one, seq);
    }

    /// Errors 3 and 4: RMS √12.5; the squares 9 and 16 have mean 12.5 and standard error
    /// 3.5, so the delta method gives 3.5/(2√12.5).
    #[test]
    fn rms_and_its_standard_error_by_the_delta_method() {
        let (rms, se) = rms_and_se(&[9.0, 16.0]);
        assert_eq!(rms, 12.5f64.sqrt());
        assert!((se - 3.5 / (2.0 * 12.5f64.sqrt())).abs() < 1e-15, "{se}");
        assert_eq!(rms_and_se(&[0.0, 0.0]), (0.0, 0.0));
    }

    /// 1, 2, 3, 4: mean 2.5, squared deviations summing to 5, so the sample variance is 5/3
    /// (divisor R − 1), the deviation √(5/3) and the standard error √(5/12); one value has
    /// no spread.
    #[test]
    fn sample_deviation_and_standard_error_by_hand() {
        let x = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(mean_and_sd(&x), (2.5, (5.0f64 / 3.0).sqrt()));
        let (m, se) = mean_and_se(&x);
        assert_eq!(m, 2.5);
        assert!((se - (5.0f64 / 12.0).sqrt()).abs() < 1e-15, "{se}");
        assert_eq!(mean_and_sd(&[7.0]), (7.0, 0.0));
    }

    #[test]
    fn first_error_in_order_wins() {
        let fail_from_3 = |r: usize, _: &mut PfRng| {
            if r >= 3 {
                Err(CoreError::Empty { what: "run" }.at_step(r))
            } else {
                Ok(r)
            }
        };
        let r = try_replicate(0, 10, Par::Rayon, fail_from_3);
        assert!(matches!(r, Err(CoreError::AtStep { t: 3, .. })), "{r:?}");
        // A count no machine could hold is refused before anything runs.
        let r = try_replicate(0, usize::MAX, Par::Rayon, fail_from_3);
        assert!(matches!(r, Err(CoreError::TooLarge { .. })), "{r:?}");
        // So is a count within the limit whose results would not fit (2³² results of
        // 4 KiB, 16 TiB, as nested arrays, which serde encodes up to 32 long), before any replication runs (on Linux, where the machine's memory
        // is known; elsewhere the reservation alone decides).
        #[cfg(target_os = "linux")]
        {
            let ran = std::sync::atomic::AtomicBool::new(false);
            let r = try_replicate(0, crate::limits::MAX_COUNT, Par::Rayon, |_, _| {
                ran.store(true, std::sync::atomic::Ordering::Relaxed);
                Ok::<_, CoreError>([[[0u8; 32]; 32]; 4])
            });
            assert!(matches!(r, Err(CoreError::TooLarge { .. })));
            assert!(!ran.into_inner());
        }
    }
}
