//! libFuzzer target: sinscal_lab::fuzz::read_labels (the labels file of `sinscal import columns`; a panic, or an Err,
//! is a finding).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(reason) = sinscal_lab::fuzz::read_labels(data) {
        panic!("{reason}");
    }
});
