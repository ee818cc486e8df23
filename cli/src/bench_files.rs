//! Files the benchmarks keep: sequences written once and reused until the
//! simulator that wrote them changes, and the marked sections of a results
//! page that `--update` rewrites.

use std::path::Path;

use crate::args::TableOutputs;
use crate::CliError;

/// The file in a cached sequence's folder that records what wrote it.
const FINGERPRINT_FILE: &str = "synth-fingerprint.txt";

/// Runs `write` into a fresh `<dir>.partial` and renames it to `dir`,
/// unless `dir` is complete and its fingerprint file says `print`.
pub(crate) fn ensure_written(
    dir: &Path,
    print: &str,
    write: impl FnOnce(&Path) -> Result<(), CliError>,
) -> Result<(), CliError> {
    let cached = std::fs::read_to_string(dir.join(FINGERPRINT_FILE)).ok();
    // The fingerprint is written last, and the folder renamed into place
    // only after it: a folder with it is complete.
    if dir.join("dlo.json").is_file() && cached.as_deref() == Some(print) {
        return Ok(());
    }
    if dir.exists() {
        eprintln!(
            "{} was written by another simulator: writing it again",
            dir.display()
        );
        std::fs::remove_dir_all(dir)
            .map_err(|e| CliError::input(format!("{}: {e}", dir.display())))?;
    }
    eprintln!("writing {} ...", dir.display());
    let partial = dir.with_extension("partial");
    if partial.exists() {
        std::fs::remove_dir_all(&partial)
            .map_err(|e| CliError::input(format!("{}: {e}", partial.display())))?;
    }
    write(&partial)?;
    std::fs::write(partial.join(FINGERPRINT_FILE), print)
        .map_err(|e| CliError::input(format!("{}: {e}", partial.display())))?;
    std::fs::rename(&partial, dir)
        .map_err(|e| CliError::input(format!("{}: {e}", dir.display())))?;
    Ok(())
}

/// Removes `dir`'s fingerprint (if any): what is written there next is no
/// benchmark's cache.
pub(crate) fn forget_written(dir: &Path) -> Result<(), CliError> {
    match std::fs::remove_file(dir.join(FINGERPRINT_FILE)) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(CliError::input(format!("{}: {e}", dir.display())))
        }
        _ => Ok(()),
    }
}

/// Prints a benchmark's table `text`, and writes `rows` where `--json`
/// says, `text` where `--markdown` says and between the lines `markers` of
/// the page `--update` names.
pub(crate) fn publish<T: serde::Serialize>(
    text: &str,
    rows: &T,
    outputs: &TableOutputs,
    update: Option<&Path>,
    (begin, end): (&str, &str),
) -> Result<(), CliError> {
    println!("{text}");
    if let Some(p) = &outputs.json {
        upetrack_io::write::write_json(p, rows)?;
    }
    if let Some(p) = &outputs.markdown {
        upetrack_io::write::write_file(p, text.as_bytes())?;
    }
    if let Some(p) = update {
        update_between(p, text, begin, end)?;
    }
    Ok(())
}

/// Replaces what lies between the lines `begin` and `end` of `page` with `text`.
pub(crate) fn update_between(
    page: &Path,
    text: &str,
    begin: &str,
    end: &str,
) -> Result<(), CliError> {
    let old = std::fs::read_to_string(page)
        .map_err(|e| CliError::input(format!("{}: {e}", page.display())))?;
    let (Some(a), Some(b)) = (old.find(begin), old.find(end)) else {
        return Err(CliError::input(format!(
            "{}: needs the lines {begin} and {end}",
            page.display()
        )));
    };
    if b < a {
        return Err(CliError::input(format!(
            "{}: {end} comes before {begin}",
            page.display()
        )));
    }
    let new = format!("{}{begin}\n{text}\n{}", &old[..a], &old[b..]);
    upetrack_io::write::write_file(page, new.as_bytes())?;
    Ok(())
}
