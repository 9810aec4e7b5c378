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
