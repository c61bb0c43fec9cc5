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
/// and so do the rayon calls inside it (see [`calling_thread`]).
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
    calling_thread(work)
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
