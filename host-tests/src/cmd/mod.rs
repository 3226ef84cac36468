//! One module per subcommand of `sinscal`: its arguments (`Args`, clap), its `run`, and its human summary.
//! Every subcommand prints a summary to stdout and, with `--json FILE`, writes its machine-readable result
//! (`-` = stdout). The command line is described in docs/cli.md.

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
pub mod noise;
pub mod simulate;
pub mod study;

pub use crate::io::{out, StdoutError};

/// A result was written but failed some of its checks (docs/cli.md#checks): `main` prints each line on
/// stderr (`sinscal: check failed: fit: ...`) and exits with status 3.
#[derive(Debug)]
pub struct ChecksFailed(pub Vec<String>);

impl std::fmt::Display for ChecksFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0.join("; "))
    }
}

impl std::error::Error for ChecksFailed {}

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
