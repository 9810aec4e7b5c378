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
}
