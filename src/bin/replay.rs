//! Firmware: replays a recorded calibration sequence in the emulated Cortex-M4F (QEMU mps2-an386).
//!
//! Usage (through `sinscal calibrate RECORDING --on qemu`, which writes the replay file):
//!     qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic \
//!       -semihosting-config enable=on,target=native,arg=sinscal-replay,arg=IN.ssrp,arg=OUT.ssro -kernel ELF
//! The frames of IN go through the replay SPI device, the ADIS driver, the sampling queue, the calibration
//! sequence and the core; the outcome is written to OUT (f32 bit patterns), events are logged with defmt.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {}

#[cfg(target_os = "none")]
mod firmware {

    use cortex_m as _;
    use cortex_m_rt::entry;
    use defmt_full as defmt;
    use sinscal::board::exit;
    use sinscal::instrument::main_loop::log_event;
    use sinscal::instrument::wire::outcome::MAX_BYTES as MAX_OUTCOME_BYTES;
    use sinscal::rig::replay::run_replay;
    use sinscal::rig::semihost::FileSource;
    use sinscal::run::sequence::SequenceSolution;

    fn fail(what: &str) -> ! {
        defmt::error!("sinscal-replay: {=str}", what);
        exit(1)
    }

    fn log_result(result: &SequenceSolution) {
        match result {
            SequenceSolution::Angles(r) => {
                let s = &r.solution;
                let v = |e: Option<sinscal::calib::angles::Estimate>| e.map_or(f32::NAN, |e| e.value);
                defmt::info!(
                    "angle method, {=u32} passes: gyro bias [{=f32}, {=f32}, {=f32}] rad/s, accel bias [{=f32}, {=f32}, {=f32}] m/s^2",
                    r.passes,
                    v(s.gyro_bias_b_radps[0]),
                    v(s.gyro_bias_b_radps[1]),
                    v(s.gyro_bias_b_radps[2]),
                    v(s.accel_bias_b_mps2[0]),
                    v(s.accel_bias_b_mps2[1]),
                    v(s.accel_bias_b_mps2[2])
                )
            }
            SequenceSolution::Channels(c) => defmt::info!(
                "general estimator, {=u32} passes: chi-square {=f32} on {=u32} degrees of freedom, suspect dwells {=u64:b}",
                c.iterations,
                c.chi_square,
                c.degrees_of_freedom,
                c.suspect
            ),
        }
    }

    #[entry]
    fn main() -> ! {
        let (Some(input), Some(output)) = (sinscal::rig::semihost::arg_path(1), sinscal::rig::semihost::arg_path(2))
        else {
            fail("usage: sinscal-replay IN OUT (paths up to 255 bytes)")
        };
        let Some(source) = FileSource::open(&input) else { fail("cannot open the replay file") };
        let outcome = match run_replay(source, log_event) {
            Ok(o) => o,
            Err(_) => fail("replay file unreadable"),
        };
        if let Some(r) = &outcome.result {
            log_result(r);
        }
        let s = &outcome.sampling;
        defmt::info!(
            "sampling: {=u32} events, {=u32} readings, {=u32} queue full, {=u32} faults, {=u32} missed",
            s.events,
            s.readings,
            s.queue_full,
            s.faults(),
            s.missed_samples
        );
        static mut OUT: [u8; MAX_OUTCOME_BYTES] = [0; MAX_OUTCOME_BYTES];
        // Single-threaded firmware: the only reference to OUT.
        #[allow(static_mut_refs)]
        let bytes = unsafe { &mut OUT };
        let Ok(n) = outcome.encode(bytes) else { fail("outcome too large") };
        if !sinscal::rig::semihost::write_file(&output, &bytes[..n]) {
            fail("cannot write the outcome file");
        }
        exit(0)
    }
}
