//! Optional progress bars: tqdm's, when it is installed and asked for.

use pyo3::prelude::*;

/// A tqdm bar over `total` units, or nothing.
pub struct Progress {
    bar: Option<Py<PyAny>>,
    shown: u64,
}

impl Progress {
    /// A bar when `show` and tqdm can be imported; nothing otherwise.
    pub fn new(py: Python<'_>, show: bool, total: u64, what: &str) -> PyResult<Progress> {
        let bar = if show {
            match py.import("tqdm") {
                Ok(tqdm) => {
                    let kw = pyo3::types::PyDict::new(py);
                    kw.set_item("total", total)?;
                    kw.set_item("desc", what)?;
                    Some(tqdm.getattr("tqdm")?.call((), Some(&kw))?.unbind())
                }
                Err(_) => None,
            }
        } else {
            None
        };
        Ok(Progress { bar, shown: 0 })
    }

    /// Moves the bar to `done` units.
    pub fn update(&mut self, py: Python<'_>, done: u64) {
        if let Some(bar) = &self.bar
            && done > self.shown
        {
            // A bar that fails to draw is no reason to stop the work.
            let _ = bar.call_method1(py, "update", (done - self.shown,));
            self.shown = done;
        }
    }

    /// Closes the bar.
    pub fn close(self, py: Python<'_>) {
        if let Some(bar) = self.bar {
            let _ = bar.call_method0(py, "close");
        }
    }
}
