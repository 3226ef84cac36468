//! What the commands that keep no rows need of a dwell, gathered one row at a time: its label, first line,
//! sample count and time span, and its reference attitude (docs/formats.md#speed-and-memory).

use std::collections::HashMap;

use crate::io::error::InputError;
use crate::io::recording::{DwellAttitude, Row, MAX_DWELL_ATTITUDE_SPREAD_DEG};

/// One reference angle of a dwell, row by row: the sums of its circular mean, and its extremes about the
/// dwell's first value, which are all the spread check needs.
#[derive(Clone, Debug, Default)]
struct AngleTally {
    known: usize,
    /// Line of the first row where the angle is empty.
    first_empty_line: Option<usize>,
    first_deg: f64,
    sum_sin: f64,
    sum_cos: f64,
    /// The last value's bits, its sine and cosine and its difference from the first value: a dwell's angle
    /// rarely changes from row to row.
    last: Option<(u64, f64, f64, f64)>,
    /// The smallest and the largest difference from the first value (wrapped to +-180 deg), deg, with the
    /// line and value of each.
    low: (f64, usize, f64),
    high: (f64, usize, f64),
}

/// Shortest signed angle from `from_deg` to `to_deg` (`to - from` wrapped to [-180, 180)), degrees.
pub fn angle_step_deg(from_deg: f64, to_deg: f64) -> f64 {
    (to_deg - from_deg + 540.0).rem_euclid(360.0) - 180.0
}

impl AngleTally {
    fn push(&mut self, value_deg: Option<f64>, line: usize) {
        let Some(v) = value_deg else {
            self.first_empty_line.get_or_insert(line);
            return;
        };
        if self.known == 0 {
            self.first_deg = v;
            self.low = (0.0, line, v);
            self.high = (0.0, line, v);
        }
        self.known += 1;
        let (sin, cos, d) = match self.last {
            Some((bits, sin, cos, d)) if bits == v.to_bits() => (sin, cos, d),
            _ => {
                let r = v.to_radians();
                let (sin, cos, d) = (r.sin(), r.cos(), angle_step_deg(self.first_deg, v));
                self.last = Some((v.to_bits(), sin, cos, d));
                (sin, cos, d)
            }
        };
        self.sum_sin += sin;
        self.sum_cos += cos;
        if d < self.low.0 {
            self.low = (d, line, v);
        }
        if d > self.high.0 {
            self.high = (d, line, v);
        }
    }

    /// The circular mean of the angle, in the range of the dwell's first value (270 stays 270, not -90);
    /// `None` when it is empty in every row. An angle empty in some rows only, or spread by more than
    /// [`MAX_DWELL_ATTITUDE_SPREAD_DEG`] about its mean (the table moved), is an error naming the line.
    fn mean_deg(&self, name: &str, dwell: &DwellTally, source: &str) -> Result<Option<f64>, InputError> {
        if self.known == 0 {
            return Ok(None);
        }
        if let Some(line) = self.first_empty_line {
            return Err(InputError::at(
                source,
                line,
                format!("dwell {}: {name} is empty in some rows only", dwell.pos),
            ));
        }
        let mean = self.sum_sin.atan2(self.sum_cos).to_degrees();
        // Every value lies between the two extremes, so these two decide the spread.
        for (_, line, v) in [self.low, self.high] {
            if angle_step_deg(mean, v).abs() > MAX_DWELL_ATTITUDE_SPREAD_DEG {
                return Err(InputError::at(
                    source,
                    line,
                    format!(
                        "dwell {}: {name} {v} deg differs from the dwell's mean {mean:.4} deg: the table moves",
                        dwell.pos
                    ),
                ));
            }
        }
        Ok(Some(self.first_deg - angle_step_deg(mean, self.first_deg)))
    }
}

/// A dwell's label, first line, samples, time span and reference attitude, gathered row by row.
#[derive(Clone, Debug)]
pub struct DwellTally {
    /// Position label.
    pub pos: u32,
    /// Line of its first row.
    pub first_line: usize,
    /// Its rows.
    pub samples: usize,
    /// Time of its first and last row, s.
    pub first_t_s: f64,
    /// Time of its last row, s.
    pub last_t_s: f64,
    angles: [AngleTally; 3],
}

impl DwellTally {
    /// The tally of the first row of a dwell.
    pub fn new(row: &Row) -> DwellTally {
        let mut tally = DwellTally {
            pos: row.pos,
            first_line: row.line,
            samples: 0,
            first_t_s: row.t_s,
            last_t_s: row.t_s,
            angles: Default::default(),
        };
        tally.push(row);
        tally
    }

    /// Adds a row of the dwell (the first row is added by [`DwellTally::new`]).
    pub fn push(&mut self, row: &Row) {
        if self.samples > 0 {
            self.last_t_s = row.t_s;
        }
        self.samples += 1;
        self.angles[0].push(Some(row.pitch_deg), row.line);
        self.angles[1].push(Some(row.roll_deg), row.line);
        self.angles[2].push(row.heading_deg, row.line);
    }

    /// The reference attitude of the dwell: the circular mean of each angle over its rows (a read-out
    /// jitter averages out). A spread above [`MAX_DWELL_ATTITUDE_SPREAD_DEG`] means the table moved: an error.
    pub fn attitude(&self, source: &str) -> Result<DwellAttitude, InputError> {
        Ok(DwellAttitude {
            pitch_deg: self.angles[0].mean_deg("pitch_deg", self, source)?.unwrap_or(0.0),
            roll_deg: self.angles[1].mean_deg("roll_deg", self, source)?.unwrap_or(0.0),
            heading_deg: self.angles[2].mean_deg("heading_deg", self, source)?,
        })
    }

    /// The reference attitude with its heading, which `purpose` ("the calibration", "navigation") needs;
    /// an empty heading is an error naming the dwell.
    pub fn attitude_with_heading(&self, source: &str, purpose: &str) -> Result<(DwellAttitude, f64), InputError> {
        let attitude = self.attitude(source)?;
        let heading_deg = attitude.heading_deg.ok_or_else(|| {
            InputError::at(
                source,
                self.first_line,
                format!("dwell {}: heading is unknown (empty): {purpose} needs the reference heading", self.pos),
            )
        })?;
        Ok((attitude, heading_deg))
    }
}

/// The reason for a recording without a dwell.
pub const NO_DWELL: &str = "no dwell: every row has pos = 0";

/// Most dwells a command that keeps no rows reads from one recording: a turntable session has tens.
pub const MAX_DWELLS_READ: usize = 10_000;

/// The dwells of a recording, row by row, in order of first appearance of their label: rows with the same
/// non-zero label form one dwell (docs/formats.md#recording); label 0 rows are skipped.
#[derive(Clone, Debug)]
pub struct DwellTallies {
    /// The dwells so far.
    pub dwells: Vec<DwellTally>,
    /// Label -> index: one look-up per row, whatever the number of labels.
    index: HashMap<u32, usize>,
    /// The label of the last row and its index, so that a dwell's rows cost no look-up.
    last: Option<(u32, usize)>,
    limit: usize,
    /// Why there is a limit, for the message.
    why: &'static str,
}

impl DwellTallies {
    /// Tallies of at most `limit` dwells: the row that starts one more is an error naming its line and `why`
    /// there is a limit.
    pub fn new(limit: usize, why: &'static str) -> DwellTallies {
        DwellTallies { dwells: Vec::new(), index: HashMap::new(), last: None, limit, why }
    }

    /// Tallies of at most [`MAX_DWELLS_READ`] dwells, for a command without a limit of its own.
    pub fn bounded() -> DwellTallies {
        DwellTallies::new(MAX_DWELLS_READ, "sinscal reads at most that many from one recording")
    }

    /// The dwells, at least one: none is an error (`no dwell: every row has pos = 0`).
    pub fn at_least_one(self, source: &str) -> Result<Vec<DwellTally>, InputError> {
        if self.dwells.is_empty() {
            return Err(InputError::file(source, NO_DWELL));
        }
        Ok(self.dwells)
    }

    /// Adds a row; returns the index of its dwell (`None` for label 0).
    pub fn push(&mut self, row: &Row, source: &str) -> Result<Option<usize>, InputError> {
        if row.pos == 0 {
            return Ok(None);
        }
        let i = match self.last {
            Some((pos, i)) if pos == row.pos => {
                self.dwells[i].push(row);
                i
            }
            _ => match self.index.get(&row.pos) {
                Some(&i) => {
                    self.dwells[i].push(row);
                    i
                }
                None => {
                    if self.dwells.len() == self.limit {
                        let reason = format!("more than {} positions ({})", self.limit, self.why);
                        return Err(InputError::at(source, row.line, reason));
                    }
                    self.index.insert(row.pos, self.dwells.len());
                    self.dwells.push(DwellTally::new(row));
                    self.dwells.len() - 1
                }
            },
        };
        self.last = Some((row.pos, i));
        Ok(Some(i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(line: usize, pos: u32, pitch_deg: f64, heading_deg: Option<f64>) -> Row {
        Row {
            t_s: line as f64 * 0.01,
            pos,
            pitch_deg,
            roll_deg: 0.0,
            heading_deg,
            rate_b_radps: [0.0; 3],
            force_b_mps2: [0.0, 0.0, 9.8],
            temp_c: None,
            turn_axis: None,
            line,
        }
    }

    fn tally(rows: &[Row]) -> DwellTally {
        let mut t = DwellTally::new(&rows[0]);
        rows[1..].iter().for_each(|r| t.push(r));
        t
    }

    #[test]
    fn a_moving_table_is_named_at_its_farthest_value() {
        // Mean of the pitches -0.0022 deg: 0.005 is 0.0072 from it, -0.02 is 0.0178 (beyond 0.01).
        let pitches = [0.0, 0.004, 0.005, -0.02, 0.0];
        let rows: Vec<Row> = pitches.iter().enumerate().map(|(k, &p)| row(10 + k, 1, p, Some(90.0))).collect();
        let e = tally(&rows).attitude("r.csv").unwrap_err().to_string();
        assert!(
            e.starts_with("r.csv:13: dwell 1: pitch_deg -0.02 deg differs from the dwell's mean -0.0022 deg"),
            "{e}"
        );
        // Within the spread the mean is the circular mean, in the range of the first value.
        let rows: Vec<Row> =
            [359.996, 0.004, 359.999].iter().enumerate().map(|(k, &h)| row(k, 2, 0.0, Some(h))).collect();
        let h = tally(&rows).attitude("r.csv").unwrap().heading_deg.unwrap();
        assert!((h - 359.999_666_666_666_7).abs() < 1e-9, "{h}");
    }

    #[test]
    fn a_heading_empty_in_some_rows_only_is_named_at_the_first_empty_one() {
        let rows = [row(5, 1, 0.0, Some(10.0)), row(6, 1, 0.0, None), row(7, 1, 0.0, None)];
        let e = tally(&rows).attitude("r.csv").unwrap_err().to_string();
        assert_eq!(e, "r.csv:6: dwell 1: heading_deg is empty in some rows only");
        let rows = [row(5, 1, 0.0, None), row(6, 1, 0.0, None)];
        let t = tally(&rows);
        assert_eq!(t.attitude("r.csv").unwrap().heading_deg, None);
        let e = t.attitude_with_heading("r.csv", "navigation").unwrap_err().to_string();
        assert_eq!(e, "r.csv:5: dwell 1: heading is unknown (empty): navigation needs the reference heading");
    }

    #[test]
    fn tallies_group_labels_in_order_of_first_appearance_up_to_the_limit() {
        let mut tallies = DwellTallies::new(2, "the core's limit");
        let labels = [0, 7, 7, 0, 3, 7, 3];
        for (k, &pos) in labels.iter().enumerate() {
            let i = tallies.push(&row(k + 1, pos, 0.0, None), "r.csv").unwrap();
            assert_eq!(i, [None, Some(0), Some(0), None, Some(1), Some(0), Some(1)][k]);
        }
        let d = &tallies.dwells;
        assert_eq!((d[0].pos, d[0].first_line, d[0].samples, d[0].first_t_s, d[0].last_t_s), (7, 2, 3, 0.02, 0.06));
        assert_eq!((d[1].pos, d[1].first_line, d[1].samples), (3, 5, 2));
        let e = tallies.push(&row(8, 9, 0.0, None), "r.csv").unwrap_err().to_string();
        assert_eq!(e, "r.csv:8: more than 2 positions (the core's limit)");
    }
}
