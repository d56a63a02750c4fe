//! Vectorised kernels: a lock-step multi-lane random generator, ziggurat normals and
//! exponentials, and branch-free `exp`s, with run-time CPU dispatch.
//!
//! Every kernel is plain Rust written so that LLVM can vectorise it (fixed-width lanes,
//! selects instead of branches). `dispatch` compiles it twice: once for the baseline
//! target, and once inside a function with `#[target_feature(enable = "avx2,fma")]`, chosen
//! at run time when the CPU has both. A few kernels on the hottest paths also have an
//! AVX-512 twin written with `core::arch` intrinsics (see the private module `avx512`), chosen
//! at run time when the CPU has AVX-512.
//!
//! All copies perform the same IEEE-754 operations in the same order: Rust never contracts
//! `a * b + c` into a fused multiply-add, the kernels that want one ask for it with
//! `f64::mul_add` (correctly rounded everywhere: one instruction where the CPU has FMA, the
//! C library's exact `fma` on the portable copy), and no kernel calls a libm function whose
//! result could depend on the instruction set. So **every path gives bit-identical
//! results** (tested); the wider ones only make them faster. [`Simd::Avx2`] and
//! [`Simd::Portable`] cap the instruction set, for comparison and audits.

pub(crate) mod avx2;
pub(crate) mod avx512;
mod lanes;
pub mod math;
pub mod special;
mod tables;

pub use lanes::{LANES, LaneRng};

/// Which compiled copy of the vectorised kernels runs. All give the same numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Simd {
    /// The widest copy the CPU runs (detected at run time): the AVX-512 kernels where it
    /// has AVX-512, the AVX2 copy where it has AVX2 and FMA, the portable one otherwise.
    #[default]
    Auto,
    /// At most the AVX2 copy, even on a CPU with AVX-512: for comparison.
    Avx2,
    /// Always the portable copy (baseline x86-64: SSE2), for comparison and audits. Kernels
    /// with fused multiply-adds compute them in the C library's `fma` here, which is exact
    /// but slow: the batch filter is about 10× slower here than on the AVX-512 kernels (its
    /// weights' `exp` is fused), 5× with multinomial resampling. It is also what `Auto`
    /// runs on an x86-64 CPU without AVX2
    /// and FMA, where the C library computes `fma` in software.
    Portable,
}

impl Simd {
    /// Every option, for the command line and tests.
    pub const ALL: [Simd; 3] = [Simd::Auto, Simd::Avx2, Simd::Portable];

    /// The lower-case name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Simd::Auto => "auto",
            Simd::Avx2 => "avx2",
            Simd::Portable => "portable",
        }
    }

    /// The copy of the kernels that runs on this CPU under this option: `"avx512"`, `"avx2"`
    /// or `"portable"` (what a benchmark reports beside its time).
    pub fn kernels(self) -> &'static str {
        if avx512::Avx512::get(self).is_some() {
            "avx512"
        } else if avx2::Avx2::get(self).is_some() {
            "avx2"
        } else {
            "portable"
        }
    }
}

impl std::str::FromStr for Simd {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        crate::names::parse_name("kernel set", &Simd::ALL, Simd::name, s)
    }
}

impl std::fmt::Display for Simd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The positions of the set bits of `mask`, lowest first: the lanes a vectorised pass
/// marked for scalar work.
#[inline(always)]
pub(crate) fn set_bits(mut mask: u64) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let p = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            p
        })
    })
}

/// Ask the CPU to bring the cache lines holding `len` values from `p` into its caches
/// ahead of use. A hint: it reads no value into the program and never faults, whatever the
/// address (so `p` may point past the caller's slice); on other architectures it does
/// nothing.
///
/// The batch filter reads and writes its arrays in bursts, chunk by chunk, with L1-resident
/// work in between; once they outgrow the caches, it uses this to overlap the next chunk's
/// memory traffic with the current chunk's arithmetic (see `filter::batch`).
#[inline(always)]
pub(crate) fn prefetch<T>(p: *const T, len: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // Every line the values touch, the last one too when `p` starts mid-line.
        let bytes = len * size_of::<T>();
        let lines = if bytes == 0 {
            0
        } else {
            (p.addr() % 64 + bytes).div_ceil(64)
        };
        for i in 0..lines {
            let line = p.cast::<i8>().wrapping_add(64 * i);
            // SAFETY: `_mm_prefetch` is `unsafe` only
            // because it is declared for the `sse` target feature, which every x86-64 CPU
            // has (it is part of the baseline). The instruction is a hint: it dereferences
            // nothing the program sees and cannot fault on any address.
            #[allow(unsafe_code)]
            unsafe {
                _mm_prefetch::<_MM_HINT_T0>(line);
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (p, len);
}

/// Run `f`, compiled with AVX2 and FMA enabled when `simd` allows it and the CPU has both.
///
/// `f` should be an `#[inline(always)]` closure whose helpers are `#[inline(always)]` too, so
/// that its whole body is compiled inside the AVX2 function.
#[inline]
pub(crate) fn dispatch<R>(simd: Simd, f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if simd != Simd::Portable {
        return avx2::run(f);
    }
    let _ = simd;
    f()
}

/// Run `f` compiled with AVX2 and FMA enabled where the CPU has both, so that LLVM
/// vectorises its loops four lanes wide: for loops over [`special`]'s functions outside the
/// batch filter (whose model calls are compiled so already).
///
/// `f` should be an `#[inline(always)]` closure whose helpers are `#[inline(always)]` too.
/// Rust never fuses a multiply and an add on its own, so `f` gives the same bits in either
/// copy.
#[inline]
pub fn vectorised<R>(f: impl FnOnce() -> R) -> R {
    dispatch(Simd::Auto, f)
}

/// Run `f` compiled as the batch filter's chunk step is: with the AVX-512 features where
/// the CPU has them, else with AVX2 and FMA, else for baseline x86-64. For timing a model's
/// loops outside the filter on the code the filter runs (pf-mpf's calibration of eq. (11)),
/// since the same loop compiled for baseline x86-64 can take several times as long.
///
/// `f` should be an `#[inline(always)]` closure whose helpers are `#[inline(always)]` too.
#[inline]
pub fn widest<R>(f: impl FnOnce() -> R) -> R {
    dispatch_widest(avx512::Avx512::get(Simd::Auto), Simd::Auto, f)
}

/// Run `f` compiled with the AVX-512 features where the caller holds the token, else as
/// [`dispatch`] compiles it under `simd`: the batch filter's chunk step and [`widest`].
#[inline(always)]
pub(crate) fn dispatch_widest<R>(
    avx512: Option<avx512::Avx512>,
    simd: Simd,
    f: impl FnOnce() -> R,
) -> R {
    match avx512 {
        Some(cpu) => cpu.run(f),
        None => dispatch(simd, f),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `widest` and `vectorised` run a loop as compiled for wider instruction sets, never
    /// with other results: the same bits as the baseline loop (Rust fuses no multiply-add
    /// on its own), here for `atan2` and `hypot` over values spanning many magnitudes.
    #[test]
    fn wider_copies_of_a_loop_give_the_same_bits() {
        let xs: Vec<f64> = (0..1000)
            .map(|i| (i as f64 - 500.0) * 1.37f64.powi(i % 40 - 20))
            .collect();
        #[inline(always)]
        fn run(xs: &[f64], out: &mut Vec<f64>) {
            out.clear();
            out.extend(
                xs.iter()
                    .zip(xs.iter().rev())
                    .map(|(&y, &x)| special::atan2(y, x) + special::hypot(x, y)),
            );
        }
        let (mut base, mut wide, mut avx2) = (Vec::new(), Vec::new(), Vec::new());
        run(&xs, &mut base);
        widest(
            #[inline(always)]
            || run(&xs, &mut wide),
        );
        vectorised(
            #[inline(always)]
            || run(&xs, &mut avx2),
        );
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&wide), bits(&base));
        assert_eq!(bits(&avx2), bits(&base));
    }

    /// The command line's names round-trip, a bad one lists them all, and the portable
    /// option always runs the portable copy while `avx2` never runs the AVX-512 twins.
    #[test]
    fn names_round_trip_and_options_cap_the_kernels() {
        for s in Simd::ALL {
            assert_eq!(s.to_string().parse::<Simd>(), Ok(s));
        }
        let e = "sse9".parse::<Simd>().unwrap_err();
        assert!(
            e.contains("sse9") && e.contains("auto, avx2 or portable"),
            "{e}"
        );
        assert_eq!(Simd::Portable.kernels(), "portable");
        assert_ne!(Simd::Avx2.kernels(), "avx512");
        let widest = Simd::Auto.kernels();
        assert_eq!(
            widest == "avx512",
            avx512::Avx512::get(Simd::Auto).is_some()
        );
        // Where the CPU has AVX2 and FMA the `avx2` copy really runs, so the tests that
        // compare it with the portable copy compare two different compilations.
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            assert_eq!(Simd::Avx2.kernels(), "avx2");
            assert_ne!(widest, "portable");
        }
    }
}
