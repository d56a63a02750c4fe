//! [`ParticleBuf`]: the batch filter's particle-sized arrays, starting on a cache line, and
//! on 2 MiB pages when they are large.
//!
//! At N = 10⁶ one step of the batch filter streams through four 8 MiB arrays, 8192 pages of
//! 4 KiB, more than a second-level TLB holds; on 2 MiB pages they take 16 entries. That
//! makes the filter about 4 % faster at N = 10⁶ (no change at 10⁷, where memory itself
//! dominates).

use bytemuck::{Pod, Zeroable};
use memmap2::MmapMut;
use std::marker::PhantomData;
use std::ops::{Deref, DerefMut};

/// From this size a buffer is mapped on its own and advised onto huge pages: one 2 MiB
/// page (a smaller array could not fill one).
const HUGE_MIN_BYTES: usize = 2 << 20;

/// A zero-initialised array of `T` that derefs to `[T]` and starts on a 64-byte boundary
/// (see [`Line`]). Of 2 MiB or more it is an
/// anonymous mapping of its own, advised with `MADV_HUGEPAGE` before its first write, so
/// that Linux backs it with transparent huge pages where it has them (in the `madvise`
/// mode that many distributions default to, the advice is what turns them on; kernels
/// before 6.7 may place the mapping off a 2 MiB boundary and leave its ends on small
/// pages). Off Linux the mapping goes without the advice; below 2 MiB, or if the mapping
/// fails, the array is a `Vec` of [`Line`]s. The values are the same either way; only the
/// speed differs.
///
/// (Asking glibc for huge pages for its whole heap, `GLIBC_TUNABLES=glibc.malloc.hugetlb=1`,
/// does the same but needs the user to set it; advising each `Vec` before its first write
/// was only partly effective, since glibc served them from a heap not aligned to 2 MiB.)
pub(crate) struct ParticleBuf<T: Pod> {
    store: Store,
    of: PhantomData<T>,
}

enum Store {
    /// `len` values in the first bytes of the lines.
    Heap {
        lines: Vec<Line>,
        len: usize,
    },
    Mapped(MmapMut),
}

/// One cache line, the unit of a heap buffer, so that the buffer starts on a line: each of
/// the filter's AVX-512 loads and stores of eight values then touches one line, not two
/// (glibc's heap aligns to 16 bytes). With the chunk scratch aligned too, that is about 2 %
/// of the filter's time at N = 10⁴.
#[derive(Debug, Clone, Copy, Zeroable, Pod)]
#[repr(C, align(64))]
pub(crate) struct Line([u8; 64]);

impl Line {
    /// Lines that hold `n` values of `T`.
    fn count<T>(n: usize) -> usize {
        n.saturating_mul(size_of::<T>()).div_ceil(size_of::<Line>())
    }

    /// Zeroed lines for at least `n` values of `f64`: a chunk's scratch (see [`Line::f64s`]).
    pub(crate) fn zeroed_for_f64s(n: usize) -> Vec<Line> {
        vec![Line::zeroed(); Line::count::<f64>(n)]
    }

    /// The lines' bytes as `f64`s.
    pub(crate) fn f64s(lines: &mut [Line]) -> &mut [f64] {
        bytemuck::cast_slice_mut(lines)
    }
}

impl<T: Pod> ParticleBuf<T> {
    /// `n` zeros, or [`CoreError::TooLarge`](crate::CoreError::TooLarge) when they cannot be
    /// allocated.
    pub(crate) fn zeroed(n: usize) -> crate::error::Result<Self> {
        // Whole values to a line, so that the lines cast to `[T]`.
        const { assert!(size_of::<Line>().is_multiple_of(size_of::<T>())) };
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
                of: PhantomData,
            });
        }
        // `try_filled` checks the lines against the machine's memory; its error names the
        // values asked for, not the lines.
        let what = crate::limits::PARTICLE_BUFFERS;
        let lines = crate::limits::try_filled(what, Line::count::<T>(n), Line::zeroed())
            .map_err(|_| crate::CoreError::TooLarge { what, len: n })?;
        Ok(ParticleBuf {
            store: Store::Heap { lines, len: n },
            of: PhantomData,
        })
    }
}

impl<T: Pod> Deref for ParticleBuf<T> {
    type Target = [T];

    #[inline]
    fn deref(&self) -> &[T] {
        match &self.store {
            // A line holds whole values (checked in `zeroed`), and a mapping is
            // page-aligned and `n·size_of::<T>()` long, so the casts hold.
            Store::Heap { lines, len } => &bytemuck::cast_slice(lines)[..*len],
            Store::Mapped(m) => bytemuck::cast_slice(m),
        }
    }
}

impl<T: Pod> DerefMut for ParticleBuf<T> {
    #[inline]
    fn deref_mut(&mut self) -> &mut [T] {
        match &mut self.store {
            Store::Heap { lines, len } => &mut bytemuck::cast_slice_mut(lines)[..*len],
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
            assert!(b.as_ptr().cast::<Line>().is_aligned(), "n = {n}");
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
