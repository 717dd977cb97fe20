//! Progress bars for the library's long stages (indicatif), and Ctrl-C as
//! cancellation: the first interrupt asks the running stage to stop at its
//! next safe point (so no half-written output is left), a second one quits
//! at once.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

use indicatif::{ProgressBar, ProgressStyle};
use organtex::progress::Progress;

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Route Ctrl-C to [`Bars::cancelled`]. Call once, at start-up.
pub fn catch_interrupts() {
    // Failing to install the handler only loses graceful cancellation.
    let _ = ctrlc::set_handler(|| {
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!("\ninterrupted: stopping at the next safe point (Ctrl-C again to quit now)");
    });
}

/// One bar per stage; a new stage finishes the previous bar. Hidden when
/// stderr is not a terminal (indicatif's default), so logs stay clean.
pub struct Bars {
    current: Mutex<Option<ProgressBar>>,
}

// The lock is poisoned only if a thread panicked while holding it, and no
// code below can panic while it is held; so `expect("progress lock")`
// cannot fire.
impl Bars {
    pub fn new() -> Self {
        Bars {
            current: Mutex::new(None),
        }
    }

    pub fn finish(&self) {
        if let Some(bar) = self.current.lock().expect("progress lock").take() {
            bar.finish();
        }
    }
}

impl Progress for Bars {
    fn stage(&self, name: &str, total: u64) {
        let mut current = self.current.lock().expect("progress lock");
        if let Some(bar) = current.take() {
            bar.finish();
        }
        let bar = ProgressBar::new(total);
        bar.set_style(
            // A constant template: it parses, or every run would fail.
            ProgressStyle::with_template("{msg:>12} [{bar:30}] {pos}/{len} {elapsed}")
                .expect("valid template")
                .progress_chars("=> "),
        );
        bar.set_message(name.to_string());
        *current = Some(bar);
    }

    fn advance(&self, n: u64) {
        if let Some(bar) = self.current.lock().expect("progress lock").as_ref() {
            bar.inc(n);
        }
    }

    fn cancelled(&self) -> bool {
        INTERRUPTED.load(Ordering::Relaxed)
    }
}
