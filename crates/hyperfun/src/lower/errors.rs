//! The table behind the error output: code `k > 0` names entry `k - 1`.

use std::sync::{Arc, Mutex};

/// A run-time error as the reference reports it: message and the position of
/// the offending operator or call (the core's type, shared by every model source).
pub use microfrep_core::RuntimeError;

/// Shared, append-only table of error sites. The lowered graph fills it once;
/// the per-point fallback may add sites as it meets them.
#[derive(Clone, Debug, Default)]
pub struct ErrorTable(Arc<Mutex<Vec<RuntimeError>>>);

impl ErrorTable {
    /// The code (1-based) of an error site, adding it if new.
    pub fn code(&self, e: RuntimeError) -> f64 {
        let mut t = self.0.lock().unwrap_or_else(|p| p.into_inner());
        let i = match t.iter().position(|x| *x == e) {
            Some(i) => i,
            None => {
                t.push(e);
                t.len() - 1
            }
        };
        (i + 1) as f64
    }

    /// The error a code stands for; `None` for 0 (no error) or an unknown code.
    pub fn get(&self, code: f64) -> Option<RuntimeError> {
        // NaN and codes below 1 name no error.
        if code.is_nan() || code < 1.0 {
            return None;
        }
        let t = self.0.lock().unwrap_or_else(|p| p.into_inner());
        t.get(code.round() as usize - 1).cloned()
    }

    /// A copy of the sites known so far.
    pub fn snapshot(&self) -> Vec<RuntimeError> {
        self.0.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }
}

impl microfrep_core::ErrorSource for ErrorTable {
    fn decode(&self, code: f64) -> Option<RuntimeError> {
        self.get(code)
    }
}
