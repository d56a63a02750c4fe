//! Monte Carlo studies dealt to MPI ranks (the `mpi` feature).
//!
//! A binary built with the feature calls [`install`] at start-up. Launched by `mpirun`,
//! `mpiexec` or Slurm's `srun` (found from the launcher's environment: `OMPI_COMM_WORLD_SIZE`,
//! `PMIX_RANK`, `PMI_RANK`, `PMI_SIZE`), it initialises MPI and every process learns its
//! rank; launched any other way, or built without the feature, nothing is initialised and
//! every function here answers as for one process.
//!
//! With more than one rank, the outermost [`try_replicate`](super::try_replicate) of the
//! program is a distributed study ([`replicate`](super::replicate), for results of any
//! type, always runs whole on the calling process):
//!
//! * Replication indices `0..n` are dealt in contiguous blocks, rank `k` of `K` taking
//!   `⌈n/K⌉` or `⌊n/K⌋` of them ([`share`]), lower ranks the larger blocks: uneven shares
//!   are fine, a rank may get none (more ranks than replications), one rank takes all.
//! * Each rank runs its block on its rayon pool with the streams `(seed, r)` of a
//!   one-process run, so each replication's result is the one a one-process run computes.
//! * Every rank receives every rank's results (an all-gather: the program continues
//!   identically on every rank, whatever it does with them next) and concatenates them in
//!   rank order, which is replication order. The results cross ranks as MessagePack
//!   (rmp-serde), which writes an `f64` as its eight bytes, so they arrive bit for bit; structs
//!   go as maps of their field names, so a field that `skip_serializing_if` leaves out
//!   decodes to its default, as it does from JSON.
//! * A failing replication sends a marker with its index and message in place of results:
//!   every rank takes part in every exchange, so none waits for a rank that gave up, and
//!   every rank returns the same error, [`CoreError::Replication`], for the lowest failing
//!   index (as a one-process run returns that replication's error). A panic in a
//!   replication is carried the same way and raised on every rank.
//!
//! A `try_replicate` inside a replication (or inside [`local`]) runs on the calling rank
//! as usual. Before its results, each rank sends the study's number, seed and count: ranks
//! whose programs took different paths (a decision made on measured time, say) get
//! [`CoreError::Distributed`] instead of each other's results. Code whose studies depend
//! on such decisions runs them inside [`local`], where each rank runs everything itself.
//!
//! [`finish`] ends a run: every rank waits there for the others, and learns whether they
//! all got there (rather than one stopping inside a study).

use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use crate::CoreError;

/// How many distributed studies or [`local`] scopes are open on this process: a study is
/// dealt to ranks only when none is.
static DEPTH: AtomicUsize = AtomicUsize::new(0);
/// The progress weight of the open distributed study (`f64` bits), 1 outside one.
static WEIGHT: AtomicU64 = AtomicU64::new(1.0f64.to_bits());

/// The replications of `0..n` that rank `rank` of `size` runs: a contiguous block, the
/// first `n mod size` ranks taking one more than the others.
pub fn share(n: usize, rank: usize, size: usize) -> std::ops::Range<usize> {
    let size = size.max(1);
    let (base, extra) = (n / size, n % size);
    let start = rank * base + rank.min(extra);
    let len = base + usize::from(rank < extra);
    start.min(n)..(start + len).min(n)
}

/// This process's rank, 0 without MPI.
pub fn rank() -> usize {
    imp::world().map_or(0, |w| w.rank)
}

/// The number of ranks, 1 without MPI.
pub fn size() -> usize {
    imp::world().map_or(1, |w| w.size)
}

/// Whether this process is rank 0, the one that prints and writes files (always true
/// without MPI).
pub fn is_root() -> bool {
    rank() == 0
}

/// Run `f` with every study inside it run whole on this process, not dealt to ranks.
///
/// Every rank must call it at the same point of the program (as every rank calls the
/// studies themselves). For work whose studies depend on something that differs between
/// ranks, such as measured time.
pub fn local<R>(f: impl FnOnce() -> R) -> R {
    let _open = Open::local();
    f()
}

/// By how much rank 0 multiplies a tick counted inside a replication to show the whole
/// study's progress: `n` over rank 0's share while a distributed study runs, 1 otherwise.
pub fn progress_weight() -> f64 {
    f64::from_bits(WEIGHT.load(Ordering::Relaxed))
}

/// An open study or [`local`] scope; closing it (also by a panic) restores the state.
struct Open {
    study: bool,
}

impl Open {
    fn local() -> Self {
        DEPTH.fetch_add(1, Ordering::SeqCst);
        Open { study: false }
    }

    /// The outermost study, if none is open on this process.
    fn study() -> Option<Self> {
        DEPTH
            .compare_exchange(0, 1, Ordering::SeqCst, Ordering::SeqCst)
            .ok()
            .map(|_| Open { study: true })
    }
}

impl Drop for Open {
    fn drop(&mut self) {
        if self.study {
            WEIGHT.store(1.0f64.to_bits(), Ordering::Relaxed);
        }
        DEPTH.fetch_sub(1, Ordering::SeqCst);
    }
}

/// The MPI environment of a run, from [`install`] to the end of `main`: dropping it
/// finalises MPI. Without the `mpi` feature none is ever made.
pub struct Session {
    #[cfg(feature = "mpi")]
    _universe: mpi::environment::Universe,
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("rank", &rank())
            .field("size", &size())
            .finish()
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        imp::uninstall();
    }
}

/// Initialise MPI if this process was started by an MPI launcher (and the `mpi` feature is
/// on); keep the returned [`Session`] until the program ends.
///
/// # Errors
/// [`CoreError::Distributed`] if MPI was initialised already, or cannot run the studies from
/// worker threads (it provides less than `MPI_THREAD_SERIALIZED`).
pub fn install() -> Result<Option<Session>, CoreError> {
    imp::install()
}

/// Whether every rank reached [`finish`] (true without MPI or with one rank). Every rank
/// calls it once, at the end of the program, whether it succeeded or not; a rank that gets
/// `false` should [`abort`] the run, since another rank is still inside a study.
pub fn finish() -> bool {
    imp::finish()
}

/// End the whole run with status `code`: `MPI_Abort` on every rank when there are several,
/// otherwise a plain exit.
pub fn abort(code: i32) -> ! {
    imp::abort(code)
}

/// A study being dealt to ranks.
#[cfg_attr(not(feature = "mpi"), allow(dead_code))]
pub(crate) struct Study {
    _open: Open,
    seed: u64,
    n: usize,
}

impl Study {
    /// The outermost study of an MPI run with several ranks; `None` runs it locally.
    pub(crate) fn begin(seed: u64, n: usize) -> Option<Study> {
        let w = imp::world().filter(|w| w.size > 1)?;
        let open = Open::study()?;
        let root = share(n, 0, w.size).len().max(1);
        WEIGHT.store((n as f64 / root as f64).to_bits(), Ordering::Relaxed);
        Some(Study {
            _open: open,
            seed,
            n,
        })
    }
}

#[cfg(feature = "mpi")]
mod imp {
    //! The MPI side: initialisation, the study's exchange, abort.

    use std::any::Any;
    use std::panic::{AssertUnwindSafe, catch_unwind};
    use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};

    use mpi::Count;
    use mpi::datatype::PartitionMut;
    use mpi::environment::Threading;
    use mpi::topology::SimpleCommunicator;
    use mpi::traits::{Communicator, CommunicatorCollectives};
    use rayon::prelude::*;
    use serde::de::DeserializeOwned;
    use serde::{Deserialize, Serialize};

    use super::{Session, Study, share};
    use crate::CoreError;
    use crate::mc::{Par, PfRng, stream_rng};

    static INSTALLED: AtomicBool = AtomicBool::new(false);
    static RANK: AtomicUsize = AtomicUsize::new(0);
    static SIZE: AtomicUsize = AtomicUsize::new(1);
    /// Distributed studies begun on this process; the same on every rank while their
    /// programs agree.
    static STUDIES: AtomicU64 = AtomicU64::new(0);
    /// `PF_MPI_FAIL_REPLICATION + 1` (0: none): the replication every distributed study
    /// fails, to test that a failure on one rank ends the run cleanly.
    static FAIL: AtomicU64 = AtomicU64::new(0);
    /// The study number [`finish`] sends: no study has it.
    const FINISHED: u64 = u64::MAX;

    /// The hidden variable naming a replication that fails on purpose (tests only).
    pub(super) const FAIL_VAR: &str = "PF_MPI_FAIL_REPLICATION";
    /// Set (to anything), rank 0 prints one line per distributed study to stderr: its size,
    /// rank 0's compute time and the bytes exchanged (for scaling estimates).
    const TRACE_VAR: &str = "PF_MPI_TRACE";
    static TRACE: AtomicBool = AtomicBool::new(false);

    #[derive(Clone, Copy)]
    pub(super) struct World {
        pub(super) rank: usize,
        pub(super) size: usize,
    }

    pub(super) fn world() -> Option<World> {
        INSTALLED.load(Ordering::Acquire).then(|| World {
            rank: RANK.load(Ordering::Relaxed),
            size: SIZE.load(Ordering::Relaxed),
        })
    }

    /// Whether an MPI launcher started this process (Open MPI, MPICH/Hydra, Slurm PMI).
    fn launched() -> bool {
        ["OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"]
            .iter()
            .any(|v| std::env::var_os(v).is_some())
    }

    fn error(message: impl Into<String>) -> CoreError {
        CoreError::Distributed {
            message: message.into(),
        }
    }

    pub(super) fn install() -> Result<Option<Session>, CoreError> {
        if !launched() {
            return Ok(None);
        }
        let (universe, threading) = mpi::initialize_with_threading(Threading::Serialized)
            .ok_or_else(|| error("MPI is initialised already"))?;
        if threading < Threading::Serialized {
            return Err(error(format!(
                "the MPI library provides {threading:?} threading; studies need Serialized"
            )));
        }
        let w = universe.world();
        RANK.store(w.rank() as usize, Ordering::Relaxed);
        SIZE.store(w.size() as usize, Ordering::Relaxed);
        if let Some(r) = std::env::var(FAIL_VAR)
            .ok()
            .and_then(|v| v.trim().parse::<u64>().ok())
        {
            FAIL.store(r.saturating_add(1), Ordering::Relaxed);
        }
        TRACE.store(std::env::var_os(TRACE_VAR).is_some(), Ordering::Relaxed);
        INSTALLED.store(true, Ordering::Release);
        Ok(Some(Session {
            _universe: universe,
        }))
    }

    pub(super) fn uninstall() {
        INSTALLED.store(false, Ordering::Release);
    }

    pub(super) fn abort(code: i32) -> ! {
        match world() {
            Some(w) if w.size > 1 => SimpleCommunicator::world().abort(code),
            _ => std::process::exit(code),
        }
    }

    /// What each rank says before its results: study number, seed, count, and the length
    /// of its encoded results.
    type Announce = [u64; 4];

    /// Every rank's announcement.
    fn announce(a: Announce) -> Vec<Announce> {
        let size = SIZE.load(Ordering::Relaxed);
        let mut all = vec![0u64; 4 * size];
        SimpleCommunicator::world().all_gather_into(&a[..], &mut all[..]);
        all.chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()
    }

    pub(super) fn finish() -> bool {
        match world() {
            Some(w) if w.size > 1 => announce([FINISHED, 0, 0, 0])
                .iter()
                .all(|a| a[0] == FINISHED),
            _ => true,
        }
    }

    /// A rank's results as sent: its block, or the first failure in it.
    #[derive(Serialize)]
    enum Sent<'a, T> {
        Done(&'a [T]),
        Failed {
            replication: u64,
            message: &'a str,
            panicked: bool,
        },
    }

    /// A rank's results as received (the same encoding as [`Sent`]).
    #[derive(Deserialize)]
    enum Received<T> {
        Done(Vec<T>),
        Failed {
            replication: u64,
            message: String,
            panicked: bool,
        },
    }

    /// The message of a panic's payload.
    fn panic_message(p: &(dyn Any + Send)) -> String {
        p.downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown cause".to_owned())
    }

    impl Study {
        /// Run this rank's block, exchange, and return every replication's result in order.
        pub(crate) fn run<T, E, F>(self, par: Par, f: F) -> Result<Vec<T>, E>
        where
            T: Send + Serialize + DeserializeOwned,
            E: Send + std::fmt::Display + From<CoreError>,
            F: Fn(usize, &mut PfRng) -> Result<T, E> + Sync,
        {
            let (rank, size) = (RANK.load(Ordering::Relaxed), SIZE.load(Ordering::Relaxed));
            let study = STUDIES.fetch_add(1, Ordering::Relaxed);
            let (seed, n) = (self.seed, self.n);
            let fail = FAIL.load(Ordering::Relaxed).checked_sub(1);
            let one = |r: usize| {
                catch_unwind(AssertUnwindSafe(|| {
                    if fail == Some(r as u64) {
                        return Err(E::from(error(format!(
                            "failure injected by {FAIL_VAR} on rank {rank}"
                        ))));
                    }
                    f(r, &mut stream_rng(seed, r as u64))
                }))
            };
            let started = std::time::Instant::now();
            let block = share(n, rank, size);
            let lo = block.start;
            let outcomes: Vec<_> = match par {
                Par::Seq => block.map(one).collect(),
                Par::Rayon => block.into_par_iter().map(one).collect(),
            };
            let computed = started.elapsed();
            // This rank's results, or its first failure (a panic before an error, as a
            // one-process run raises a panic whatever else failed).
            let mut mine = Vec::with_capacity(outcomes.len());
            let mut failed: Option<(u64, String, bool)> = None;
            for (i, o) in outcomes.into_iter().enumerate() {
                let r = (lo + i) as u64;
                match o {
                    Ok(Ok(t)) => mine.push(t),
                    Ok(Err(e)) => {
                        if failed.is_none() {
                            failed = Some((r, e.to_string(), false));
                        }
                    }
                    Err(p) => {
                        if !failed.as_ref().is_some_and(|f| f.2) {
                            failed = Some((r, panic_message(&*p), true));
                        }
                    }
                }
            }
            let sent = match &failed {
                None => Sent::Done(&mine),
                Some((r, m, p)) => Sent::Failed {
                    replication: *r,
                    message: m,
                    panicked: *p,
                },
            };
            // Encoding a block of plain numbers cannot fail; a type that cannot be encoded
            // is sent as a failure, so the exchange still happens.
            let bytes = rmp_serde::to_vec_named(&sent).or_else(|e| {
                let message = format!("the results of rank {rank} cannot be encoded: {e}");
                let instead: Sent<'_, T> = Sent::Failed {
                    replication: lo as u64,
                    message: &message,
                    panicked: false,
                };
                rmp_serde::to_vec_named(&instead)
            });
            let bytes = bytes.unwrap_or_default();
            let all = announce([study, seed, n as u64, bytes.len() as u64]);
            // Every rank sees the same announcements, so every rank takes the same branch.
            if let Some((k, a)) = all
                .iter()
                .enumerate()
                .find(|(_, a)| a[..3] != [study, seed, n as u64])
            {
                let theirs = if a[0] == FINISHED {
                    "has finished".to_owned()
                } else {
                    format!(
                        "runs study #{} (seed {}, {} replications)",
                        a[0], a[1], a[2]
                    )
                };
                return Err(E::from(error(format!(
                    "rank {k} {theirs} where rank {rank} runs study #{study} (seed {seed}, \
                     {n} replications): the ranks' programs took different paths"
                ))));
            }
            let lens: Vec<u64> = all.iter().map(|a| a[3]).collect();
            let received = exchange(&bytes, &lens).map_err(E::from)?;
            if rank == 0 && TRACE.load(Ordering::Relaxed) {
                eprintln!(
                    "{TRACE_VAR}: study #{study} (seed {seed}): {n} replications on {size} ranks; \
                     rank 0 computed its {} in {:.3} s, then waited for the others and \
                     exchanged {} bytes in {:.4} s",
                    share(n, 0, size).len(),
                    computed.as_secs_f64(),
                    lens.iter().sum::<u64>(),
                    (started.elapsed() - computed).as_secs_f64()
                );
            }
            drop(bytes);
            let mut out: Vec<T> = crate::limits::try_with_capacity("the replications", n)?;
            for (k, part) in received.iter().enumerate() {
                if k == rank {
                    if let Some((r, m, p)) = failed.take() {
                        return Err(fail_everywhere(r, m, p));
                    }
                    out.append(&mut mine);
                    continue;
                }
                let decoded: Received<T> = rmp_serde::from_slice(part).map_err(|e| {
                    E::from(error(format!(
                        "the results of rank {k} for study #{study} cannot be decoded: {e}"
                    )))
                })?;
                match decoded {
                    Received::Done(mut v) => {
                        if v.len() != share(n, k, size).len() {
                            return Err(E::from(error(format!(
                                "rank {k} sent {} results for study #{study}, not {}",
                                v.len(),
                                share(n, k, size).len()
                            ))));
                        }
                        out.append(&mut v);
                    }
                    Received::Failed {
                        replication,
                        message,
                        panicked,
                    } => return Err(fail_everywhere(replication, message, panicked)),
                }
            }
            Ok(out)
        }
    }

    /// The failure of replication `r`, the same on every rank: its error, or its panic
    /// raised again.
    fn fail_everywhere<E: From<CoreError>>(r: u64, message: String, panicked: bool) -> E {
        if panicked {
            std::panic::panic_any(format!("replication {r} panicked: {message}"));
        }
        E::from(CoreError::Replication {
            replication: r as usize,
            message,
        })
    }

    /// Every rank's bytes, given every rank's length.
    fn exchange(mine: &[u8], lens: &[u64]) -> Result<Vec<Vec<u8>>, CoreError> {
        let total: u64 = lens.iter().sum();
        // MPI counts are C ints: one exchange carries at most 2³¹ − 1 bytes.
        let fits = |v: u64| Count::try_from(v).ok();
        let (Some(_), Some(counts)) = (
            fits(total),
            lens.iter()
                .map(|&l| fits(l))
                .collect::<Option<Vec<Count>>>(),
        ) else {
            return Err(CoreError::TooLarge {
                what: "the bytes of one study's results exchanged between MPI ranks",
                len: usize::try_from(total).unwrap_or(usize::MAX),
            });
        };
        let displs: Vec<Count> = counts
            .iter()
            .scan(0, |acc, &c| {
                let d = *acc;
                *acc += c;
                Some(d)
            })
            .collect();
        let mut buf: Vec<u8> =
            crate::limits::try_with_capacity("the results exchanged", total as usize)?;
        buf.resize(total as usize, 0);
        {
            let mut part = PartitionMut::new(&mut buf[..], &counts[..], &displs[..]);
            SimpleCommunicator::world().all_gather_varcount_into(mine, &mut part);
        }
        Ok(counts
            .iter()
            .zip(&displs)
            .map(|(&c, &d)| buf[d as usize..(d + c) as usize].to_vec())
            .collect())
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        /// What a rank sends decodes to the same values bit for bit: NaN payloads, −0,
        /// subnormals, infinities, nested vectors and options, fields skipped when empty; a
        /// failure keeps its index and message.
        #[test]
        fn results_cross_ranks_bit_for_bit() {
            let odd = [
                f64::from_bits(0x7ff8_dead_beef_0001),
                -0.0,
                f64::MIN_POSITIVE / 3.0,
                f64::NEG_INFINITY,
                0.1 + 0.2,
            ];
            let block: Vec<(f64, Option<Vec<f64>>, bool)> = odd
                .iter()
                .enumerate()
                .map(|(i, &x)| (x, (i % 2 == 0).then(|| odd.to_vec()), i == 3))
                .collect();
            let bytes = rmp_serde::to_vec_named(&Sent::Done(&block)).unwrap();
            let Received::Done(back) = rmp_serde::from_slice::<Received<_>>(&bytes).unwrap() else {
                panic!("a block decoded as a failure")
            };
            let bits = |v: &[(f64, Option<Vec<f64>>, bool)]| {
                v.iter()
                    .map(|(x, o, b)| {
                        let o: Option<Vec<u64>> =
                            o.as_ref().map(|o| o.iter().map(|y| y.to_bits()).collect());
                        (x.to_bits(), o, *b)
                    })
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&back), bits(&block));

            let sent: Sent<'_, f64> = Sent::Failed {
                replication: 5,
                message: "at step 3: boom",
                panicked: false,
            };
            let bytes = rmp_serde::to_vec_named(&sent).unwrap();
            match rmp_serde::from_slice::<Received<f64>>(&bytes).unwrap() {
                Received::Failed {
                    replication,
                    message,
                    panicked,
                } => assert_eq!(
                    (replication, message.as_str(), panicked),
                    (5, "at step 3: boom", false)
                ),
                Received::Done(_) => panic!("a failure decoded as results"),
            }
            // A field left out by `skip_serializing_if` decodes to its default.
            #[derive(Debug, PartialEq, Serialize, Deserialize)]
            struct Sparse {
                x: f64,
                #[serde(default, skip_serializing_if = "Vec::is_empty")]
                records: Vec<u8>,
                y: Option<f64>,
            }
            let block = [
                Sparse {
                    x: 1.5,
                    records: Vec::new(),
                    y: Some(-0.0),
                },
                Sparse {
                    x: f64::NAN,
                    records: vec![7],
                    y: None,
                },
            ];
            let bytes = rmp_serde::to_vec_named(&Sent::Done(&block)).unwrap();
            let Received::Done(back) = rmp_serde::from_slice::<Received<Sparse>>(&bytes).unwrap()
            else {
                panic!("a block decoded as a failure")
            };
            assert_eq!((back[0].x, &back[0].records), (1.5, &Vec::new()));
            assert_eq!(back[0].y.map(f64::to_bits), Some((-0.0f64).to_bits()));
            assert_eq!(
                (back[1].x.to_bits(), &back[1].records),
                (f64::NAN.to_bits(), &vec![7])
            );

            let e: CoreError = fail_everywhere(5, "boom".into(), false);
            assert_eq!(e.to_string(), "replication 5: boom");
        }
    }
}

#[cfg(not(feature = "mpi"))]
mod imp {
    //! Without the `mpi` feature: one process, nothing to exchange.

    use serde::Serialize;
    use serde::de::DeserializeOwned;

    use super::{Session, Study};
    use crate::CoreError;
    use crate::mc::{Par, PfRng};

    #[derive(Clone, Copy)]
    pub(super) struct World {
        pub(super) rank: usize,
        pub(super) size: usize,
    }

    pub(super) fn world() -> Option<World> {
        None
    }

    pub(super) fn install() -> Result<Option<Session>, CoreError> {
        Ok(None)
    }

    pub(super) fn uninstall() {}

    pub(super) fn finish() -> bool {
        true
    }

    pub(super) fn abort(code: i32) -> ! {
        std::process::exit(code)
    }

    impl Study {
        /// Never called: without MPI, [`Study::begin`] makes no study.
        pub(crate) fn run<T, E, F>(self, _par: Par, _f: F) -> Result<Vec<T>, E>
        where
            T: Send + Serialize + DeserializeOwned,
            E: Send + std::fmt::Display + From<CoreError>,
            F: Fn(usize, &mut PfRng) -> Result<T, E> + Sync,
        {
            Err(E::from(CoreError::Distributed {
                message: "no MPI in this build".into(),
            }))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blocks tile `0..n` in order, differ in length by at most one, and give rank 0 a
    /// largest one; ranks beyond `n` get none.
    #[test]
    fn shares_tile_the_replications() {
        for size in 1..=9 {
            for n in 0..=30 {
                let blocks: Vec<_> = (0..size).map(|k| share(n, k, size)).collect();
                let mut next = 0;
                for b in &blocks {
                    assert_eq!(b.start, next, "n {n} size {size}");
                    next = b.end;
                }
                assert_eq!(next, n);
                let lens: Vec<usize> = blocks.iter().map(|b| b.len()).collect();
                let (min, max) = (lens.iter().min().unwrap(), lens.iter().max().unwrap());
                assert!(max - min <= 1);
                assert_eq!(lens[0], *max);
            }
        }
        assert_eq!(share(2, 2, 3), 2..2);
        assert_eq!(share(7, 0, 1), 0..7);
    }

    /// Without an MPI launcher this is one process, and a study is never dealt out.
    #[test]
    fn one_process_without_a_launcher() {
        assert_eq!((rank(), size(), is_root()), (0, 1, true));
        assert!(Study::begin(1, 10).is_none());
        assert!(finish());
        assert_eq!(progress_weight(), 1.0);
        assert_eq!(local(|| 3), 3);
    }
}
