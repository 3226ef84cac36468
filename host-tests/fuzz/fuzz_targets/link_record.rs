//! libFuzzer target: sinscal_lab::fuzz::read_link_record, the workstation's reading of a stored calibration record (a
//! panic, or an Err, is a finding).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(reason) = sinscal_lab::fuzz::read_link_record(data) {
        panic!("{reason}");
    }
});
