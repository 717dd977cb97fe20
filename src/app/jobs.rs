//! Work the viewer runs off the UI thread (unwrapping, building tissue
//! textures, synthesising the interior block): a thread, its progress
//! (the library's `Progress` hooks, read by the progress bar) and a cancel
//! flag. Frames keep coming while a job runs.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use crate::error::Result;
use crate::progress::Progress;

#[derive(Default)]
pub struct Shared {
    stage: Mutex<String>,
    total: AtomicU64,
    done: AtomicU64,
    cancel: AtomicBool,
}

impl Progress for Shared {
    fn stage(&self, name: &str, total: u64) {
        *self.stage.lock().expect("not poisoned") = name.to_string();
        self.total.store(total, Ordering::Relaxed);
        self.done.store(0, Ordering::Relaxed);
    }
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }
    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
}

/// A job seen from the status bar, whatever it returns.
pub trait Running {
    /// "what: stage", and the fraction of the stage done (None: unknown).
    fn status(&self) -> (String, Option<f32>);
    fn cancel(&self);
}

impl<T> Running for Job<T> {
    fn status(&self) -> (String, Option<f32>) {
        let total = self.shared.total.load(Ordering::Relaxed);
        let done = self.shared.done.load(Ordering::Relaxed);
        let stage = self.shared.stage.lock().expect("not poisoned").clone();
        let what = if stage.is_empty() {
            self.what.clone()
        } else {
            format!("{}: {stage}", self.what)
        };
        (
            what,
            (total > 0).then(|| (done as f32 / total as f32).min(1.0)),
        )
    }

    fn cancel(&self) {
        self.shared.cancel.store(true, Ordering::Relaxed);
    }
}

pub struct Job<T> {
    /// What the job does, for the status bar.
    pub what: String,
    shared: Arc<Shared>,
    handle: Option<JoinHandle<Result<T>>>,
}

impl<T: Send + 'static> Job<T> {
    /// Run `work` on its own thread; `wake` is called when it ends (the
    /// viewer asks for a repaint).
    pub fn spawn(
        what: impl Into<String>,
        wake: impl Fn() + Send + 'static,
        work: impl FnOnce(&dyn Progress) -> Result<T> + Send + 'static,
    ) -> Job<T> {
        let shared = Arc::new(Shared::default());
        let s = shared.clone();
        let handle = std::thread::spawn(move || {
            let r = work(&*s);
            wake();
            r
        });
        Job {
            what: what.into(),
            shared,
            handle: Some(handle),
        }
    }

    /// The result, once the job has ended.
    pub fn poll(&mut self) -> Option<Result<T>> {
        if self.handle.as_ref().is_some_and(|h| h.is_finished()) {
            let r = self.handle.take().expect("checked").join();
            return Some(r.unwrap_or_else(|_| {
                Err(crate::error::Error::invalid(format!(
                    "{} failed unexpectedly",
                    self.what
                )))
            }));
        }
        None
    }
}
