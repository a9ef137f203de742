//! Diagnostics: `file:line:col: severity: message`, the source line and a caret.

use crate::ast::Pos;
use std::fmt;

/// How serious a [`Diagnostic`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    /// The file cannot be used.
    Error,
    /// Accepted, but worth knowing (e.g. a CR line end).
    Warning,
}

/// One located message.
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnostic {
    /// Error or warning.
    pub severity: Severity,
    /// Where in the file.
    pub pos: Pos,
    /// The text, in the reference interpreter's wording where it has one.
    pub message: String,
}

/// All messages for one file. `file`, `message` and `pos` repeat the first
/// error (the one the reference interpreter would report) for callers that
/// need only that.
#[derive(Clone, Debug, Default)]
pub struct Diagnostics {
    /// File name, as given by the caller.
    pub file: String,
    /// Message of the first error (empty when there is none).
    pub message: String,
    /// Position of the first error (`0:0` when there is none).
    pub pos: Pos,
    /// Errors and warnings in source order.
    pub items: Vec<Diagnostic>,
}

impl Diagnostics {
    pub(crate) fn new(file: &str, mut items: Vec<Diagnostic>) -> Self {
        items.sort_by_key(|d| d.pos);
        let first = items.iter().find(|d| d.severity == Severity::Error);
        let (message, pos) = first.map_or_else(Default::default, |d| (d.message.clone(), d.pos));
        Diagnostics {
            file: file.to_string(),
            message,
            pos,
            items,
        }
    }

    /// The errors, in source order.
    pub fn errors(&self) -> impl Iterator<Item = &Diagnostic> {
        self.items.iter().filter(|d| d.severity == Severity::Error)
    }

    /// Whether any item is an error.
    pub fn has_errors(&self) -> bool {
        self.errors().next().is_some()
    }

    /// Every message with its source line and a caret under the column.
    pub fn render(&self, src: &str) -> String {
        let mut out = String::new();
        for d in &self.items {
            let kind = match d.severity {
                Severity::Error => "error",
                Severity::Warning => "warning",
            };
            let (line, col) = (d.pos.line, d.pos.col);
            // Lines split at LF only, as the scanner counts them; CR is shown
            // as nothing, a byte-order mark is skipped as the scanner does.
            let src = src.strip_prefix('\u{feff}').unwrap_or(src);
            let text = src
                .split('\n')
                .nth(line.saturating_sub(1) as usize)
                .unwrap_or("");
            let text = text.replace('\r', "");
            let (text, col_in_text) = excerpt(&text, col.saturating_sub(1) as usize);
            let pad: String = text
                .chars()
                .take(col_in_text)
                .map(|c| if c == '\t' { '\t' } else { ' ' })
                .collect();
            out += &format!(
                "{}:{line}:{col}: {kind}: {}\n  {text}\n  {pad}^\n",
                self.file, d.message
            );
        }
        out
    }
}

/// Characters of context shown on each side of the caret.
const CONTEXT: usize = 80;

/// The part of a long line around character `col` (0-based): at most
/// [`CONTEXT`] characters each side, with `...` where text was cut, and the
/// caret's position in the excerpt. A generated model can be one line of
/// megabytes.
fn excerpt(line: &str, col: usize) -> (String, usize) {
    let n = line.chars().count();
    if n <= 2 * CONTEXT + 1 {
        return (line.to_string(), col);
    }
    let from = col.saturating_sub(CONTEXT);
    let to = (col + CONTEXT + 1).min(n);
    let mut text: String = line.chars().skip(from).take(to - from).collect();
    let mut caret = col - from;
    if from > 0 {
        text.insert_str(0, "...");
        caret += 3;
    }
    if to < n {
        text.push_str("...");
    }
    (text, caret)
}

impl fmt::Display for Diagnostics {
    /// The first error as `file:line:col: message`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}:{}: {}",
            self.file, self.pos.line, self.pos.col, self.message
        )?;
        let more = self.errors().count().saturating_sub(1);
        if more > 0 {
            write!(f, " (and {more} more errors)")?;
        }
        Ok(())
    }
}

impl std::error::Error for Diagnostics {}
