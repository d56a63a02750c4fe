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

/// `n` copies of `value`, or [`CoreError::TooLarge`] when the allocator refuses them.
///
/// # Errors
/// The allocation failed.
pub fn try_filled<T: Clone>(what: &'static str, n: usize, value: T) -> Result<Vec<T>> {
    let mut v = try_with_capacity(what, n)?;
    v.resize(n, value);
    Ok(v)
}

/// An empty vector with room for `n`, or [`CoreError::TooLarge`] when the allocator
/// refuses it.
///
/// # Errors
/// The allocation failed.
pub fn try_with_capacity<T>(what: &'static str, n: usize) -> Result<Vec<T>> {
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
}
