//! Running a solve on a Rust thread while the calling thread waits without the GIL: it wakes
//! every few milliseconds to run Python's signal handlers (Ctrl-C raises `KeyboardInterrupt`
//! and sets the solve's stop flag) and to pass progress to the caller's callback.

use crate::errors::panicked;
use cellseq::{Observer, Progress};
use pyo3::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::time::Duration;

/// How often the waiting thread looks at signals.
const POLL: Duration = Duration::from_millis(20);

/// Sends each improvement to the waiting thread.
pub struct Forward(pub Sender<Progress>);

impl Observer for Forward {
    fn improved(&mut self, p: Progress) {
        // the receiver is gone only after the solve has been stopped
        let _ = self.0.send(p);
    }
}

/// Runs `work(observer, stop)` on a scoped thread; the calling thread releases the GIL while
/// it waits, calls `progress(evaluations, seconds, best)` for every improvement (when given),
/// and on a pending signal that raises (Ctrl-C) or a callback that raises, sets `stop`,
/// waits for the work to return its best so far, and raises that exception. A panic in the
/// work becomes an `InternalError`.
pub fn run_polling<T: Send>(
    py: Python<'_>,
    what: &str,
    progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce(&mut Forward, &AtomicBool) -> PyResult<T> + Send,
) -> PyResult<T> {
    let stop = AtomicBool::new(false);
    let (tx, rx) = mpsc::channel::<Progress>();
    // the receiver is used by this thread alone; the mutex makes it `Sync` for `detach`
    let rx = Mutex::new(rx);
    std::thread::scope(|scope| {
        let stop_ref = &stop;
        let handle = scope.spawn(move || {
            let mut fwd = Forward(tx);
            work(&mut fwd, stop_ref)
        });
        let mut raised: Option<PyErr> = None;
        loop {
            let got = py.detach(|| match rx.lock() {
                Ok(r) => r.recv_timeout(POLL),
                Err(_) => Err(RecvTimeoutError::Disconnected),
            });
            match got {
                Ok(p) => {
                    if raised.is_none()
                        && let Some(cb) = progress
                        && let Err(e) = cb.call1((p.evaluations, p.elapsed_s, p.best))
                    {
                        stop.store(true, Ordering::SeqCst);
                        raised = Some(e);
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
                // the work has returned (its sender dropped)
                Err(RecvTimeoutError::Disconnected) => break,
            }
            if raised.is_none()
                && let Err(e) = py.check_signals()
            {
                stop.store(true, Ordering::SeqCst);
                raised = Some(e);
            }
        }
        let out = py.detach(|| handle.join());
        match (raised, out) {
            (Some(e), _) => Err(e),
            (None, Ok(r)) => r,
            (None, Err(p)) => Err(panicked(what, p)),
        }
    })
}

/// What a solve needs, without the observer and stop flag (which live on the solver thread):
/// built into a [`cellseq::Solve`] there.
pub struct Spec {
    /// The solver.
    pub solver: cellseq::SolverKind,
    /// Parameters given.
    pub params: Vec<(String, cellseq::params::ParamValue)>,
    /// Seed.
    pub seed: u64,
    /// Budget.
    pub budget: cellseq::Budget,
    /// Objective.
    pub objective: Option<cellseq::model::Objective>,
    /// Compute a lower bound after the solve.
    pub lower_bound: bool,
}

impl Spec {
    /// The solve of this spec.
    pub fn build<'o>(&self) -> cellseq::Solve<'o> {
        let mut s = cellseq::Solve::new(self.solver)
            .seed(self.seed)
            .budget(self.budget)
            .lower_bound(self.lower_bound);
        if let Some(o) = self.objective {
            s = s.objective(o);
        }
        for (k, v) in &self.params {
            s = s.param(k, v.clone());
        }
        s
    }
}
