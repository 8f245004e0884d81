//! Long jobs from Python: the job runs on a worker thread (in its own rayon pool) with the GIL
//! released, while the calling thread wakes every 100 ms to look for Ctrl-C and to report
//! progress. Progress callbacks are called on the calling thread only, with the GIL held, so a
//! tqdm bar or any Python callable is safe whatever the worker threads do.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

/// Most worker threads (as the command line allows).
pub const MAX_THREADS: usize = 256;

/// What a job sees: a tick to call per unit of progress and the flag that asks it to stop.
pub struct Handle {
    done: AtomicU64,
    /// Set on Ctrl-C: the job ends as soon as it can.
    pub stop: AtomicBool,
}

impl Handle {
    /// One unit of progress.
    pub fn tick(&self) {
        self.done.fetch_add(1, Ordering::Relaxed);
    }
}

/// Runs `job` on `threads` worker threads (0: every core) with the GIL released; calls
/// `progress(done, total)` on this thread as progress is made; on Ctrl-C (or any signal whose
/// handler raises) stops the job, waits for it and raises. A job returning None was stopped.
pub fn run<T: Send + 'static>(
    py: Python<'_>,
    threads: usize,
    total: u64,
    progress: Option<&Bound<'_, PyAny>>,
    job: impl FnOnce(&Handle) -> Option<T> + Send + 'static,
) -> PyResult<T> {
    if threads > MAX_THREADS {
        return Err(PyValueError::new_err(format!("threads = {threads}: at most {MAX_THREADS} (0 uses every core)")));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start worker threads: {e}")))?;
    let handle = Arc::new(Handle { done: AtomicU64::new(0), stop: AtomicBool::new(false) });
    let (tx, rx) = mpsc::channel();
    // Waited on with the GIL released, so shared with the closure that waits.
    let rx = std::sync::Mutex::new(rx);
    let worker = {
        let handle = handle.clone();
        std::thread::Builder::new()
            .name("proxform-run".into())
            .spawn(move || {
                let out = pool.install(|| job(&handle));
                // The receiver is gone only if the caller already gave up waiting.
                let _ = tx.send(out);
            })
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start a worker thread: {e}")))?
    };
    let mut reported = u64::MAX;
    let mut report = || -> PyResult<()> {
        let done = handle.done.load(Ordering::Relaxed).min(total);
        if let Some(cb) = progress {
            if done != reported {
                reported = done;
                cb.call1((done, total))?;
            }
        }
        Ok(())
    };
    let stop_and_join = |handle: &Handle, worker: std::thread::JoinHandle<()>, py: Python<'_>| {
        handle.stop.store(true, Ordering::Relaxed);
        // A stopped flight ends at its next step: the wait is short.
        py.detach(|| {
            let _ = worker.join();
        });
    };
    loop {
        let received = py.detach(|| match rx.lock() {
            Ok(rx) => rx.recv_timeout(Duration::from_millis(100)),
            Err(_) => Err(mpsc::RecvTimeoutError::Disconnected),
        });
        match received {
            Ok(out) => {
                let _ = worker.join();
                report()?;
                return out.ok_or_else(|| PyRuntimeError::new_err("the run was stopped"));
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals().and_then(|_| report()) {
                    stop_and_join(&handle, worker, py);
                    return Err(e);
                }
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                let _ = worker.join();
                return Err(PyRuntimeError::new_err(
                    "proxform's worker thread failed (an internal error: please report it with the scenario)",
                ));
            }
        }
    }
}
