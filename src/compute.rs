//! The crate's one pool for heavy parallel work: a rayon pool of as many threads as Bevy's
//! `ComputeTaskPool`, which the fluid's passes over neighbours and gravity's tree build and
//! field evaluation run on (in [`region`]s), so the two never compete with a third pool for the
//! same cores. Bevy's own pool still runs the systems and the light per-component passes.

use bevy::tasks::ComputeTaskPool;

/// Runs `work` as one parallel region on the crate's pool: rayon calls inside it (`par_iter`,
/// `join`) run on the pool's threads, which stay awake from one pass to the next. Measured with
/// the `bench` example on the demo's dam break, two threads: with a task per pass on Bevy's
/// pool, whose threads sleep between passes, 10,000 particles ran at 0.11x real time (1.1-1.4
/// times one thread) and 2,500 no faster than on one thread; in regions, 0.17x (1.7 times one
/// thread) and 1.37x (from 0.93-1.0x).
///
/// The pool is sized from the `ComputeTaskPool` of the first app that uses it (one process, one
/// pool). Without the `parallel` feature there is no pool: `work` runs on the calling thread,
/// and so do the rayon calls inside it (see
/// [`calling_thread`](crate::sim::parallel::calling_thread)).
#[cfg(feature = "parallel")]
pub fn region<R: Send>(work: impl FnOnce() -> R + Send) -> R {
    static POOL: std::sync::OnceLock<rayon::ThreadPool> = std::sync::OnceLock::new();
    POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads())
            .thread_name(|k| format!("bevy_sph2d compute {k}"))
            .build()
            .expect("a rayon pool")
    })
    .install(work)
}

/// Runs `work` as one region on the calling thread (the build without the `parallel` feature).
#[cfg(not(feature = "parallel"))]
pub fn region<R: Send>(work: impl FnOnce() -> R + Send) -> R {
    crate::sim::parallel::calling_thread(work)
}

/// How many threads a [`region`] runs on: Bevy's compute threads, one without the `parallel`
/// feature.
pub fn threads() -> usize {
    if cfg!(feature = "parallel") {
        ComputeTaskPool::get_or_init(Default::default)
            .thread_num()
            .max(1)
    } else {
        1
    }
}
