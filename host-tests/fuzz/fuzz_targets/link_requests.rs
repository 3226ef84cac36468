//! libFuzzer target: sinscal_lab::fuzz::read_link_requests, the device's request decoders, on frames with a right CRC
//! (a panic, or an Err, is a finding).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(reason) = sinscal_lab::fuzz::read_link_requests(data) {
        panic!("{reason}");
    }
});
