//! libFuzzer target: sinscal_lab::fuzz::read_link_frames, the device link's frame decoder, each frame answered by the
//! device (a panic, or an Err, is a finding).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(reason) = sinscal_lab::fuzz::read_link_frames(data) {
        panic!("{reason}");
    }
});
