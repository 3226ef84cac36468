//! libFuzzer target: sinscal_lab::fuzz::read_imucal_raw, the imucal raw-counts importer (a panic, or an Err, is a
//! finding).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(reason) = sinscal_lab::fuzz::read_imucal_raw(data) {
        panic!("{reason}");
    }
});
