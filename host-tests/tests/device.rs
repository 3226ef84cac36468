//! The instrument end to end in QEMU: `sinscal device run` (configure over the link, the recording replayed
//! through the emulated IMU, result, store in the flash file) then `sinscal device show` (a second boot reads the
//! record back): the same JSON, equal to `calibrate --on host` in every field but "on". And bad messages over the
//! link: each gets an error reply and the device keeps answering. Needs qemu-system-arm and the thumbv7em target
//! (scripts/setup installs both); in CI (`SINSCAL_REQUIRE_ALL` set by .ci/run) a missing QEMU is a failure, elsewhere the test reports itself
//! as skipped.

mod common;

use assert_cmd::Command;
use sinscal::instrument::link::{encode_frame, MAX_WIRE_BYTES, PROTOCOL_VERSION};
use sinscal::instrument::message::{kind, DeviceState, ErrorCode};
use sinscal_host::calibration::qemu::firmware_binary;
use sinscal_host::calibration::qemu::QEMU;
use sinscal_host::calibration::result::CalibrationJson;
use sinscal_host::calibration::Options;
use sinscal_host::device::client::LinkError;
use sinscal_host::device::{boot_elf, boot_qemu, calibration_of_record, configuration_body, read_record, replay_for};
use sinscal_host::model::synth::Scenario;

fn sinscal() -> Command {
    Command::cargo_bin("sinscal").unwrap()
}

fn json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn device_run_then_show_gives_the_host_replay_json() {
    if !common::qemu_available("") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let rec_path = dir.path().join("example.csv");
    let rec = Scenario { dwell_s: 30.0, ..Scenario::example() }.recording(11, "example.csv");
    rec.write(&rec_path).unwrap();
    let flash = dir.path().join("flash.img");
    let (run_json, show_json, host_json) =
        (dir.path().join("run.json"), dir.path().join("show.json"), dir.path().join("host.json"));
    // Nothing stored yet: exit 1 with a reason.
    let empty = sinscal().args(["device", "show", "--qemu", "--flash"]).arg(&flash).output().unwrap();
    assert_eq!(empty.status.code(), Some(1), "{}", String::from_utf8_lossy(&empty.stderr));
    assert!(String::from_utf8_lossy(&empty.stderr).contains("no calibration record is stored"));
    // Every check passes, with either model (the full model's unobservable terms are fitted together as the
    // completion, docs/method.md#observability, not left in the residuals).
    let checked = |code: Option<i32>, stderr: &str, _model: &str, what: &str| {
        assert_eq!(code, Some(0), "{what}: {stderr}");
    };
    for (model, store) in [("biases", 1), ("full", 2)] {
        let run = sinscal()
            .args(["device", "run"])
            .arg(&rec_path)
            .args(["--qemu", "--flash"])
            .arg(&flash)
            .args(["--model", model, "--json"])
            .arg(&run_json)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        checked(run.status.code(), &stderr, model, "device run");
        assert!(stderr.contains(&format!("stored calibration record {store} ")), "{stderr}");
        let mut show = sinscal();
        let show = show.args(["device", "show", "--qemu", "--flash"]).arg(&flash).arg("--json").arg(&show_json);
        let show = show.output().unwrap();
        checked(show.status.code(), &String::from_utf8_lossy(&show.stderr), model, "device show");
        let mut host = sinscal();
        host.arg("calibrate").arg(&rec_path).args(["--on", "host", "--model", model, "--json"]).arg(&host_json);
        let host = host.output().unwrap();
        checked(host.status.code(), &String::from_utf8_lossy(&host.stderr), model, "calibrate --on host");
        let (run_v, show_v, mut host_v) = (json(&run_json), json(&show_json), json(&host_json));
        assert_eq!(run_v, show_v, "model {model}: the stored record reads back as the run reported it");
        assert_eq!(run_v["on"], "device");
        assert_eq!(host_v["on"], "host");
        assert_eq!(run_v["record"]["sequence"], store, "model {model}: the record the run stored");
        host_v["on"] = "device".into();
        assert_eq!(without_record(run_v), host_v, "model {model}: the device's result equals the host replay's");
    }
    // The calibration firmware (the budget binary: its IMU is the board's SPI port, which QEMU leaves empty, so
    // it samples nothing) boots on the same flash: it finds the record, compensates with it, and gives it back.
    let elf = firmware_binary("sinscal-firmware").unwrap();
    let mut firmware = boot_elf(&elf, &flash, None).unwrap();
    let id = firmware.client.identify().unwrap();
    assert!(id.firmware.starts_with("sinscal "), "{id:?}");
    let status = firmware.client.status().unwrap();
    assert!(status.compensating && status.stored == Some(2), "{status:?}");
    assert_eq!(status.sampling[0], 0, "no data-ready events without an IMU");
    let read = read_record(&mut firmware.client).unwrap();
    let record = read.record.expect("a record");
    assert_eq!((record.sequence, read.damaged_newer), (2, None));
    let from_firmware =
        serde_json::to_value(CalibrationJson::new(&calibration_of_record(&record, None).unwrap())).unwrap();
    assert_eq!(from_firmware, json(&show_json), "sinscal-firmware reads the record sinscal-device stored");
    drop(firmware);
    // `--port`: the same record through a serial port, here the pseudo-terminal QEMU gives UART0.
    let port_json = dir.path().join("port.json");
    let (mut qemu, pty) = boot_on_pty(&flash);
    let port = sinscal().args(["device", "show", "--port", &pty, "--json"]).arg(&port_json).output().unwrap();
    let _ = qemu.kill();
    let _ = qemu.wait();
    checked(port.status.code(), &String::from_utf8_lossy(&port.stderr), "full", "device show --port");
    assert_eq!(json(&port_json), json(&show_json), "the record read through a serial port");
    newest_record_damaged(&flash, &show_json);
}

/// One bit of the newest record (2, in slot 1) cleared, as NOR flash can lose it: `device show` shows the older
/// record 1, says in one line that the newest is damaged, and exits 3; the firmware's status says the same.
fn newest_record_damaged(flash: &std::path::Path, show_json: &std::path::Path) {
    let mut image = std::fs::read(flash).unwrap();
    // QEMU's flash file: two slots of one 16-KiB sector each (docs/device.md); a record's payload starts 20 bytes
    // into its slot.
    let slot_bytes = 16 * 1024;
    assert_eq!(image.len(), 2 * slot_bytes);
    let at = slot_bytes + 20 + (slot_bytes + 20..image.len()).position(|i| image[i] & 0x10 != 0).unwrap();
    image[at] &= !0x10;
    std::fs::write(flash, &image).unwrap();
    let show = sinscal()
        .args(["device", "show", "--qemu", "--flash"])
        .arg(flash)
        .arg("--json")
        .arg(show_json)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&show.stderr);
    assert_eq!(show.status.code(), Some(3), "{stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| l.contains("stored_record")).collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(lines[0].contains("newest record (2) is damaged") && lines[0].contains("older record 1"), "{stderr}");
    let shown = json(show_json);
    assert_eq!(
        (shown["record"]["sequence"].as_u64(), shown["record"]["damaged_newer_sequence"].as_u64()),
        (Some(1), Some(2))
    );
    assert_eq!(
        shown["model"],
        serde_json::json!(["gyro_bias", "accel_bias"]),
        "the older record is the biases-only calibration"
    );
    let elf = firmware_binary("sinscal-firmware").unwrap();
    let mut firmware = boot_elf(&elf, flash, None).unwrap();
    let status = firmware.client.status().unwrap();
    assert_eq!((status.stored, status.damaged_newer, status.compensating), (Some(1), Some(2), true), "{status:?}");
}

/// A device's calibration JSON without what only a device has: its record and the check of it.
fn without_record(mut v: serde_json::Value) -> serde_json::Value {
    let o = v.as_object_mut().unwrap();
    o.remove("record");
    o["checks"].as_array_mut().unwrap().retain(|c| c["check"] != "stored_record");
    v
}

/// Boots `sinscal-device` with UART0 on a pseudo-terminal; the terminal's path from QEMU's message.
fn boot_on_pty(flash: &std::path::Path) -> (std::process::Child, String) {
    use std::io::BufRead;
    let elf = firmware_binary("sinscal-device").unwrap();
    let semihosting = format!("enable=on,target=native,arg=sinscal-device,arg={},arg=-", flash.display());
    let mut child = std::process::Command::new(QEMU)
        .args(["-cpu", "cortex-m4", "-machine", "mps2-an386", "-nographic", "-monitor", "none", "-serial", "pty"])
        .args(["-semihosting-config", &semihosting, "-kernel"])
        .arg(&elf)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // QEMU names the terminal on its standard output, before the firmware's defmt frames.
    let mut stdout = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut line = Vec::new();
    while stdout.read_until(b'\n', &mut line).unwrap() > 0 {
        let text = String::from_utf8_lossy(&line);
        if let Some(at) = text.find("/dev/pts/") {
            let pty = text[at..].split_whitespace().next().unwrap().to_string();
            // The rest of standard output (the defmt log) is drained, so that QEMU never blocks on it.
            std::thread::spawn(move || std::io::copy(&mut stdout, &mut std::io::sink()));
            return (child, pty);
        }
        line.clear();
    }
    let _ = child.kill();
    let _ = child.wait();
    panic!("QEMU named no pseudo-terminal");
}

#[test]
fn bad_messages_get_an_error_reply_and_the_device_keeps_running() {
    if !common::qemu_available("") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let rec = Scenario { dwell_s: 30.0, ..Scenario::example() }.recording(3, "example.csv");
    let (replay, _) = replay_for(&rec, &Options::default()).unwrap();
    let mut device = boot_qemu(&dir.path().join("flash.img"), Some(replay.path())).unwrap();
    let c = &mut device.client;
    let refused = |r: Result<Vec<u8>, LinkError>| match r {
        Err(LinkError::Refused { code, detail, .. }) => (code, detail),
        other => panic!("expected a refusal, got {other:?}"),
    };
    let mut wire = vec![0u8; MAX_WIRE_BYTES];
    // A good frame, then the same frame truncated (its last 6 bytes and delimiter lost) before a good one.
    let n = encode_frame(kind::IDENTIFY, 1, &[], &mut wire).unwrap();
    let mut truncated = wire[..n - 6].to_vec();
    truncated.push(0);
    c.send_raw(&truncated).unwrap();
    let truncated_reply = c.reply("truncated", kind::IDENTIFY, None);
    assert!(
        matches!(truncated_reply, Err(LinkError::Refused { code: ErrorCode::Frame | ErrorCode::Crc, .. })),
        "{truncated_reply:?}"
    );
    // A bad CRC: one bit of the body flipped.
    let n = encode_frame(kind::STATUS, 2, &[], &mut wire).unwrap();
    wire[2] ^= 0x04;
    c.send_raw(&wire[..n]).unwrap();
    let crc = c.reply("bad CRC", kind::STATUS, None);
    assert!(matches!(crc, Err(LinkError::Refused { code: ErrorCode::Crc | ErrorCode::Frame, .. })), "{crc:?}");
    // Unknown version: a frame of version 2 with a correct CRC.
    let mut raw = vec![PROTOCOL_VERSION + 1, kind::IDENTIFY, 3];
    raw.extend_from_slice(&sinscal::instrument::crc::crc32(&raw).to_le_bytes());
    let stuffed = cobs(&raw);
    c.send_raw(&stuffed).unwrap();
    assert!(matches!(
        c.reply("version", kind::IDENTIFY, None),
        Err(LinkError::Refused { code: ErrorCode::Version, detail: 2, .. })
    ));
    // Unknown kind, a body where none belongs, start before configure, store and read without anything.
    assert_eq!(refused(c.request("kind", 0x3F, &[])), (ErrorCode::UnknownKind, 0x3F));
    assert_eq!(refused(c.request("identify", kind::IDENTIFY, &[1])).0, ErrorCode::Body);
    assert_eq!(refused(c.request("start", kind::START, &[])).0, ErrorCode::NotConfigured);
    assert_eq!(refused(c.request("store", kind::STORE, &[])).0, ErrorCode::NoResult);
    assert_eq!(refused(c.request("record", kind::READ_RECORD, &0u32.to_le_bytes())).0, ErrorCode::NothingStored);
    assert_eq!(refused(c.request("result", kind::READ_RESULT, &0u32.to_le_bytes())).0, ErrorCode::NoResult);
    // A schedule the core cannot hold (65 positions), and a truncated configuration.
    let head = std::fs::read(replay.path()).unwrap();
    let header_len = sinscal::rig::replay::replay_header_bytes(6);
    let good = configuration_body(&head[..header_len]).unwrap();
    let mut too_many = good.clone();
    too_many[10..12].copy_from_slice(&65u16.to_le_bytes());
    assert_eq!(refused(c.request("configure", kind::CONFIGURE, &too_many)).0, ErrorCode::Configuration);
    assert_eq!(refused(c.request("configure", kind::CONFIGURE, &good[..good.len() - 20])).0, ErrorCode::Configuration);
    // A note longer than the device keeps.
    let note = [b'x'; 1000];
    let mut body = vec![0, 0];
    body.extend_from_slice(&4000u16.to_le_bytes());
    body.extend_from_slice(&note);
    assert_eq!(refused(c.request("note", kind::ANNOTATE, &body)).0, ErrorCode::NoteTooLong);
    // The host's own note too long is the host's refusal, before anything is sent, with both lengths.
    let err = c.annotate(&[b'x'; 3000]).unwrap_err();
    assert!(matches!(err, LinkError::NoteTooLong { len: 3000, max: 2048 }), "{err}");
    assert!(err.to_string().starts_with("the provenance note is 3000 bytes, the device keeps at most 2048"));
    // Configure during a run.
    c.configure(&good).unwrap();
    c.request("start", kind::START, &[]).unwrap();
    let during = c.request("configure", kind::CONFIGURE, &good);
    let status = c.status().unwrap();
    if status.state == DeviceState::Running {
        assert_eq!(refused(during).0, ErrorCode::Busy);
    } else {
        // The replay is fast: the run may have ended before the request arrived; then configure is accepted.
        assert!(during.is_ok(), "{during:?}");
    }
    // Still answering, and every refusal counted.
    let id = c.identify().unwrap();
    assert_eq!(id.protocol, PROTOCOL_VERSION);
    let s = c.status().unwrap();
    let [requests, crc_errors, frame_errors, version_errors, refused_count, overruns] = s.link;
    println!("link counters: {:?}", s.link);
    assert!(requests >= 15, "{requests}");
    assert_eq!(crc_errors + frame_errors, 2, "the truncated and the corrupted frame");
    assert_eq!(version_errors, 1);
    assert!(refused_count >= 9, "{refused_count}");
    assert_eq!(overruns, 0);
}

/// COBS stuffing of a frame, with its delimiter (written here independently of the core's encoder).
fn cobs(raw: &[u8]) -> Vec<u8> {
    let mut out = vec![0u8];
    let mut code_at = 0;
    for &b in raw {
        if b == 0 {
            out[code_at] = (out.len() - code_at) as u8;
            code_at = out.len();
            out.push(0);
        } else {
            out.push(b);
            if out.len() - code_at == 255 {
                out[code_at] = 255;
                code_at = out.len();
                out.push(0);
            }
        }
    }
    out[code_at] = (out.len() - code_at) as u8;
    out.push(0);
    out
}

/// 19 positions: the record such a run could store passes the 16-KiB slot, and `device run` says so before the
/// run starts (the limit and the bound), instead of after the whole calibration; 24 positions: the note passes
/// the device's limit, said the same way.
#[test]
fn a_schedule_whose_record_or_note_could_not_be_kept_is_refused_before_the_run() {
    if !common::qemu_available("") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (positions, words) in [
        (19, "refused before the run starts: the record of this run could take"),
        (24, "the device keeps at most 2048"),
    ] {
        let poses = sinscal_host::model::synth::TABLE1_DEG;
        let positions_deg: Vec<[f64; 3]> = (0..positions).map(|k| poses[k % 6]).collect();
        let rec =
            Scenario { dwell_s: 2.0, settle_s: 0.5, positions_deg, ..Scenario::example() }.recording(3, "many.csv");
        let path = dir.path().join(format!("many{positions}.csv"));
        rec.write(&path).unwrap();
        let flash = dir.path().join(format!("flash{positions}.img"));
        let started = std::time::Instant::now();
        let run =
            sinscal().args(["device", "run"]).arg(&path).args(["--qemu", "--flash"]).arg(&flash).output().unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{positions} positions: {stderr}");
        assert!(stderr.contains(words), "{positions} positions: {stderr}");
        assert!(
            !stderr.contains("position 1 of"),
            "{positions} positions: no progress, the run never started: {stderr}"
        );
        println!("{positions} positions: refused after {:.1} s: {}", started.elapsed().as_secs_f64(), stderr.trim());
    }
}
