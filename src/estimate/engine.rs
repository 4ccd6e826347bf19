//! The parallel engine (pyPESTO's `engine`): one rayon thread pool, built once by the
//! caller (the command line, a test) and passed to everything that works in parallel.
//!
//! Work submitted from inside the pool (a diagnosis' fits, each a multi-start) runs on the
//! same threads by work stealing: there are no pools inside pools. Every parallel map keeps
//! the order of its input, so results never depend on the number of threads.

use crate::estimate::error::EstimateError;
use rayon::prelude::*;

/// A thread pool to run estimation work on.
pub struct Engine {
    pool: rayon::ThreadPool,
}

impl Engine {
    /// Wraps a pool the caller built.
    pub fn new(pool: rayon::ThreadPool) -> Self {
        Self { pool }
    }

    /// Convenience constructor: a pool of `threads` workers (None: one per core). The only
    /// place of the library that builds a pool.
    pub fn with_threads(threads: Option<usize>) -> Result<Self, EstimateError> {
        let mut builder = rayon::ThreadPoolBuilder::new();
        if let Some(k) = threads {
            builder = builder.num_threads(k);
        }
        Ok(Self::new(builder.build()?))
    }

    /// Number of worker threads.
    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// `f` of every item, in parallel, results in input order.
    pub fn map<T, R, F>(&self, items: &[T], f: F) -> Vec<R>
    where
        T: Sync,
        R: Send,
        F: Fn(&T) -> R + Sync + Send,
    {
        self.pool.install(|| items.par_iter().map(f).collect())
    }

    /// `f` on every item in place, in parallel.
    pub(crate) fn for_each_mut<T, F>(&self, items: &mut [T], f: F)
    where
        T: Send,
        F: Fn(&mut T) + Sync + Send,
    {
        self.pool.install(|| items.par_iter_mut().for_each(f))
    }
}
