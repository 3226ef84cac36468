//! `sinscal device run|show`: the calibration firmware as an instrument, over its serial link: in QEMU (the
//! firmware with the emulated IMU, its flash a host file) or on a board at a serial port.

use std::fs::{File, OpenOptions};
use std::io::{Read, Write};
use std::path::PathBuf;

use crate::calibration::Calibration;
use crate::cmd::calibrate::{finish, CalibrationArgs};
use crate::device::client::{Client, Status};
use crate::device::{
    boot_qemu, calibration_of_record, read_record, replay_for, run_calibration, DeviceRun, RecordRead,
};
use crate::io::recording::RecordingFile;

/// Arguments of `sinscal device`.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    action: Action,
}

#[derive(clap::Subcommand)]
enum Action {
    /// Configure the device from a recording, run the calibration (in QEMU: the recording replayed through the
    /// emulated IMU), read the result and store it in the device's flash.
    Run(RunArgs),
    /// Read the calibration record stored in the device back (exit 1 when nothing is stored).
    Show(ShowArgs),
}

/// Where the device is.
#[derive(clap::Args)]
#[group(required = true, multiple = true)]
struct Target {
    /// The firmware in QEMU (mps2-an386), its link on UART0; needs --flash.
    #[arg(long, requires = "flash", conflicts_with = "port")]
    qemu: bool,
    /// The emulated flash: a host file kept across runs (created if missing).
    #[arg(long, requires = "qemu")]
    flash: Option<PathBuf>,
    /// A board at this serial port (115200 baud, 8N1, configured with stty).
    #[arg(long)]
    port: Option<PathBuf>,
}

#[derive(clap::Args)]
struct RunArgs {
    /// The recording: its site, schedule and reference attitudes configure the device; in QEMU its rows are
    /// the IMU's samples.
    recording: PathBuf,
    #[command(flatten)]
    target: Target,
    /// Write the result as JSON to this file ('-' = stdout).
    #[arg(long)]
    json: Option<PathBuf>,
    #[command(flatten)]
    calibration: CalibrationArgs,
}

#[derive(clap::Args)]
struct ShowArgs {
    #[command(flatten)]
    target: Target,
    /// Write the stored calibration as JSON to this file ('-' = stdout).
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Runs `sinscal device`.
pub fn run(args: Args) -> anyhow::Result<()> {
    match args.action {
        Action::Run(a) => device_run(a),
        Action::Show(a) => device_show(a),
    }
}

/// A serial port with the line set up by `stty` (raw, 115200 baud, reads return after 0.1 s without data).
struct SerialPort(File);

impl SerialPort {
    fn open(path: &PathBuf) -> anyhow::Result<SerialPort> {
        let status = std::process::Command::new("stty")
            .arg("-F")
            .arg(path)
            .args(["115200", "raw", "-echo", "min", "0", "time", "1"])
            .status()
            .map_err(|e| anyhow::anyhow!("stty: {e}"))?;
        if !status.success() {
            anyhow::bail!("{}: stty could not set up the serial port", path.display());
        }
        let file = OpenOptions::new().read(true).write(true).open(path)?;
        Ok(SerialPort(file))
    }
}

impl Read for SerialPort {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        match self.0.read(buf)? {
            0 => Err(std::io::ErrorKind::WouldBlock.into()),
            n => Ok(n),
        }
    }
}

impl Write for SerialPort {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}

/// Progress of a running calibration on stderr, once per change of position.
fn progress() -> impl FnMut(&Status) {
    let mut last = None;
    move |s: &Status| {
        let now = (s.state, s.position);
        if last != Some(now) {
            last = Some(now);
            eprintln!("device: {:?}, position {} of {}", s.state, (s.position + 1).min(s.positions), s.positions);
        }
    }
}

fn report_run(run: &DeviceRun, json: Option<&std::path::Path>) -> anyhow::Result<()> {
    let s = &run.stored;
    eprintln!(
        "device: stored calibration record {} ({} bytes) in slot {}, {} sector erase(s)",
        s.sequence, s.bytes, s.slot, s.erases
    );
    finish(&run.calibration, json)
}

fn device_run(a: RunArgs) -> anyhow::Result<()> {
    let options = a.calibration.options(true)?;
    let rec = RecordingFile::open(&a.recording)?;
    let options = a.calibration.with_recording(options, true, &rec)?;
    let (replay, plan) = replay_for(&rec, &options)?;
    let run = match (&a.target.port, &a.target.flash) {
        (Some(port), _) => {
            let mut client = Client::new(SerialPort::open(port)?);
            client.timeout = std::time::Duration::from_secs(5);
            // A board's own IMU on a real turntable: settle, then dwells of the sequence's length.
            run_calibration(
                &mut client,
                &rec,
                &options,
                &replay,
                &plan,
                Some(sinscal::instrument::wire::configuration::Thresholds::table()),
                progress(),
            )?
        }
        (None, Some(flash)) => {
            let mut device = boot_qemu(flash, Some(replay.path())).map_err(anyhow::Error::msg)?;
            run_calibration(&mut device.client, &rec, &options, &replay, &plan, None, progress())?
        }
        (None, None) => anyhow::bail!("give --qemu --flash IMAGE or --port SERIAL"),
    };
    report_run(&run, a.json.as_deref())
}

fn show_record(read: RecordRead, json: Option<&std::path::Path>, what: &str) -> anyhow::Result<()> {
    let Some(record) = read.record else {
        match read.damaged_newer {
            Some(sequence) => eprintln!(
                "{what}: no valid calibration record: the only one with a header ({sequence}) is damaged (its CRC \
                 does not match); the device compensates nothing"
            ),
            None => eprintln!("{what}: no calibration record is stored"),
        }
        std::process::exit(1);
    };
    let calibration: Calibration = calibration_of_record(&record, read.damaged_newer)?;
    finish(&calibration, json)
}
fn device_show(a: ShowArgs) -> anyhow::Result<()> {
    match (&a.target.port, &a.target.flash) {
        (Some(port), _) => {
            let mut client = Client::new(SerialPort::open(port)?);
            let record = read_record(&mut client)?;
            show_record(record, a.json.as_deref(), &port.display().to_string())
        }
        (None, Some(flash)) => {
            let mut device = boot_qemu(flash, None).map_err(anyhow::Error::msg)?;
            let record = read_record(&mut device.client)?;
            // The device is stopped before the process may exit.
            drop(device);
            show_record(record, a.json.as_deref(), &flash.display().to_string())
        }
        (None, None) => anyhow::bail!("give --qemu --flash IMAGE or --port SERIAL"),
    }
}
