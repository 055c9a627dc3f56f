//! Progress on standard error for host jobs that may take long (loading and rendering large
//! scenes): nothing is shown for jobs that finish within a second.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// How long a job runs before its progress is shown.
pub const SHOW_AFTER: Duration = Duration::from_secs(1);

/// A progress bar (with a length) or spinner (without) that appears after [`SHOW_AFTER`].
pub struct Progress {
    bar: ProgressBar,
    done: Arc<AtomicBool>,
}

impl Progress {
    /// Starts tracking a job of `len` units (bytes, passes), or of unknown length.
    pub fn start(message: &str, len: Option<u64>) -> Progress {
        let bar = match len {
            Some(n) => ProgressBar::with_draw_target(Some(n), ProgressDrawTarget::hidden())
                .with_style(
                    ProgressStyle::with_template("{msg} [{bar:30}] {percent:>3} % ({elapsed})")
                        .unwrap_or_else(|_| ProgressStyle::default_bar()),
                ),
            None => ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden()),
        };
        bar.set_message(message.to_string());
        let done = Arc::new(AtomicBool::new(false));
        let (b, d) = (bar.clone(), done.clone());
        std::thread::spawn(move || {
            let start = std::time::Instant::now();
            while start.elapsed() < SHOW_AFTER {
                if d.load(Ordering::Relaxed) {
                    return;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
            if !d.load(Ordering::Relaxed) {
                b.set_draw_target(ProgressDrawTarget::stderr());
                b.enable_steady_tick(Duration::from_millis(200));
            }
        });
        Progress { bar, done }
    }

    /// Sets how much is done.
    pub fn set(&self, position: u64) {
        self.bar.set_position(position);
    }

    /// Ends the job and clears its line.
    pub fn finish(self) {
        self.done.store(true, Ordering::Relaxed);
        self.bar.finish_and_clear();
    }
}
