//! The one place where per-UAV work is split between threads or run in order.
//!
//! Every split is by index, and every item's result depends only on its index and the step's
//! read-only data, so the outcome is the same bits for any thread count and either way.

use rayon::prelude::*;

/// Items per work unit when run in parallel.
pub const MIN_ITEMS: usize = 1024;

/// `f(index, item)` for every item, on the current rayon pool when `parallel`, else in order.
pub fn for_each_mut<T: Send>(items: &mut [T], parallel: bool, f: impl Fn(usize, &mut T) + Sync + Send) {
    if parallel {
        items.par_iter_mut().enumerate().with_min_len(MIN_ITEMS).for_each(|(i, x)| f(i, x));
    } else {
        items.iter_mut().enumerate().for_each(|(i, x)| f(i, x));
    }
}

/// `f` over chunks `0..n` of `chunk` items (the last one shorter), results in chunk order.
pub fn map_chunks<R: Send>(
    n: usize,
    chunk: usize,
    parallel: bool,
    f: impl Fn(std::ops::Range<usize>) -> R + Sync + Send,
) -> Vec<R> {
    let ranges = (0..n.div_ceil(chunk)).map(|c| c * chunk..((c + 1) * chunk).min(n));
    if parallel {
        ranges.collect::<Vec<_>>().into_par_iter().map(f).collect()
    } else {
        ranges.map(f).collect()
    }
}
