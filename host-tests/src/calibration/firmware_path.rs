//! The recording as the IMU would have delivered it: a replay file (format in `sinscal::rig::replay`) of
//! ADIS16505-2 burst frames, quantised to the device's 32-bit output LSB, with the turntable's position
//! signal; and the calibration of such a replay on the host (`--on host`) or in QEMU (`--on qemu`).

use sinscal::calib::align::{position_angles, DwellValue};
use sinscal::calib::dwell::Prefilter;
use sinscal::rig::replay::{
    decode_outcome, encode_outcome, read_header, run_replay, ReplayOutcome, MAGIC, MAX_OUTCOME_BYTES, VERSION,
};
use sinscal::run::sequence::SequenceFailure;
use sinscal::sensor::adis::{encode_burst, Burst, Model, BURST32_LEN, I16F16};

use crate::calibration::{
    calibration_dwells, prefilter_of, site_of, Calibration, Estimates, Method, Options, PositionResult,
};
use crate::io::error::InputError;
use crate::io::recording::{DwellAttitude, Recording};

/// The sensor model the replay files emulate.
pub const REPLAY_MODEL: Model = Model::Adis16505_2;

/// Writes the replay file of a recording for the given calibration options.
pub fn replay_file(rec: &Recording, options: &Options) -> Result<(Vec<u8>, Vec<DwellAttitude>), InputError> {
    let source = rec.source.as_str();
    let dwells = calibration_dwells(rec, sinscal::calib::solve::MAX_POSITIONS)?;
    // The firmware path needs each dwell as one contiguous stretch of rows (one turntable stop).
    let mut seen = Vec::new();
    let mut previous = 0;
    for row in &rec.rows {
        if row.pos != 0 && row.pos != previous {
            if seen.contains(&row.pos) {
                return Err(InputError::at(
                    source,
                    row.line,
                    format!("dwell {} is not contiguous: the firmware path needs one stretch per position", row.pos),
                ));
            }
            seen.push(row.pos);
        }
        previous = row.pos;
    }
    let (site, _) = site_of(&rec.header);
    let (prefilter_code, [a_gyro, a_accel]) = match prefilter_of(options, &dwells[0], source)? {
        Prefilter::None => (0u8, [1.0f32, 1.0]),
        Prefilter::HmmKf { gyro, accel } => (1, [gyro.a, accel.a]),
    };
    let mut out = Vec::with_capacity(64 + rec.rows.len() * (1 + BURST32_LEN));
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.push(1); // ADIS16505-2
    out.push(0);
    out.extend_from_slice(&site.latitude_rad.to_le_bytes());
    out.extend_from_slice(&site.gravity_mps2.to_le_bytes());
    out.extend_from_slice(&(dwells.len() as u16).to_le_bytes());
    out.extend_from_slice(&[0, 0]);
    out.push(prefilter_code);
    out.push(match options.dwell_value {
        DwellValue::Mean => 0,
        DwellValue::Settled => 1,
    });
    out.push(options.max_passes.min(255) as u8);
    out.push(options.estimate_reference_offset as u8);
    out.extend_from_slice(&a_gyro.to_le_bytes());
    out.extend_from_slice(&a_accel.to_le_bytes());
    let mut attitudes = Vec::new();
    for d in &dwells {
        let (att, heading) = d.attitude_with_heading(source, "the calibration")?;
        for v in [att.pitch_deg, att.roll_deg, heading] {
            out.extend_from_slice(&(v as f32).to_radians().to_le_bytes());
        }
        out.extend_from_slice(&(d.pos.min(u16::MAX as u32) as u16).to_le_bytes());
        out.extend_from_slice(&[0, 0]);
        attitudes.push(att);
    }
    out.extend_from_slice(&(rec.rows.len() as u32).to_le_bytes());
    let lsb_rate = (REPLAY_MODEL.radps_per_lsb() as f64) / 65536.0;
    let lsb_force = (REPLAY_MODEL.accel_mps2_per_lsb() as f64) / 65536.0;
    let quantise = |value: f64, lsb: f64, line: usize, what: &str| -> Result<I16F16, InputError> {
        let counts = (value / lsb).round();
        if counts.abs() >= i32::MAX as f64 {
            return Err(InputError::at(source, line, format!("{what} {value} is outside the ADIS16505-2 range")));
        }
        Ok(I16F16::from_bits(counts as i32))
    };
    let mut frame = [0u8; BURST32_LEN];
    for (k, row) in rec.rows.iter().enumerate() {
        let table =
            if row.pos == 0 { 0 } else { dwells.iter().position(|d| d.pos == row.pos).map_or(0, |i| i + 1) as u8 };
        let mut gyro = [I16F16::ZERO; 3];
        let mut accel = [I16F16::ZERO; 3];
        for i in 0..3 {
            gyro[i] = quantise(row.rate_b_radps[i], lsb_rate, row.line, "angular rate")?;
            accel[i] = quantise(row.force_b_mps2[i], lsb_force, row.line, "specific force")?;
        }
        let temp_raw = (row.temp_c.unwrap_or(25.0) / 0.1).round().clamp(i16::MIN as f64, i16::MAX as f64) as i16;
        let burst = Burst { diag_stat: 0, gyro_lsb: gyro, accel_lsb: accel, temp_raw, data_counter: k as u16 };
        encode_burst(REPLAY_MODEL, &burst, &mut frame);
        out.push(table);
        out.extend_from_slice(&frame);
    }
    Ok((out, attitudes))
}

/// The calibration of a replay outcome, in the host's report types (angles per position recomputed with
/// the core from the replayed dwell statistics).
pub fn calibration_from_outcome(
    rec: &Recording,
    options: &Options,
    attitudes: &[DwellAttitude],
    outcome: &ReplayOutcome,
) -> Result<Calibration, InputError> {
    let source = rec.source.as_str();
    let site = outcome.header.site;
    if let Some(f) = &outcome.failure {
        let reason = match f {
            SequenceFailure::PositionAborted { index, reason } => format!(
                "calibration sequence failed: position {} (dwell {}) aborted: {reason:?}",
                index + 1,
                outcome.header.labels.get(*index).copied().unwrap_or(0)
            ),
            SequenceFailure::Calibration(e) => format!("calibration sequence failed: {e}"),
            _ => "calibration sequence failed".to_string(),
        };
        return Err(InputError::file(source, reason));
    }
    let result = outcome.result.ok_or_else(|| {
        InputError::file(
            source,
            format!(
                "the calibration sequence ended after {} of {} positions",
                outcome.positions.len(),
                outcome.header.schedule.len()
            ),
        )
    })?;
    let dwells = rec.dwells();
    let mut positions = Vec::new();
    for (k, p) in outcome.positions.iter().enumerate() {
        let angles = position_angles(&p.summary, options.dwell_value, &p.c_b_n, &site)
            .map_err(|e| InputError::at(source, dwells[k].first_line(), format!("dwell {}: {e}", dwells[k].pos)))?;
        positions.push(PositionResult {
            pos: outcome.header.labels[k] as u32,
            first_line: dwells[k].first_line(),
            attitude: attitudes[k],
            summary: p.summary,
            angles: Some(angles),
        });
    }
    Ok(Calibration {
        source: source.to_string(),
        latitude_deg: rec.header.latitude_deg,
        site,
        gravity_source: site_of(&rec.header).1,
        prefilter: outcome.header.settings.prefilter,
        options: Options { method: Method::Angles, ..*options },
        positions,
        estimates: Estimates::from_angles(&result.solution),
        solution: Some(result.solution),
        channels: None,
        has_gyro: true,
        without_suspect: None,
        passes: result.passes,
        converged: result.converged,
        sampling: Some(outcome.sampling),
        on: "host",
    })
}

/// `calibrate --on host`: the replay file through the firmware path on x86. The outcome goes through the
/// same byte encoding as the firmware's, so both report from identical bits.
pub fn calibrate_on_host(rec: &Recording, options: &Options) -> Result<Calibration, InputError> {
    let (file, attitudes) = replay_file(rec, options)?;
    let source = rec.source.as_str();
    let outcome = run_replay(&file[..], |_| {}).map_err(|e| InputError::file(source, format!("replay: {e}")))?;
    let mut bytes = vec![0u8; MAX_OUTCOME_BYTES];
    let n = encode_outcome(&outcome, &mut bytes).map_err(|e| InputError::file(source, format!("replay: {e}")))?;
    let header = read_header(&mut &file[..]).map_err(|e| InputError::file(source, format!("replay: {e}")))?;
    let decoded = decode_outcome(&header, &bytes[..n]).map_err(|e| InputError::file(source, format!("replay: {e}")))?;
    calibration_from_outcome(rec, options, &attitudes, &decoded)
}
