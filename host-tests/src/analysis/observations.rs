//! A recording as the analysis sees it: its dwells with their reference attitude, cut into blocks whose
//! means, minus what the reference attitude predicts, are the observations; and the base model's columns
//! (one bias per channel).

use std::collections::HashMap;

use crate::calibration::site_of;
use crate::io::dwell_tally::{DwellTallies, DwellTally};
use crate::io::error::InputError;
use crate::io::recording::{Row, RowSource};
use crate::model::synth::{c_b_n, earth_rate_n_radps, mul_t_vec, M3};

use super::parallel::on_cores;
use super::{AXES, BLOCK_SAMPLES, MAX_BLOCKS_PER_DWELL, MIN_DWELL_SAMPLES};

/// One dwell's samples and reference attitude.
pub(super) struct DwellData {
    /// Position label.
    pub pos: u32,
    /// Reference C_b^n, when the heading is known.
    pub c_b_n: Option<M3>,
    /// Reference C_b^n with heading 0 (tilt only), for the gravity prediction.
    pub c_tilt: M3,
    /// Times, s.
    pub t: Vec<f64>,
    /// The six channels (gx..az), SI.
    pub y: [Vec<f64>; 6],
    /// Temperature, deg C, when every row has one.
    pub temp: Option<Vec<f64>>,
}

/// A dwell's samples as they are read: columns that grow row by row.
#[derive(Default)]
struct DwellColumns {
    t: Vec<f64>,
    y: [Vec<f64>; 6],
    /// Temperatures while every row so far has one.
    temp: Option<Vec<f64>>,
}

impl DwellColumns {
    fn push(&mut self, row: &Row) {
        if self.t.is_empty() {
            self.temp = Some(Vec::new());
        }
        self.t.push(row.t_s);
        for c in 0..3 {
            self.y[c].push(row.rate_b_radps[c]);
            self.y[3 + c].push(row.force_b_mps2[c]);
        }
        match (&mut self.temp, row.temp_c) {
            (Some(temp), Some(t)) => temp.push(t),
            (temp, _) => *temp = None,
        }
    }
}

impl DwellData {
    /// The samples of dwell `d` of `source` and its reference attitude.
    fn new(d: &DwellTally, columns: DwellColumns, source: &str) -> Result<DwellData, InputError> {
        let att = d.attitude(source)?;
        if d.samples < MIN_DWELL_SAMPLES {
            return Err(InputError::at(
                source,
                d.first_line,
                format!("dwell {}: {} rows, the analysis needs at least {MIN_DWELL_SAMPLES}", d.pos, d.samples),
            ));
        }
        let DwellColumns { t, y, temp } = columns;
        Ok(DwellData {
            pos: d.pos,
            c_b_n: att.heading_deg.map(|h| c_b_n(att.pitch_deg, att.roll_deg, h)),
            c_tilt: c_b_n(att.pitch_deg, att.roll_deg, 0.0),
            t,
            y,
            temp,
        })
    }

    /// What the reference attitude predicts for `channel` (the Earth rate or gravity in the body); `None`
    /// for a gyro when the heading is unknown, unless the gyro's axis is vertical ([`Self::rate_b_radps`]).
    fn predicted(&self, channel: usize, w_n: [f64; 3], f_n: [f64; 3]) -> Option<f64> {
        if channel < 3 {
            let rate = self.rate_b_radps(w_n)[channel];
            rate.is_finite().then_some(rate)
        } else {
            Some(mul_t_vec(&self.c_tilt, f_n)[channel - 3])
        }
    }

    /// The Earth rate `w_n` (e, n, u) in the body, rad/s. With the heading unknown, only the component along a
    /// vertical body axis is known (`+-W sin L`, whatever the heading: the axis has no east or north
    /// component); the others are NaN.
    pub fn rate_b_radps(&self, w_n: [f64; 3]) -> [f64; 3] {
        match &self.c_b_n {
            Some(c) => mul_t_vec(c, w_n),
            None => std::array::from_fn(|axis| match self.vertical_axis() {
                Some((vertical, _)) if vertical == axis => self.c_tilt[2][axis] * w_n[2],
                _ => f64::NAN,
            }),
        }
    }

    /// The body axis (0 = x, 1 = y, 2 = z) that the label puts vertical, and +1 when it points up, -1 down:
    /// the axis whose east and north components are rounding ([`super::candidates::ROUNDING`]). `None` for a
    /// tilted pose.
    pub fn vertical_axis(&self) -> Option<(usize, f64)> {
        let c = &self.c_tilt;
        let level = |axis: usize| (0..2).all(|k| c[k][axis].abs() <= super::candidates::ROUNDING);
        (0..3).find(|&axis| level(axis)).map(|axis| (axis, c[2][axis].signum()))
    }
}

/// A recording's dwells and the navigation-frame quantities the reference predicts from.
pub(super) struct Session {
    /// Earth rate in the navigation frame (e, n, u), rad/s.
    pub w_n: [f64; 3],
    /// Specific force at rest in the navigation frame, m/s^2.
    pub f_n: [f64; 3],
    /// Time of the first row, s.
    pub t0: f64,
    /// Sample rate, Hz (the header's, else measured).
    pub rate_hz: f64,
    /// Sample interval, s.
    pub dt: f64,
    /// The dwells, in order of first appearance.
    pub dwells: Vec<DwellData>,
    /// The recording has gyro columns (an accelerometer-only recording has none: its gyros are absent, not
    /// zero).
    pub has_gyro: bool,
}

impl Session {
    /// Reads the dwells of `recording` in one pass, keeping of each row only its time and six channels (and
    /// temperature) in the dwell's columns; an error if a dwell is too short or there is none.
    pub fn read(recording: &impl RowSource) -> Result<Session, InputError> {
        let source = recording.source();
        let header = recording.header();
        let (site, _) = site_of(header);
        let g = site.gravity_mps2 as f64;
        let lat = header.latitude_deg.to_radians();
        let mut tallies = DwellTallies::bounded();
        let mut columns: Vec<DwellColumns> = Vec::new();
        let (mut rows, mut t0, mut t_last) = (0usize, None, 0.0);
        recording.for_each_row(&mut |row| {
            rows += 1;
            t0.get_or_insert(row.t_s);
            t_last = row.t_s;
            if let Some(i) = tallies.push(row, source)? {
                if i == columns.len() {
                    columns.push(DwellColumns::default());
                }
                columns[i].push(row);
            }
            Ok(())
        })?;
        let t0 = t0.unwrap_or(0.0);
        // The header's rate, else measured from the time column, else 100 Hz.
        let rate_hz = match header.rate_hz {
            Some(r) => r,
            None if rows > 1 => (rows - 1) as f64 / (t_last - t0),
            None => 100.0,
        };
        let dwells = tallies
            .at_least_one(source)?
            .iter()
            .zip(columns)
            .map(|(d, c)| DwellData::new(d, c, source))
            .collect::<Result<Vec<_>, _>>()?;
        let w_n = earth_rate_n_radps(lat);
        Ok(Session { w_n, f_n: [0.0, 0.0, g], t0, rate_hz, dt: 1.0 / rate_hz, dwells, has_gyro: recording.has_gyro() })
    }

    /// Every dwell has a temperature.
    pub fn has_temp(&self) -> bool {
        self.dwells.iter().all(|d| d.temp.is_some())
    }

    /// Every dwell has a heading (the Earth rate in the body is known).
    pub fn all_heading(&self) -> bool {
        self.dwells.iter().all(|d| d.c_b_n.is_some())
    }

    /// The channels the recording has (gx..az = 0..5): all six, or the accelerometers' 3..5.
    pub fn channels(&self) -> std::ops::Range<usize> {
        if self.has_gyro {
            0..6
        } else {
            3..6
        }
    }

    /// Index of the longest dwell.
    pub fn longest(&self) -> usize {
        (0..self.dwells.len()).max_by_key(|&i| self.dwells[i].t.len()).unwrap_or(0)
    }
}

/// One block: rows `range` of dwell `dwell`, channel `channel`.
pub(super) struct BlockObs {
    /// Dwell index.
    pub dwell: usize,
    /// Channel, 0..5.
    pub channel: usize,
    /// Rows of the dwell, half-open.
    pub range: (usize, usize),
}

/// The block observations of a recording.
pub(super) struct Blocks {
    /// The blocks, dwell by dwell, channel by channel.
    pub list: Vec<BlockObs>,
    /// Block mean minus the reference prediction, SI.
    pub y: Vec<f64>,
    /// Channel of each observation.
    pub group: Vec<usize>,
    /// Position label of each observation.
    pub obs_pos: Vec<u32>,
    /// Channels with observations (the gyros need the heading).
    pub present: [bool; 6],
}

impl Blocks {
    /// Cuts every dwell of `session` into blocks, on every channel the reference predicts.
    pub fn cut(session: &Session) -> Blocks {
        let mut blocks =
            Blocks { list: Vec::new(), y: Vec::new(), group: Vec::new(), obs_pos: Vec::new(), present: [false; 6] };
        for (di, d) in session.dwells.iter().enumerate() {
            for channel in session.channels() {
                // Heading unknown: the Earth rate in the body is unknown (but along a vertical axis).
                let Some(predicted) = d.predicted(channel, session.w_n, session.f_n) else { continue };
                for range in block_ranges(d.t.len()) {
                    let s = &d.y[channel][range.0..range.1];
                    blocks.y.push(s.iter().sum::<f64>() / s.len() as f64 - predicted);
                    blocks.group.push(channel);
                    blocks.obs_pos.push(d.pos);
                    blocks.list.push(BlockObs { dwell: di, channel, range });
                }
            }
        }
        blocks.present = std::array::from_fn(|c| blocks.group.contains(&c));
        blocks
    }

    /// `f` of every block.
    pub fn column(&self, f: impl Fn(&BlockObs) -> f64) -> Vec<f64> {
        self.list.iter().map(f).collect()
    }

    /// Per function of `fs`, per block: the mean of `f(t)` over the block's rows (`t` in s). The channels'
    /// blocks share their dwell's rows, so each mean is computed once per row range (the same sum as over
    /// each block), and the functions are spread over the available cores.
    pub fn time_means<F: Fn(f64) -> f64 + Sync>(&self, session: &Session, fs: &[F]) -> Vec<Vec<f64>> {
        let mut ranges: Vec<(usize, (usize, usize))> = Vec::new();
        let mut seen: HashMap<(usize, (usize, usize)), usize> = HashMap::new();
        let range_of: Vec<usize> = self
            .list
            .iter()
            .map(|b| {
                *seen.entry((b.dwell, b.range)).or_insert_with(|| {
                    ranges.push((b.dwell, b.range));
                    ranges.len() - 1
                })
            })
            .collect();
        on_cores(fs.len(), |i| {
            let means: Vec<f64> = ranges
                .iter()
                .map(|&(d, (a, b))| {
                    let t = &session.dwells[d].t[a..b];
                    t.iter().map(|&t| fs[i](t)).sum::<f64>() / t.len() as f64
                })
                .collect();
            range_of.iter().map(|&r| means[r]).collect()
        })
    }

    /// The column that is `values` (one per block) on the blocks of channel `c` and zero elsewhere.
    pub fn on_channel(&self, c: usize, values: &[f64]) -> Vec<f64> {
        self.list.iter().zip(values).map(|(b, &v)| if b.channel == c { v } else { 0.0 }).collect()
    }

    /// The base model: one bias column per channel present, with its name ("gyro_bias_x"); the biases of
    /// the channels absent go to `unobservable`.
    pub fn base_columns(&self, unobservable: &mut Vec<String>) -> (Vec<Vec<f64>>, Vec<String>) {
        let (mut base, mut names) = (Vec::new(), Vec::new());
        for c in 0..6 {
            let name = if c < 3 { format!("gyro_bias_{}", AXES[c]) } else { format!("accel_bias_{}", AXES[c - 3]) };
            if self.present[c] {
                base.push(self.column(|b| if b.channel == c { 1.0 } else { 0.0 }));
                names.push(name);
            } else {
                unobservable.push(name);
            }
        }
        (base, names)
    }
}

/// The blocks of a dwell of `n` samples: about [`BLOCK_SAMPLES`] long, 4 to [`MAX_BLOCKS_PER_DWELL`] of them,
/// at least 16 samples each.
fn block_ranges(n: usize) -> Vec<(usize, usize)> {
    let blocks = (n / BLOCK_SAMPLES).clamp(4, MAX_BLOCKS_PER_DWELL).min(n / 16).max(1);
    (0..blocks).map(|b| (b * n / blocks, (b + 1) * n / blocks)).collect()
}
