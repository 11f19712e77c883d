//! Long calls off the interpreter: the work runs on a thread of its own with
//! the GIL released, while the calling thread wakes every 50 ms to honour
//! Ctrl-C and to draw progress.

use pyo3::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

/// How often the waiting thread checks for signals.
const TICK: Duration = Duration::from_millis(50);

/// Runs `work` with the GIL released and returns its result. Every 50 ms the
/// calling thread takes the GIL, calls `tick` (progress) and checks for
/// signals: on Ctrl-C (or any signal handler that raises) it sets the flag
/// `work` receives, waits for `work` to return, and raises what the handler
/// raised. Work that polls the flag stops early; work that does not is
/// waited for.
pub fn interruptible<T: Send>(py: Python<'_>, work: impl FnOnce(&AtomicBool) -> T + Send, mut tick: impl FnMut(Python<'_>)) -> PyResult<T> {
    let cancel = AtomicBool::new(false);
    std::thread::scope(|s| {
        let (tx, rx) = mpsc::channel();
        let cancel = &cancel;
        s.spawn(move || {
            // The receiver outlives the worker inside the scope.
            let _ = tx.send(work(cancel));
        });
        let rx = Mutex::new(rx);
        let mut raised: Option<PyErr> = None;
        loop {
            let got = py.detach(|| rx.lock().map_err(|_| RecvTimeoutError::Disconnected)?.recv_timeout(TICK));
            match got {
                Ok(value) => {
                    tick(py);
                    return match raised {
                        Some(e) => Err(e),
                        None => Ok(value),
                    };
                }
                Err(RecvTimeoutError::Timeout) => {
                    tick(py);
                    if raised.is_none()
                        && let Err(e) = py.check_signals()
                    {
                        cancel.store(true, Ordering::Relaxed);
                        raised = Some(e);
                    }
                }
                // The worker panicked; the scope re-raises its panic, which
                // PyO3 turns into a PanicException.
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(raised.unwrap_or_else(|| crate::error::vpl_err("the computation stopped without a result")));
                }
            }
        }
    })
}
