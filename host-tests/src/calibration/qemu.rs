//! `calibrate --on qemu`: the replay file through the firmware in QEMU (mps2-an386, Cortex-M4F).
//!
//! The firmware ELF is `target/thumbv7em-none-eabihf/firmware/sinscal-replay` of this workspace (built on
//! first use with cargo), or the file named by `SINSCAL_FIRMWARE`. QEMU runs it with semihosting: the
//! firmware reads the replay file and writes its outcome file; its defmt log goes to QEMU's stdout and is
//! decoded with `defmt-print` when that is installed (scripts/setup installs it).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use sinscal::instrument::wire::outcome::Outcome;
use sinscal::rig::replay::read_header;

use crate::calibration::firmware_path::{calibration_from_outcome, write_replay_file, ReadSource};
use crate::calibration::{Calibration, Options};
use crate::io::error::InputError;
use crate::io::recording::RowSource;
use crate::io::ScratchFile;

/// QEMU command and machine.
pub const QEMU: &str = "qemu-system-arm";

/// The workspace root (where `cargo build` of the firmware runs).
fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// The replay firmware ELF, built if needed.
pub fn firmware_elf() -> Result<PathBuf, String> {
    if let Some(p) = std::env::var_os("SINSCAL_FIRMWARE") {
        return Ok(PathBuf::from(p));
    }
    firmware_binary("sinscal-replay")
}

/// A firmware binary of this workspace (`sinscal-replay`, `sinscal-selftest`, `sinscal-bench`), built
/// (all of them, with the firmware profile) if needed.
pub fn firmware_binary(name: &str) -> Result<PathBuf, String> {
    let root = workspace_root();
    let elf = root.join("target/thumbv7em-none-eabihf/firmware").join(name);
    let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .current_dir(&root)
        .args(["build", "-q", "-p", "sinscal", "--profile", "firmware", "--target", "thumbv7em-none-eabihf", "--bins"])
        .args(["--features", "mps2-an386"])
        .stdout(Stdio::null())
        .status()
        .map_err(|e| format!("cannot run cargo to build the firmware: {e}"))?;
    if !status.success() || !elf.exists() {
        return Err(
            "building the firmware failed (is the thumbv7em-none-eabihf target installed? run scripts/setup)".into()
        );
    }
    Ok(elf)
}

/// Runs the firmware on a replay file in QEMU; returns the outcome bytes and the decoded defmt log (if
/// defmt-print is available).
pub fn run_firmware(elf: &Path, replay: &[u8]) -> Result<(Vec<u8>, String), String> {
    let input = ScratchFile::new("in.ssrp");
    std::fs::write(input.path(), replay).map_err(|e| format!("{}: {e}", input.path().display()))?;
    run_firmware_on(elf, input.path())
}

/// [`run_firmware`] on a replay file on disk.
pub fn run_firmware_on(elf: &Path, input: &Path) -> Result<(Vec<u8>, String), String> {
    let output = ScratchFile::new("out.ssro");
    let semihosting =
        format!("enable=on,target=native,arg=sinscal-replay,arg={},arg={}", input.display(), output.path().display());
    let run = Command::new(QEMU)
        .args(["-cpu", "cortex-m4", "-machine", "mps2-an386", "-nographic", "-monitor", "none", "-serial", "none"])
        .args(["-semihosting-config", &semihosting, "-kernel"])
        .arg(elf)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run {QEMU} ({e}): install it with scripts/setup"))?;
    let log = decode_defmt(elf, &run.stdout);
    let result = std::fs::read(output.path());
    if !run.status.success() {
        return Err(format!("the firmware exited with {} in QEMU: {}", run.status, log.trim()));
    }
    let bytes = result.map_err(|e| format!("the firmware wrote no outcome ({e}); log: {}", log.trim()))?;
    Ok((bytes, log))
}

/// Runs a firmware binary that takes one output-file argument (self-test, benchmark) and returns its exit
/// code and the text it wrote. `icount` runs QEMU with `-icount shift=0` (instruction counting). The
/// self-test's flash image, the output file's name plus `.flash`, is removed if the firmware left it.
pub fn run_with_output(elf: &Path, icount: bool) -> Result<(i32, String), String> {
    let out = ScratchFile::new("fw.txt");
    let semihosting = format!("enable=on,target=native,arg=fw,arg={}", out.path().display());
    let mut cmd = Command::new(QEMU);
    cmd.args(["-cpu", "cortex-m4", "-machine", "mps2-an386", "-nographic", "-monitor", "none", "-serial", "none"]);
    if icount {
        cmd.args(["-icount", "shift=0"]);
    }
    let run = cmd
        .args(["-semihosting-config", &semihosting, "-kernel"])
        .arg(elf)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run {QEMU} ({e}): install it with scripts/setup"))?;
    let text = std::fs::read_to_string(out.path()).unwrap_or_default();
    let mut flash_image = out.path().as_os_str().to_owned();
    flash_image.push(".flash");
    let _ = std::fs::remove_file(flash_image);
    Ok((run.status.code().unwrap_or(-1), text))
}

/// Decodes defmt frames with defmt-print, if installed; otherwise says how many bytes there were.
fn decode_defmt(elf: &Path, frames: &[u8]) -> String {
    use std::io::Write as _;
    let child = Command::new("defmt-print")
        .args(["-e"])
        .arg(elf)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn();
    let Ok(mut child) = child else {
        return format!("({} bytes of defmt log; install defmt-print to read them)", frames.len());
    };
    if let Some(mut stdin) = child.stdin.take() {
        let _ = stdin.write_all(frames);
    }
    match child.wait_with_output() {
        Ok(out) => String::from_utf8_lossy(&out.stdout).into_owned(),
        Err(_) => String::new(),
    }
}

/// `calibrate --on qemu`: the replay file is written to a scratch file, which the firmware reads.
pub fn calibrate_on_qemu(rec: &impl RowSource, options: &Options) -> Result<Calibration, InputError> {
    let source = rec.source();
    let replay = ScratchFile::new("replay.ssrp");
    let plan = write_replay_file(rec, options, &replay)?;
    let elf = firmware_elf().map_err(|e| InputError::file(source, format!("--on qemu: {e}")))?;
    let (bytes, log) =
        run_firmware_on(&elf, replay.path()).map_err(|e| InputError::file(source, format!("--on qemu: {e}")))?;
    if std::env::var_os("SINSCAL_FIRMWARE_LOG").is_some() {
        eprint!("{log}");
    }
    let fail = |e: String| InputError::file(source, format!("replay: {e}"));
    let file = std::fs::File::open(replay.path()).map_err(|e| fail(e.to_string()))?;
    let header = read_header(&mut ReadSource(std::io::BufReader::new(file))).map_err(|e| fail(e.to_string()))?;
    let outcome = Outcome::decode(&header.configuration, &bytes)
        .map_err(|e| InputError::file(source, format!("--on qemu: outcome: {e}")))?;
    let mut cal = calibration_from_outcome(rec, options, &plan, &outcome)?;
    cal.on = "qemu";
    Ok(cal)
}
