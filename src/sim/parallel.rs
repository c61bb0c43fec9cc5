//! Running independent pieces of work on several threads without tying the pure algorithms to
//! a thread pool: the passes take a `Parallel`, which is rayon's current pool (the
//! plain-vector world runs on the caller's pool, the ECS driver on the crate's pool in a
//! region) or the calling thread; and the fixed-size slot chunks that keep every sum in one
//! order whatever the thread count.

/// Runs independent pieces of work, possibly in parallel.
pub(crate) trait Parallel: Sync {
    /// Calls `work` once for every item, in any order, possibly on several threads.
    fn for_each<T: Send, F: Fn(&mut T) + Sync>(&self, items: &mut [T], work: F);

    /// Whether everything runs on the calling thread, known when compiling: the slot passes
    /// then fold their chunks in place, with no list of jobs to hand out.
    const HERE: bool = false;

    /// Runs `a` and `b`, possibly at the same time, and returns both results.
    fn join<A, B, RA, RB>(&self, a: A, b: B) -> (RA, RB)
    where
        A: FnOnce() -> RA + Send,
        B: FnOnce() -> RB + Send,
        RA: Send,
        RB: Send,
    {
        (a(), b())
    }
}

/// Runs everything on the calling thread.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Sequential;

impl Parallel for Sequential {
    const HERE: bool = true;

    fn for_each<T: Send, F: Fn(&mut T) + Sync>(&self, items: &mut [T], work: F) {
        items.iter_mut().for_each(work);
    }
}

/// [`Parallel`] on rayon's current thread pool.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Rayon;

impl Parallel for Rayon {
    fn for_each<T: Send, F: Fn(&mut T) + Sync>(&self, items: &mut [T], work: F) {
        use rayon::prelude::*;
        if items.len() <= 1 {
            items.iter_mut().for_each(work);
            return;
        }
        // One task per item, so that an idle thread can take any: with rayon's default split,
        // the other thread, busy in a `join`, found little left to take.
        items.par_iter_mut().with_max_len(1).for_each(&work);
    }

    fn join<A, B, RA, RB>(&self, a: A, b: B) -> (RA, RB)
    where
        A: FnOnce() -> RA + Send,
        B: FnOnce() -> RB + Send,
        RA: Send,
        RB: Send,
    {
        rayon::join(a, b)
    }
}

/// Slots per parallel task of the slot passes, fixed (not from the thread count) so that sums
/// over slots add up in the same order on any number of threads. Measured with the `bench`
/// example, the demo's DFSPH dam break at 2,500 particles on two threads: 1.37x real time with
/// 256, 1.22x with 512.
pub(crate) const CHUNK: usize = 256;

/// Fewest particles whose slot passes run in parallel. Worth it only on a pool whose threads
/// stay awake between passes (the ECS runs its passes in rayon regions for that): at 2,500
/// particles a pass is tens of microseconds, less than waking a sleeping thread.
pub const PARALLEL_SLOTS: usize = 1024;

/// Runs the jobs of a pass over `slots` particles: on `parallel` from [`PARALLEL_SLOTS`] on, on
/// the calling thread below (waking a pool's threads costs more than a small pass). The jobs are
/// the same either way, so are the sums.
pub(crate) fn run_jobs<T: Send>(
    parallel: &impl Parallel,
    slots: usize,
    jobs: &mut [T],
    work: impl Fn(&mut T) + Sync,
) {
    if slots < PARALLEL_SLOTS {
        jobs.iter_mut().for_each(work);
    } else {
        parallel.for_each(jobs, work);
    }
}

/// Runs `work(slot, &mut out[slot])` for every slot, in parallel chunks of [`CHUNK`] slots, and
/// returns the sum of what it returns, added chunk by chunk in slot order: the same on any
/// number of threads.
pub(crate) fn for_each_slot<T: Send>(
    out: &mut [T],
    parallel: &impl Parallel,
    work: impl Fn(usize, &mut T) -> f64 + Sync,
) -> f64 {
    fold_slots(out, parallel, work, |a, b| a + b)
}

/// Runs `work(slot, &mut out[slot])` for every slot, in parallel chunks of [`CHUNK`] slots, and
/// folds what it returns with `add` from `R::default()`: slot by slot within a chunk, then chunk
/// by chunk in slot order, so the result is the same on any number of threads.
pub(crate) fn fold_slots<T: Send, R: Copy + Default + Send, P: Parallel>(
    out: &mut [T],
    parallel: &P,
    work: impl Fn(usize, &mut T) -> R + Sync,
    add: impl Fn(R, R) -> R + Sync,
) -> R {
    if P::HERE {
        let chunks = out.chunks_mut(CHUNK).enumerate();
        return chunks.fold(R::default(), |total, (k, values)| {
            let slots = values.iter_mut().enumerate();
            let chunk = slots.fold(R::default(), |sum, (i, v)| add(sum, work(k * CHUNK + i, v)));
            add(total, chunk)
        });
    }
    let n = out.len();
    let mut jobs: Vec<_> = out
        .chunks_mut(CHUNK)
        .enumerate()
        .map(|(k, values)| (k * CHUNK, values, R::default()))
        .collect();
    run_jobs(parallel, n, &mut jobs, |(start, values, total)| {
        for (k, value) in values.iter_mut().enumerate() {
            *total = add(*total, work(*start + k, value));
        }
    });
    jobs.iter()
        .fold(R::default(), |total, job| add(total, job.2))
}

/// [`fold_slots`] over two arrays of the same length at once: `work(slot, &mut a[slot], &mut
/// b[slot])`, in the same chunks and order.
pub(crate) fn fold_slots2<A: Send, B: Send, R: Copy + Default + Send, P: Parallel>(
    a: &mut [A],
    b: &mut [B],
    parallel: &P,
    work: impl Fn(usize, &mut A, &mut B) -> R + Sync,
    add: impl Fn(R, R) -> R + Sync,
) -> R {
    debug_assert_eq!(a.len(), b.len());
    let n = a.len();
    let chunks = a.chunks_mut(CHUNK).zip(b.chunks_mut(CHUNK)).enumerate();
    if P::HERE {
        return chunks.fold(R::default(), |total, (k, (a, b))| {
            let slots = a.iter_mut().zip(b.iter_mut()).enumerate();
            let chunk = slots.fold(R::default(), |sum, (i, (a, b))| {
                add(sum, work(k * CHUNK + i, a, b))
            });
            add(total, chunk)
        });
    }
    let mut jobs: Vec<_> = chunks
        .map(|(k, (a, b))| (k * CHUNK, a, b, R::default()))
        .collect();
    run_jobs(parallel, n, &mut jobs, |(start, a, b, total)| {
        for (k, (a, b)) in a.iter_mut().zip(b.iter_mut()).enumerate() {
            *total = add(*total, work(*start + k, a, b));
        }
    });
    jobs.iter()
        .fold(R::default(), |total, job| add(total, job.3))
}

/// A chunk length that splits `len` items into about `pieces` chunks of at least `min` items.
pub(crate) fn chunk_size(len: usize, pieces: usize, min: usize) -> usize {
    len.div_ceil(pieces.max(1)).max(min).max(1)
}

/// Runs `work` on the calling thread, rayon calls inside it included: the calling thread becomes
/// the one thread of a rayon pool of its own (rayon's `use_current_thread`), so nothing is ever
/// spawned and every parallel iterator runs in order on it. Inside a rayon pool already (a
/// caller's own), `work` runs on that pool. This is what the crate does everywhere without the
/// `parallel` feature, for targets without threads.
pub fn calling_thread<R: Send>(work: impl FnOnce() -> R + Send) -> R {
    thread_local! {
        static POOL: Option<rayon::ThreadPool> = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .use_current_thread()
            .build()
            .ok();
    }
    if rayon::current_thread_index().is_some() {
        return work();
    }
    POOL.with(|pool| match pool {
        Some(pool) => pool.install(work),
        None => work(),
    })
}

/// Runs `work` where a caller's own rayon work runs: on the current rayon pool with the
/// `parallel` feature, on the calling thread without ([`calling_thread`]). The slice driver's
/// passes use it.
pub fn current<R: Send>(work: impl FnOnce() -> R + Send) -> R {
    if cfg!(feature = "parallel") {
        work()
    } else {
        calling_thread(work)
    }
}
