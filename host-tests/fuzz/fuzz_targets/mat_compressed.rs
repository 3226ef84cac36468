//! libFuzzer target: sinscal_lab::fuzz::read_mat from the compressed, big-endian seed (`mat-compressed`), so
//! that the mutations reach the inflated elements (a panic, or an Err, is a finding).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(reason) = sinscal_lab::fuzz::read_mat(data) {
        panic!("{reason}");
    }
});
