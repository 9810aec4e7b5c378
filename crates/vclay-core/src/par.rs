//! Parallelism policy for batched work.
//!
//! Batched evaluation (grids of parameters, many mesh vertices) splits work over rayon's thread
//! pool only when the batch is large enough to repay the scheduling cost. The caller chooses the
//! policy; [`Parallelism::Auto`] is the default.

/// Default batch size (number of output items) above which [`Parallelism::Auto`] goes parallel.
pub const DEFAULT_PARALLEL_THRESHOLD: usize = 16_384;

/// How a batched operation may use threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Parallelism {
    /// Single thread, always.
    Sequential,
    /// Rayon's global pool, always.
    Rayon,
    /// Rayon when the batch has at least [`DEFAULT_PARALLEL_THRESHOLD`] items, else one thread.
    #[default]
    Auto,
}

impl Parallelism {
    /// Whether a batch of `items` outputs should run in parallel under this policy.
    pub fn is_parallel(self, items: usize) -> bool {
        match self {
            Parallelism::Sequential => false,
            Parallelism::Rayon => true,
            Parallelism::Auto => items >= DEFAULT_PARALLEL_THRESHOLD,
        }
    }

    /// As [`Parallelism::is_parallel`], with `Auto` going parallel from `threshold` items
    /// instead of [`DEFAULT_PARALLEL_THRESHOLD`] (for work whose per-item cost or setup makes
    /// the break-even point differ, measured at the call site).
    pub fn is_parallel_from(self, items: usize, threshold: usize) -> bool {
        match self {
            Parallelism::Auto => items >= threshold,
            other => other.is_parallel(items),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_apply_to_auto_only() {
        assert!(!Parallelism::Auto.is_parallel_from(999, 1000));
        assert!(Parallelism::Auto.is_parallel_from(1000, 1000));
        assert!(Parallelism::Rayon.is_parallel_from(1, 1000));
        assert!(!Parallelism::Sequential.is_parallel_from(1 << 30, 1000));
        assert_eq!(
            Parallelism::Auto.is_parallel_from(5000, DEFAULT_PARALLEL_THRESHOLD),
            Parallelism::Auto.is_parallel(5000)
        );
    }
}

/// A value on a cache line of its own: aligned to 64 bytes (and so padded to a multiple of 64).
///
/// Two uses in vclay: flags that different threads write at the same moment (the thread
/// team's task claims, [`crate::team`]), which would bounce a shared line between the cores;
/// and small arrays on the stack that a kernel reads and writes as vectors (the spring force
/// kernel's batches in `vclay-solids`), where a stack frame's 16-byte alignment lets every
/// other vector access split two cache lines, and, for the placements that cross a 4096-byte
/// page, two pages (`docs/performance.md`, "Level-2 spring phase, session 22 (h61)": 55-61 us
/// instead of 50-53 for the level-2 cube's spring phase in the processes where it did).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub struct CacheAligned<T>(pub T);

impl<T> std::ops::Deref for CacheAligned<T> {
    type Target = T;
    #[inline(always)]
    fn deref(&self) -> &T {
        &self.0
    }
}

impl<T> std::ops::DerefMut for CacheAligned<T> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut T {
        &mut self.0
    }
}

#[cfg(test)]
mod cache_aligned_tests {
    use super::CacheAligned;

    #[test]
    fn a_cache_aligned_value_starts_on_a_cache_line() {
        assert_eq!(std::mem::align_of::<CacheAligned<u8>>(), 64);
        assert_eq!(std::mem::size_of::<CacheAligned<[f64; 48]>>(), 384);
        for _ in 0..4 {
            let x = CacheAligned([0.0f64; 3]);
            assert_eq!(&x as *const _ as usize % 64, 0);
            assert_eq!(x.len(), 3, "derefs to the value");
        }
    }
}
