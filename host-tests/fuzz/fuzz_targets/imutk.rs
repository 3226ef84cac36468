//! libFuzzer target: sinscal_lab::fuzz::read_imutk, the imu_tk importer (accelerometer file, a zero byte, gyro file) (a
//! panic, or an Err, is a finding).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(reason) = sinscal_lab::fuzz::read_imutk(data) {
        panic!("{reason}");
    }
});
