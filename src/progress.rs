//! Progress reporting and cancellation for long stages. The library calls
//! these hooks; the CLI shows bars, the viewer shows its own bar and sets
//! the cancel flag. Implementations must be cheap: stages call `advance`
//! from worker threads. And where the time went: `Span`s, one per stage
//! and item, for a bake's profile.

use crate::error::{Error, Result};

/// `n` with its digits grouped in threes, as reports print counts:
/// 56172 -> "56,172".
pub fn thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

pub trait Progress: Sync {
    /// A stage begins; `total` steps are expected (0 when unknown).
    fn stage(&self, _name: &str, _total: u64) {}
    /// `n` more steps of the current stage are done.
    fn advance(&self, _n: u64) {}
    /// Whether the user asked to stop.
    fn cancelled(&self) -> bool {
        false
    }
}

/// Reports nothing and never cancels.
pub struct Silent;
impl Progress for Silent {}

/// `Err` when the user cancelled, for `?` at safe points.
pub fn check(progress: &dyn Progress) -> Result<()> {
    if progress.cancelled() {
        Err(Error::Cancelled)
    } else {
        Ok(())
    }
}

/// Forwards only cancellation: for work run many times in parallel, whose
/// own stages would fight over one bar.
pub struct CancelOnly<'a>(pub &'a dyn Progress);
impl Progress for CancelOnly<'_> {
    fn cancelled(&self) -> bool {
        self.0.cancelled()
    }
}

/// One of two jobs run side by side: forwards `inner` (only its
/// cancellation when `quiet`, so the two do not fight over one bar), and
/// is cancelled too once `failed` is set, which either job sets when it
/// fails, so the other stops at its next check rather than running on for
/// nothing (`bake` runs the interiors beside the surface).
pub struct Beside<'a> {
    pub inner: &'a dyn Progress,
    pub quiet: bool,
    pub failed: &'a std::sync::atomic::AtomicBool,
}
impl Progress for Beside<'_> {
    fn stage(&self, name: &str, total: u64) {
        if !self.quiet {
            self.inner.stage(name, total)
        }
    }
    fn advance(&self, n: u64) {
        if !self.quiet {
            self.inner.advance(n)
        }
    }
    fn cancelled(&self) -> bool {
        self.inner.cancelled() || self.failed.load(std::sync::atomic::Ordering::Relaxed)
    }
}

/// Both results of two jobs run side by side (`Beside`), or the error to
/// report: `first`'s, unless it only stopped because the other failed.
pub fn both<A, B>(first: Result<A>, second: Result<B>) -> Result<(A, B)> {
    match (first, second) {
        (Ok(a), Ok(b)) => Ok((a, b)),
        (Err(Error::Cancelled), Err(e)) => Err(e),
        (Err(e), _) | (_, Err(e)) => Err(e),
    }
}

/// The wall-clock time one stage took on one item (a node, a facet), for a
/// profile of where a long job's time goes.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Span {
    pub stage: String,
    /// What it worked on ("uterus", "uterus/wall"); empty for the whole job.
    pub item: String,
    pub seconds: f64,
    /// Run beside other spans of the same stage (their seconds add up to
    /// more than the stage's wall-clock time).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub parallel: bool,
}

/// `work`'s result, its time pushed onto `spans` as `stage` on `item`.
pub fn timed<T>(spans: &mut Vec<Span>, stage: &str, item: &str, work: impl FnOnce() -> T) -> T {
    let start = std::time::Instant::now();
    let out = work();
    spans.push(Span {
        stage: stage.into(),
        item: item.into(),
        seconds: start.elapsed().as_secs_f64(),
        parallel: false,
    });
    out
}
