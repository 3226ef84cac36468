//! libFuzzer target: sinscal_lab::fuzz::read_mat, the MAT-file reader from the version 7.3 (HDF5) seed (a panic, or an
//! Err, is a finding).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(reason) = sinscal_lab::fuzz::read_mat(data) {
        panic!("{reason}");
    }
});
