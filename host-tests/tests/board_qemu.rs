//! The STM32F405 board's firmware (`boards/stm32f405`) on its link, in QEMU's model of the STM32F405
//! (`netduinoplus2`): built with its feature `qemu-netduinoplus2` (the clocks left on the HSI, the only change),
//! booted with USART1 on a Unix socket, and asked over the link what the QEMU board's instrument is asked. It
//! answers as the same device: the same identity, an idle status with no samples (QEMU has no IMU on SPI1, so the
//! board runs without one, as on a bench), nothing stored, and refusals of bad frames with the device still
//! answering. What QEMU does not model (the data-ready edge, flash programming, the IWDG, the clocks) is on the
//! bring-up checklist of docs/board.md.
//!
//! Needs qemu-system-arm, the thumbv7em target and flip-link (scripts/setup installs them); in CI (`SINSCAL_REQUIRE_ALL` set) a
//! missing one is a failure, elsewhere the test reports itself as skipped.

mod common;

use std::path::PathBuf;
use std::process::{Command, Stdio};

use sinscal::instrument::link::{encode_frame, MAX_WIRE_BYTES};
use sinscal::instrument::message::{kind, DeviceState, ErrorCode};
use sinscal_host::device::client::LinkError;
use sinscal_host::device::{boot_qemu, boot_stm32f405, read_record};

/// Builds the board's firmware for QEMU (profile `qemu`: the release settings in their own folder).
fn board_elf() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../boards/stm32f405");
    if Command::new("flip-link").arg("--version").output().is_err() {
        common::skipped("the STM32F405 board in QEMU", "flip-link not found (run scripts/setup)");
        return None;
    }
    let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .current_dir(&dir)
        .args(["build", "-q", "--profile", "qemu", "--features", "qemu-netduinoplus2"])
        .stdout(Stdio::null())
        .status()
        .expect("cargo runs");
    assert!(status.success(), "building the board's firmware for QEMU failed");
    Some(dir.join("target/thumbv7em-none-eabihf/qemu/sinscal-stm32f405"))
}

#[test]
fn the_stm32f405_firmware_answers_its_link_as_the_same_device() {
    if !common::qemu_available("") {
        return;
    }
    let Some(elf) = board_elf() else { return };
    let mut board = boot_stm32f405(&elf).unwrap();
    let c = &mut board.client;
    // A request that arrives before the board has enabled its USART is lost, as on the chip (the USART drops
    // what it receives while disabled), or only its first bytes are, and the rest is refused as a broken frame.
    let identity = c.identify_after_boot(std::time::Duration::from_secs(20));
    let identity = identity.unwrap();
    println!("STM32F405 in QEMU: {identity:?}");
    // The QEMU board's instrument, on the same core: the same identity.
    let dir = tempfile::tempdir().unwrap();
    let mut reference = boot_qemu(&dir.path().join("flash.img"), None).unwrap();
    assert_eq!(identity, reference.client.identify().unwrap(), "the two boards' devices differ");
    assert_eq!(identity.imu_model, 1, "ADIS16505-2");
    // No IMU on QEMU's SPI1: idle, no samples, and the link answers.
    let status = c.status().unwrap();
    println!("status: {status:?}");
    assert_eq!(status.state, DeviceState::Idle);
    assert!(status.sampling.iter().all(|&n| n == 0), "samples without an IMU: {:?}", status.sampling);
    // The record's sectors hold no record (QEMU's flash there reads as zeros): nothing stored, read through the
    // board's flash driver and the core's store.
    assert_eq!(read_record(c).unwrap().record, None);
    // A bad CRC is refused, an unknown kind too, and the device keeps answering.
    let mut wire = vec![0u8; MAX_WIRE_BYTES];
    let n = encode_frame(kind::STATUS, 7, &[], &mut wire).unwrap();
    wire[2] ^= 0x04;
    c.send_raw(&wire[..n]).unwrap();
    let crc = c.reply("bad CRC", kind::STATUS, None);
    assert!(matches!(crc, Err(LinkError::Refused { code: ErrorCode::Crc | ErrorCode::Frame, .. })), "{crc:?}");
    assert!(matches!(c.request("kind", 0x3F, &[]), Err(LinkError::Refused { code: ErrorCode::UnknownKind, .. })));
    let after = c.status().unwrap();
    println!("link counters after the bad frames: {:?}", after.link);
    assert_eq!(after.state, DeviceState::Idle);
    assert!(after.link[1] + after.link[2] >= 1, "the bad frame was not counted: {:?}", after.link);
    assert!(after.link[4] >= 1, "the unknown kind was not counted as refused: {:?}", after.link);
}
