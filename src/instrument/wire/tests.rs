//! Round trips of every wire format over pseudo-random values: encode, decode, the same value; every
//! truncation and every unknown code refused.

use heapless::Vec;

use super::codes::{EstimatorCode, ImuCode};
use super::configuration::{Configuration, DeviceConfiguration, RestLimits, Thresholds, MAX_DEVICE_BYTES};
use super::outcome::{Outcome, MAX_BYTES};
use super::record::{Record, RecordHead};
use super::Writer;
use crate::calib::align::DwellValue;
use crate::calib::angles::{BiasSolution, Estimate, MAX_PARAMETERS, MAX_POSITIONS};
use crate::calib::angles::{CalibrationResult, PositionInput};
use crate::calib::compensation::Compensation;
use crate::calib::dwell::{DwellAllan, DwellSummary, MeanNoise, Prefilter};
use crate::calib::general::{ChannelSolution, Model as Terms, Term, PARAMETERS};
use crate::calib::noise_model::{ChannelNoiseTerms, NoiseModel, TERM_VALUES};
use crate::calib::prefilter::PrefilterSettings;
use crate::nav::earth::Site;
use crate::nav::frames::Attitude;
use crate::run::sampling::SamplingStats;
use crate::run::sequence::{SequenceFailure, SequenceSolution};

/// A xorshift generator: the same values on every machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn f32(&mut self) -> f32 {
        (self.next() % 2_000_001) as f32 * 1e-6 - 1.0
    }
    fn positive(&mut self) -> f32 {
        self.f32().abs() + 1e-3
    }
    fn vec3(&mut self) -> [f32; 3] {
        [self.f32(), self.f32(), self.f32()]
    }
}

fn configuration(rng: &mut Rng) -> Configuration {
    let terms = Term::ALL.iter().fold(Terms::EMPTY, |m, t| if rng.below(2) == 1 { m.with(*t) } else { m });
    let prefilter = match rng.below(2) {
        0 => Prefilter::None,
        _ => Prefilter::HmmKf {
            gyro: PrefilterSettings::paper_gyro().with_a(rng.positive()),
            accel: PrefilterSettings::paper_accel().with_a(rng.positive()),
        },
    };
    let positions = 1 + rng.below(MAX_POSITIONS as u64) as usize;
    let mut c = Configuration {
        imu: ImuCode::ALL[rng.below(2) as usize].model(),
        estimator: EstimatorCode::ALL[rng.below(3) as usize],
        terms,
        site: Site { latitude_rad: rng.f32(), gravity_mps2: 9.0 + rng.positive() },
        schedule: Vec::new(),
        labels: Vec::new(),
        unknown_headings: 0,
        prefilter,
        dwell_value: if rng.below(2) == 0 { DwellValue::Mean } else { DwellValue::Settled },
        max_passes: rng.below(256) as u8,
        estimate_reference_offset: rng.below(2) == 1,
        rest: RestLimits {
            force_error_max_mps2: rng.positive(),
            gravity_angle_max_rad: rng.positive(),
            rate_max_radps: rng.positive(),
        },
        pose_tolerance_rad: if rng.below(2) == 0 { 0.0 } else { 0.1 * rng.positive().min(1.0) },
        noise: (rng.below(2) == 1).then(|| noise_model(rng)),
    };
    for k in 0..positions {
        let [pitch_rad, roll_rad, heading_rad] = rng.vec3();
        c.schedule.push(Attitude { pitch_rad, roll_rad, heading_rad }).unwrap();
        c.labels.push(rng.below(65_536) as u16).unwrap();
        if rng.below(3) == 0 {
            c.unknown_headings |= 1 << k;
        }
    }
    c
}

/// A valid noise model with every term drawn (some left out).
fn noise_model(rng: &mut Rng) -> NoiseModel {
    let channels = core::array::from_fn(|_| {
        let mut v = [0.0f32; TERM_VALUES];
        for x in &mut v {
            *x = if rng.below(3) == 0 { 0.0 } else { rng.positive() };
        }
        // Some term beyond the correlation times, and those times wherever the Gauss-Markov sigma and sway are.
        v[1] = rng.positive();
        v[4] = rng.positive();
        v[8] = rng.positive();
        ChannelNoiseTerms::from_array(v)
    });
    NoiseModel { sample_interval_s: rng.positive(), channels }
}

fn encoded(encode: impl Fn(&mut Writer<'_>), out: &mut [u8]) -> usize {
    let mut w = Writer::new(out);
    encode(&mut w);
    w.written().expect("the buffer holds the longest encoding")
}

#[test]
fn configurations_round_trip_and_every_truncation_or_unknown_code_is_refused() {
    let mut rng = Rng(0x5eed_c0de);
    let mut bytes = [0u8; MAX_DEVICE_BYTES + 1];
    for _ in 0..300 {
        let configured = DeviceConfiguration {
            configuration: configuration(&mut rng),
            thresholds: Thresholds {
                settle_samples: rng.next() as u32,
                dwell_samples: rng.next() as u32,
                min_dwell_samples: rng.next() as u32,
            },
        };
        let n = encoded(|w| configured.encode(w), &mut bytes);
        assert_eq!(n, configured.configuration.encoded_bytes() + 12);
        assert_eq!(DeviceConfiguration::decode(&bytes[..n]), Ok(configured.clone()));
        let cut = rng.below(n as u64) as usize;
        assert!(DeviceConfiguration::decode(&bytes[..cut]).is_err(), "a configuration cut to {cut} of {n} bytes");
        assert!(DeviceConfiguration::decode(&bytes[..n + 1]).is_err(), "a byte too many");
    }
    // Unknown codes of the IMU, the estimator, the prefilter, the dwell value and a term bit.
    let configured = DeviceConfiguration { configuration: configuration(&mut rng), thresholds: Thresholds::REPLAY };
    let n = encoded(|w| configured.encode(w), &mut bytes);
    for (at, value) in [(0, 2u8), (1, 3), (14, 2), (15, 2), (13, 0x80)] {
        let mut bad = bytes;
        bad[at] = value;
        assert!(DeviceConfiguration::decode(&bad[..n]).is_err(), "byte {at} = {value} accepted");
    }
    // A noise model with a negative or non-finite term, or a negative sample interval (bytes 42..46, then the
    // terms of gyro x from byte 46): refused.
    let mut c = configuration(&mut rng);
    c.estimator = EstimatorCode::General;
    c.noise = Some(noise_model(&mut rng));
    let configured = DeviceConfiguration { configuration: c, thresholds: Thresholds::REPLAY };
    let n = encoded(|w| configured.encode(w), &mut bytes);
    assert_eq!(DeviceConfiguration::decode(&bytes[..n]), Ok(configured.clone()));
    for (at, value) in [(42, -1.0f32), (46, -1.0), (50, f32::NAN), (54, f32::INFINITY)] {
        let mut bad = bytes;
        bad[at..at + 4].copy_from_slice(&value.to_le_bytes());
        assert!(DeviceConfiguration::decode(&bad[..n]).is_err(), "bytes {at}.. = {value} accepted");
    }
}

fn dwell(rng: &mut Rng) -> DwellSummary {
    let mut d = DwellSummary {
        // A dwell's three counts share one 32-bit counter (the decoder refuses a sum past it).
        samples: (rng.next() >> 34) as u32,
        rejected: (rng.next() >> 34) as u32,
        spikes: (rng.next() >> 34) as u32,
        rate_mean_b_radps: rng.vec3(),
        force_mean_b_mps2: rng.vec3(),
        rate_sample_std_b_radps: rng.vec3(),
        force_sample_std_b_mps2: rng.vec3(),
        rate_settled_b_radps: rng.vec3(),
        force_settled_b_mps2: rng.vec3(),
        settled_noise_gain: [rng.f32(), rng.f32()],
        mean_noise: [MeanNoise::default(); 6],
        allan: [DwellAllan::default(); 6],
    };
    for m in d.mean_noise.iter_mut() {
        (m.white_equivalent_var, m.dof, m.cluster_samples) = (rng.positive(), rng.positive(), rng.next() as u32);
    }
    for a in d.allan.iter_mut() {
        a.avar.iter_mut().for_each(|v| *v = rng.positive());
    }
    d
}

fn general_solution(rng: &mut Rng, model: Terms, dwells: usize) -> ChannelSolution {
    let mut c = ChannelSolution::empty(model, dwells);
    c.parameters_si.iter_mut().for_each(|p| *p = rng.f32());
    (c.observable, c.unobservable, c.suspect, c.gauge) = (rng.next(), rng.next(), rng.next(), rng.next());
    c.completion = rng.next();
    c.covariance_si.iter_mut().flatten().for_each(|v| *v = rng.f32());
    for k in 0..dwells {
        (c.heading_rad[k], c.heading_std_rad[k], c.dwell_statistic[k]) = (rng.f32(), rng.f32(), rng.f32());
        (c.residual_rate_b_radps[k], c.residual_force_b_mps2[k], c.up_b[k]) = (rng.vec3(), rng.vec3(), rng.vec3());
    }
    (c.chi_square, c.degrees_of_freedom, c.iterations) = (rng.positive(), rng.next() as u32, rng.next() as u32);
    (c.converged, c.earth_rate_resolved, c.blind_spots) = (rng.below(2) == 1, rng.below(2) == 1, rng.next() as u32);
    c
}

fn outcome(rng: &mut Rng) -> Outcome {
    let configuration = configuration(rng);
    let mut counters = [0u32; 10];
    counters.iter_mut().for_each(|c| *c = rng.next() as u32);
    let done = rng.below(configuration.schedule.len() as u64 + 1) as usize;
    let mut positions = Vec::new();
    for a in &configuration.schedule[..done] {
        positions.push(PositionInput { c_b_n: a.c_b_n(), summary: dwell(rng) }).unwrap();
    }
    let (result, failure) = match rng.below(3) {
        0 => (
            None,
            Some(SequenceFailure::Channels(crate::calib::general::ChannelError::Diverged {
                parameter: rng.below(PARAMETERS as u64) as usize,
                value: rng.f32(),
            })),
        ),
        1 => (Some(SequenceSolution::Channels(general_solution(rng, configuration.terms, done))), None),
        _ => {
            let mut estimate = || (rng.below(2) == 1).then(|| Estimate { value: rng.f32(), std_error: rng.positive() });
            let solution = BiasSolution {
                gyro_bias_b_radps: [estimate(), estimate(), estimate()],
                accel_bias_b_mps2: [estimate(), estimate(), estimate()],
                reference_offset_n_rad: [estimate(), estimate(), estimate()],
                reference_offset_estimated: rng.below(2) == 1,
                positions: done,
                residual_n_rad: [[0.0; 3]; MAX_POSITIONS].map(|_| rng.vec3()),
                chi_square: rng.positive(),
                degrees_of_freedom: rng.next() as u32,
                covariance_si: [[0.0; MAX_PARAMETERS]; MAX_PARAMETERS].map(|row| row.map(|_| rng.f32())),
            };
            let r = CalibrationResult {
                solution,
                passes: rng.next() as u32,
                converged: true,
                last_correction_sigma: rng.f32(),
            };
            (Some(SequenceSolution::Angles(r)), None)
        }
    };
    let sampling = SamplingStats::from_counters(counters);
    Outcome { configuration, positions, result, failure, sampling, aborted_dwells: rng.next() as u32 }
}

#[test]
fn outcomes_round_trip_whole_and_in_windows_and_truncations_are_refused() {
    let mut rng = Rng(0x0dd_ba11);
    let mut bytes = std::vec![0u8; MAX_BYTES];
    for _ in 0..60 {
        let o = outcome(&mut rng);
        let n = o.encode(&mut bytes).unwrap();
        assert_eq!(Outcome::decode(&o.configuration, &bytes[..n]), Ok(o.clone()));
        // The bound a device checks before a run: reached by a solved outcome of every position, never passed.
        let estimator = match o.result {
            Some(SequenceSolution::Angles(_)) => EstimatorCode::Angles,
            _ => EstimatorCode::General,
        };
        let bound = super::outcome::max_bytes_for(o.positions.len(), estimator);
        if o.result.is_some() {
            assert_eq!(n, bound, "a solved outcome of {} positions", o.positions.len());
        }
        assert!(n <= super::outcome::max_bytes_for(o.configuration.schedule.len(), EstimatorCode::General));
        // A window of the encoding is the same bytes (a link reply, a flash page).
        let (start, len) = (rng.below(n as u64) as usize, 1 + rng.below(1024) as usize);
        let mut part = std::vec![0u8; len];
        assert_eq!(super::outcome::encode_part(&o.view(), start, &mut part), n);
        let end = (start + len).min(n);
        assert_eq!(&part[..end - start], &bytes[start..end]);
        let cut = rng.below(n as u64) as usize;
        assert!(Outcome::decode(&o.configuration, &bytes[..cut]).is_err(), "an outcome cut to {cut} of {n} bytes");
    }
}

#[test]
fn a_record_reads_back_as_its_parts() {
    let mut rng = Rng(0xfeed);
    let o = outcome(&mut rng);
    let (configuration, note) = ([7u8; 40], *b"provenance");
    let record = Record::new(Compensation::IDENTITY, &configuration, &note, o.view());
    let mut bytes = std::vec![0u8; record.record_bytes()];
    record.write_part(0, &mut bytes);
    let head = RecordHead::decode(&bytes).unwrap();
    let [_, (k, kl), (n, nl), (oo, ol)] = head.parts();
    assert_eq!((&bytes[k..k + kl], &bytes[n..n + nl]), (&configuration[..], &note[..]));
    assert_eq!(Outcome::decode(&o.configuration, &bytes[oo..oo + ol]), Ok(o));
}

#[test]
fn status_replies_round_trip_and_truncations_and_unknown_states_are_refused() {
    use super::status::{Status, BYTES};
    use crate::instrument::message::DeviceState;
    let mut rng = Rng(0x5eed_57a7);
    for (i, state) in
        [DeviceState::Idle, DeviceState::Configured, DeviceState::Running, DeviceState::Solved, DeviceState::Failed]
            .into_iter()
            .enumerate()
    {
        let status = Status {
            state,
            position: rng.next() as u16,
            positions: rng.next() as u16,
            sampling: core::array::from_fn(|_| rng.next() as u32),
            link: core::array::from_fn(|_| rng.next() as u32),
            stored: (i % 2 == 0).then_some(rng.next() as u32),
            compensating: i % 3 == 0,
            streaming: i % 2 == 1,
            damaged_newer: (i > 2).then_some(rng.next() as u32),
        };
        let mut out = [0u8; BYTES + 8];
        let n = status.encode(&mut out).expect("fits");
        assert_eq!(n, BYTES);
        assert_eq!(Status::decode(&out[..n]), Ok(status.clone()));
        for cut in 0..n {
            assert!(Status::decode(&out[..cut]).is_err(), "{cut} bytes");
        }
        assert!(Status::decode(&out[..n + 1]).is_err(), "a byte more");
        assert!(status.encode(&mut out[..n - 1]).is_none(), "a buffer a byte short");
        out[0] = 5;
        assert!(Status::decode(&out[..n]).is_err(), "an unknown state");
    }
}
