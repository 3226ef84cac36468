//! `sinscal device`: the calibration firmware as an instrument, driven over its serial link. [`client`] is the
//! link; this module boots the firmware in QEMU with its flash in a host file, runs a calibration on a recording
//! (configure, replay through the emulated IMU, result, store) and reads the stored record back.

pub mod client;

use std::io::{Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use sinscal::instrument::message::{kind, DeviceState};
use sinscal::instrument::wire::configuration::{DeviceConfiguration, Thresholds};
use sinscal::instrument::wire::outcome::Outcome;
use sinscal::instrument::wire::record::{RecordHead, RECORD_HEAD_BYTES};
use sinscal::rig::replay::{read_header, ReplayHeader};

use crate::calibration::firmware_path::{calibration_from_outcome, write_replay_file, ReplayPlan};
use crate::calibration::qemu::{firmware_binary, QEMU};
use crate::calibration::{Calibration, Options, RecordIdentity};
use crate::io::error::InputError;
use crate::io::recording::{Header, Recording, RowSource};
use crate::io::ScratchFile;
use client::{Client, LinkError, Stored};
use sinscal::instrument::message::MAX_NOTE_BYTES;
use sinscal::instrument::wire::record::max_record_bytes;

pub use note::Provenance;

mod note;

/// The firmware QEMU boots for `device`: the instrument with the emulated IMU.
pub const DEVICE_FIRMWARE: &str = "sinscal-device";

/// A device firmware running in QEMU, with its link on a Unix socket; killed when dropped.
pub struct QemuDevice {
    child: Child,
    _socket_dir: ScratchFile,
    /// The link.
    pub client: Client<UnixStream>,
}

impl Drop for QemuDevice {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Boots the device firmware in QEMU (mps2-an386): its flash is the host file `flash`, its IMU replays the
/// frames of `replay` (none: the IMU delivers nothing), its UART0 is the link.
pub fn boot_qemu(flash: &Path, replay: Option<&Path>) -> Result<QemuDevice, String> {
    // The firmware opens the image itself: what it cannot open would read as an empty flash.
    if let Some(m) = std::fs::metadata(flash).ok().filter(|m| !m.is_file()) {
        let what = if m.is_dir() { "a directory" } else { "not a regular file" };
        return Err(format!("--flash {}: {what}, not a flash image file (created if missing)", flash.display()));
    }
    let elf = match std::env::var_os("SINSCAL_DEVICE_FIRMWARE") {
        Some(p) => PathBuf::from(p),
        None => firmware_binary(DEVICE_FIRMWARE)?,
    };
    boot_elf(&elf, flash, replay)
}

/// Boots a firmware ELF of this workspace's instrument (`sinscal-device`, or `sinscal-firmware`, which takes
/// no replay and whose IMU is the board's SPI port) in QEMU with its flash file and UART0 on a Unix socket.
pub fn boot_elf(elf: &Path, flash: &Path, replay: Option<&Path>) -> Result<QemuDevice, String> {
    let semihosting = format!(
        "enable=on,target=native,arg={DEVICE_FIRMWARE},arg={},arg={}",
        flash.display(),
        replay.map_or_else(|| "-".to_string(), |p| p.display().to_string())
    );
    boot_machine(&["-cpu", "cortex-m4", "-machine", "mps2-an386", "-semihosting-config", &semihosting], elf)
}

/// Boots the STM32F405 board's firmware (`boards/stm32f405`, built with its feature `qemu-netduinoplus2`) in
/// QEMU's model of that MCU, with USART1, its link, on a Unix socket. QEMU models no EXTI edge, no flash
/// programming and no IWDG there: the link, the main loop and the record's read path are what run.
pub fn boot_stm32f405(elf: &Path) -> Result<QemuDevice, String> {
    boot_machine(&["-machine", "netduinoplus2"], elf)
}

/// A listener on the Unix socket `path`. A socket file already there is stale: the path's directory is this
/// process's own (its id and a counter in the name), so what is there was left by a process that ended
/// without removing it; it is removed first (binding over it fails with "Address already in use").
fn bind_fresh(path: &Path) -> Result<UnixListener, String> {
    use std::os::unix::fs::FileTypeExt;
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_socket()) {
        std::fs::remove_file(path).map_err(|e| format!("{}: a stale socket cannot be removed: {e}", path.display()))?;
    }
    UnixListener::bind(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// Boots `elf` in QEMU with `machine_args`, its first serial port on a Unix socket, and connects the link.
fn boot_machine(machine_args: &[&str], elf: &Path) -> Result<QemuDevice, String> {
    let dir = ScratchFile::new("link");
    std::fs::create_dir_all(dir.path()).map_err(|e| format!("{}: {e}", dir.path().display()))?;
    let socket = dir.path().join("uart0");
    let listener = bind_fresh(&socket)?;
    let mut child = Command::new(QEMU)
        .args(machine_args)
        .args(["-nographic", "-monitor", "none"])
        .args(["-serial", &format!("unix:{}", socket.display())])
        .arg("-kernel")
        .arg(elf)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot run {QEMU} ({e}): install it with scripts/setup"))?;
    listener.set_nonblocking(true).map_err(|e| e.to_string())?;
    let deadline = Instant::now() + Duration::from_secs(20);
    let stream = loop {
        match listener.accept() {
            Ok((s, _)) => break s,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock && Instant::now() < deadline => {
                if let Ok(Some(status)) = child.try_wait() {
                    let mut err = String::new();
                    if let Some(mut e) = child.stderr.take() {
                        let _ = e.read_to_string(&mut err);
                    }
                    return Err(format!("QEMU exited ({status}) before connecting its serial port: {}", err.trim()));
                }
                std::thread::sleep(Duration::from_millis(10));
            }
            Err(e) => {
                let _ = child.kill();
                return Err(format!("QEMU did not connect its serial port: {e}"));
            }
        }
    };
    stream.set_nonblocking(false).map_err(|e| e.to_string())?;
    stream.set_read_timeout(Some(Duration::from_millis(100))).map_err(|e| e.to_string())?;
    Ok(QemuDevice { child, _socket_dir: dir, client: Client::new(stream) })
}

/// The configure message's body for a replay file's header (its bytes): the header's configuration with the
/// thresholds of a replayed sequence ([`Thresholds::REPLAY`]: no settling, dwells as long as the table says,
/// the core's fewest samples), which make a device's result equal to the host replay's.
pub fn configuration_body(replay_header: &[u8]) -> Result<Vec<u8>, String> {
    let header = read_header(&mut &replay_header[..]).map_err(|e| e.to_string())?;
    Ok(device_configuration_body(&header, Thresholds::REPLAY))
}

/// The configure message's body: a replay header's configuration with `thresholds`.
pub fn device_configuration_body(header: &ReplayHeader, thresholds: Thresholds) -> Vec<u8> {
    let configured = DeviceConfiguration { configuration: header.configuration.clone(), thresholds };
    let mut body = vec![0u8; sinscal::instrument::wire::configuration::MAX_DEVICE_BYTES];
    let mut w = sinscal::instrument::wire::Writer::new(&mut body);
    configured.encode(&mut w);
    // The buffer holds the longest configuration.
    let n = w.written().unwrap_or(0);
    body.truncate(n);
    body
}

/// What `device run` did.
pub struct DeviceRun {
    /// The calibration, from the device's result.
    pub calibration: Calibration,
    /// The store.
    pub stored: Stored,
    /// The status at the end.
    pub status: client::Status,
}

/// `device run` on a device reached through `client`: configure from the recording (with `thresholds`, or the
/// replay's), start, wait (with progress on stderr), read the result, store it, and check the stored record
/// against the result.
pub fn run_calibration<T: Read + Write>(
    client: &mut Client<T>,
    rec: &impl RowSource,
    options: &Options,
    replay: &ScratchFile,
    plan: &ReplayPlan,
    thresholds: Option<Thresholds>,
    mut progress: impl FnMut(&client::Status),
) -> Result<DeviceRun, anyhow::Error> {
    let source = rec.source();
    let header = replay_header(replay.path())?;
    let identity = client.identify()?;
    let body = device_configuration_body(&header, thresholds.unwrap_or(Thresholds::REPLAY));
    let provenance = Provenance::of(rec, options, plan);
    let note = provenance.to_bytes();
    if note.len() > MAX_NOTE_BYTES {
        return Err(LinkError::NoteTooLong { len: note.len(), max: MAX_NOTE_BYTES }.into());
    }
    let c = &header.configuration;
    let len = max_record_bytes(body.len(), note.len(), c.schedule.len(), c.estimator);
    if len > identity.max_record_bytes as usize {
        let (max, positions) = (identity.max_record_bytes as usize, c.schedule.len());
        return Err(LinkError::RecordTooLarge { len, max, positions, note: note.len() }.into());
    }
    client.configure(&body)?;
    client.annotate(&note)?;
    client.request("start", kind::START, &[])?;
    let status = loop {
        let status = client.status()?;
        progress(&status);
        if matches!(status.state, DeviceState::Solved | DeviceState::Failed) {
            break status;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let result = client.read_all("the result", kind::READ_RESULT)?;
    let outcome = Outcome::decode(&header.configuration, &result)
        .map_err(|e| InputError::file(source, format!("result: {e}")))?;
    let mut calibration = calibration_from_outcome(rec, options, plan, &outcome)?;
    calibration.on = "device";
    let stored = client.store()?;
    calibration.record = Some(RecordIdentity {
        sequence: stored.sequence,
        run_started_utc: provenance.run_started_utc,
        damaged_newer: None,
    });
    let record = client.read_all("the record", kind::READ_RECORD)?;
    let parts = split_record(&record)?;
    if parts.outcome != result || parts.note != note {
        anyhow::bail!("the record read back from the device differs from the result it stored");
    }
    Ok(DeviceRun { calibration, stored, status })
}

/// The replay file's header, read from the file's start.
fn replay_header(path: &Path) -> Result<ReplayHeader, anyhow::Error> {
    let longest = sinscal::rig::replay::replay_header_bytes(sinscal::calib::angles::MAX_POSITIONS);
    let mut bytes = Vec::with_capacity(longest);
    std::fs::File::open(path)?.take(longest as u64).read_to_end(&mut bytes)?;
    read_header(&mut bytes.as_slice()).map_err(|e| anyhow::anyhow!("replay: {e}"))
}

/// The parts of a stored record.
pub struct RecordParts<'a> {
    /// The compensation's bytes.
    pub compensation: &'a [u8],
    /// The configuration body.
    pub configuration: &'a [u8],
    /// The provenance note.
    pub note: &'a [u8],
    /// The outcome.
    pub outcome: &'a [u8],
}

/// Splits a record into its parts.
pub fn split_record(record: &[u8]) -> Result<RecordParts<'_>, anyhow::Error> {
    let head = RecordHead::decode(record).ok_or_else(|| anyhow::anyhow!("record of an unknown version"))?;
    if head.record_bytes() != record.len() || record.len() < RECORD_HEAD_BYTES {
        anyhow::bail!("record of {} bytes, its head says {}", record.len(), head.record_bytes());
    }
    let [c, k, n, o] = head.parts().map(|(at, len)| &record[at..at + len]);
    Ok(RecordParts { compensation: c, configuration: k, note: n, outcome: o })
}

/// The calibration of a stored record (the same report as the run that stored it).
pub fn calibration_of_record(read: &DeviceRecord, damaged_newer: Option<u32>) -> Result<Calibration, anyhow::Error> {
    let parts = split_record(&read.bytes)?;
    let configured =
        DeviceConfiguration::decode(parts.configuration).map_err(|e| anyhow::anyhow!("stored configuration: {e}"))?;
    let note = Provenance::from_bytes(parts.note)?;
    let outcome = Outcome::decode(&configured.configuration, parts.outcome)
        .map_err(|e| anyhow::anyhow!("stored outcome: {e}"))?;
    let rec = Recording {
        source: note.source.clone(),
        header: Header {
            latitude_deg: note.latitude_deg,
            height_m: note.height_m,
            rate_hz: None,
            gravity_mps2: note.gravity_mps2,
            comments: Vec::new(),
            truth: None,
            pose_tolerance_deg: None,
        },
        rows: Vec::new(),
        has_gyro: note.has_gyro,
    };
    let mut options = note.options()?;
    // The noise model the device weighted by, and where the workstation had it from.
    options.noise = configured.configuration.noise.map(|m| crate::io::noise_file::NoiseTerms {
        channels: core::array::from_fn(|i| (note.has_gyro || i >= 3).then_some(m.channels[i])),
        from_recording: note.options.noise_from_recording,
    });
    let mut calibration = calibration_from_outcome(&rec, &options, &note.plan, &outcome)?;
    calibration.on = "device";
    calibration.record =
        Some(RecordIdentity { sequence: read.sequence, run_started_utc: note.run_started_utc, damaged_newer });
    Ok(calibration)
}

/// Writes the replay file of a recording for `device run`.
pub fn replay_for(rec: &impl RowSource, options: &Options) -> Result<(ScratchFile, ReplayPlan), InputError> {
    let replay = ScratchFile::new("device.ssrp");
    let plan = write_replay_file(rec, options, &replay)?;
    Ok((replay, plan))
}

/// Reads the stored record of a device (the one it uses, with its sequence number from the status) and whether a
/// damaged newer record was passed over.
pub fn read_record<T: Read + Write>(client: &mut Client<T>) -> Result<RecordRead, LinkError> {
    client.identify()?;
    let status = client.status()?;
    let record = match client.read_all("the record", kind::READ_RECORD) {
        Ok(bytes) => Some(DeviceRecord { bytes, sequence: status.stored.unwrap_or(0) }),
        Err(LinkError::Refused { code: sinscal::instrument::message::ErrorCode::NothingStored, .. }) => None,
        Err(e) => return Err(e),
    };
    Ok(RecordRead { record, damaged_newer: status.damaged_newer })
}

/// A record read from a device: its bytes and its sequence number.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceRecord {
    /// The record's bytes.
    pub bytes: Vec<u8>,
    /// Its sequence number in the device's store.
    pub sequence: u32,
}

/// What [`read_record`] found: the newest valid record (`None`: none is stored), and the sequence number of a
/// damaged record newer than it, which the device passed over.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordRead {
    /// The record the device uses.
    pub record: Option<DeviceRecord>,
    /// A damaged newer record's sequence number.
    pub damaged_newer: Option<u32>,
}

#[cfg(test)]
mod tests {
    use super::bind_fresh;
    use crate::io::ScratchFile;

    /// A socket left by a listener that is gone (a process that was killed) does not stop the next bind; the
    /// scratch directory that held it is removed with what it holds.
    #[test]
    fn a_stale_socket_is_bound_over_and_its_directory_removed() {
        let dir = ScratchFile::new("link-test");
        std::fs::create_dir_all(dir.path()).unwrap();
        let socket = dir.path().join("uart0");
        drop(std::os::unix::net::UnixListener::bind(&socket).unwrap());
        assert!(socket.exists(), "the socket file outlives its listener");
        let err = std::os::unix::net::UnixListener::bind(&socket).unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::AddrInUse, "{err}");
        bind_fresh(&socket).expect("the stale socket is removed and bound again");
        let path = dir.path().to_path_buf();
        drop(dir);
        assert!(!path.exists(), "{} is left behind", path.display());
    }
}
