//! libFuzzer target: sinscal_lab::fuzz::read_mat from the little-endian, uncompressed seed (a panic, or an Err,
//! is a finding). `mat_compressed.rs` runs the same reader from the compressed seed.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(reason) = sinscal_lab::fuzz::read_mat(data) {
        panic!("{reason}");
    }
});
