//! Sizes a user asks for, checked before anything is allocated: a count that could not be
//! held is an error, never a capacity overflow panic or an aborted allocation.

use crate::error::{CoreError, Result};

/// The largest count of particles, steps, replications or iterations accepted: 2³². Sums
/// such as `n + 1` cannot overflow below it, and buffers of that many elements are far
/// beyond any machine this runs on, so anything larger is a typing error.
pub const MAX_COUNT: usize = 1 << 32;

/// What the filters' particle arrays are called in a [`CoreError::TooLarge`].
pub(crate) const PARTICLE_BUFFERS: &str = "the particle buffers";

/// `n`, or [`CoreError::TooLarge`] naming `what` when it is above [`MAX_COUNT`].
///
/// # Errors
/// `n > MAX_COUNT`.
pub fn check_count(what: &'static str, n: usize) -> Result<usize> {
    if n > MAX_COUNT {
        return Err(CoreError::TooLarge { what, len: n });
    }
    Ok(n)
}

/// `len` elements taking `bytes` in all, or [`CoreError::TooLarge`] naming `what` when that
/// is more memory than this machine has: its RAM and swap, or its cgroup's limit where that
/// is lower (Linux; elsewhere nothing is checked).
///
/// Linux overcommits memory: a request beyond what the machine has is often granted, and the
/// process is killed, with no message, when it first touches the pages. So a caller that
/// allocates several buffers checks their total here before it maps any of them, and every
/// allocation in this module checks its own size.
///
/// # Errors
/// `bytes` exceeds the machine's memory.
pub fn check_memory(what: &'static str, len: usize, bytes: usize) -> Result<()> {
    match machine_memory() {
        Some(limit) if bytes > limit => Err(CoreError::TooLarge { what, len }),
        _ => Ok(()),
    }
}

/// The bytes this process could ever be given, read once: `MemTotal + SwapTotal` from
/// `/proc/meminfo`, capped by cgroup v2's `memory.max` (plus `memory.swap.max` where that
/// is a number). `None` where neither can be read.
fn machine_memory() -> Option<usize> {
    static MEMORY: std::sync::OnceLock<Option<usize>> = std::sync::OnceLock::new();
    *MEMORY.get_or_init(|| {
        let read = |path: &str| std::fs::read_to_string(path).ok();
        let meminfo = read("/proc/meminfo").and_then(|text| {
            let kib = |key: &str| -> Option<usize> {
                let line = text.lines().find(|l| l.starts_with(key))?;
                line[key.len()..]
                    .trim()
                    .trim_end_matches("kB")
                    .trim()
                    .parse()
                    .ok()
            };
            let total = kib("MemTotal:")?.checked_add(kib("SwapTotal:").unwrap_or(0))?;
            total.checked_mul(1024)
        });
        // "max" (no limit) or a byte count; swap counts only where the cgroup caps RAM.
        let limit = |path: &str| read(path).and_then(|t| t.trim().parse::<usize>().ok());
        let cgroup = limit("/sys/fs/cgroup/memory.max")
            .map(|ram| ram.saturating_add(limit("/sys/fs/cgroup/memory.swap.max").unwrap_or(0)));
        match (meminfo, cgroup) {
            (Some(m), Some(c)) => Some(m.min(c)),
            (m, c) => m.or(c),
        }
    })
}

/// `n` copies of `value`, or [`CoreError::TooLarge`] when the allocator refuses them.
///
/// # Errors
/// The allocation failed.
pub fn try_filled<T: Clone>(what: &'static str, n: usize, value: T) -> Result<Vec<T>> {
    let mut v = try_with_capacity(what, n)?;
    v.resize(n, value);
    Ok(v)
}

/// An empty vector with room for `n`, or [`CoreError::TooLarge`] when that is more than the
/// machine's memory ([`check_memory`]) or the allocator refuses it.
///
/// # Errors
/// The allocation failed, or would exceed the machine's memory.
pub fn try_with_capacity<T>(what: &'static str, n: usize) -> Result<Vec<T>> {
    check_memory(what, n, n.saturating_mul(size_of::<T>()))?;
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| CoreError::TooLarge { what, len: n })?;
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_above_the_limit_and_refused_allocations_are_errors() {
        assert_eq!(check_count("N", MAX_COUNT), Ok(MAX_COUNT));
        assert!(matches!(
            check_count("N", MAX_COUNT + 1),
            Err(CoreError::TooLarge { what: "N", .. })
        ));
        // More bytes than the address space: refused by the allocator, not a panic.
        assert!(matches!(
            try_filled("particles", usize::MAX / 2, 0.0f64),
            Err(CoreError::TooLarge { len, .. }) if len == usize::MAX / 2
        ));
        assert_eq!(try_filled("w", 3, 1.5), Ok(vec![1.5; 3]));
    }

    /// On Linux the machine's memory is known, lies between 64 MiB and 2⁶⁰ bytes, and
    /// bounds what is accepted; a request of a few bytes always passes.
    #[test]
    #[cfg(target_os = "linux")]
    fn requests_beyond_the_machines_memory_are_refused() {
        let limit = machine_memory().expect("/proc/meminfo is readable");
        assert!(limit > 64 << 20 && limit < 1 << 60, "{limit}");
        assert_eq!(check_memory("x", 1, 8), Ok(()));
        assert_eq!(check_memory("x", 1, limit), Ok(()));
        assert_eq!(
            check_memory("x", 7, limit + 1),
            Err(CoreError::TooLarge { what: "x", len: 7 })
        );
        // A vector the address space could map but the machine could not hold.
        assert!(matches!(
            try_with_capacity::<u8>("bytes", limit + 1),
            Err(CoreError::TooLarge { what: "bytes", .. })
        ));
    }
}
