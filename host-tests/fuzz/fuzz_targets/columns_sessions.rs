//! libFuzzer target: sinscal_lab::fuzz::read_columns_sessions, import columns of two text files as
//! sessions (a panic, or an Err, is a finding).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(reason) = sinscal_lab::fuzz::read_columns_sessions(data) {
        panic!("{reason}");
    }
});
