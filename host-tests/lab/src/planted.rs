//! Hidden effects in MEASURED noise (docs/analysis.md#hidden-effects-in-measured-noise): the trials of
//! [`crate::hidden`] with the simulated white noise replaced by the noise of a real recording.
//!
//! **Construction** ([`Construction`]). One static stretch of a measured record (one real pose: a stretch of
//! the PSINS record over which its vehicle does not tilt, [`constant_pose_stretches`]; the first static
//! interval of the imu_tk record) is cut into the dwells of a schedule of known poses, the paper's Table 1
//! ([`Layout`]). Every sample becomes its measured value minus the session's own straight line (the
//! record's slow drift over the session, removed through its quantiser: `session_drift`), plus what its
//! pose predicts (the Earth rate and gravity through the pose's `C_b^n`) plus the clean scenario's constant
//! biases. One line per channel is removed and one constant per dwell added: the sample-to-sample values,
//! the dwell-to-dwell wander, and with them the Allan curve, the correlation and the quantisation lattice of
//! the differences are the measured ones. (Centring each stretch of a different real pose on its own mean
//! would leave dwell means without noise; the multi-pose records are therefore used through one static
//! stretch only.)
//!
//! **Planting** ([`plant`]). One effect of the catalogue, by the sensor model of docs/conventions.md (the
//! same as the simulator's): effects constant within a dwell (scale factors, misalignments, g-sensitivity,
//! reference offset, position error) are added as that constant; effects that move within a dwell (drift,
//! warm-up, vibration, correlated noise) are added through a quantiser with the measured record's step, so
//! that a quantised channel stays on its lattice: for the PSINS increments the remainder is carried from
//! sample to sample as a pulse-output sensor does, from the record's unknown remainder drawn uniform
//! (`carried_with_unknown_carry`), for the imu_tk sampled counts the sum is rounded again with the record's
//! unknown rounding error drawn uniform (`sample_quantised`); a planted quantisation requantises the
//! channel to a coarser step. The planting itself ([`plant_into`]) takes any record with its poses
//! ([`Base`]); [`crate::own_poses`] plants in the records' own poses.
//!
//! **Magnitudes** ([`draw`]): 10 to 20 standard errors of the effect in that construction. For the effects
//! linear in their parameter the standard error is the one `sinscal analyze` gives the candidate fitted
//! with the base model alone on the untouched construction (the measured block noise and the design); a
//! dimensionless or angle term is planted only where 20 standard errors stay below [`LINEAR_LIMIT`]. The
//! others follow [`crate::hidden`] with the measured noise: warm-up from the base model's block
//! residual RMS, vibration from the noise density at the line's frequency, correlated noise and
//! quantisation from the detrended RMS of the samples.

use std::collections::BTreeMap;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::hidden::{catalogue, Hidden};
use sinscal_host::analysis::{analyze_recording, Analysis, Effect, BLOCK_SAMPLES, CHANNELS, MAX_BLOCKS_PER_DWELL};
use sinscal_host::calibration::site_of;
use sinscal_host::io::error::InputError;
use sinscal_host::io::recording::{Header, Recording, Row};
use sinscal_host::model::catalogue::{EffectKind, Sensor};
use sinscal_host::model::sensor::Term;
use sinscal_host::model::simulator::{clean_scenario, normal};
use sinscal_host::model::synth::{c_b_n, earth_rate_n_radps, mul, mul_t_vec, rotation, M3, TABLE1_DEG};
use sinscal_host::stats::noise::{detect_quantization, welch_psd};

/// The measured records the trials take their noise from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Source {
    /// The PSINS ring-laser-gyro record: one static pose, 100 Hz, 30.8 min (docs/data.md#psins-lasergyro).
    Psins,
    /// The first static interval of the imu_tk Xsens record: one pose, 100 Hz, 52 s
    /// (docs/data.md#imu-tk-xsens).
    Imutk,
}

impl Source {
    /// How the record's quantised channels take a planted signal.
    pub fn quantiser(self) -> Quantiser {
        match self {
            Source::Psins => Quantiser::Carried,
            Source::Imutk => Quantiser::Sampled,
        }
    }

    /// The data set's folder name.
    pub fn name(self) -> &'static str {
        match self {
            Source::Psins => "psins-lasergyro",
            Source::Imutk => "imu-tk-xsens",
        }
    }
}

/// How a record's quantised channel is read out, and so how a signal planted on it is quantised
/// ([`plant_into`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantiser {
    /// Increments of a pulse-output sensor (the PSINS record): the quantiser carries its remainder from
    /// sample to sample (`carried_with_unknown_carry`).
    Carried,
    /// Sampled counts (imu_tk, the imucal BMI160): each sample is rounded on its own, with an unknown
    /// rounding error (`sample_quantised`).
    Sampled,
}

/// What planting needs of a base recording: its rows, the site's Earth rate and specific force at rest, and
/// per channel the record's quantisation step and how its quantiser reads out.
#[derive(Clone, Copy, Debug)]
pub struct Base<'a> {
    /// The untouched recording.
    pub recording: &'a Recording,
    /// Per position label, the `C_b^n` the planting takes as the sensor's attitude instead of the one its rows
    /// state (a record levelled from its own raw accelerometers states attitudes that carry its biases).
    pub attitudes: Option<&'a BTreeMap<u32, M3>>,
    /// Earth rate in the navigation frame, rad/s.
    pub w_n_radps: [f64; 3],
    /// Specific force at rest in the navigation frame, m/s^2.
    pub f_n_mps2: [f64; 3],
    /// Per channel (gx..az): the record's quantisation step, SI, when its samples are quantised.
    pub steps_si: [Option<f64>; 6],
    /// How the quantised channels read out.
    pub quantiser: Quantiser,
}

/// Body axis names.
const AXES: [&str; 3] = ["x", "y", "z"];
/// Per-channel axes as [`catalogue`] names them.
const CHANNEL_AXES: [&str; 6] = ["gx", "gy", "gz", "ax", "ay", "az"];

/// A measured record laid over known poses: the untouched base of the trials.
#[derive(Clone, Debug)]
pub struct Construction {
    /// Where the noise comes from.
    pub source: Source,
    /// Which part of the record and which poses ("offset 120 s", "poses shifted by 2").
    pub segmentation: String,
    /// The untouched construction.
    pub recording: Recording,
    /// Per row of `recording`: the row of the measured record it came from.
    pub source_rows: Vec<usize>,
    /// Per row of `recording`, per channel (gx..az): the record's own drift over the session removed from it,
    /// SI (`session_drift`).
    pub drift_removed_si: Vec<[f64; 6]>,
    /// Per channel (gx..az): the measured record's quantisation step, SI, when its samples are quantised.
    pub steps_si: [Option<f64>; 6],
    /// Earth rate in the navigation frame, rad/s.
    pub w_n_radps: [f64; 3],
    /// Specific force at rest in the navigation frame, m/s^2.
    pub f_n_mps2: [f64; 3],
}

impl Construction {
    /// The construction as the base of a planting.
    pub fn base(&self) -> Base<'_> {
        Base {
            recording: &self.recording,
            attitudes: None,
            w_n_radps: self.w_n_radps,
            f_n_mps2: self.f_n_mps2,
            steps_si: self.steps_si,
            quantiser: self.source.quantiser(),
        }
    }
}

/// A stretch of the measured record placed at one pose (`pos` 0: between dwells).
struct Piece {
    rows: Vec<usize>,
    pos: u32,
    pose_deg: [f64; 3],
}

/// Channel `c` (gx..az) of a row.
fn channel(row: &Row, c: usize) -> f64 {
    if c < 3 {
        row.rate_b_radps[c]
    } else {
        row.force_b_mps2[c - 3]
    }
}

/// The clean scenario's constant biases, gx..az, SI.
fn biases_si() -> [f64; 6] {
    let s = clean_scenario();
    std::array::from_fn(|c| if c < 3 { s.gyro.bias_radps[c] } else { s.accel.bias_mps2[c - 3] })
}

/// How a schedule of Table 1 poses is laid over one static stretch of a record: each position is `settle_s`
/// of rows between dwells, then a dwell of `dwell_s`, with `move_s` more between positions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layout {
    /// Dwell, s.
    pub dwell_s: f64,
    /// Rows before each dwell that belong to none, s.
    pub settle_s: f64,
    /// Rows between positions that belong to none, s.
    pub move_s: f64,
}

/// The PSINS sessions: the clean scenario's schedule (1 s settling, 60 s dwells, 5 s moves: 391 s).
pub const PSINS_LAYOUT: Layout = Layout { dwell_s: 60.0, settle_s: 1.0, move_s: 5.0 };

/// The imu_tk sessions: six dwells of 8 s, 0.5 s apart, in the record's first static interval (52 s).
pub const IMUTK_LAYOUT: Layout = Layout { dwell_s: 8.0, settle_s: 0.5, move_s: 0.0 };

/// One session laid over `stretch` (rows of `record` in time order, one real pose) from its row `start`,
/// position k of the session at pose `(k + shift) mod 6` of Table 1; `None` when the stretch is too short.
fn session(
    record: &Recording,
    source: Source,
    stretch: &[usize],
    start: usize,
    layout: Layout,
    shift: usize,
) -> Option<Construction> {
    let rate_hz = record.header.rate_hz.unwrap_or(100.0);
    let n = |s: f64| (s * rate_hz).round() as usize;
    let positions = TABLE1_DEG.len();
    let mut pieces = Vec::new();
    let mut i = start;
    for p in 0..positions {
        let pose_deg = TABLE1_DEG[(p + shift) % positions];
        for (len, pos) in
            [(if p > 0 { n(layout.move_s) } else { 0 }, 0), (n(layout.settle_s), 0), (n(layout.dwell_s), p as u32 + 1)]
        {
            pieces.push(Piece { rows: stretch.get(i..i + len)?.to_vec(), pos, pose_deg });
            i += len;
        }
    }
    let offset_s = record.rows[stretch[start]].t_s - record.rows[stretch[0]].t_s;
    let segmentation = format!("offset {offset_s:.0} s, poses shifted by {shift}");
    Some(construct(record, source, segmentation, &pieces))
}

/// Largest change of the horizontal specific force between successive [`TILT_WINDOW_S`] means within one
/// pose, m/s^2: 2e-3 m/s^2 is a tilt of 0.2 mrad. The parked vehicle of the PSINS record tilts in steps of 1
/// to 3 mrad (someone moving in or around it; docs/analysis.md#hidden-effects-in-measured-noise): a session
/// across such a step carries a real attitude change, not noise.
pub const TILT_STEP_MPS2: f64 = 2e-3;

/// Window of the means that [`TILT_STEP_MPS2`] compares, s.
pub const TILT_WINDOW_S: f64 = 10.0;

/// The stretches of `record` (row ranges, half-open) over which its pose is constant: maximal runs of
/// [`TILT_WINDOW_S`] windows whose horizontal accelerometer means (x and y) change by at most
/// [`TILT_STEP_MPS2`] from one window to the next.
pub fn constant_pose_stretches(record: &Recording) -> Vec<(usize, usize)> {
    let rate_hz = record.header.rate_hz.unwrap_or(100.0);
    let w = ((TILT_WINDOW_S * rate_hz).round() as usize).max(1);
    let means: Vec<[f64; 2]> = record
        .rows
        .chunks_exact(w)
        .map(|rows| {
            let m = |c: usize| rows.iter().map(|r| r.force_b_mps2[c]).sum::<f64>() / w as f64;
            [m(0), m(1)]
        })
        .collect();
    let mut stretches = Vec::new();
    let mut first = 0;
    for k in 1..=means.len() {
        let step = k == means.len() || (0..2).any(|c| (means[k][c] - means[k - 1][c]).abs() > TILT_STEP_MPS2);
        if step {
            stretches.push((first * w, k * w));
            first = k;
        }
    }
    stretches
}

/// Sessions of the one-pose PSINS record ([`PSINS_LAYOUT`]) at `count` start times spread evenly over the
/// start times that keep the whole session inside one stretch of constant pose
/// ([`constant_pose_stretches`]); the sessions overlap when `count` exceeds what those stretches hold.
pub fn psins_constructions(record: &Recording, count: usize) -> Vec<Construction> {
    let all: Vec<usize> = (0..record.rows.len()).collect();
    let rate_hz = record.header.rate_hz.unwrap_or(100.0);
    let l = PSINS_LAYOUT;
    let session_rows = ((6.0 * (l.dwell_s + l.settle_s) + 5.0 * l.move_s) * rate_hz).round() as usize;
    let starts: Vec<(usize, usize)> = constant_pose_stretches(record)
        .into_iter()
        .filter(|(a, b)| b - a >= session_rows)
        .map(|(a, b)| (a, b - session_rows))
        .collect();
    let span: usize = starts.iter().map(|(a, b)| b - a).sum();
    // The k-th of `count` evenly spread points of the concatenated ranges of start rows.
    let start_at = |mut offset: usize| {
        for &(a, b) in &starts {
            if offset <= b - a {
                return Some(a + offset);
            }
            offset -= b - a + 1;
        }
        None
    };
    (0..count)
        .filter_map(|k| {
            let offset = if count > 1 { k * span / (count - 1) } else { 0 };
            session(record, Source::Psins, &all, start_at(offset)?, l, 0)
        })
        .collect()
}

/// Sessions in the first static interval of the imu_tk import (one real pose, z up, 52 s; [`IMUTK_LAYOUT`]):
/// the same noise at the six shifts of the Table 1 poses, `shift` = 0 .. `shifts - 1`.
pub fn imutk_constructions(record: &Recording, shifts: usize) -> Vec<Construction> {
    let first = record.rows.iter().map(|r| r.pos).find(|&p| p != 0).unwrap_or(0);
    let stretch: Vec<usize> = (0..record.rows.len()).filter(|&i| record.rows[i].pos == first && first != 0).collect();
    if stretch.is_empty() {
        return Vec::new();
    }
    (0..shifts).filter_map(|shift| session(record, Source::Imutk, &stretch, 0, IMUTK_LAYOUT, shift)).collect()
}

/// Mean of each channel over `rows` of `record`.
fn mean_of(record: &Recording, rows: impl Iterator<Item = usize>) -> [f64; 6] {
    let (mut sum, mut n) = ([0.0; 6], 0usize);
    for i in rows {
        for (c, s) in sum.iter_mut().enumerate() {
            *s += channel(&record.rows[i], c);
        }
        n += 1;
    }
    sum.map(|s| s / n.max(1) as f64)
}

/// The construction of `pieces` of `record` (see the module's documentation).
fn construct(record: &Recording, source: Source, segmentation: String, pieces: &[Piece]) -> Construction {
    let (site, _) = site_of(&record.header);
    let f_n_mps2 = [0.0, 0.0, site.gravity_mps2 as f64];
    let w_n_radps = earth_rate_n_radps(record.header.latitude_deg.to_radians());
    let bias = biases_si();
    let dwell_rows = || pieces.iter().filter(|p| p.pos != 0).flat_map(|p| p.rows.iter().copied());
    let session_mean = mean_of(record, dwell_rows());
    let t_start = pieces.iter().find_map(|p| p.rows.first()).map_or(0.0, |&i| record.rows[i].t_s);
    let steps_si: [Option<f64>; 6] = std::array::from_fn(|c| {
        let raw: Vec<f64> = dwell_rows().map(|i| channel(&record.rows[i], c)).collect();
        detect_quantization(&raw).ok().filter(|q| q.quantized).map(|q| q.step)
    });
    let all_rows: Vec<usize> = pieces.iter().flat_map(|p| p.rows.iter().copied()).collect();
    let drift = session_drift(record, &dwell_rows().collect::<Vec<_>>(), session_mean, &all_rows, &steps_si);
    let (mut rows, mut source_rows) = (Vec::new(), Vec::new());
    for piece in pieces {
        let [pitch, roll, heading] = piece.pose_deg;
        let c = c_b_n(pitch, roll, heading);
        let (w_b, f_b) = (mul_t_vec(&c, w_n_radps), mul_t_vec(&c, f_n_mps2));
        let predicted: [f64; 6] = std::array::from_fn(|k| if k < 3 { w_b[k] } else { f_b[k - 3] });
        for &i in &piece.rows {
            let r = &record.rows[i];
            let removed = drift[rows.len()];
            let out: [f64; 6] =
                std::array::from_fn(|k| channel(r, k) - session_mean[k] - removed[k] + predicted[k] + bias[k]);
            rows.push(Row {
                t_s: r.t_s - t_start,
                pos: piece.pos,
                pitch_deg: pitch,
                roll_deg: roll,
                heading_deg: Some(heading.rem_euclid(360.0)),
                rate_b_radps: [out[0], out[1], out[2]],
                force_b_mps2: [out[3], out[4], out[5]],
                temp_c: r.temp_c,
                turn_axis: None,
                line: r.line,
            });
            source_rows.push(i);
        }
    }
    let header = Header {
        latitude_deg: record.header.latitude_deg,
        height_m: record.header.height_m,
        rate_hz: record.header.rate_hz,
        gravity_mps2: record.header.gravity_mps2,
        comments: vec![format!(
            "measured noise of {} ({segmentation}) around the poses of the paper's Table 1, with the clean \
             scenario's biases: the base of the planted-effect trials",
            source.name()
        )],
        truth: None,
        pose_tolerance_deg: None,
    };
    let source_name = format!("{} ({segmentation})", source.name());
    Construction {
        source,
        segmentation,
        recording: Recording { source: source_name, header, rows, has_gyro: true },
        source_rows,
        drift_removed_si: drift,
        steps_si,
        w_n_radps,
        f_n_mps2,
    }
}

/// The record's own drift over a session, removed from every row of it (`rows`, in order): per channel the
/// least-squares line of the session's dwell samples (`dwell_rows`, whose means are `dwell_mean_si`) against
/// time, less its value at their mean time, so that the session mean stays. A quantised channel (`steps_si`) has the line removed through
/// the quantiser that carries its remainder, so that the channel stays on its lattice. A measured record is
/// not free of slow effects (the PSINS vehicle's tilt drifts by about 0.5 urad/s on its quiet stretches;
/// docs/analysis.md#hidden-effects-in-measured-noise): without this the untouched construction carries a
/// bias drift that the analysis rightly finds.
fn session_drift(
    record: &Recording,
    dwell_rows: &[usize],
    dwell_mean_si: [f64; 6],
    rows: &[usize],
    steps_si: &[Option<f64>; 6],
) -> Vec<[f64; 6]> {
    let n = dwell_rows.len().max(1) as f64;
    let t_mean = dwell_rows.iter().map(|&i| record.rows[i].t_s).sum::<f64>() / n;
    let stt: f64 = dwell_rows.iter().map(|&i| (record.rows[i].t_s - t_mean).powi(2)).sum();
    let mut removed = vec![[0.0; 6]; rows.len()];
    for c in 0..6 {
        let sty: f64 = dwell_rows
            .iter()
            .map(|&i| (record.rows[i].t_s - t_mean) * (channel(&record.rows[i], c) - dwell_mean_si[c]))
            .sum();
        let slope = if stt > 0.0 { sty / stt } else { 0.0 };
        let line: Vec<f64> = rows.iter().map(|&i| slope * (record.rows[i].t_s - t_mean)).collect();
        let line = match steps_si[c] {
            Some(q) => carry_quantised(&line, q),
            None => line,
        };
        for (r, v) in removed.iter_mut().zip(line) {
            r[c] = v;
        }
    }
    removed
}

/// The blocks of a dwell of `n` samples, as the analysis cuts them (docs/analysis.md#observations).
pub(crate) fn block_ranges(n: usize) -> Vec<(usize, usize)> {
    let blocks = (n / BLOCK_SAMPLES).clamp(4, MAX_BLOCKS_PER_DWELL).min(n / 16).max(1);
    (0..blocks).map(|b| (b * n / blocks, (b + 1) * n / blocks)).collect()
}

/// What the untouched construction says about its noise, for the magnitudes of the planted effects.
#[derive(Clone, Debug)]
pub(crate) struct Reference {
    /// Standard error of every linear candidate fitted with the base model alone, by the analysis's name.
    pub(crate) std_error: BTreeMap<String, f64>,
    /// Per channel: RMS residual of the block means after the base model.
    block_sigma: [f64; 6],
    /// Per channel: RMS of the samples after each dwell's mean and trend.
    pub(crate) sample_sigma: [f64; 6],
    /// Per channel: one-sided noise density averaged over the dwells (frequencies, Hz; density, SI^2/Hz).
    pub(crate) spectra: Vec<(Vec<f64>, Vec<f64>)>,
    /// The sample times of every block (all dwells), s.
    block_times: Vec<Vec<f64>>,
    /// Samples of each dwell.
    pub(crate) dwell_samples: Vec<usize>,
    /// Sample rate, Hz.
    pub(crate) rate_hz: f64,
    /// Position labels.
    positions: Vec<u32>,
}

impl Reference {
    /// Samples in the dwells.
    pub(crate) fn samples(&self) -> usize {
        self.dwell_samples.iter().sum()
    }

    /// What the analysis `untouched` of `rec` says about its noise.
    pub(crate) fn new(rec: &Recording, untouched: &Analysis) -> Reference {
        let dwells = rec.dwells();
        let rate_hz = rec.header.rate_hz.unwrap_or(100.0);
        let shortest = dwells.iter().map(|d| d.rows.len()).min().unwrap_or(0);
        let segment = (1usize..=10).map(|k| 1usize << k).filter(|&l| l <= shortest.min(1024)).max().unwrap_or(2);
        let spectra = (0..6)
            .map(|ch| {
                let (mut freqs, mut sum, mut weight) = (Vec::new(), Vec::new(), 0.0);
                for d in &dwells {
                    let y: Vec<f64> = d.rows.iter().map(|r| channel(r, ch)).collect();
                    let Ok(psd) = welch_psd(&y, rate_hz, segment) else { continue };
                    if sum.is_empty() {
                        sum = vec![0.0; psd.density.len()];
                        freqs = psd.frequencies_hz.clone();
                    }
                    let w = psd.segments as f64;
                    sum.iter_mut().zip(&psd.density).for_each(|(s, d)| *s += w * d);
                    weight += w;
                }
                (freqs, sum.into_iter().map(|s| s / weight.max(1.0)).collect())
            })
            .collect();
        let block_times = dwells
            .iter()
            .flat_map(|d| {
                block_ranges(d.rows.len()).into_iter().map(|(a, b)| d.rows[a..b].iter().map(|r| r.t_s).collect())
            })
            .collect();
        let by_channel =
            |map: &BTreeMap<String, f64>| std::array::from_fn(|ch| map.get(CHANNELS[ch]).copied().unwrap_or(0.0));
        Reference {
            std_error: untouched.tested.iter().map(|t| (t.name.clone(), t.std_error)).collect(),
            block_sigma: by_channel(&untouched.base_model.block_residual_rms),
            sample_sigma: std::array::from_fn(|ch| untouched.diagnostics.get(ch).map_or(0.0, |d| d.detrended_rms)),
            spectra,
            block_times,
            dwell_samples: dwells.iter().map(|d| d.rows.len()).collect(),
            rate_hz,
            positions: dwells.iter().map(|d| d.pos).collect(),
        }
    }

    /// The per-sample white noise that would have the channel's measured noise density at `f_hz`: the median
    /// of the density over the bins within 20 % of `f_hz` (at least two bins either side), `sqrt(S rate / 2)`.
    pub(crate) fn line_sigma(&self, ch: usize, f_hz: f64) -> f64 {
        let (freqs, density) = &self.spectra[ch];
        let resolution = freqs.get(1).copied().unwrap_or(1.0);
        let half_width = (0.2 * f_hz).max(2.0 * resolution);
        let mut near: Vec<f64> = freqs
            .iter()
            .zip(density)
            .skip(2)
            .filter(|(f, _)| (*f - f_hz).abs() <= half_width)
            .map(|(_, d)| *d)
            .collect();
        near.sort_by(f64::total_cmp);
        let s = near.get(near.len() / 2).copied().unwrap_or(0.0);
        (s * self.rate_hz / 2.0).sqrt()
    }
}

/// A construction analysed untouched: the false-alarm trial and the reference of the planted trials.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The construction.
    pub construction: Construction,
    /// `sinscal analyze` of the untouched construction: every effect it reports is a false alarm.
    pub untouched: Analysis,
    reference: Reference,
}

/// Analyses the untouched construction.
pub fn prepare(construction: Construction) -> Result<Prepared, InputError> {
    let untouched = analyze_recording(&construction.recording)?;
    let reference = Reference::new(&construction.recording, &untouched);
    Ok(Prepared { construction, untouched, reference })
}

/// Largest planted scale factor or misalignment (1) or table attitude error (rad): 20 standard errors above
/// it would leave the small-error model the analysis fits (a gyro that does not resolve the Earth rate).
pub const LINEAR_LIMIT: f64 = 0.1;

/// The effects a construction can carry, with their axes ([`catalogue`]: the Table 1 poses see and tell
/// apart the same terms as the simulated trials); temperature only with a temperature column; dimensionless
/// and angle terms only on the axes where 20 standard errors (at every position) stay below
/// [`LINEAR_LIMIT`].
pub fn carried(p: &Prepared) -> Vec<(EffectKind, Vec<&'static str>)> {
    let has_temp = p.construction.recording.rows.iter().all(|r| r.temp_c.is_some());
    let r = &p.reference;
    let small = |effect: EffectKind, axes: &str| -> bool {
        if !matches!(effect.unit(Sensor::Gyro), "1" | "rad") {
            return true;
        }
        let names: Vec<String> = match effect {
            EffectKind::PositionError => r.positions.iter().map(|q| format!("{effect}:{axes}:pos{q}")).collect(),
            _ => vec![format!("{effect}:{axes}")],
        };
        names.iter().all(|n| r.std_error.get(n).is_some_and(|se| 20.0 * se <= LINEAR_LIMIT))
    };
    catalogue()
        .into_iter()
        .filter_map(|(name, axes)| name.parse::<EffectKind>().ok().map(|e| (e, axes)))
        .filter(|(e, _)| has_temp || *e != EffectKind::TemperatureBias)
        .map(|(e, axes)| (e, axes.into_iter().filter(|a| small(e, a)).collect::<Vec<_>>()))
        .filter(|(_, axes)| !axes.is_empty())
        .collect()
}

/// The truth of a planted trial and the random numbers its planting needs.
#[derive(Clone, Debug)]
pub struct Planted {
    /// The truth, as [`crate::hidden`] states it.
    pub hidden: Hidden,
    /// Vibration phase, rad.
    pub phase_rad: f64,
    /// Seed of the correlated noise.
    pub seed: u64,
}

/// The analysis's name of the candidate that estimates `h` ("accel_scale_factor:xz",
/// "position_error:e:pos3", "bias_drift:x (gyro)").
pub fn candidate_name(h: &Hidden) -> String {
    match h.pos {
        Some(p) => format!("{}:{}:pos{p}", h.effect, h.axes),
        None if h.effect.sensor().is_none() => format!("{}:{} ({})", h.effect, h.axes, h.sensor),
        None => format!("{}:{}", h.effect, h.axes),
    }
}

/// Euclidean norm of `v` after its mean is removed.
fn centred_norm(v: &[f64]) -> f64 {
    let m = v.iter().sum::<f64>() / v.len().max(1) as f64;
    v.iter().map(|x| (x - m) * (x - m)).sum::<f64>().sqrt()
}

/// Draws trial `seed` of `effect` on `p`: axes, sign and 10 to 20 standard errors as the simulated trials
/// draw them; warm-up time constants of 5 to 26 % of the session (20 to 100 s on PSINS, as in the simulated
/// trials; 10 to 20 s on imu_tk's 52 s), correlated-noise time constants of 0.2 to 2 s, frequencies 0.3 to
/// 30 Hz, quantisation steps 0.3 to 3 times the noise per sample.
pub fn draw(p: &Prepared, effect: EffectKind, seed: u64) -> Result<Planted, String> {
    let r = &p.reference;
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ effect.name().len() as u64);
    let axes_list = carried(p).into_iter().find(|(e, _)| *e == effect).map(|(_, a)| a);
    let axes_list = axes_list.ok_or_else(|| format!("{effect}: not carried by {}", p.construction.recording.source))?;
    let axes = axes_list[rng.random_range(0..axes_list.len())];
    let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
    let snr: f64 = rng.random_range(10.0..20.0);
    let ch = CHANNEL_AXES.iter().position(|a| *a == axes).unwrap_or(0);
    let (sensor, hidden_axes) = match effect.sensor() {
        Some(s) => (s, axes),
        None => (Sensor::of_channel(ch), AXES[ch % 3]),
    };
    let mut h = Hidden::new(effect, sensor, hidden_axes);
    if effect == EffectKind::PositionError {
        h.pos = Some(r.positions[rng.random_range(0..r.positions.len())]);
    }
    let se = |h: &Hidden| {
        r.std_error.get(&candidate_name(h)).copied().ok_or_else(|| format!("{}: not tested", candidate_name(h)))
    };
    let value = match effect {
        EffectKind::Vibration => {
            let f = rng.random_range(0.3..30.0);
            h.frequency_hz = Some(f);
            snr * r.line_sigma(ch, f) * (2.0 / r.samples() as f64).sqrt()
        }
        EffectKind::BiasWarmup => {
            // 5 to 26 % of the session, as 20 to 100 s are of the simulated trials' 391 s, and at least 10 s
            // (twice the shortest time constant the analysis tries): a warm-up that outlasts the session is a
            // drift there.
            let session_s = r.block_times.iter().flatten().fold(0.0f64, |m, &t| m.max(t));
            let tau_lo_s = (0.05 * session_s).max(10.0);
            let tau = rng.random_range(tau_lo_s..(0.26 * session_s).max(2.0 * tau_lo_s));
            h.tau_s = Some(tau);
            let shape: Vec<f64> = r
                .block_times
                .iter()
                .map(|t| t.iter().map(|t| (-t / tau).exp()).sum::<f64>() / t.len() as f64)
                .collect();
            sign * snr * 1.5 * r.block_sigma[ch] / centred_norm(&shape)
        }
        EffectKind::CorrelatedNoise => {
            h.tau_s = Some(rng.random_range(0.2..2.0));
            rng.random_range(1.0..3.0) * r.sample_sigma[ch]
        }
        EffectKind::Quantization => rng.random_range(0.3..3.0) * r.sample_sigma[ch],
        EffectKind::TemperatureBias => return Err("temperature_bias: no temperature column".into()),
        _ => sign * snr * se(&h)?,
    };
    h.value = value;
    Ok(Planted { hidden: h, phase_rad: rng.random::<f64>() * std::f64::consts::TAU, seed })
}

/// The term of the sensor model that `effect` on `axes` ("xz", "x") names.
fn term_of(effect: EffectKind, axes: &str) -> Option<Term> {
    Term::all(true).into_iter().find(|t| {
        let name = if t.axis == t.along && effect != EffectKind::GyroGSensitivity {
            AXES[t.axis].to_string()
        } else {
            format!("{}{}", AXES[t.axis], AXES[t.along])
        };
        t.effect == effect && name == axes
    })
}

/// Navigation axis of "e", "n", "u".
fn enu_axis(axes: &str) -> usize {
    match axes {
        "e" => 0,
        "n" => 1,
        _ => 2,
    }
}

/// The construction with the planted effect (see the module's documentation).
pub fn plant(c: &Construction, planted: &Planted) -> Recording {
    plant_into(&c.base(), planted)
}

/// `base`'s recording with the planted effect, by the sensor model (see the module's documentation): the
/// effects constant within a dwell added as that constant at each row's pose, the moving ones through the
/// record's quantiser, a planted quantisation as the channel requantised.
pub fn plant_into(base: &Base, planted: &Planted) -> Recording {
    let mut rec = base.recording.clone();
    let h = &planted.hidden;
    let ch = if h.sensor == Sensor::Gyro { 0 } else { 3 } + AXES.iter().position(|a| *a == h.axes).unwrap_or(0);
    match h.effect {
        EffectKind::Quantization => requantise(&mut rec, ch, h.value),
        // Off the lattice: through the record's quantiser, with the rounding the record made drawn afresh, a
        // white noise weaker than a step would add about `0.8 e q` to the variance where the sensor's own
        // noise (which dithers its quantiser) would add `e^2` (PSINS accelerometers: twice the excess).
        EffectKind::NoiseWarmup => {
            let signal = moving_signal(&rec, planted);
            for (row, s) in rec.rows.iter_mut().zip(signal) {
                add(row, ch, s);
            }
        }
        EffectKind::BiasDrift | EffectKind::BiasWarmup | EffectKind::Vibration | EffectKind::CorrelatedNoise => {
            let signal = moving_signal(&rec, planted);
            let signal = match (base.steps_si[ch], base.quantiser) {
                (Some(q), Quantiser::Carried) => carried_with_unknown_carry(&signal, q, planted.seed ^ 0x5eed),
                (Some(q), Quantiser::Sampled) => sample_quantised(&signal, q, planted.seed ^ 0x5eed),
                (None, _) => signal,
            };
            for (row, s) in rec.rows.iter_mut().zip(signal) {
                add(row, ch, s);
            }
        }
        _ => {
            for row in rec.rows.iter_mut() {
                let delta = static_signal(base, h, row);
                for (k, d) in delta.iter().enumerate() {
                    add(row, k, *d);
                }
            }
        }
    }
    rec.source = format!("{} with {} planted", base.recording.source, candidate_name(h));
    rec
}

/// Adds `v` to channel `c` of `row`.
fn add(row: &mut Row, c: usize, v: f64) {
    if c < 3 {
        row.rate_b_radps[c] += v;
    } else {
        row.force_b_mps2[c - 3] += v;
    }
}

/// The change of the six channels of `row` that a constant effect makes at its pose (an unknown heading
/// taken as 0: the analysis uses the Earth rate of such a pose only along a vertical axis, where the heading
/// does not matter).
fn static_signal(c: &Base, h: &Hidden, row: &Row) -> [f64; 6] {
    let stated = || c_b_n(row.pitch_deg, row.roll_deg, row.heading_deg.unwrap_or(0.0));
    let cbn = c.attitudes.and_then(|a| a.get(&row.pos).copied()).unwrap_or_else(stated);
    let (w_b, f_b) = (mul_t_vec(&cbn, c.w_n_radps), mul_t_vec(&cbn, c.f_n_mps2));
    let mut delta = [0.0; 6];
    match h.effect {
        EffectKind::ReferenceOffset | EffectKind::PositionError => {
            if h.pos.is_some_and(|p| p != row.pos) {
                return delta;
            }
            // C_true = (I - [err x]) C_ref, exactly: a rotation by -err (docs/conventions.md#reference-errors).
            let mut err = [0.0; 3];
            err[enu_axis(&h.axes)] = -h.value;
            let c_true: M3 = mul(&rotation(err), &cbn);
            let (w_t, f_t) = (mul_t_vec(&c_true, c.w_n_radps), mul_t_vec(&c_true, c.f_n_mps2));
            for k in 0..3 {
                delta[k] = w_t[k] - w_b[k];
                delta[3 + k] = f_t[k] - f_b[k];
            }
        }
        effect => {
            if let Some(t) = term_of(effect, &h.axes) {
                delta[t.channel()] = h.value * t.per_unit(w_b, f_b);
            }
        }
    }
    delta
}

/// A drift, warm-up, vibration or Gauss-Markov signal at every row, each sample the average over its
/// interval as the simulator makes it (the Gauss-Markov process at the sample times, started stationary).
/// Time runs from the recording's first row, the warm-up's origin in the analysis.
fn moving_signal(rec: &Recording, planted: &Planted) -> Vec<f64> {
    let h = &planted.hidden;
    let dt = 1.0 / rec.header.rate_hz.unwrap_or(100.0);
    let tau = h.tau_s.unwrap_or(1.0);
    let mut markov_rng = ChaCha8Rng::seed_from_u64(planted.seed ^ 0x5E_ED0F_6A55);
    let mut x = h.value * normal(&mut markov_rng);
    let t0 = rec.rows.first().map_or(0.0, |r| r.t_s);
    let mut last_t = 0.0;
    rec.rows
        .iter()
        .map(|r| {
            let t = r.t_s - t0;
            match h.effect {
                EffectKind::BiasDrift => h.value * (t + 0.5 * dt),
                EffectKind::BiasWarmup => h.value * tau / dt * ((-t / tau).exp() - (-(t + dt) / tau).exp()),
                EffectKind::Vibration => {
                    let w = std::f64::consts::TAU * h.frequency_hz.unwrap_or(1.0);
                    let p = planted.phase_rad;
                    h.value / (w * dt) * ((w * t + p).cos() - (w * (t + dt) + p).cos())
                }
                // White noise of the excess standard deviation until the noise has settled.
                EffectKind::NoiseWarmup if t < h.settled_s.unwrap_or(0.0) => h.value * normal(&mut markov_rng),
                EffectKind::NoiseWarmup => 0.0,
                _ => {
                    let phi = (-(t - last_t) / tau).exp();
                    x = phi * x + h.value * (1.0 - phi * phi).sqrt() * normal(&mut markov_rng);
                    last_t = t;
                    x
                }
            }
        })
        .collect()
}

/// `signal` delivered through a quantiser of step `q` that carries its remainder from sample to sample:
/// every output is a multiple of `q` and the running sum is kept within `q / 2`.
fn carry_quantised(signal: &[f64], q: f64) -> Vec<f64> {
    let mut carry = 0.0;
    signal
        .iter()
        .map(|s| {
            let total = carry + s / q;
            let steps = total.round();
            carry = total - steps;
            steps * q
        })
        .collect()
}

/// `signal` added to the output of a quantiser that carries its remainder (a pulse-output sensor, as the PSINS
/// increments are): the record's sample is on the lattice, what the sensor's quantiser carried after each
/// sample is unknown and is drawn uniform over a step (seeded, independent from sample to sample, as the
/// remainder of a sensor whose noise spans many steps is), and the quantiser is run again on the record's
/// input plus `signal` from the same remainder. Every output is a multiple of `q`; with `signal` zero it is
/// zero (the record comes back unchanged); the running sum of the outputs stays within a step of the
/// signal's. Quantising the signal alone (`carry_quantised`) would not do: a line whose integral stays within
/// half a step comes out as no pulse at all (measured: a 0.048 m/s^2 line at 27.7 Hz on the PSINS
/// accelerometers, step 0.122 m/s^2, vanished; with this quantiser it is found at 0.0489).
fn carried_with_unknown_carry(signal: &[f64], q: f64, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // The sensor's carry less the record's, after the previous sample: it starts at 0 (the same sensor) and
    // stays within (-1, 1).
    let mut lead = 0.0;
    signal
        .iter()
        .map(|s| {
            let record_carry = rng.random::<f64>() - 0.5;
            let steps = (lead + record_carry + s / q).round();
            lead += s / q - steps;
            steps * q
        })
        .collect()
}

/// `signal` added to samples of a sampling quantiser of step `q` (a sensor that outputs sampled counts, as
/// the imu_tk record does): the measured sample is on the lattice, what the quantiser rounded away is unknown
/// and is drawn uniform over a step (seeded), and the sum is rounded again. Every output is a multiple of
/// `q`, and its mean is `signal` (a uniform rounding error makes the rounding unbiased). Quantising the
/// signal alone would not do: a line weaker than a step at a quarter of the sample rate comes out 1.3 to 1.4
/// times too strong (measured on the imu_tk trials, 2 of 20).
fn sample_quantised(signal: &[f64], q: f64, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    signal.iter().map(|s| q * ((s + q * (rng.random::<f64>() - 0.5)) / q).round()).collect()
}

/// Channel `ch` of `rec` requantised to step `q` (remainder carried).
fn requantise(rec: &mut Recording, ch: usize, q: f64) {
    let values: Vec<f64> = rec.rows.iter().map(|r| channel(r, ch)).collect();
    for (row, v) in rec.rows.iter_mut().zip(carry_quantised(&values, q)) {
        let old = channel(row, ch);
        add(row, ch, v - old);
    }
}

/// How a planted trial came out, first match in this order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Verdict {
    /// The verdict (the first effect) is the planted one: effect, sensor, axes, position and sign right,
    /// magnitude within 30 %.
    Detected,
    /// Found fully right, but another effect is stronger (first).
    RightNotFirst,
    /// Found at the right axes with the right sign, magnitude more than 30 % off.
    WrongMagnitude,
    /// Found at the right axes with the wrong sign.
    WrongSign,
    /// The effect is found on other axes (or another position) only, where the untouched construction shows
    /// none.
    WrongAxis,
    /// Not found.
    Missed,
}

impl Verdict {
    /// Every verdict, in order.
    pub const ALL: [Verdict; 6] = [
        Verdict::Detected,
        Verdict::RightNotFirst,
        Verdict::WrongMagnitude,
        Verdict::WrongSign,
        Verdict::WrongAxis,
        Verdict::Missed,
    ];

    /// The verdict in words (a column of the table).
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Detected => "detected",
            Verdict::RightNotFirst => "right, not first",
            Verdict::WrongMagnitude => "wrong magnitude",
            Verdict::WrongSign => "wrong sign",
            Verdict::WrongAxis => "wrong axis",
            Verdict::Missed => "missed",
        }
    }
}

/// One planted trial.
#[derive(Clone, Debug)]
pub struct Trial {
    /// The truth.
    pub hidden: Hidden,
    /// How it came out.
    pub verdict: Verdict,
    /// The first effect found, as "effect:sensor:axes".
    pub first: Option<String>,
    /// The first effect found that the untouched construction does not report (or that sits where the
    /// effect was planted) is the planted one, fully right: the verdict with the measured noise's own
    /// findings set aside.
    pub first_new_right: bool,
    /// The estimate of the effect found where it was planted (effect, sensor, axes, position), SI.
    pub found_estimate: Option<f64>,
    /// The planted candidate fitted with the base model alone (the linear effects, from the analysis's
    /// `tested`): estimate and standard error, SI.
    pub fitted: Option<(f64, f64)>,
}

impl Trial {
    /// (estimate - truth) / standard error of the planted candidate fitted with the base model alone.
    pub fn fit_error_se(&self) -> Option<f64> {
        self.fitted.map(|(estimate, se)| (estimate - self.hidden.value) / se)
    }
}

/// "effect:sensor:axes" (position errors: ":posN").
pub fn effect_label(e: &Effect) -> String {
    match e.pos {
        Some(p) => format!("{}:{}:{}:pos{p}", e.effect, e.sensor, e.axes),
        None => format!("{}:{}:{}", e.effect, e.sensor, e.axes),
    }
}

/// A line at `found_hz` is the one at `reference_hz`: within 2 % of it (at least 0.02 Hz). Without both
/// frequencies (an effect that is not a line), true.
pub(crate) fn same_line(reference_hz: Option<f64>, found_hz: Option<f64>) -> bool {
    match (reference_hz, found_hz) {
        (Some(r), Some(f)) => (f - r).abs() <= 0.02 * r.max(1.0),
        _ => true,
    }
}

/// Judges `analysis` of a planted recording against the truth `h`; `untouched` is the analysis of the
/// construction without it.
pub fn judge(analysis: &Analysis, untouched: &Analysis, h: &Hidden) -> Trial {
    let same_kind = |e: &Effect| e.effect == h.effect && e.sensor == h.sensor.name();
    // A vibration is a line: at the planted frequency, not another line of the same channel.
    let same_place =
        |e: &Effect| same_kind(e) && e.axes == h.axes && e.pos == h.pos && same_line(h.frequency_hz, e.frequency_hz);
    let sign_right = |e: &Effect| e.estimate.signum() == h.value.signum();
    let right = |e: &Effect| same_place(e) && sign_right(e) && ((e.estimate - h.value) / h.value).abs() <= 0.3;
    let in_untouched = |e: &Effect| {
        untouched
            .effects
            .iter()
            .any(|u| effect_label(u) == effect_label(e) && same_line(u.frequency_hz, e.frequency_hz))
    };
    let found = &analysis.effects;
    let verdict = if found.first().is_some_and(right) {
        Verdict::Detected
    } else if found.iter().any(right) {
        Verdict::RightNotFirst
    } else if found.iter().any(|e| same_place(e) && sign_right(e)) {
        Verdict::WrongMagnitude
    } else if found.iter().any(same_place) {
        Verdict::WrongSign
    } else if found.iter().any(|e| same_kind(e) && !in_untouched(e)) {
        Verdict::WrongAxis
    } else {
        Verdict::Missed
    };
    let name = candidate_name(h);
    let fitted = analysis
        .tested
        .iter()
        .find(|t| t.name == name && h.effect != EffectKind::BiasWarmup)
        .map(|t| (t.estimate, t.std_error));
    let first_new = found.iter().find(|e| same_place(e) || !in_untouched(e));
    Trial {
        hidden: h.clone(),
        verdict,
        first: found.first().map(effect_label),
        first_new_right: first_new.is_some_and(right),
        found_estimate: found.iter().find(|e| same_place(e)).map(|e| e.estimate),
        fitted,
    }
}

/// One trial: draw, plant, analyse, judge.
pub fn trial(p: &Prepared, effect: EffectKind, seed: u64) -> Result<Trial, String> {
    let planted = draw(p, effect, seed)?;
    let rec = plant(&p.construction, &planted);
    let analysis = analyze_recording(&rec).map_err(|e| e.to_string())?;
    Ok(judge(&analysis, &p.untouched, &planted.hidden))
}

/// The markdown table of the trials of one record: per effect the trials, each verdict's share, how often
/// the planted candidate fitted alone lies within 3 standard errors of the truth, and the first effect most
/// often reported when the planted one is not.
pub fn effect_table(rows: &[(EffectKind, Vec<Trial>)]) -> String {
    let mut out = String::from("| planted effect | trials |");
    for v in Verdict::ALL {
        out.push_str(&format!(" {} |", v.name()));
    }
    out.push_str(
        " first new effect right | fitted alone, within 3 SE | first effect otherwise (most often) |\n|---|---|",
    );
    out.push_str(&"---|".repeat(Verdict::ALL.len() + 3));
    out.push('\n');
    for (effect, trials) in rows {
        let n = trials.len().max(1) as f64;
        out.push_str(&format!("| {effect} | {} |", trials.len()));
        for v in Verdict::ALL {
            let k = trials.iter().filter(|t| t.verdict == v).count();
            out.push_str(&format!(" {:.0} % |", 100.0 * k as f64 / n));
        }
        let new_right = trials.iter().filter(|t| t.first_new_right).count();
        out.push_str(&format!(" {:.0} % |", 100.0 * new_right as f64 / n));
        let fits: Vec<f64> = trials.iter().filter_map(|t| t.fit_error_se()).collect();
        let within = fits.iter().filter(|z| z.abs() <= 3.0).count();
        let fit = if fits.is_empty() { "-".to_string() } else { format!("{within}/{}", fits.len()) };
        let mut firsts: BTreeMap<&str, usize> = BTreeMap::new();
        for t in trials.iter().filter(|t| t.verdict != Verdict::Detected) {
            *firsts.entry(t.first.as_deref().unwrap_or("none")).or_default() += 1;
        }
        let top = firsts.iter().max_by_key(|(_, k)| **k).map_or("-".to_string(), |(f, k)| format!("{f} ({k})"));
        out.push_str(&format!(" {fit} | {top} |\n"));
    }
    out
}

/// The false alarms of untouched constructions: how many report any effect, how many an effect of the
/// block means (the static and slow effects, not the noise models of the samples), and every effect
/// reported with the number of constructions that report it, its median estimate and median delta BIC,
/// most frequent first.
pub fn false_alarm_table(prepared: &[&Prepared]) -> String {
    let count = |f: &dyn Fn(&Effect) -> bool| prepared.iter().filter(|p| p.untouched.effects.iter().any(f)).count();
    let (alarms, block_alarms) = (count(&|_| true), count(&|e| e.residual_of == "block means"));
    let share = |k: usize| 100.0 * k as f64 / prepared.len().max(1) as f64;
    let mut out = format!(
        "false alarms: {alarms}/{n} untouched constructions report an effect ({:.0} %); {block_alarms}/{n} an \
         effect of the block means ({:.0} %)\n\n| effect reported on the untouched construction | constructions | \
         median estimate | unit | median delta BIC |\n|---|---|---|---|---|\n",
        share(alarms),
        share(block_alarms),
        n = prepared.len(),
    );
    let mut seen: BTreeMap<String, (Vec<f64>, Vec<f64>, String)> = BTreeMap::new();
    for p in prepared {
        for e in &p.untouched.effects {
            let entry = seen.entry(effect_label(e)).or_insert_with(|| (Vec::new(), Vec::new(), e.unit.clone()));
            entry.0.push(e.estimate);
            entry.1.push(e.delta_bic);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let mut rows: Vec<_> = seen.into_iter().collect();
    rows.sort_by_key(|(_, (v, _, _))| std::cmp::Reverse(v.len()));
    for (label, (mut est, mut bic, unit)) in rows {
        let k = est.len();
        out.push_str(&format!(
            "| {label} | {k}/{} | {:+.3e} | {unit} | {:.1} |\n",
            prepared.len(),
            median(&mut est),
            median(&mut bic)
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A static record at 100 Hz, `n` rows, accelerometer x as `ax(i)`, the rest constant.
    fn record(n: usize, ax: impl Fn(usize) -> f64) -> Recording {
        let header = Header {
            latitude_deg: 45.0,
            height_m: 0.0,
            rate_hz: Some(100.0),
            gravity_mps2: Some(9.8),
            comments: Vec::new(),
            truth: None,
            pose_tolerance_deg: None,
        };
        let rows = (0..n)
            .map(|i| Row {
                t_s: i as f64 * 0.01,
                pos: 1,
                pitch_deg: 0.0,
                roll_deg: 0.0,
                heading_deg: Some(0.0),
                rate_b_radps: [0.0; 3],
                force_b_mps2: [ax(i), 0.0, 9.8],
                temp_c: None,
                turn_axis: None,
                line: i + 2,
            })
            .collect();
        Recording { source: "synthetic".into(), header, rows, has_gyro: true }
    }

    #[test]
    fn a_line_within_half_a_step_survives_the_carrying_quantiser_of_an_unknown_remainder() {
        // A line of 0.4 steps at 0.277 cycles per sample: its integral stays within half a step, so the
        // quantiser of the signal alone emits nothing; with the record's unknown remainder it comes through.
        let (q, n) = (1.0, 20_000);
        let w = std::f64::consts::TAU * 0.277;
        let line: Vec<f64> = (0..n).map(|i| 0.4 * q * (w * i as f64).sin()).collect();
        assert!(carry_quantised(&line, q).iter().all(|v| *v == 0.0));
        let out = carried_with_unknown_carry(&line, q, 7);
        assert!(out.iter().all(|v| (v / q - (v / q).round()).abs() < 1e-12), "off the lattice");
        let (mut c, mut s) = (0.0, 0.0);
        for (i, v) in out.iter().enumerate() {
            c += v * (w * i as f64).sin();
            s += v * (w * i as f64).cos();
        }
        let amplitude = 2.0 * c.hypot(s) / n as f64;
        assert!((amplitude - 0.4 * q).abs() < 0.02 * q, "amplitude {amplitude}");
        // The running sum follows the signal's within a step; no signal, no change.
        let (mut sum_out, mut sum_in) = (0.0, 0.0);
        for (o, l) in out.iter().zip(&line) {
            sum_out += o;
            sum_in += l;
            assert!((sum_out - sum_in).abs() < q, "running sums {sum_out} and {sum_in}");
        }
        assert!(carried_with_unknown_carry(&[0.0; 100], q, 7).iter().all(|v| *v == 0.0));
    }

    #[test]
    fn a_tilt_step_splits_the_record_into_constant_pose_stretches() {
        // A tilt of 0.5 mrad (4.9e-3 m/s^2 on accelerometer x) at 100 s; a ramp below the threshold after it.
        let rec = record(30_000, |i| if i < 10_000 { 0.0 } else { 4.9e-3 + 1e-8 * i as f64 });
        assert_eq!(constant_pose_stretches(&rec), vec![(0, 10_000), (10_000, 30_000)]);
        // The step exactly at the threshold does not split; just beyond it does.
        let at = record(4_000, |i| if i < 2_000 { 0.0 } else { TILT_STEP_MPS2 * 0.999 });
        assert_eq!(constant_pose_stretches(&at), vec![(0, 4_000)]);
        let beyond = record(4_000, |i| if i < 2_000 { 0.0 } else { TILT_STEP_MPS2 * 1.001 });
        assert_eq!(constant_pose_stretches(&beyond), vec![(0, 2_000), (2_000, 4_000)]);
    }

    #[test]
    fn the_session_drift_is_removed_and_a_quantised_channel_stays_on_its_lattice() {
        // Accelerometer x: a drift of 1e-4 (m/s^2)/s on a lattice of 0.1 m/s^2 (the counts carried).
        let q = 0.1;
        let clean: Vec<f64> = (0..2_000).map(|i| 1e-4 * i as f64 * 0.01).collect();
        let on_lattice = carry_quantised(&clean, q);
        let rec = record(2_000, |i| on_lattice[i] + 3.0 * q);
        let rows: Vec<usize> = (0..2_000).collect();
        let steps = [None, None, None, Some(q), None, None];
        let removed = session_drift(&rec, &rows, mean_of(&rec, rows.iter().copied()), &rows, &steps);
        let left: Vec<f64> = rows.iter().map(|&i| rec.rows[i].force_b_mps2[0] - removed[i][3]).collect();
        for v in &left {
            assert!(((v / q) - (v / q).round()).abs() < 1e-9, "{v} is off the lattice");
        }
        // What is left has no drift: its least-squares slope is below 2 % of the one removed (the lattice's
        // rounding is all that remains).
        let n = left.len() as f64;
        let (tm, ym) = (rows.iter().map(|&i| rec.rows[i].t_s).sum::<f64>() / n, left.iter().sum::<f64>() / n);
        let sxy: f64 = rows.iter().map(|&i| (rec.rows[i].t_s - tm) * (left[i] - ym)).sum();
        let sxx: f64 = rows.iter().map(|&i| (rec.rows[i].t_s - tm).powi(2)).sum();
        assert!((sxy / sxx).abs() < 2e-6, "slope left {:e}", sxy / sxx);
        // An unquantised channel (accelerometer z) with no drift is left alone.
        assert!(removed.iter().all(|r| r[5].abs() < 1e-15));
    }
}
