//! libFuzzer target: sinscal_lab::fuzz::read_columns_side_by_side, import columns of two binary files
//! side by side (a panic, or an Err, is a finding).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(reason) = sinscal_lab::fuzz::read_columns_side_by_side(data) {
        panic!("{reason}");
    }
});
