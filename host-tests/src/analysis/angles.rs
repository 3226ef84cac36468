//! The angles-file front end (docs/formats.md#angles): the file read, its per-position angles as
//! observations, the base model of the six biases through the alignment equations (the core's design rows,
//! docs/method.md), the sensor terms mapped the same way, and the reference offset and position errors,
//! which enter the angles directly.

use std::collections::BTreeMap;

use sinscal::nav::earth::Site;

use crate::calibration::site_of;
use crate::io::error::InputError;
use crate::model::catalogue::{EffectKind, Sensor};
use crate::model::synth::{c_b_n, earth_rate_n_radps};
use crate::stats::linfit::Observations;

use super::candidates::{in_body, sensor_terms, Candidate};
use super::column::Column;
use super::result::{assemble, effects_of, residuals_by_group, Findings, ANGLES};
use super::selection::{select, Problem};
use super::{Analysis, FigureData, ENU};

/// One position of an angles file (docs/formats.md#angles).
#[derive(Clone, Debug, PartialEq)]
pub struct AnglesRow {
    /// Position label.
    pub pos: u32,
    /// Reference pitch, roll, heading, degrees.
    pub attitude_deg: [f64; 3],
    /// Alignment error (e, n, u), rad.
    pub phi_rad: [f64; 3],
    /// Its standard deviations, rad, if given.
    pub phi_std_rad: Option<[f64; 3]>,
}

/// An angles file.
#[derive(Clone, Debug, PartialEq)]
pub struct AnglesFile {
    /// File name.
    pub source: String,
    /// Latitude, degrees north.
    pub latitude_deg: f64,
    /// Gravity, m/s^2, if given.
    pub gravity_mps2: Option<f64>,
    /// Positions.
    pub rows: Vec<AnglesRow>,
}

impl AnglesFile {
    /// Parses the text of an angles file.
    pub fn parse(text: &str, source: &str) -> Result<AnglesFile, InputError> {
        let mut parser = Parser { source, latitude: None, gravity: None, version: None, names: None, rows: Vec::new() };
        for (i, line) in text.lines().enumerate() {
            parser.line(i + 1, line.trim())?;
        }
        parser.finish()
    }
}

/// The state of reading an angles file.
struct Parser<'a> {
    source: &'a str,
    latitude: Option<f64>,
    gravity: Option<f64>,
    /// Line and value of the version header.
    version: Option<(usize, String)>,
    /// Line and names of the column line.
    names: Option<(usize, Vec<String>)>,
    rows: Vec<AnglesRow>,
}

impl Parser<'_> {
    /// Line `n` (trimmed): blank, a header, the column line or a position.
    fn line(&mut self, n: usize, line: &str) -> Result<(), InputError> {
        if line.is_empty() {
            return Ok(());
        }
        if let Some(h) = line.strip_prefix('#') {
            return self.header(n, h);
        }
        let cells: Vec<&str> = line.split(',').map(|c| c.trim()).collect();
        let Some((_, cols)) = &self.names else {
            self.names = Some((n, cells.iter().map(|c| c.to_string()).collect()));
            return Ok(());
        };
        if cells.len() != cols.len() {
            return Err(InputError::at(
                self.source,
                n,
                format!("{} cells, the column line has {}", cells.len(), cols.len()),
            ));
        }
        let row = Cells { source: self.source, n, cols, cells: &cells }.row()?;
        self.rows.push(row);
        Ok(())
    }

    /// A header line `# key: value` (after the `#`); unknown keys and comments are skipped.
    fn header(&mut self, n: usize, h: &str) -> Result<(), InputError> {
        let Some((k, v)) = h.split_once(':') else { return Ok(()) };
        let v = v.split_whitespace().next().unwrap_or("");
        let num = || {
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| InputError::at(self.source, n, format!("header {}: '{v}' is not a number", k.trim())))
        };
        match k.trim() {
            "sinscal-angles" => self.version = Some((n, v.to_string())),
            "latitude_deg" => {
                let latitude_deg = num()?;
                if !crate::io::recording::latitude_ok(latitude_deg) {
                    let limit = crate::io::recording::MAX_LATITUDE_DEG;
                    return Err(InputError::at(
                        self.source,
                        n,
                        format!(
                            "latitude_deg {} outside [-{limit}, {limit}]: nearer a pole the horizontal Earth rate \
                             that the heading angle rests on vanishes",
                            crate::io::recording::shown(latitude_deg)
                        ),
                    ));
                }
                self.latitude = Some(latitude_deg);
            }
            "gravity_mps2" => self.gravity = Some(num()?),
            _ => {}
        }
        Ok(())
    }

    /// The file, once every line is read: version 1, a latitude, at least 3 positions, standard deviations
    /// for all positions or none.
    fn finish(self) -> Result<AnglesFile, InputError> {
        let source = self.source;
        match self.version {
            Some((_, v)) if v == "1" => {}
            Some((n, v)) => {
                return Err(InputError::at(
                    source,
                    n,
                    format!("unsupported angles version '{v}' (this sinscal reads 1)"),
                ))
            }
            None => return Err(InputError::file(source, "not an angles file: no '# sinscal-angles: 1' line")),
        }
        let latitude_deg = self.latitude.ok_or_else(|| InputError::file(source, "header has no latitude_deg"))?;
        let rows = self.rows;
        if rows.len() < 3 {
            return Err(InputError::file(source, format!("{} positions; the analysis needs at least 3", rows.len())));
        }
        let with_std = rows.iter().filter(|r| r.phi_std_rad.is_some()).count();
        if with_std != 0 && with_std != rows.len() {
            return Err(InputError::file(source, "standard deviations given for some positions only"));
        }
        Ok(AnglesFile { source: source.into(), latitude_deg, gravity_mps2: self.gravity, rows })
    }
}

/// The cells of position line `n` under the column names `cols`.
struct Cells<'a> {
    source: &'a str,
    n: usize,
    cols: &'a [String],
    cells: &'a [&'a str],
}

impl Cells<'_> {
    /// Column `name` if the file has it: a finite number.
    fn get(&self, name: &str) -> Result<Option<f64>, InputError> {
        match self.cols.iter().position(|c| c == name) {
            None => Ok(None),
            Some(j) => self.cells[j].parse::<f64>().ok().filter(|v| v.is_finite()).map(Some).ok_or_else(|| {
                InputError::at(
                    self.source,
                    self.n,
                    format!("column '{name}': '{}' is not a finite number", self.cells[j]),
                )
            }),
        }
    }

    /// Column `name`, which the file must have.
    fn need(&self, name: &str) -> Result<f64, InputError> {
        self.get(name)?.ok_or_else(|| InputError::at(self.source, self.n, format!("missing column '{name}'")))
    }

    /// The position of this line.
    fn row(&self) -> Result<AnglesRow, InputError> {
        let pos = self.need("pos")?;
        if pos < 1.0 || pos.fract() != 0.0 {
            return Err(InputError::at(self.source, self.n, format!("pos {pos} is not a positive integer")));
        }
        let stds = [self.get("phi_e_std_rad")?, self.get("phi_n_std_rad")?, self.get("phi_u_std_rad")?];
        // An angle of the alignment is a small misalignment: beyond a radian (or a standard deviation beyond
        // one) it is not a measurement, and its square overflows the fit's sums.
        let angle = |x: f64| x.abs() <= MAX_ANGLE_RAD;
        let phi_std_rad = match stds {
            [Some(a), Some(b), Some(c)] if [a, b, c].iter().all(|&s| s > 0.0 && angle(s)) => Some([a, b, c]),
            [None, None, None] => None,
            _ => {
                return Err(InputError::at(
                    self.source,
                    self.n,
                    format!("phi_*_std_rad: all three, positive and at most {MAX_ANGLE_RAD} rad, or none"),
                ))
            }
        };
        let phi_rad = [self.need("phi_e_rad")?, self.need("phi_n_rad")?, self.need("phi_u_rad")?];
        if !phi_rad.iter().all(|&p| angle(p)) {
            return Err(InputError::at(self.source, self.n, format!("phi_*_rad: beyond {MAX_ANGLE_RAD} rad")));
        }
        Ok(AnglesRow {
            pos: pos as u32,
            attitude_deg: [self.need("pitch_deg")?, self.need("roll_deg")?, self.need("heading_deg")?],
            phi_rad,
            phi_std_rad,
        })
    }
}

/// Largest angle (and standard deviation) an angles file may hold, rad.
pub const MAX_ANGLE_RAD: f64 = 1.0;

/// Analyses an angles file.
pub fn analyze_angles(file: &AnglesFile) -> Result<Analysis, InputError> {
    // Three angles per position; over all of them the sensor terms (at most 30) and the reference offset; a
    // position error per position and axis on one angle each.
    let positions = file.rows.len() as u64;
    let entries = (30 + 3) * 3 * positions + 3 * positions;
    super::check_column_memory(&format!("{positions} positions"), 3 * file.rows.len(), entries, &file.source)?;
    let obs = AngleObservations::new(file);
    let mut problem = obs.problem(file);
    let selection = select(&mut problem, 0).map_err(|e| InputError::file(&file.source, e))?;
    let effects = effects_of(&problem, &selection);
    let residual_rms: BTreeMap<String, f64> =
        problem.group_names.iter().enumerate().map(|(gi, name)| (name.clone(), selection.base_fit.rms[gi])).collect();
    let figures = FigureData {
        residuals: residuals_by_group(&problem, &selection),
        residual_names: problem.group_names.clone(),
        ..FigureData::default()
    };
    let m = selection.observable as f64;
    let findings = Findings {
        effects,
        residual_rms,
        block_residual_rms: BTreeMap::new(),
        m,
        diagnostics: Vec::new(),
        noise_model: Vec::new(),
        figures,
        model_fit: None,
        windows: None,
    };
    Ok(assemble(problem, selection, findings, ANGLES, &file.source))
}

/// The site of an angles file: its latitude at sea level, its gravity or normal gravity.
fn site(file: &AnglesFile) -> Site {
    let header = crate::io::recording::Header {
        latitude_deg: file.latitude_deg,
        height_m: 0.0,
        rate_hz: None,
        gravity_mps2: file.gravity_mps2,
        comments: Vec::new(),
        truth: None,
        pose_tolerance_deg: None,
    };
    site_of(&header).0
}

/// The observation group of angle `k` (e, n, u): the level angles, or the heading angle.
fn angle_group(k: usize) -> usize {
    if k == 2 {
        1
    } else {
        0
    }
}

/// The angles as observations, three per position, with what the candidates need of each.
struct AngleObservations {
    y: Vec<f64>,
    group: Vec<usize>,
    sigma: Vec<f64>,
    obs_pos: Vec<u32>,
    /// The design row (6 biases) of each observation.
    design: Vec<[f64; 6]>,
    /// Per observation: the Earth rate and the specific force in the body at its position.
    predicted: Vec<([f64; 3], [f64; 3])>,
    /// Per observation: (position index, angle).
    which: Vec<(usize, usize)>,
}

impl AngleObservations {
    fn new(file: &AnglesFile) -> AngleObservations {
        let site = site(file);
        let g = site.gravity_mps2 as f64;
        let w_n = earth_rate_n_radps(file.latitude_deg.to_radians());
        let f_n = [0.0, 0.0, g];
        let mut o = AngleObservations {
            y: Vec::new(),
            group: Vec::new(),
            sigma: Vec::new(),
            obs_pos: Vec::new(),
            design: Vec::new(),
            predicted: Vec::new(),
            which: Vec::new(),
        };
        for (pi, r) in file.rows.iter().enumerate() {
            let c = c_b_n(r.attitude_deg[0], r.attitude_deg[1], r.attitude_deg[2]);
            let c32 = sinscal::math::linalg::Mat3(std::array::from_fn(|i| std::array::from_fn(|j| c[i][j] as f32)));
            let rows = sinscal::calib::angles::design_rows_si(&c32, &site);
            for k in 0..3 {
                o.y.push(r.phi_rad[k]);
                o.group.push(angle_group(k));
                o.sigma.push(r.phi_std_rad.map_or(1.0, |s| s[k]));
                o.obs_pos.push(r.pos);
                o.design.push(std::array::from_fn::<f64, 6, _>(|j| rows[k][j] as f64));
                o.predicted.push((in_body(&c, w_n), in_body(&c, f_n)));
                o.which.push((pi, k));
            }
        }
        o
    }

    /// The linear problem: the angles (weighted by their standard deviations when the file gives them), the
    /// six biases through the design rows, the candidates.
    fn problem(self, file: &AnglesFile) -> Problem {
        let known = file.rows[0].phi_std_rad.is_some();
        let base: Vec<Vec<f64>> = (0..6).map(|j| self.design.iter().map(|d| d[j]).collect()).collect();
        let base_names = ["gyro_bias_x", "gyro_bias_y", "gyro_bias_z", "accel_bias_x", "accel_bias_y", "accel_bias_z"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let candidates = self.candidates(file);
        Problem {
            obs: Observations {
                y: self.y,
                group: self.group,
                groups: 2,
                sigma: if known { Some(self.sigma) } else { None },
            },
            base,
            base_names,
            group_names: vec!["phi_en_rad".into(), "phi_u_rad".into()],
            group_units: vec!["rad", "rad"],
            obs_pos: self.obs_pos,
            obs_pose: None,
            obs_block: None,
            candidates,
            unobservable: Vec::new(),
            residual_of: "angles",
        }
    }

    /// A sensor error at a position maps to the angles through the design rows; the reference offset and
    /// the position errors are the angles themselves.
    fn candidates(&self, file: &AnglesFile) -> Vec<Candidate> {
        let nobs = self.y.len();
        let mut candidates = Vec::new();
        for t in sensor_terms(true) {
            let col = Column::new(
                (0..nobs)
                    .map(|i| self.design[i][t.channel] * t.per_unit(self.predicted[i].0, self.predicted[i].1))
                    .collect(),
            );
            let sensor = t.sensor();
            candidates.push(Candidate::single(t.effect, sensor, t.axes, col, vec![0, 1]));
        }
        for k in 0..3 {
            let col = Column::new(self.which.iter().map(|&(_, kk)| if kk == k { 1.0 } else { 0.0 }).collect());
            candidates.push(Candidate::single(
                EffectKind::ReferenceOffset,
                Sensor::Reference,
                ENU[k].into(),
                col,
                vec![angle_group(k)],
            ));
        }
        for (pi, r) in file.rows.iter().enumerate() {
            for k in 0..3 {
                // Position `pi`'s angle `k` is observation `3 pi + k` (`which`).
                let col = Column::from_entries(nobs, [(3 * pi + k, 1.0)]);
                candidates.push(Candidate {
                    pos: Some(r.pos),
                    ..Candidate::single(
                        EffectKind::PositionError,
                        Sensor::Reference,
                        ENU[k].into(),
                        col,
                        vec![angle_group(k)],
                    )
                });
            }
        }
        // No time terms in angles: the session's length does not enter.
        Candidate::set_limits(&mut candidates, 1.0, 1.0);
        candidates
    }
}
