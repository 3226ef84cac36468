//! One module per subcommand of `sinscal`: its arguments (`Args`, clap), its `run`, and its human summary.
//! Every subcommand prints a summary to stdout and, with `--json FILE`, writes its machine-readable result
//! (`-` = stdout). The command line is described in docs/cli.md.

use std::io::Write as _;
use std::path::Path;

use anyhow::Context as _;

pub mod align;
pub mod analyze;
pub mod apply;
pub mod calibrate;
pub mod demo;
pub mod device;
pub mod example;
pub mod import;
pub mod montecarlo;
pub mod navigate;
pub mod simulate;
pub mod study;

/// Standard output could not be written: the reader closed it (a broken pipe: `sinscal ... | head`), or
/// it failed (a full disk, `/dev/full`). `main` ends quietly with status 0 on a broken pipe (the reader
/// wanted no more) and with the error and status 1 otherwise; nothing panics.
#[derive(Debug)]
pub struct StdoutError(pub std::io::Error);

impl std::fmt::Display for StdoutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "writing to standard output: {}", self.0)
    }
}

impl std::error::Error for StdoutError {}

/// Writes `text` to standard output (and flushes it), with a [`StdoutError`] when that fails.
pub fn out(text: &str) -> anyhow::Result<()> {
    let mut stdout = std::io::stdout().lock();
    stdout.write_all(text.as_bytes()).and_then(|()| stdout.flush()).map_err(|e| StdoutError(e).into())
}

/// Writes `text` to `path`, or to stdout when `path` is `-`.
pub fn write_output(path: &Path, text: &str) -> anyhow::Result<()> {
    if path == Path::new("-") {
        return out(text);
    }
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

/// Writes `value` as pretty JSON with a final newline to `path` (`-` = stdout).
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> anyhow::Result<()> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    write_output(path, &text)
}

/// Whether the JSON goes to stdout (then the human summary is not printed).
pub fn json_to_stdout(json: Option<&Path>) -> bool {
    json == Some(Path::new("-"))
}
