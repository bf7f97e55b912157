//! How a caller watches and stops a run: a progress sink, an interrupt flag with its cause,
//! and a wall-time budget.
//!
//! Engines and the run path never print. The CLI turns [`Progress`] calls into a progress bar
//! and stops the run from its signal handler (Ctrl-C, SIGTERM, SIGUSR1: [`Control::stop`]);
//! Python polls its own signals from [`Progress::poll`] (the only place a long call comes back
//! to the caller). With a budget ([`Control::with_walltime`]) the driver stops by itself at the
//! last checkpoint that fits in it.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU8, AtomicU64, Ordering};
use std::time::Instant;

/// Why a run was asked to stop (it then writes a checkpoint at the next point it can, and
/// ends with [`crate::Interrupted`]). The CLI exits with a status of its own per cause
/// (docs/cluster.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    /// Ctrl-C (SIGINT), Python's `KeyboardInterrupt`, or a caller's [`Control::interrupt`].
    Interrupt,
    /// SIGTERM (`kill`, a batch scheduler at the end of a job, a container stop).
    Terminate,
    /// SIGUSR1 (a batch scheduler's warning ahead of the time limit).
    User1,
    /// The wall-time budget ([`Control::with_walltime`]) would not hold another chunk of work
    /// and a checkpoint.
    WallTime,
}

impl Stop {
    /// A small number for the flag and for the ranks of a decomposed run to agree on (0 is
    /// "not stopped"; the larger number wins when ranks saw different causes).
    pub fn code(self) -> u8 {
        match self {
            Stop::Interrupt => 1,
            Stop::Terminate => 2,
            Stop::User1 => 3,
            Stop::WallTime => 4,
        }
    }

    /// The cause of a [`Stop::code`] (`None` for 0 or an unknown code).
    pub fn from_code(code: u8) -> Option<Self> {
        match code {
            1 => Some(Stop::Interrupt),
            2 => Some(Stop::Terminate),
            3 => Some(Stop::User1),
            4 => Some(Stop::WallTime),
            _ => None,
        }
    }

    /// What happened, for messages: `interrupted`, `stopped by SIGTERM`, ...
    pub fn what(self) -> &'static str {
        match self {
            Stop::Interrupt => "interrupted",
            Stop::Terminate => "stopped by SIGTERM",
            Stop::User1 => "stopped by SIGUSR1",
            Stop::WallTime => "stopped by the wall-time budget",
        }
    }

    /// What stops at once without a checkpoint while the run goes on to one.
    pub fn again(self) -> &'static str {
        match self {
            Stop::Interrupt => "Ctrl-C again stops at once",
            Stop::Terminate | Stop::User1 => "a second signal stops at once",
            Stop::WallTime => "Ctrl-C stops at once",
        }
    }
}

/// A wall-time budget: seconds from `start` (the program's start) within which the run must
/// have written its last checkpoint.
#[derive(Clone)]
struct Budget {
    seconds: f64,
    start: Instant,
    /// The test hook's clock (seconds as `f64` bits), shared by the members of an ensemble.
    fake: Arc<AtomicU64>,
}

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
    cause: Arc<AtomicU8>,
    progress: Arc<dyn Progress>,
    budget: Option<Budget>,
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
            cause: Arc::new(AtomicU8::new(0)),
            progress,
            budget: None,
        }
    }

    /// This control with a wall-time budget of `seconds` counted from `start` (`colloidsim run
    /// --walltime`): the run stops at the last checkpoint that fits (the driver measures the
    /// time per step and per checkpoint; docs/cluster.md gives the safety margin).
    pub fn with_walltime(mut self, seconds: f64, start: Instant) -> Self {
        self.budget = Some(Budget {
            seconds,
            start,
            fake: Arc::new(AtomicU64::new(0f64.to_bits())),
        });
        self
    }

    /// The wall-time budget in seconds, if any.
    pub fn walltime(&self) -> Option<f64> {
        self.budget.as_ref().map(|b| b.seconds)
    }

    /// Seconds of the budget spent: since its start, or on the test hook's clock when `fake`.
    pub(crate) fn spent(&self, fake: bool) -> f64 {
        match &self.budget {
            Some(b) if fake => f64::from_bits(b.fake.load(Ordering::SeqCst)),
            Some(b) => b.start.elapsed().as_secs_f64(),
            None => 0.0,
        }
    }

    /// Advance the test hook's clock by `seconds`.
    pub(crate) fn spend_fake(&self, seconds: f64) {
        if let Some(b) = &self.budget {
            let now = f64::from_bits(b.fake.load(Ordering::SeqCst));
            b.fake.store((now + seconds).to_bits(), Ordering::SeqCst);
        }
    }

    /// The flag that stops the run when set (as [`Control::interrupt`]).
    pub fn interrupt_flag(&self) -> Arc<AtomicBool> {
        self.interrupt.clone()
    }

    /// Ask the run to stop at the next point where it can write a checkpoint (as Ctrl-C).
    pub fn interrupt(&self) {
        self.stop(Stop::Interrupt);
    }

    /// Ask the run to stop at the next point where it can write a checkpoint, for `cause`
    /// (the first cause given is kept).
    pub fn stop(&self, cause: Stop) {
        let _ = self
            .cause
            .compare_exchange(0, cause.code(), Ordering::SeqCst, Ordering::SeqCst);
        self.interrupt.store(true, Ordering::SeqCst);
    }

    /// Why the run was asked to stop, if it was (a flag set from outside counts as
    /// [`Stop::Interrupt`]).
    pub fn stop_cause(&self) -> Option<Stop> {
        if !self.interrupted() {
            return None;
        }
        Some(Stop::from_code(self.cause.load(Ordering::SeqCst)).unwrap_or(Stop::Interrupt))
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
