//! Progress reporting and cancellation for long stages. The library calls
//! these hooks; the CLI shows bars, the viewer shows its own bar and sets
//! the cancel flag. Implementations must be cheap: stages call `advance`
//! from worker threads.

use crate::error::{Error, Result};

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
