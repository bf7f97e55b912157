//! How a caller watches and stops a run: a progress sink and an interrupt flag.
//!
//! Engines and the run path never print. The CLI turns [`Progress`] calls into a progress bar
//! and sets the interrupt flag from its Ctrl-C handler; Python polls its own signals from
//! [`Progress::poll`] (the only place a long call comes back to the caller).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// What a caller is told while a run goes on. Every method has a default that does nothing.
pub trait Progress: Send + Sync {
    /// A run (or a theory solve) starts: `total` units of work, `done` of them already done
    /// (a restart).
    fn begin(&self, _label: &str, _total: u64, _done: u64) {}
    /// `done` units are done.
    fn advance(&self, _done: u64) {}
    /// Where the run stands, in one line (step, simulated time, temperature where the method
    /// has one, throughput); the CLI shows it beside its progress bar.
    fn status(&self, _text: &str) {}
    /// A message for the user (e.g. why the run goes on after Ctrl-C).
    fn message(&self, _text: &str) {}
    /// A warning (the CLI prints `warning: ...`); every warning is also in the run's report.
    fn warning(&self, _text: &str) {}
    /// The run ended (finished, stopped or failed).
    fn end(&self) {}
    /// Called between chunks of work; returning true asks the run to stop as on Ctrl-C.
    fn poll(&self) -> bool {
        false
    }
}

/// A progress sink that reports nothing.
pub struct Silent;

impl Progress for Silent {}

/// The caller's side of a run: where progress goes and whether it was asked to stop.
#[derive(Clone)]
pub struct Control {
    interrupt: Arc<AtomicBool>,
    progress: Arc<dyn Progress>,
}

impl Default for Control {
    fn default() -> Self {
        Self::new(Arc::new(Silent))
    }
}

impl Control {
    /// A control reporting to `progress`.
    pub fn new(progress: Arc<dyn Progress>) -> Self {
        Self {
            interrupt: Arc::new(AtomicBool::new(false)),
            progress,
        }
    }

    /// The flag that stops the run when set (a Ctrl-C handler sets it).
    pub fn interrupt_flag(&self) -> Arc<AtomicBool> {
        self.interrupt.clone()
    }

    /// Ask the run to stop at the next point where it can write a checkpoint.
    pub fn interrupt(&self) {
        self.interrupt.store(true, Ordering::SeqCst);
    }

    /// Has the run been asked to stop (flag set, or the progress sink asks)?
    pub fn interrupted(&self) -> bool {
        if self.progress.poll() {
            self.interrupt();
        }
        self.interrupt.load(Ordering::Relaxed)
    }

    /// The progress sink.
    pub fn progress(&self) -> &dyn Progress {
        &*self.progress
    }
}
