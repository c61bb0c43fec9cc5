//! Running independent pieces of work on several threads without tying the pure algorithms to
//! a thread pool: the slice solver passes rayon, the ECS systems Bevy's compute task pool.
//! See [`SphPlugin`](crate::fluid::SphPlugin).

/// Runs independent pieces of work, possibly in parallel.
pub trait Parallel: Sync {
    /// Calls `work` once for every item, in any order, possibly on several threads.
    fn for_each<T: Send, F: Fn(&mut T) + Sync>(&self, items: &mut [T], work: F);

    /// How many threads `for_each` may use.
    fn threads(&self) -> usize;
}

/// Runs everything on the calling thread.
#[derive(Debug, Clone, Copy, Default)]
pub struct Sequential;

impl Parallel for Sequential {
    fn for_each<T: Send, F: Fn(&mut T) + Sync>(&self, items: &mut [T], work: F) {
        items.iter_mut().for_each(work);
    }

    fn threads(&self) -> usize {
        1
    }
}

/// [`Parallel`] on rayon's current thread pool.
#[derive(Debug, Clone, Copy, Default)]
pub struct Rayon;

impl Parallel for Rayon {
    fn for_each<T: Send, F: Fn(&mut T) + Sync>(&self, items: &mut [T], work: F) {
        use rayon::prelude::*;
        if items.len() <= 1 {
            items.iter_mut().for_each(work);
            return;
        }
        items.par_iter_mut().for_each(&work);
    }

    fn threads(&self) -> usize {
        rayon::current_num_threads()
    }
}

/// A chunk length that splits `len` items into about `pieces` chunks of at least `min` items.
pub fn chunk_size(len: usize, pieces: usize, min: usize) -> usize {
    len.div_ceil(pieces.max(1)).max(min).max(1)
}
