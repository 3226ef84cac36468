//! libFuzzer target: sinscal_lab::fuzz::read_imucal, the imucal Ferraris importer (session CSV, a zero byte, labels
//! JSON) (a panic, or an Err, is a finding).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(reason) = sinscal_lab::fuzz::read_imucal(data) {
        panic!("{reason}");
    }
});
