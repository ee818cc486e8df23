//! Progress bars on long work: drawn on standard error when it is a
//! terminal, nothing otherwise or with `--quiet`.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};

use indicatif::{ProgressBar, ProgressState, ProgressStyle};

/// Set once by `--quiet`.
static QUIET: AtomicBool = AtomicBool::new(false);

/// Stops every later bar from drawing (`--quiet`).
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// `true` when bars are drawn: standard error is a terminal and `--quiet` is off.
pub fn shown() -> bool {
    !QUIET.load(Ordering::Relaxed) && std::io::stderr().is_terminal()
}

/// How a bar reads: what is counted, with rate and time left.
const TEMPLATE: &str = "{msg} [{bar:30}] {pos}/{len} {unit} ({rate}/s, {eta} left)";

/// A bar of `len` `unit`s (frames, runs, scenes) labelled `label`; hidden
/// when bars are not [`shown`].
pub fn bar(len: u64, unit: &str, label: impl Into<String>) -> ProgressBar {
    if !shown() {
        return ProgressBar::hidden();
    }
    let style = ProgressStyle::with_template(&TEMPLATE.replace("{unit}", unit))
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .with_key(
            "rate",
            |state: &ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = write!(w, "{:.0}", state.per_sec());
            },
        )
        .progress_chars("=> ");
    ProgressBar::new(len)
        .with_style(style)
        .with_message(label.into())
}

/// Prints `line` on standard error above `bar` (or alone when it is hidden),
/// so that log lines and the bar do not overwrite each other.
pub fn say(bar: &ProgressBar, line: &str) {
    if bar.is_hidden() {
        eprintln!("{line}");
    } else {
        bar.suspend(|| eprintln!("{line}"));
    }
}
