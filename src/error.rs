//! The error type of the core. The Python layer maps each variant onto geocull's exception hierarchy
//! (`InputError` for bad arguments, `DeviceError` for adapter/driver trouble, `KeyboardInterrupt`
//! for [`Error::Interrupted`]), and the cancellation hook [`Interrupt`] that long work polls.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

/// Everything that can go wrong in geocull, as values (the core never panics on bad input).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A bad argument. `arg` names the argument as the caller spelled it.
    #[error("{}", if msg.starts_with(arg.as_str()) { msg.clone() } else { format!("{arg}: {msg}") })]
    Input { arg: String, msg: String },
    /// No usable GPU adapter, or the driver rejected the work.
    #[error("{0}")]
    Device(String),
    /// The caller's [`Interrupt`] asked to stop (Ctrl-C in Python). Nothing was changed: a scene
    /// gets no new object, a renderer stays usable for the next frame.
    #[error("interrupted")]
    Interrupted,
}

pub type Result<T> = std::result::Result<T, Error>;

/// A number for a message: plain where that is short, scientific (`1e300`) where it is not.
pub fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-4..1e15).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Shorthand for an [`Error::Input`] naming `arg`.
pub fn input_err(arg: impl Into<String>, msg: impl Into<String>) -> Error {
    Error::Input { arg: arg.into(), msg: msg.into() }
}

/// Returns `Err(Error::Input)` unless `cond` holds.
pub fn ensure(cond: bool, arg: &str, msg: impl FnOnce() -> String) -> Result<()> {
    if cond {
        Ok(())
    } else {
        Err(input_err(arg, msg()))
    }
}

/// An integer argument `v` as a count in `lo..=hi` (bindings pass Python ints as i64, so range
/// checks live here with the other value checks).
#[cfg(feature = "python")]
pub fn int_in(v: i64, arg: &str, lo: i64, hi: i64) -> Result<usize> {
    ensure((lo..=hi).contains(&v), arg, || format!("{v} is outside {lo}..{hi}"))?;
    Ok(v as usize)
}

/// An object id (ids are u32; anything else names no object).
#[cfg(feature = "python")]
pub fn object_id(v: i64) -> Result<u32> {
    u32::try_from(v).map_err(|_| input_err("id", format!("no object with id {v} in this scene")))
}

/// A cancellation hook that long work polls, so that Ctrl-C is honoured within a fraction of a
/// second rather than at the end of a multi-second frame or build.
///
/// Design: the core stays free of Python. A hook is any `Fn() -> bool` (true = stop), carried by
/// the options of a call (`RenderOptions`, `AddOptions`, `IsoOptions`); the default has none and
/// costs nothing. The core calls it **only on the thread that called into the core**, because
/// Python runs signal handlers on its main thread only: the binding's hook is
/// `Python::attach(|py| py.check_signals())` (src/python/mod.rs), which re-takes the GIL for a
/// moment and runs the handlers; KeyboardInterrupt (or whatever a handler raised) makes it return
/// true, and the binding raises that exception. It is polled only where stopping leaves
/// everything usable:
///
/// - between the stages of a frame (after upload, after the strategy, after the draw is
///   recorded) and while waiting for the GPU (`GpuContext::submit_and_wait`, in slices of
///   [`Interrupt::POLL`]; on GL, whose submit does the work, large frames are submitted from a
///   worker thread; the GPU finishes abandoned work on its own, and the next frame waits for it
///   before its clock starts);
/// - while a parallel build runs ([`Interrupt::run_parallel`]): the calling thread polls while
///   rayon's workers build tiles, and a set flag makes the workers skip the tiles not started.
///
/// No global state: two renders on two threads each have their own hook.
///
/// Progress rides along: a hook may carry a progress callback ([`Interrupt::with_progress`]),
/// which [`Interrupt::run_parallel`]'s polling loop calls on the same calling thread with the
/// number of items the job's workers have finished so far (`Work::item_done`) and their total
/// where the job has said it (`Work::set_total`; 0 = not said); it returns true to stop the
/// work, like the hook (the binding's callback raised).
#[derive(Clone, Default)]
pub struct Interrupt(
    Option<Arc<dyn Fn() -> bool + Send + Sync>>,
    Option<Arc<dyn Fn(usize, usize) -> bool + Send + Sync>>,
);

impl std::fmt::Debug for Interrupt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.is_some() { "Interrupt(hook)" } else { "Interrupt(none)" })
    }
}

/// What the workers of a parallel build share with the polling thread: the stop flag (the
/// `&AtomicBool` the tile loops read, through `Deref`), the count of finished items (tiles)
/// that progress reports, and their total once the job knows it.
#[derive(Debug, Default)]
pub struct Work {
    stop: AtomicBool,
    done: AtomicUsize,
    total: AtomicUsize,
}

impl std::ops::Deref for Work {
    type Target = AtomicBool;
    fn deref(&self) -> &AtomicBool {
        &self.stop
    }
}

/// A parallel job's view of its [`Work`]: the stop flag, and where finished items are counted
/// (nowhere for a bare `AtomicBool`, as tests pass).
pub trait Progress: Sync {
    fn stop_flag(&self) -> &AtomicBool;
    fn item_done(&self) {}
}

impl Progress for AtomicBool {
    fn stop_flag(&self) -> &AtomicBool {
        self
    }
}

impl Progress for Work {
    fn stop_flag(&self) -> &AtomicBool {
        &self.stop
    }
    fn item_done(&self) {
        Work::item_done(self)
    }
}

impl Work {
    /// One more item finished (any worker thread).
    #[inline]
    pub fn item_done(&self) {
        self.done.fetch_add(1, Ordering::Relaxed);
    }
    /// Items finished so far.
    pub fn done(&self) -> usize {
        self.done.load(Ordering::Relaxed)
    }
    /// The job will finish `n` items in all (for progress, where the caller could not know it
    /// beforehand: an isosurface's tiles exist only once it is extracted).
    pub fn set_total(&self, n: usize) {
        self.total.store(n, Ordering::Relaxed);
    }
    /// The total set by [`Self::set_total`]; 0 when not set.
    pub fn total(&self) -> usize {
        self.total.load(Ordering::Relaxed)
    }
}

impl Interrupt {
    /// How often a waiting thread polls the hook.
    pub const POLL: Duration = Duration::from_millis(25);

    /// A hook: `stop()` returns true when the work should stop.
    pub fn new(stop: impl Fn() -> bool + Send + Sync + 'static) -> Self {
        Self(Some(Arc::new(stop)), None)
    }

    /// This hook with a progress callback: `progress(done, total)` is called while
    /// [`Self::run_parallel`] waits (every [`Self::POLL`], on the calling thread) with the items
    /// finished so far and their total (0 until the job sets it); true stops the work as the
    /// hook does.
    pub fn with_progress(self, progress: impl Fn(usize, usize) -> bool + Send + Sync + 'static) -> Self {
        let stop = self.0.unwrap_or_else(|| Arc::new(|| false));
        Self(Some(stop), Some(Arc::new(progress)))
    }

    /// Calls the progress callback (if any) with `done` and `total`; true = stop.
    fn report(&self, done: usize, total: usize) -> bool {
        self.1.as_ref().is_some_and(|p| p(done, total))
    }

    /// Whether there is a hook at all (without one, nothing needs polling).
    pub fn is_set(&self) -> bool {
        self.0.is_some()
    }

    /// `Err(Error::Interrupted)` when the hook says stop.
    pub fn check(&self) -> Result<()> {
        match &self.0 {
            Some(stop) if stop() => Err(Error::Interrupted),
            _ => Ok(()),
        }
    }

    /// Runs `job` (which may use rayon; on this process's pool, `in_pool`) while this thread
    /// polls the hook, once before and then every [`Self::POLL`]; when it says stop, the flag
    /// passed to `job` is set, `job` should return soon (skipping work not started) and the
    /// result is `Err(Error::Interrupted)`.
    /// Without a hook, `job` runs on this thread.
    pub fn run_parallel<T: Send>(&self, job: impl FnOnce(&Work) -> T + Send) -> Result<T> {
        let stop = Work::default();
        if !self.is_set() {
            return Ok(job(&stop));
        }
        self.check()?;
        let (tx, rx) = mpsc::channel::<()>();
        let out = std::thread::scope(|s| {
            let stop = &stop;
            let worker = s.spawn(move || {
                let out = in_pool(|| job(stop));
                let _ = tx.send(());
                out
            });
            // Until the job reports (or its thread dies: the channel disconnects).
            while let Err(mpsc::RecvTimeoutError::Timeout) = rx.recv_timeout(Self::POLL) {
                if !stop.load(Ordering::Relaxed) && (self.check().is_err() || self.report(stop.done(), stop.total())) {
                    stop.store(true, Ordering::Relaxed);
                }
            }
            worker.join()
        });
        match out {
            Err(panic) => std::panic::resume_unwind(panic),
            Ok(_) if stop.load(Ordering::Relaxed) => Err(Error::Interrupted),
            Ok(v) => Ok(v),
        }
    }
}

/// The process whose threads rayon's global pool has (or will have): the first to use geocull.
static FIRST_PROCESS: std::sync::OnceLock<u32> = std::sync::OnceLock::new();

/// Records this process as the one whose threads rayon's global pool has (the Python module does
/// at import; otherwise the first [`in_pool`] call does).
#[cfg(feature = "python")]
pub fn record_process() {
    FIRST_PROCESS.get_or_init(std::process::id);
}

/// Runs `f` where its rayon work can run: directly (rayon's global pool) in the process that
/// first used geocull; in a process forked from it, which inherits the global pool without its
/// threads (work given to it would wait forever), on a worker of a pool of that process's own,
/// made on its first call.
pub fn in_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    let pid = std::process::id();
    if *FIRST_PROCESS.get_or_init(|| pid) == pid {
        return f();
    }
    static POOL: std::sync::Mutex<Option<(u32, std::sync::Arc<rayon::ThreadPool>)>> = std::sync::Mutex::new(None);
    let pool = {
        let mut slot = POOL.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        match &*slot {
            Some((p, pool)) if *p == pid => pool.clone(),
            _ => {
                // The pool of a process this one was forked from is forgotten, not dropped: its
                // threads are not here.
                std::mem::forget(slot.take());
                let pool = rayon::ThreadPoolBuilder::new()
                    .thread_name(|i| format!("geocull-{i}"))
                    .build()
                    .map(std::sync::Arc::new)
                    .expect("a thread pool (the system refused to start threads)");
                *slot = Some((pid, pool.clone()));
                pool
            }
        }
    };
    pool.install(f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;

    #[test]
    fn check_and_run_parallel_without_a_hook() {
        assert!(Interrupt::default().check().is_ok());
        assert_eq!(Interrupt::default().run_parallel(|_| 5).unwrap(), 5);
        assert!(matches!(Interrupt::new(|| true).check(), Err(Error::Interrupted)));
        assert_eq!(Interrupt::new(|| false).run_parallel(|_| 6).unwrap(), 6);
    }

    /// The hook fires on its second poll, while the job runs: the job sees the flag, the call
    /// returns Interrupted.
    #[test]
    fn run_parallel_sets_the_flag_while_the_job_runs() {
        let calls = Arc::new(AtomicUsize::new(0));
        let c = calls.clone();
        let hook = Interrupt::new(move || c.fetch_add(1, Ordering::Relaxed) >= 1);
        let t0 = std::time::Instant::now();
        let r = hook.run_parallel(|stop| {
            while !stop.load(Ordering::Relaxed) && t0.elapsed() < Duration::from_secs(10) {
                std::thread::sleep(Duration::from_millis(1));
            }
            stop.load(Ordering::Relaxed)
        });
        assert!(matches!(r, Err(Error::Interrupted)));
        assert_eq!(calls.load(Ordering::Relaxed), 2);
        assert!(t0.elapsed() < Duration::from_secs(2), "{:?}", t0.elapsed());
    }

    /// Progress is reported on the polling thread with monotone counts of the items done; a
    /// callback that returns true stops the job like the hook.
    #[test]
    fn run_parallel_reports_progress_and_stops_on_request() {
        let seen = Arc::new(std::sync::Mutex::new(Vec::new()));
        let s = seen.clone();
        let caller = std::thread::current().id();
        let hook = Interrupt::default().with_progress(move |done, total| {
            assert_eq!(std::thread::current().id(), caller);
            assert!(total == 0 || total == 6, "{total}");
            s.lock().unwrap().push((done, total));
            false
        });
        let n = hook
            .run_parallel(|work| {
                std::thread::sleep(Duration::from_millis(40));
                work.set_total(6);
                for _ in 0..6 {
                    std::thread::sleep(Duration::from_millis(15));
                    work.item_done();
                }
                work.done()
            })
            .unwrap();
        assert_eq!(n, 6);
        let seen = seen.lock().unwrap().clone();
        assert!(
            !seen.is_empty() && seen.windows(2).all(|w| w[0] <= w[1]) && seen.iter().all(|&(d, _)| d <= 6),
            "{seen:?}"
        );
        assert!(seen.iter().any(|&(_, t)| t == 6), "the total reaches the callback: {seen:?}");
        let stopper = Interrupt::default().with_progress(|done, _| done >= 1);
        let r = stopper.run_parallel(|work| {
            while !work.load(Ordering::Relaxed) {
                work.item_done();
                std::thread::sleep(Duration::from_millis(1));
            }
        });
        assert!(matches!(r, Err(Error::Interrupted)));
    }
}
