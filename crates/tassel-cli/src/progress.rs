//! A progress bar on standard error, drawn only when standard error is a terminal (a
//! pipe, a file or CI's log gets nothing).

use std::io::{IsTerminal, Write};

/// One bar; redrawn when the shown percentage changes.
pub struct Progress {
    enabled: bool,
    label: String,
    shown: Option<usize>,
}

impl Progress {
    pub fn new(label: &str) -> Self {
        Self {
            enabled: std::io::stderr().is_terminal(),
            label: label.to_string(),
            shown: None,
        }
    }

    pub fn update(&mut self, done: usize, total: usize) {
        if !self.enabled || total == 0 {
            return;
        }
        let pct = done * 100 / total;
        if self.shown == Some(pct) {
            return;
        }
        self.shown = Some(pct);
        let width = 30;
        let filled = done * width / total;
        let mut err = std::io::stderr();
        let _ = write!(
            err,
            "\r{} [{}{}] {pct:3}%",
            self.label,
            "#".repeat(filled),
            " ".repeat(width - filled)
        );
        let _ = err.flush();
    }

    pub fn finish(&mut self) {
        if self.enabled && self.shown.is_some() {
            let _ = writeln!(std::io::stderr());
        }
    }
}
