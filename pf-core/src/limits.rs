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
/// is more memory than this machine has: its RAM and swap, or its cgroup's limit (v1 or v2)
/// where that is lower (Linux; elsewhere nothing is checked).
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
/// `/proc/meminfo`, capped by the smallest memory limit of its cgroup and the cgroup's
/// ancestors ([`cgroup_limit`]). `None` where `/proc/meminfo` cannot be read.
fn machine_memory() -> Option<usize> {
    static MEMORY: std::sync::OnceLock<Option<usize>> = std::sync::OnceLock::new();
    *MEMORY.get_or_init(|| {
        let read = |path: &str| std::fs::read_to_string(path).ok();
        let text = read("/proc/meminfo")?;
        let kib = |key: &str| -> Option<usize> {
            let line = text.lines().find(|l| l.starts_with(key))?;
            let value = line[key.len()..].trim().trim_end_matches("kB").trim();
            value.parse::<usize>().ok()?.checked_mul(1024)
        };
        let (ram, swap) = (kib("MemTotal:")?, kib("SwapTotal:").unwrap_or(0));
        let total = ram.saturating_add(swap);
        Some(match cgroup_limit(&read) {
            // The cgroup's swap limit, where it has one, cannot give more than the swap.
            Some((cap, cap_swap)) => {
                total.min(cap.saturating_add(cap_swap.unwrap_or(swap).min(swap)))
            }
            None => total,
        })
    })
}

/// The smallest memory limit of this process's cgroup and its ancestors, `(RAM, swap)`
/// with swap `None` where it is not limited, from `/proc/self/cgroup`: cgroup v2 (`0::path`,
/// `memory.max` and `memory.swap.max` under `/sys/fs/cgroup` or its `unified` mount) or
/// the v1 memory controller (`memory.limit_in_bytes`, and `memory.memsw.limit_in_bytes`,
/// which counts RAM and swap together). `None` where no level sets a limit.
fn cgroup_limit(read: &dyn Fn(&str) -> Option<String>) -> Option<(usize, Option<usize>)> {
    // "max", or v1's "unlimited" (a page-rounded 2⁶³ − 1), is no limit.
    let bytes = |path: String| -> Option<usize> {
        read(&path)?
            .trim()
            .parse::<usize>()
            .ok()
            .filter(|&b| b < 1 << 62)
    };
    let cgroups = read("/proc/self/cgroup")?;
    let mut best: Option<(usize, Option<usize>)> = None;
    for line in cgroups.lines() {
        let mut fields = line.splitn(3, ':');
        let (id, controllers, path) = (fields.next()?, fields.next()?, fields.next()?);
        let (v2, v1) = (
            id == "0" && controllers.is_empty(),
            controllers.split(',').any(|c| c == "memory"),
        );
        let bases: &[&str] = if v2 {
            &["/sys/fs/cgroup", "/sys/fs/cgroup/unified"]
        } else if v1 {
            &["/sys/fs/cgroup/memory"]
        } else {
            continue;
        };
        // The cgroup, then each ancestor up to the root.
        let mut dirs = vec![path.trim_end_matches('/').to_owned()];
        while let Some(cut) = dirs.last().and_then(|d| d.rfind('/')) {
            let parent = dirs.last().map(|d| d[..cut].to_owned()).unwrap_or_default();
            if parent.is_empty() {
                break;
            }
            dirs.push(parent);
        }
        dirs.push(String::new());
        for base in bases {
            for dir in &dirs {
                let at = |file: &str| format!("{base}{dir}/{file}");
                let (ram, swap) = if v2 {
                    (bytes(at("memory.max")), bytes(at("memory.swap.max")))
                } else {
                    let ram = bytes(at("memory.limit_in_bytes"));
                    let both = bytes(at("memory.memsw.limit_in_bytes"));
                    (ram, both.zip(ram).map(|(b, r)| b.saturating_sub(r)))
                };
                if let Some(ram) = ram {
                    best = Some(match best {
                        Some((r, s)) if r <= ram => (r, s.or(swap)),
                        _ => (ram, swap),
                    });
                }
            }
        }
    }
    best
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

    /// Limits are read from the process's own cgroup and its ancestors, the smallest
    /// winning, in v2 and in v1 (where the swap limit counts RAM and swap together);
    /// "max" and v1's "unlimited" are no limit.
    #[test]
    fn cgroup_limits_come_from_the_process_cgroup_and_its_ancestors() {
        let files = |pairs: &'static [(&'static str, &'static str)]| {
            move |path: &str| {
                pairs
                    .iter()
                    .find(|(p, _)| *p == path)
                    .map(|(_, v)| v.to_string())
            }
        };
        let v2 = files(&[
            ("/proc/self/cgroup", "0::/user.slice/app.scope\n"),
            ("/sys/fs/cgroup/user.slice/app.scope/memory.max", "max\n"),
            ("/sys/fs/cgroup/user.slice/memory.max", "4096\n"),
            ("/sys/fs/cgroup/user.slice/memory.swap.max", "1024\n"),
            ("/sys/fs/cgroup/memory.max", "8192\n"),
        ]);
        assert_eq!(cgroup_limit(&v2), Some((4096, Some(1024))));
        let v1 = files(&[
            ("/proc/self/cgroup", "5:devices:/\n4:memory:/api/x\n0::/\n"),
            (
                "/sys/fs/cgroup/memory/api/x/memory.limit_in_bytes",
                "2048\n",
            ),
            (
                "/sys/fs/cgroup/memory/api/x/memory.memsw.limit_in_bytes",
                "3072\n",
            ),
            (
                "/sys/fs/cgroup/memory/memory.limit_in_bytes",
                "9223372036854771712\n",
            ),
        ]);
        assert_eq!(cgroup_limit(&v1), Some((2048, Some(1024))));
        let none = files(&[
            ("/proc/self/cgroup", "0::/\n"),
            ("/sys/fs/cgroup/memory.max", "max\n"),
        ]);
        assert_eq!(cgroup_limit(&none), None);
        assert_eq!(cgroup_limit(&files(&[])), None);
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
