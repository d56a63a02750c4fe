//! [`ParticleBuf`]: the batch filter's particle-sized arrays, on 2 MiB pages when they are
//! large.
//!
//! At N = 10⁶ one step of the batch filter streams through four 8 MiB arrays, 8192 pages of
//! 4 KiB, more than twice the 3072 entries of this machine's (Zen 4) second-level TLB; on
//! 2 MiB pages they take 16 entries. Against the same filter on ordinary pages
//! (2026-11-25, 08:00–08:10 UTC):
//! criterion `batch_ar1/1-thread` at N = 10⁶ faster in five of six interleaved rounds,
//! about 4 % at the median; the scratch harness faster in six of six (1–10 %), 2–4 % on
//! two threads, and no change at 10⁷, where memory itself dominates (performance log, "Huge
//! pages, asked for by the filter").

use bytemuck::Pod;
use memmap2::MmapMut;
use std::ops::{Deref, DerefMut};

/// From this size a buffer is mapped on its own and advised onto huge pages: one 2 MiB
/// page (a smaller array could not fill one).
const HUGE_MIN_BYTES: usize = 2 << 20;

/// A zero-initialised array of `T` that derefs to `[T]`. Of 2 MiB or more it is an
/// anonymous mapping of its own, advised with `MADV_HUGEPAGE` before its first write, so
/// that Linux backs it with transparent huge pages where it has them (in the `madvise`
/// mode that many distributions default to, the advice is what turns them on; kernels
/// before 6.7 may place the mapping off a 2 MiB boundary and leave its ends on small
/// pages). Off Linux the mapping goes without the advice; below 2 MiB, or if the mapping
/// fails, the array is an ordinary `Vec`. The values are the same either way; only the
/// speed differs.
///
/// (Asking glibc for huge pages for its whole heap, `GLIBC_TUNABLES=glibc.malloc.hugetlb=1`,
/// does the same but needs the user to set it; advising each `Vec` before its first write
/// was only partly effective, since glibc served them from a heap not aligned to 2 MiB.)
pub(crate) struct ParticleBuf<T: Pod> {
    store: Store<T>,
}

enum Store<T> {
    Heap(Vec<T>),
    Mapped(MmapMut),
}

impl<T: Pod> ParticleBuf<T> {
    /// `n` zeros, or [`CoreError::TooLarge`](crate::CoreError::TooLarge) when they cannot be
    /// allocated.
    pub(crate) fn zeroed(n: usize) -> crate::error::Result<Self> {
        let bytes = n.saturating_mul(size_of::<T>());
        if bytes >= HUGE_MIN_BYTES
            && let Ok(map) = MmapMut::map_anon(bytes)
        {
            // Anonymous pages are zero and untouched until written: the advice is taken at
            // the first write. It is only advice, so an error (an old kernel, no THP)
            // leaves ordinary pages.
            #[cfg(target_os = "linux")]
            let _ = map.advise(memmap2::Advice::HugePage);
            return Ok(ParticleBuf {
                store: Store::Mapped(map),
            });
        }
        Ok(ParticleBuf {
            store: Store::Heap(crate::limits::try_filled(
                crate::limits::PARTICLE_BUFFERS,
                n,
                T::zeroed(),
            )?),
        })
    }
}

impl<T: Pod> Deref for ParticleBuf<T> {
    type Target = [T];

    #[inline]
    fn deref(&self) -> &[T] {
        match &self.store {
            Store::Heap(v) => v,
            // A mapping is page-aligned and `n·size_of::<T>()` long, so the cast holds.
            Store::Mapped(m) => bytemuck::cast_slice(m),
        }
    }
}

impl<T: Pod> DerefMut for ParticleBuf<T> {
    #[inline]
    fn deref_mut(&mut self) -> &mut [T] {
        match &mut self.store {
            Store::Heap(v) => v,
            Store::Mapped(m) => bytemuck::cast_slice_mut(m),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both kinds start at zero, hold what is written, and have the length asked for.
    #[test]
    fn small_and_large_buffers_hold_their_values() {
        for n in [0usize, 1, 1000, HUGE_MIN_BYTES / 8, HUGE_MIN_BYTES / 8 + 3] {
            let mut b = ParticleBuf::<f64>::zeroed(n).unwrap();
            assert_eq!(b.len(), n);
            assert!(b.iter().all(|&x| x == 0.0));
            b.iter_mut().enumerate().for_each(|(i, x)| *x = i as f64);
            assert!(b.iter().enumerate().all(|(i, &x)| x == i as f64));
            let u = ParticleBuf::<usize>::zeroed(n).unwrap();
            assert_eq!(u.len(), n);
            assert!(u.iter().all(|&a| a == 0));
        }
        let large = ParticleBuf::<f64>::zeroed(HUGE_MIN_BYTES / 8).unwrap();
        assert!(matches!(large.store, Store::Mapped(_)));
    }
}
