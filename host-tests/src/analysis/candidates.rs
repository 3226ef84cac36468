//! The catalogue's columns: every effect that is linear in its parameter, as a column over the block
//! observations of a recording (sensor terms, table attitude errors, drift, warm-up, temperature). The
//! angles front end maps the same sensor terms through the alignment equations (`angles`).

use crate::model::catalogue::{EffectKind, Sensor};
use crate::model::sensor::Term;
use crate::model::synth::{cross, mul_t_vec, M3};

use super::column::Column;
use super::observations::{BlockObs, Blocks, DwellData, Session};
use super::{AXES, ENU};

/// Time constants of the warm-up's grid, from 5 s to the session's span.
pub(super) const TAU_GRID_POINTS: usize = 48;

/// A candidate column (or family of columns, one per time constant).
#[derive(Clone, Debug)]
pub(super) struct Candidate {
    /// The catalogue entry.
    pub effect: EffectKind,
    /// Its sensor (for the per-channel effects, the channel's).
    pub sensor: Sensor,
    /// Axis or axis pair.
    pub axes: String,
    /// Position (position errors).
    pub pos: Option<u32>,
    /// The other face of an up/down pair that shares the position error's tilt (heading unknown).
    pub pair_pos: Option<u32>,
    /// Per variant: the time constant it stands for (warm-up) and its column.
    pub variants: Vec<(Option<f64>, Column)>,
    /// Observation groups (channels, angle groups) the effect acts on.
    pub groups: Vec<usize>,
    /// Largest plausible magnitude of the estimate, SI ([`EffectKind::plausible_limit`]).
    pub limit: Option<f64>,
}

impl Candidate {
    /// A candidate of one column, not tied to a position.
    pub fn single(effect: EffectKind, sensor: Sensor, axes: String, col: Column, groups: Vec<usize>) -> Candidate {
        Candidate { effect, sensor, axes, pos: None, pair_pos: None, variants: vec![(None, col)], groups, limit: None }
    }

    /// Sets the plausible limit of every candidate, for a session of `span_s` seconds whose temperature
    /// spans `temperature_span_k`.
    pub fn set_limits(candidates: &mut [Candidate], span_s: f64, temperature_span_k: f64) {
        for c in candidates {
            c.limit = c.effect.plausible_limit(c.sensor, &c.axes, span_s, temperature_span_k);
        }
    }

    /// "effect:axes", with the position of a position error ("position_error:e:pos3") and the sensor of
    /// the effects both sensors have ("bias_drift:x (gyro)").
    pub fn name(&self) -> String {
        match (self.pos, self.pair_pos) {
            (Some(p), Some(q)) => format!("{}:{}:pos{}+pos{}", self.effect, self.axes, p, q),
            (Some(p), None) => format!("{}:{}:pos{}", self.effect, self.axes, p),
            (None, _) if self.effect.sensor().is_none() => format!("{}:{} ({})", self.effect, self.axes, self.sensor),
            (None, _) => format!("{}:{}", self.effect, self.axes),
        }
    }

    /// Parameters the candidate adds: 2 for a family over time constants, else 1.
    pub fn parameters(&self) -> usize {
        if self.variants.len() > 1 {
            2
        } else {
            1
        }
    }

    /// SI unit of the estimate.
    pub fn unit(&self) -> &'static str {
        self.effect.unit(self.sensor)
    }
}

/// A term of the sensor model ([`crate::model::sensor::Term`]: a scale factor, a misalignment or a gyro
/// g-sensitivity) with its catalogue entry and axes.
pub(super) struct SensorTerm {
    /// The catalogue entry.
    pub effect: EffectKind,
    /// Axis ("x") or axis pair ("xy").
    pub axes: String,
    /// Output channel, 0..5.
    pub channel: usize,
    /// The term of the sensor model.
    term: Term,
}

impl SensorTerm {
    /// The sensor of the term's effect.
    pub fn sensor(&self) -> Sensor {
        Sensor::of_channel(self.channel)
    }

    /// The output error per unit parameter at true body rate `rate_b_radps` and force `force_b_mps2`.
    pub fn per_unit(&self, rate_b_radps: [f64; 3], force_b_mps2: [f64; 3]) -> f64 {
        self.term.per_unit(rate_b_radps, force_b_mps2)
    }
}

/// The terms of the catalogue's sensor model: accelerometer scale factors and misalignments, and, with
/// `gyros`, the gyro scale factors, misalignments and g-sensitivity ([`Term::all`], in its order).
pub(super) fn sensor_terms(gyros: bool) -> Vec<SensorTerm> {
    Term::all(gyros)
        .into_iter()
        .map(|term| {
            let axes = match term.effect {
                EffectKind::AccelScaleFactor | EffectKind::GyroScaleFactor => AXES[term.axis].to_string(),
                _ => format!("{}{}", AXES[term.axis], AXES[term.along]),
            };
            SensorTerm { effect: term.effect, axes, channel: term.channel(), term }
        })
        .collect()
}

/// Below this fraction of a vector's magnitude, a component of it rotated into the body is rounding, not
/// signal (a component of 1e-12 of gravity is an attitude of 1e-12 rad).
pub(super) const ROUNDING: f64 = 1e-12;

/// `C^T v`: the navigation-frame vector `v` in the body, with the components below [`ROUNDING`] of its
/// magnitude set to exactly zero, so that a column the attitude makes zero is absent, not a column of
/// rounding errors (which a fit would scale to an estimate of 1e13).
pub(super) fn in_body(c_b_n: &M3, v_n: [f64; 3]) -> [f64; 3] {
    let scale = (v_n[0] * v_n[0] + v_n[1] * v_n[1] + v_n[2] * v_n[2]).sqrt();
    mul_t_vec(c_b_n, v_n).map(|x| if x.abs() <= ROUNDING * scale { 0.0 } else { x })
}

/// Unit vector along axis `k`.
pub(super) fn unit(k: usize) -> [f64; 3] {
    let mut e = [0.0; 3];
    e[k] = 1.0;
    e
}

/// Observation groups a table attitude error about navigation axis `k` acts on: the heading error on the
/// gyros, the level errors on the accelerometers.
pub(super) fn attitude_groups(k: usize) -> Vec<usize> {
    if k == 2 {
        vec![0, 1, 2]
    } else {
        vec![3, 4, 5]
    }
}

/// The candidate columns of a recording's block observations.
pub(super) struct RecordingColumns<'a> {
    session: &'a Session,
    blocks: &'a Blocks,
}

/// The bias warm-up's shape at time `t_s`: `exp(-(t_s - t0_s) / tau_s)`, 1 at the session's first row `t0_s`
/// (times in s); the warm-up is its amplitude times this.
pub(super) fn warmup_shape(t_s: f64, t0_s: f64, tau_s: f64) -> f64 {
    (-(t_s - t0_s) / tau_s).exp()
}

impl<'a> RecordingColumns<'a> {
    /// The columns over `blocks` of `session`.
    pub fn new(session: &'a Session, blocks: &'a Blocks) -> RecordingColumns<'a> {
        RecordingColumns { session, blocks }
    }

    /// Every candidate the recording can show, in the catalogue's test order; what it cannot show goes to
    /// `unobservable` ("gyro_misalignment:xy: heading unknown", "temperature_bias:x (gyro)").
    pub fn candidates(&self, unobservable: &mut Vec<String>) -> Vec<Candidate> {
        let mut candidates = self.sensor_term_candidates(unobservable);
        candidates.extend(self.nonlinearities());
        if !self.session.has_gyro {
            use EffectKind::*;
            for effect in [GyroScaleFactor, GyroMisalignment, GyroGSensitivity] {
                unobservable.push(format!("{effect}: no gyro columns"));
            }
        }
        candidates.extend(self.table_errors(unobservable));
        let tau_grid = self.tau_grid();
        let t0 = self.session.t0;
        let shapes: Vec<_> = tau_grid.iter().map(|&tau| move |t: f64| warmup_shape(t, t0, tau)).collect();
        let warmup_means = self.blocks.time_means(self.session, &shapes);
        let span_s = tau_grid.last().copied().unwrap_or(1.0);
        for c in (0..6).filter(|&c| self.blocks.present[c]) {
            candidates.push(self.drift(c));
            candidates.push(self.warmup(c, &tau_grid, &warmup_means));
            if self.session.has_temp() {
                candidates.push(self.temperature(c));
            } else {
                unobservable.push(format!(
                    "{}:{} ({})",
                    EffectKind::TemperatureBias,
                    axis_of(c),
                    Sensor::of_channel(c)
                ));
            }
        }
        Candidate::set_limits(&mut candidates, span_s, self.temperature_span_k());
        candidates
    }

    /// The range of the temperatures of the session, K (0 without temperatures).
    fn temperature_span_k(&self) -> f64 {
        let temps = self.session.dwells.iter().filter_map(|d| d.temp.as_ref()).flatten();
        let (lo, hi) = temps.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| (lo.min(t), hi.max(t)));
        if hi >= lo {
            hi - lo
        } else {
            0.0
        }
    }

    /// The true body force at a block (the tilt suffices).
    fn force_b(&self, b: &BlockObs) -> [f64; 3] {
        let d = &self.session.dwells[b.dwell];
        in_body(d.c_b_n.as_ref().unwrap_or(&d.c_tilt), self.session.f_n)
    }

    /// The true body rate at a block: the Earth rate; with the heading unknown only along a vertical axis
    /// (the other components NaN, [`super::observations::DwellData::rate_b_radps`]).
    fn rate_b(&self, b: &BlockObs) -> [f64; 3] {
        let d = &self.session.dwells[b.dwell];
        match &d.c_b_n {
            Some(c) => in_body(c, self.session.w_n),
            None => d.rate_b_radps(self.session.w_n),
        }
    }

    /// Scale factors, misalignments, g-sensitivity: the predicted rate or force on the sensed axis. A term
    /// that needs a rate the recording does not know on one of its channel's blocks (the heading unknown and
    /// the axis not vertical) goes to `unobservable`.
    fn sensor_term_candidates(&self, unobservable: &mut Vec<String>) -> Vec<Candidate> {
        let mut candidates = Vec::new();
        for t in sensor_terms(self.session.has_gyro) {
            let values = self.blocks.column(|b| {
                if b.channel == t.channel {
                    t.per_unit(self.rate_b(b), self.force_b(b))
                } else {
                    0.0
                }
            });
            if values.iter().any(|v| !v.is_finite()) {
                unobservable.push(format!("{}:{}: heading unknown", t.effect, t.axes));
                continue;
            }
            let sensor = t.sensor();
            candidates.push(Candidate::single(t.effect, sensor, t.axes, Column::new(values), vec![t.channel]));
        }
        candidates
    }

    /// The accelerometers' second-order nonlinearity K2 (docs/analysis.md#base-model-and-candidates): axis
    /// `i` reads `K2_i f_i^2` more, so its column is the square of the predicted force along the axis. Even
    /// in the force, it tells an up face from a down one no more than a bias does, and a face across the axis
    /// from both: a schedule of one face per axis and sign sees it, one pose does not (the base model's bias
    /// explains it, and the screen names it unobservable).
    fn nonlinearities(&self) -> Vec<Candidate> {
        (0..3)
            .filter(|&i| self.blocks.present[3 + i])
            .map(|i| {
                let values = self.blocks.column(|b| if b.channel == 3 + i { self.force_b(b)[i].powi(2) } else { 0.0 });
                Candidate::single(
                    EffectKind::AccelNonlinearity,
                    Sensor::Accel,
                    AXES[i].to_string(),
                    Column::new(values),
                    vec![3 + i],
                )
            })
            .collect()
    }

    /// Table attitude error about navigation axis `k` at block `b`: d(measurement)/d(err_k) = C^T (e_k x v).
    /// With the heading unknown, the level errors (`k` = 0, 1) are about the axes of the pose's heading-0
    /// frame, and their Earth-rate term (at most `W cos L` per radian on a vertical gyro, 7.3e-5 rad/s) is
    /// left out: it needs the heading.
    fn attitude_error(&self, k: usize, b: &BlockObs) -> f64 {
        let d = &self.session.dwells[b.dwell];
        match (&d.c_b_n, b.channel < 3) {
            (Some(c), true) => in_body(c, cross(unit(k), self.session.w_n))[b.channel],
            (None, true) => 0.0,
            (c, false) => in_body(c.as_ref().unwrap_or(&d.c_tilt), cross(unit(k), self.session.f_n))[b.channel - 3],
        }
    }

    /// The reference offset (e, n, u) and, with more than one dwell, a position error per dwell and axis (a
    /// column over the dwell's own blocks, which are consecutive). With a heading unknown, the level position
    /// errors (e, n of each pose's heading-0 frame: the pose's tilt off its label) and nothing that needs the
    /// heading: the reference offset (a common table error reaches each pose through its own heading) and the
    /// heading errors go to `unobservable`.
    fn table_errors(&self, unobservable: &mut Vec<String>) -> Vec<Candidate> {
        let mut candidates = Vec::new();
        let heading = self.session.all_heading();
        if heading {
            for k in 0..3 {
                let col = Column::new(self.blocks.column(|b| self.attitude_error(k, b)));
                candidates.push(Candidate::single(
                    EffectKind::ReferenceOffset,
                    Sensor::Reference,
                    ENU[k].into(),
                    col,
                    attitude_groups(k),
                ));
            }
        } else {
            unobservable.push(format!("{}: heading unknown", EffectKind::ReferenceOffset));
            unobservable.push(format!("{}:u: heading unknown", EffectKind::PositionError));
        }
        if self.session.dwells.len() > 1 {
            let axes = if heading { 0..3 } else { 0..2 };
            let list = &self.blocks.list;
            let mut first = 0;
            for (di, d) in self.session.dwells.iter().enumerate() {
                let end = first + list[first..].iter().take_while(|b| b.dwell == di).count();
                for k in axes.clone() {
                    let entries = (first..end).map(|i| (i, self.attitude_error(k, &list[i])));
                    let col = Column::from_entries(list.len(), entries);
                    candidates.push(Candidate {
                        pos: Some(d.pos),
                        ..Candidate::single(
                            EffectKind::PositionError,
                            Sensor::Reference,
                            ENU[k].into(),
                            col,
                            attitude_groups(k),
                        )
                    });
                }
                first = end;
            }
        }
        if !heading {
            candidates.extend(self.pair_tilts());
        }
        candidates
    }

    /// With the headings unknown, a tilt shared by the two faces of an up/down pair (the same body axis
    /// vertical, up in one and down in the other): on each horizontal accelerometer of the pair, the same
    /// offset in both faces. A face's own tilt and a misalignment are the same thing in a six-face schedule
    /// (each moves one face's horizontal force); a tilt the pair shares is not a misalignment, which changes
    /// sign between the faces (docs/analysis.md#tilts). Reported as the position error of the first face
    /// (about the axis of its heading-0 frame that moves gravity onto that accelerometer), with the second
    /// face as `pair_pos`.
    fn pair_tilts(&self) -> Vec<Candidate> {
        let list = &self.blocks.list;
        let vertical = DwellData::vertical_axis;
        let mut candidates = Vec::new();
        let dwells = &self.session.dwells;
        for (i, a) in dwells.iter().enumerate() {
            let Some((axis, up)) = vertical(a) else { continue };
            // The first later dwell that is this face's opposite (one pair per face, in order).
            let Some(j) = (i + 1..dwells.len()).find(|&j| vertical(&dwells[j]) == Some((axis, -up))) else { continue };
            let b = &dwells[j];
            if (0..i).any(|k| vertical(&dwells[k]) == Some((axis, -up))) {
                continue; // this face was already paired
            }
            for h in (0..3).filter(|&h| h != axis) {
                // The axis k of face a's heading-0 frame whose tilt moves gravity onto body axis h.
                let tilt = |k: usize| in_body(&a.c_tilt, cross(unit(k), self.session.f_n))[h];
                let Some(k) = (0..2).find(|&k| tilt(k) != 0.0) else { continue };
                let value = tilt(k);
                let entries =
                    (0..list.len()).filter(|&n| list[n].channel == 3 + h && (list[n].dwell == i || list[n].dwell == j));
                let col = Column::from_entries(list.len(), entries.map(|n| (n, value)));
                candidates.push(Candidate {
                    pos: Some(a.pos),
                    pair_pos: Some(b.pos),
                    ..Candidate::single(EffectKind::PositionError, Sensor::Reference, ENU[k].into(), col, vec![3 + h])
                });
            }
        }
        candidates
    }

    /// The warm-up's time constants: 48 values from 5 s to the session length, logarithmically spaced.
    fn tau_grid(&self) -> Vec<f64> {
        let t0 = self.session.t0;
        let span =
            self.session.dwells.iter().flat_map(|d| d.t.iter()).fold(0.0f64, |m, t| m.max(t - t0)).max(self.session.dt);
        let last = (TAU_GRID_POINTS - 1) as f64;
        (0..TAU_GRID_POINTS).map(|i| 5.0 * (span / 5.0f64).powf(i as f64 / last)).collect()
    }

    /// The column of channel `c`: `f` of the block's times on its rows, zero elsewhere.
    fn channel_column(&self, c: usize, f: impl Fn(&BlockObs, &[f64]) -> f64) -> Column {
        Column::new(self.blocks.column(|b| {
            if b.channel != c {
                0.0
            } else {
                f(b, &self.session.dwells[b.dwell].t[b.range.0..b.range.1])
            }
        }))
    }

    /// Bias drift of channel `c`: block mean time minus the middle of the session.
    fn drift(&self, c: usize) -> Candidate {
        let dwells = &self.session.dwells;
        let t_mid = {
            let (lo, hi) = (dwells[0].t[0], dwells[dwells.len() - 1].t.last().copied().unwrap_or(0.0));
            0.5 * (lo + hi)
        };
        let col = self.channel_column(c, |_, t| t.iter().sum::<f64>() / t.len() as f64 - t_mid);
        Candidate::single(EffectKind::BiasDrift, Sensor::of_channel(c), axis_of(c).into(), col, vec![c])
    }

    /// Bias warm-up of channel `c`: the block mean of `exp(-(t - t0)/tau)` (`means`, per time constant and
    /// block), one variant per time constant.
    fn warmup(&self, c: usize, tau_grid: &[f64], means: &[Vec<f64>]) -> Candidate {
        let variants = tau_grid
            .iter()
            .zip(means)
            .map(|(&tau, m)| (Some(tau), Column::new(self.blocks.on_channel(c, m))))
            .collect();
        Candidate {
            effect: EffectKind::BiasWarmup,
            sensor: Sensor::of_channel(c),
            axes: axis_of(c).into(),
            pos: None,
            pair_pos: None,
            variants,
            groups: vec![c],
            limit: None,
        }
    }

    /// Temperature bias of channel `c`: the block mean temperature.
    fn temperature(&self, c: usize) -> Candidate {
        let col = self.channel_column(c, |b, _| {
            let temp = self.session.dwells[b.dwell].temp.as_ref().map_or(&[][..], |v| &v[b.range.0..b.range.1]);
            temp.iter().sum::<f64>() / temp.len().max(1) as f64
        });
        Candidate::single(EffectKind::TemperatureBias, Sensor::of_channel(c), axis_of(c).into(), col, vec![c])
    }
}

/// The body axis of channel `c` (gx..az = 0..5).
pub(super) fn axis_of(c: usize) -> &'static str {
    AXES[c % 3]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::synth::{c_b_n, earth_rate_n_radps};

    #[test]
    fn attitude_columns_map_to_the_angles_they_are() {
        // The alignment equations (the core's design rows) applied to the sensor signature of a table
        // attitude error err, C^T (e_k x v), give err back: the sign convention of the recording analysis
        // (C_true = (I - [err x]) C_ref) is the one of the angles and of phi0 in docs/method.md.
        let lat = 45.7796f64.to_radians();
        let site = sinscal::nav::earth::Site::with_normal_gravity(lat as f32, 0.0);
        let g = site.gravity_mps2 as f64;
        let w_n = earth_rate_n_radps(lat);
        for att in crate::model::synth::TABLE1_DEG {
            let c = c_b_n(att[0], att[1], att[2]);
            let c32 = sinscal::math::linalg::Mat3(std::array::from_fn(|i| std::array::from_fn(|j| c[i][j] as f32)));
            let rows = sinscal::calib::angles::design_rows_si(&c32, &site);
            for k in 0..3 {
                let dw = mul_t_vec(&c, cross(unit(k), w_n));
                let df = mul_t_vec(&c, cross(unit(k), [0.0, 0.0, g]));
                for (r, row) in rows.iter().enumerate() {
                    let phi: f64 = (0..3).map(|j| row[j] as f64 * dw[j] + row[3 + j] as f64 * df[j]).sum();
                    let want = if r == k { 1.0 } else { 0.0 };
                    assert!((phi - want).abs() < 1e-5, "att {att:?} k {k} row {r}: {phi}");
                }
            }
        }
    }
}
