//! Planted effects in the measured data sets WITH THEIR OWN POSES AND TIME BASE: each record as imported
//! (the imucal Ferraris session's six hand-placed faces, the imu_tk record's 37 levelled poses, the PSINS
//! record's one pose), not laid over the paper's Table 1 as [`crate::planted`] lays one static stretch.
//!
//! **Baseline** ([`Baseline`]). The untouched recording is analysed once. What it names is the record's
//! own (its misalignments, tilts, quantisation, ...): a trial is judged against it. What can be planted is
//! what the record can show: every linear candidate of the baseline's `tested` list (observable in these
//! poses), but for the shared tilts of an up/down pair (only single-pose position errors are planted), and
//! only where the largest planted value plus the baseline's own estimate of that candidate stays within the
//! catalogue's plausible limit; the warm-up on the channels whose warm-up is tested, where the largest size
//! stays within the plausible limit of its amplitude at some time constant of the range; vibration and
//! correlated noise on every channel; a noise warm-up on every channel of a record long enough for one;
//! quantisation on the channels where the smallest planted step is at least [`QUANTISATION_MARGIN`] times
//! the record's own.
//!
//! **Planting** ([`crate::planted::plant_into`]): the sensor model of [`crate::planted`], on the record's own
//! rows, poses (an unknown heading taken as 0: the analysis uses the Earth rate of such a pose only along a
//! vertical axis) and times (from the first row, the warm-up's origin); the moving effects through the
//! record's quantiser ([`DataSet::quantiser`]).
//!
//! **Sizes** ([`SIZES`]): 3, 5 and 10 standard errors, random sign, axes (among the plantable ones) and
//! line frequency. One standard error is
//! - a linear term (scale factor, misalignment, g-sensitivity, reference offset, position error, drift): the
//!   baseline's `tested` standard error of the candidate (fitted with the base model alone);
//! - a warm-up `A exp(-(t - t0)/tau)`: as [`crate::planted`] (1.5 times the base model's block residual RMS
//!   of the channel over the norm of the block-mean shape), the shape taken over the blocks where the
//!   analysis observes the channel and freed of the base model's columns there (levelled records: the
//!   accelerometer's share of the force along gravity, the three biases projected; gyros of unknown heading:
//!   the dwells with the gyro's axis vertical); `tau` 5 to 26 % of the session, at least 10 s, and such that
//!   the largest size stays within the plausible limit of a warm-up's amplitude;
//! - a vibration line: as [`crate::planted`], the amplitude standard error of a sinusoid in the channel's
//!   measured noise density at the line, `sqrt(S(f) rate / 2) sqrt(2 / n)`; frequency 1 Hz to 0.4 times the
//!   sample rate;
//! - a correlated noise (first-order Gauss-Markov of time constant `tau`, 0.2 to 2 s but at most 0.8 of
//!   the analysis's search range, a quarter of the shortest dwell): `k` standard errors is the variance whose
//!   expected likelihood ratio against the channel's measured noise density is `k^2`, as for the others
//!   (Whittle's likelihood, over the Fourier frequencies of every dwell but the two lowest, which the dwell's
//!   own mean and line take). A variance's standard error depends on the variance: for a weak process this
//!   is `k` standard errors of the variance estimated at zero, a strong one needs more;
//! - a noise warm-up (white noise of standard deviation `e` added until `T`, 10 to 30 % of the session, at
//!   least 30 s; on the channels whose baseline names none): `k` standard errors of the test's difference of
//!   mean log-variances of one-second blocks before and after `T`, on the record itself
//!   ([`Baseline::noise_warmup_excess`]);
//! - a quantisation step `q`: its noise `q^2 / 12` counted in standard errors of the per-sample variance
//!   (`sigma^2 sqrt(2 / n)`, `sigma` the detrended RMS per sample): `q = sqrt(12 k sigma^2 sqrt(2 / n))`.
//!
//! **Judged** ([`judge`]). FOUND: the analysis names an effect of the planted kind, sensor and axes (or
//! with the planted candidate among its aliases: two halves of a misalignment that gravity alone sees as one)
//! and position, at the planted line for a vibration, whose estimate is the planted value (linear terms:
//! within 3 of its standard errors of the planted value, plus the baseline's estimate when the baseline
//! names the same candidate; warm-up, vibration, correlated noise, noise warm-up and quantisation: within
//! 30 %; a correlated noise on a channel whose baseline names one: within 30 % of the root sum of squares of
//! the two, since independent processes add their variances, and moved from the baseline's by more than 3
//! of its standard errors), and which
//! is not the baseline's own (a candidate the baseline names counts only when the estimate moved away from
//! the baseline's by more than 3 standard errors, or 30 %). FALSE ALARM: an effect named in the trial that
//! is neither of the planted kind, sensor, axes and position nor in the baseline (same candidate, same
//! line), and that the analysis does not name as indistinguishable (an alias of any kind) from a baseline
//! effect or from the planted candidate. An effect is UNCERTAIN when the analysis ranks it so (`Effect::uncertain`: an alias of pose order,
//! the session's halves, the bias's slow wander or the thirds of the dwells, or a time constant at the end
//! of its grid).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::hidden::{catalogue, Hidden};
use crate::planted::{block_ranges, candidate_name, plant_into, same_line, Base, Planted, Quantiser, Reference};
use sinscal::calib::general::AttitudeKnowledge;
use sinscal_host::analysis::{analyze_recording, noise_warmup_scale, Analysis, Effect, CHANNELS};
use sinscal_host::calibration::{attitude_knowledge, site_of};
use sinscal_host::io::import::{import_imucal, import_imutk, import_psins, level_attitude_deg, StaticDetection};
use sinscal_host::io::recording::Recording;
use sinscal_host::model::catalogue::{EffectKind, Sensor};
use sinscal_host::model::synth::{c_b_n, earth_rate_n_radps, mul_t_vec, M3};

/// The sizes of the campaign, in standard errors (see the module's documentation).
pub const SIZES: [f64; 3] = [3.0, 5.0, 10.0];

/// A quantisation is planted only on a channel where its smallest step is at least this many times the
/// record's own step: a finer one leaves the record's lattice, and one close to it cannot be told from it.
pub const QUANTISATION_MARGIN: f64 = 1.5;

/// Body axis names.
const AXES: [&str; 3] = ["x", "y", "z"];

/// The three shared data sets (docs/data.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum DataSet {
    /// The imucal Ferraris session: six hand-placed faces of 4 to 7 s, headings unknown, 102.4 Hz.
    Ferraris,
    /// The imu_tk Xsens record: 37 static poses levelled from the accelerometers, 100 Hz, 512 s.
    Imutk,
    /// The PSINS ring-laser-gyro record: one static pose, 100 Hz, 1847 s.
    Psins,
}

impl DataSet {
    /// Every set, in the order of the campaign.
    pub const ALL: [DataSet; 3] = [DataSet::Ferraris, DataSet::Imutk, DataSet::Psins];

    /// The data set's folder name.
    pub fn name(self) -> &'static str {
        match self {
            DataSet::Ferraris => "imucal-ferraris",
            DataSet::Imutk => "imu-tk-xsens",
            DataSet::Psins => "psins-lasergyro",
        }
    }

    /// The set named `name` (its folder name, or "ferraris", "imutk", "psins").
    pub fn parse(name: &str) -> Option<DataSet> {
        DataSet::ALL.into_iter().find(|s| s.name() == name || s.name().replace(['-', '_'], "").contains(name))
    }

    /// How the record's quantised channels read out: the PSINS increments carry their remainder, the imu_tk
    /// and BMI160 counts are sampled.
    pub fn quantiser(self) -> Quantiser {
        match self {
            DataSet::Psins => Quantiser::Carried,
            DataSet::Ferraris | DataSet::Imutk => Quantiser::Sampled,
        }
    }

    /// The record, imported from the data directory `dir` as `sinscal import` does
    /// (host-tests/tests/common/mod.rs).
    pub fn import(self, dir: &Path) -> Result<Recording, String> {
        let file = |relative: &str| {
            let path = dir.join(relative);
            if path.is_file() {
                Ok(path)
            } else {
                Err(format!("{} is missing", path.display()))
            }
        };
        let imported = match self {
            DataSet::Ferraris => import_imucal(
                &file("imucal-ferraris/example_ferraris_session.csv")?,
                &file("imucal-ferraris/example_ferraris_session_list.json")?,
                None,
            ),
            DataSet::Imutk => import_imutk(
                &file("imu-tk-xsens/xsens_acc.mat")?,
                &file("imu-tk-xsens/xsens_gyro.mat")?,
                None,
                &StaticDetection::default(),
            ),
            DataSet::Psins => import_psins(&file("psins-lasergyro/lasergyro.imu")?, None),
        };
        imported.map(|i| i.recording).map_err(|e| e.to_string())
    }
}

/// Where an effect can be planted: sensor, axes as the analysis names them, position (position errors), the
/// channel (per-channel effects), and for a linear term its standard error (the baseline's `tested`).
#[derive(Clone, Debug, PartialEq)]
pub struct Target {
    /// The effect's sensor (the channel's, for the per-channel effects).
    pub sensor: Sensor,
    /// Axes ("xz", "e", "x").
    pub axes: String,
    /// Position (position errors).
    pub pos: Option<u32>,
    /// Channel gx..az = 0..5 (per-channel effects).
    pub channel: Option<usize>,
    /// Standard error of the candidate fitted with the base model alone (linear terms), SI.
    pub std_error: Option<f64>,
}

impl Target {
    /// "xz", "e:pos3", "x (gyro)".
    pub fn text(&self) -> String {
        match (self.pos, self.channel) {
            (Some(p), _) => format!("{}:pos{p}", self.axes),
            (None, Some(_)) => format!("{} ({})", self.axes, self.sensor),
            _ => self.axes.clone(),
        }
    }
}

/// One block of the analysis (docs/analysis.md#observations): its sample times and the unit vector of
/// gravity in the body at its dwell's stated pose.
#[derive(Clone, Debug)]
struct Block {
    times: Vec<f64>,
    up: [f64; 3],
}

/// A data set analysed untouched: the baseline of its trials.
#[derive(Clone, Debug)]
pub struct Baseline {
    /// Which set.
    pub set: DataSet,
    /// The record as imported.
    pub recording: Recording,
    /// `sinscal analyze` of it: every effect it names is the record's own.
    pub analysis: Analysis,
    /// Time the baseline's analysis took, s.
    pub seconds: f64,
    /// What can be planted, per effect (in the order of the catalogue).
    pub plantable: Vec<(EffectKind, Vec<Target>)>,
    reference: Reference,
    w_n_radps: [f64; 3],
    f_n_mps2: [f64; 3],
    steps_si: [Option<f64>; 6],
    blocks: Vec<Block>,
    levelled: bool,
    /// Levelled records: per position, the attitude levelled from the dwell's mean specific force less the
    /// baseline's accelerometer biases, as the analysis levels it (docs/analysis.md#attitudes-levelled-from-the-accelerometers).
    attitudes: BTreeMap<u32, M3>,
    /// Time of the first row, s (the warm-up's origin).
    t0: f64,
    /// Last dwell sample less `t0`, s (the analysis's session length).
    span_s: f64,
    /// The shortest dwell, s.
    shortest_dwell_s: f64,
}

impl Baseline {
    /// Analyses `recording` of `set` and finds what can be planted in it.
    pub fn new(set: DataSet, recording: Recording) -> Result<Baseline, String> {
        let start = Instant::now();
        let analysis = analyze_recording(&recording).map_err(|e| e.to_string())?;
        let seconds = start.elapsed().as_secs_f64();
        let reference = Reference::new(&recording, &analysis);
        let (site, _) = site_of(&recording.header);
        let rate_hz = reference.rate_hz;
        let t0 = recording.rows.first().map_or(0.0, |r| r.t_s);
        let dwells = recording.dwells();
        let levelled = matches!(attitude_knowledge(&recording.header), AttitudeKnowledge::Unknown);
        let bias = |k: &str| analysis.base_model.biases.get(&format!("accel_bias_{k}")).copied().unwrap_or(0.0);
        let accel_bias = [bias("x"), bias("y"), bias("z")];
        let (mut blocks, mut attitudes) = (Vec::new(), BTreeMap::new());
        for d in &dwells {
            let r = d.rows[0];
            let mut c = c_b_n(r.pitch_deg, r.roll_deg, r.heading_deg.unwrap_or(0.0));
            if levelled {
                let n = d.rows.len() as f64;
                let f: [f64; 3] =
                    std::array::from_fn(|k| d.rows.iter().map(|r| r.force_b_mps2[k]).sum::<f64>() / n - accel_bias[k]);
                if let Some((pitch, roll)) = level_attitude_deg(f) {
                    c = c_b_n(pitch, roll, 0.0);
                }
                attitudes.insert(d.pos, c);
            }
            let up = mul_t_vec(&c, [0.0, 0.0, 1.0]);
            for (a, b) in block_ranges(d.rows.len()) {
                blocks.push(Block { times: d.rows[a..b].iter().map(|r| r.t_s).collect(), up });
            }
        }
        let span_s = dwells.iter().flat_map(|d| d.rows.iter()).fold(0.0f64, |m, r| m.max(r.t_s - t0));
        let shortest_dwell_s = dwells.iter().map(|d| d.rows.len()).min().unwrap_or(0) as f64 / rate_hz;
        let steps_si = std::array::from_fn(|ch| analysis.diagnostics.get(ch).and_then(|d| d.quantization_step));
        let mut b = Baseline {
            set,
            w_n_radps: earth_rate_n_radps(recording.header.latitude_deg.to_radians()),
            f_n_mps2: [0.0, 0.0, site.gravity_mps2 as f64],
            recording,
            analysis,
            seconds,
            plantable: Vec::new(),
            reference,
            steps_si,
            blocks,
            levelled,
            attitudes,
            t0,
            span_s,
            shortest_dwell_s,
        };
        b.plantable = b.find_plantable();
        Ok(b)
    }

    /// The base of a planting on this record.
    pub fn base(&self) -> Base<'_> {
        Base {
            recording: &self.recording,
            attitudes: self.levelled.then_some(&self.attitudes),
            w_n_radps: self.w_n_radps,
            f_n_mps2: self.f_n_mps2,
            steps_si: self.steps_si,
            quantiser: self.set.quantiser(),
        }
    }

    /// The targets of `effect` (empty when it cannot be planted here).
    pub fn targets(&self, effect: EffectKind) -> &[Target] {
        self.plantable.iter().find(|(e, _)| *e == effect).map_or(&[], |(_, t)| t.as_slice())
    }

    /// The baseline's estimate of `effect` at `target` when it names it as an effect.
    fn named_estimate(&self, effect: EffectKind, target: &Target) -> Option<f64> {
        self.analysis
            .effects
            .iter()
            .find(|e| {
                e.effect == effect.name()
                    && e.sensor == target.sensor.name()
                    && e.axes == target.axes
                    && e.pos == target.pos
                    && e.pair_pos.is_none()
            })
            .map(|e| e.estimate)
    }

    /// Every effect of the catalogue that can be planted here, with its targets.
    fn find_plantable(&self) -> Vec<(EffectKind, Vec<Target>)> {
        let largest = SIZES.iter().fold(0.0f64, |m, &k| m.max(k));
        let smallest = SIZES.iter().fold(f64::INFINITY, |m, &k| m.min(k));
        let channels = |filter: &dyn Fn(usize) -> bool| -> Vec<Target> {
            (0..6).filter(|&ch| ch < self.analysis.diagnostics.len() && filter(ch)).map(channel_target).collect()
        };
        let mut out = Vec::new();
        // The Table 1 trials' kinds, and the noise warm-up, which they do not plant.
        let kinds = catalogue().into_iter().filter_map(|(name, _)| name.parse::<EffectKind>().ok());
        for effect in kinds.chain([EffectKind::NoiseWarmup]) {
            let targets = match effect {
                EffectKind::TemperatureBias => Vec::new(),
                EffectKind::Vibration | EffectKind::CorrelatedNoise => channels(&|_| true),
                EffectKind::NoiseWarmup => match self.noise_warmup_settled_s() {
                    // A channel whose noise has a warm-up of its own cannot show another.
                    Some(range) => channels(&|ch| {
                        self.named_estimate(EffectKind::NoiseWarmup, &channel_target(ch)).is_none()
                            && [range.start, range.end].iter().all(|&t| self.noise_warmup_excess(ch, t, 1.0).is_some())
                    }),
                    None => Vec::new(),
                },
                EffectKind::Quantization => channels(&|ch| {
                    self.steps_si[ch].is_none_or(|q| self.quantisation_step(ch, smallest) >= QUANTISATION_MARGIN * q)
                }),
                EffectKind::BiasWarmup => channels(&|ch| {
                    let tested = format!("bias_warmup:{} ({})", AXES[ch % 3], Sensor::of_channel(ch));
                    self.tested_names().any(|n| n == tested) && self.warmup_fits(ch, largest)
                }),
                _ => self.linear_targets(effect, largest),
            };
            if !targets.is_empty() {
                out.push((effect, targets));
            }
        }
        out
    }

    fn tested_names(&self) -> impl Iterator<Item = &str> {
        self.analysis.tested.iter().map(|t| t.name.as_str())
    }

    /// The candidates of the linear `effect` in the baseline's `tested` list (single-pose position errors
    /// only), where `largest` standard errors plus the baseline's named estimate stay within the plausible
    /// limit.
    fn linear_targets(&self, effect: EffectKind, largest: f64) -> Vec<Target> {
        let mut out = Vec::new();
        for t in &self.analysis.tested {
            let Some(target) = parse_candidate(&t.name, effect, t.std_error) else { continue };
            let limit = effect.plausible_limit(target.sensor, &target.axes, self.span_s, 0.0);
            let worst = self.named_estimate(effect, &target).unwrap_or(0.0).abs() + largest * t.std_error;
            if t.std_error > 0.0 && limit.is_none_or(|l| worst <= l) {
                out.push(target);
            }
        }
        out
    }

    /// The range of the warm-up time constants planted, s: 5 to 26 % of the session, at least 10 s.
    fn warmup_taus_s(&self) -> std::ops::Range<f64> {
        let lo = (0.05 * self.span_s).max(10.0);
        lo..(0.26 * self.span_s).max(2.0 * lo)
    }

    /// Whether a warm-up of `size` standard errors on channel `ch` stays within the plausible limit of its
    /// amplitude at a time constant of the range (20 tried).
    fn warmup_fits(&self, ch: usize, size: f64) -> bool {
        let limit = EffectKind::BiasWarmup.plausible_limit(Sensor::of_channel(ch), AXES[ch % 3], self.span_s, 0.0);
        let taus = self.warmup_taus_s();
        (0..20).any(|i| {
            let tau = taus.start + (taus.end - taus.start) * i as f64 / 19.0;
            limit.is_none_or(|l| size * self.warmup_unit(ch, tau) <= l)
        })
    }

    /// One standard error of a warm-up of time constant `tau_s` on channel `ch` (see the module's
    /// documentation), SI.
    pub fn warmup_unit(&self, ch: usize, tau_s: f64) -> f64 {
        let rms = &self.analysis.base_model.block_residual_rms;
        let levelled_accel = self.levelled && ch >= 3;
        let key = if levelled_accel { "f_along_gravity_mps2" } else { CHANNELS[ch] };
        let sigma = rms.get(key).copied().unwrap_or(0.0);
        let axis = ch % 3;
        let unknown_heading = ch < 3 && self.recording.rows.iter().any(|r| r.heading_deg.is_none());
        let (mut base, mut column): (Vec<Vec<f64>>, Vec<f64>) = (vec![Vec::new(); 3], Vec::new());
        for b in &self.blocks {
            if unknown_heading && b.up[axis].abs() < 0.99 {
                continue;
            }
            let shape = b.times.iter().map(|t| (-(t - self.t0) / tau_s).exp()).sum::<f64>() / b.times.len() as f64;
            if levelled_accel {
                (0..3).for_each(|k| base[k].push(b.up[k]));
                column.push(b.up[axis] * shape);
            } else {
                base[0].push(1.0);
                column.push(shape);
            }
        }
        base.retain(|c| !c.is_empty());
        1.5 * sigma / remainder_norm(&base, &column).max(f64::MIN_POSITIVE)
    }

    /// The variance of a Gauss-Markov process of time constant `tau_s` planted at `size` standard errors on
    /// channel `ch` (see the module's documentation), SI^2: the variance whose expected likelihood ratio
    /// against the channel's measured noise density is `size^2`, as a linear term's is at `size` of its
    /// standard errors. Whittle's likelihood over every dwell's own Fourier frequencies `k / T` but its two
    /// lowest (`k` = 0 and 1: what the dwell's mean and line take, which the analysis removes), the measured
    /// density `S` read at the nearest bin: with `r = v g(f) / S(f)` the process's share at `f` (`g` its
    /// density per unit variance), the expected ratio is `2 sum (r - ln(1 + r))`. For a small `v` that is
    /// `v^2` times the information at zero, `sum (g / S)^2`; a process strong in the few frequencies where its
    /// power lies gains less than that (at the campaign's 10 standard errors of the information at zero, the
    /// measured ratios were 19 to 60 on the Ferraris faces).
    pub fn markov_variance(&self, ch: usize, tau_s: f64, size: f64) -> f64 {
        let r = &self.reference;
        let (freqs, density) = &r.spectra[ch];
        let dt = 1.0 / r.rate_hz;
        let phi = (-dt / tau_s).exp();
        let bin = freqs.get(1).copied().unwrap_or(1.0);
        let per_unit = |f: f64| {
            2.0 * dt * (1.0 - phi * phi) / (1.0 - 2.0 * phi * (std::f64::consts::TAU * f * dt).cos() + phi * phi)
        };
        // The process's share per unit variance at every frequency used.
        let shares: Vec<f64> = r
            .dwell_samples
            .iter()
            .flat_map(|&n| (2..n.div_ceil(2)).map(move |k| k as f64 / (n as f64 * dt)))
            .filter_map(|f| {
                let i = ((f / bin).round() as usize).clamp(1, density.len().max(2) - 1);
                density.get(i).filter(|s| **s > 0.0).map(|s| per_unit(f) / s)
            })
            .collect();
        variance_for_ratio(&shares, size * size)
    }

    /// The quantisation step planted at `size` standard errors on channel `ch`, SI.
    pub fn quantisation_step(&self, ch: usize, size: f64) -> f64 {
        let sigma = self.reference.sample_sigma[ch];
        (12.0 * size * sigma * sigma * (2.0 / self.reference.samples() as f64).sqrt()).sqrt()
    }

    /// One standard error of a line's amplitude at `f_hz` on channel `ch`, SI.
    pub fn line_unit(&self, ch: usize, f_hz: f64) -> f64 {
        self.reference.line_sigma(ch, f_hz) * (2.0 / self.reference.samples() as f64).sqrt()
    }

    /// The times a noise warm-up planted ends at, s after the record's first sample: 10 to 30 % of the
    /// session, at least 30 s (`None` when the record is too short for that). A channel is a target when the
    /// test has blocks enough on both sides of either end ([`Baseline::noise_warmup_excess`]).
    fn noise_warmup_settled_s(&self) -> Option<std::ops::Range<f64>> {
        let (lo, hi) = ((0.1 * self.span_s).max(30.0), 0.3 * self.span_s);
        (lo < hi).then_some(lo..hi)
    }

    /// The excess standard deviation of a noise warm-up that ends at `settled_s`, planted at `size` standard
    /// errors on channel `ch`, SI: the test sets the mean log-variance of one-second blocks before against
    /// after, with the standard error `s` of that difference on the record itself (Newey-West, as the analysis
    /// has it: [`noise_warmup_scale`]). White noise of `e` added before raises it by `ln(1 + e^2 / v)` (`v` the
    /// blocks' mean variance after), so `size` standard errors are `e = sqrt(v (exp(size s) - 1))`. `None` when
    /// either side has too few blocks.
    pub fn noise_warmup_excess(&self, ch: usize, settled_s: f64, size: f64) -> Option<f64> {
        let (s, settled_variance) = noise_warmup_scale(&self.recording, ch, settled_s).ok().flatten()?;
        Some((settled_variance * ((size * s).exp() - 1.0)).sqrt())
    }

    /// The longest correlated-noise time constant planted: 0.8 of the analysis's search range (a quarter of
    /// the shortest dwell), at most 2 s.
    fn longest_markov_tau_s(&self) -> f64 {
        (0.8 * self.shortest_dwell_s / 4.0).min(2.0)
    }

    /// One line on the baseline: the record, its dwells and what the analysis names.
    pub fn summary(&self) -> String {
        let rec = &self.recording;
        let uncertain = self.analysis.effects.iter().filter(|e| is_uncertain(e)).count();
        format!(
            "{}: {} rows, {} dwells, {:.1} Hz, {:.0} s; baseline analysis {:.1} s names {} effects ({uncertain} \
             uncertain)",
            self.set.name(),
            rec.rows.len(),
            rec.dwells().len(),
            self.reference.rate_hz,
            self.span_s,
            self.seconds,
            self.analysis.effects.len(),
        )
    }
}

/// The expected likelihood ratio of a process of variance `v` whose share per unit variance at each
/// frequency is `shares` (Whittle): `2 sum (r - ln(1 + r))`, `r = v g`.
fn expected_ratio(shares: &[f64], v: f64) -> f64 {
    2.0 * shares.iter().map(|g| v * g - (v * g).ln_1p()).sum::<f64>()
}

/// The variance whose [`expected_ratio`] is `ratio` (bisection in `ln v`: the ratio increases with `v`).
fn variance_for_ratio(shares: &[f64], ratio: f64) -> f64 {
    let at_zero = (ratio / shares.iter().map(|g| g * g).sum::<f64>()).sqrt();
    let (mut lo, mut hi) = ((0.1 * at_zero).ln(), (1e6 * at_zero).ln());
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if expected_ratio(shares, mid.exp()) < ratio {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (0.5 * (lo + hi)).exp()
}

/// The norm of `column` less its least-squares fit by the `base` columns (modified Gram-Schmidt).
fn remainder_norm(base: &[Vec<f64>], column: &[f64]) -> f64 {
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut ortho: Vec<Vec<f64>> = Vec::new();
    for c in base {
        let mut v = c.clone();
        for q in &ortho {
            let p = dot(&v, q);
            v.iter_mut().zip(q).for_each(|(x, y)| *x -= p * y);
        }
        let n = dot(&v, &v).sqrt();
        if n > 1e-12 * dot(c, c).sqrt().max(f64::MIN_POSITIVE) {
            ortho.push(v.into_iter().map(|x| x / n).collect());
        }
    }
    let mut r = column.to_vec();
    for q in &ortho {
        let p = dot(&r, q);
        r.iter_mut().zip(q).for_each(|(x, y)| *x -= p * y);
    }
    dot(&r, &r).sqrt()
}

/// The target of the `tested` candidate `name` ("accel_misalignment:xz", "position_error:e:pos3",
/// "bias_drift:x (gyro)") when it is one of `effect` that can be planted (not a pair's shared tilt).
fn parse_candidate(name: &str, effect: EffectKind, std_error: f64) -> Option<Target> {
    let (body, sensor) = match name.rsplit_once(" (") {
        Some((body, s)) => (body, Some(s.trim_end_matches(')'))),
        None => (name, None),
    };
    let mut parts = body.split(':');
    if parts.next()? != effect.name() {
        return None;
    }
    let axes = parts.next()?.to_string();
    let pos = match parts.next() {
        Some(p) if p.contains('+') => return None,
        Some(p) => Some(p.strip_prefix("pos")?.parse().ok()?),
        None => None,
    };
    let sensor = match (effect.sensor(), sensor) {
        (Some(s), _) => s,
        (None, Some("gyro")) => Sensor::Gyro,
        (None, Some("accel")) => Sensor::Accel,
        _ => return None,
    };
    let channel = effect
        .sensor()
        .is_none()
        .then(|| AXES.iter().position(|a| *a == axes).map(|a| a + if sensor == Sensor::Gyro { 0 } else { 3 }))
        .flatten();
    Some(Target { sensor, axes, pos, channel, std_error: Some(std_error) })
}

/// The target of a per-channel effect on channel `ch` (0 to 5, gx to az).
fn channel_target(ch: usize) -> Target {
    Target {
        sensor: Sensor::of_channel(ch),
        axes: AXES[ch % 3].to_string(),
        pos: None,
        channel: Some(ch),
        std_error: None,
    }
}

/// Whether the analysis ranks `e` with the uncertain effects ([`Effect::uncertain`]).
pub fn is_uncertain(e: &Effect) -> bool {
    e.uncertain
}

/// "effect:sensor:axes", with ":posP" (position errors) and "+posQ" (a pair's shared tilt).
pub fn label(e: &Effect) -> String {
    let mut s = format!("{}:{}:{}", e.effect, e.sensor, e.axes);
    if let Some(p) = e.pos {
        s.push_str(&format!(":pos{p}"));
    }
    if let Some(q) = e.pair_pos {
        s.push_str(&format!("+pos{q}"));
    }
    s
}

/// Draws the trial `seed` of `effect` at `size` standard errors on `b` (see the module's documentation).
pub fn draw(b: &Baseline, effect: EffectKind, size: f64, seed: u64) -> Result<Planted, String> {
    let targets = b.targets(effect);
    if targets.is_empty() {
        return Err(format!("{effect}: nothing to plant it on in {}", b.set.name()));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(
        seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ ((effect as u64) << 40) ^ (size * 1000.0) as u64,
    );
    let target = &targets[rng.random_range(0..targets.len())];
    let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
    let mut h = Hidden::new(effect, target.sensor, &target.axes);
    h.pos = target.pos;
    let ch = target.channel.unwrap_or(0);
    h.value = match effect {
        EffectKind::BiasWarmup => {
            let tau = warmup_tau(b, target, &mut rng)?;
            h.tau_s = Some(tau);
            sign * size * b.warmup_unit(ch, tau)
        }
        EffectKind::Vibration => {
            let f = rng.random_range(1.0..0.4 * b.reference.rate_hz);
            h.frequency_hz = Some(f);
            size * b.line_unit(ch, f)
        }
        EffectKind::CorrelatedNoise => {
            let tau = rng.random_range(0.2..b.longest_markov_tau_s().max(0.25));
            h.tau_s = Some(tau);
            b.markov_variance(ch, tau, size).sqrt()
        }
        EffectKind::NoiseWarmup => {
            let range = b.noise_warmup_settled_s().ok_or("noise_warmup: the record is too short")?;
            let settled_s = rng.random_range(range);
            h.settled_s = Some(settled_s);
            b.noise_warmup_excess(ch, settled_s, size).ok_or("noise_warmup: too few blocks on a side")?
        }
        EffectKind::Quantization => b.quantisation_step(ch, size),
        _ => sign * size * target.std_error.ok_or_else(|| format!("{effect}: no standard error"))?,
    };
    Ok(Planted { hidden: h, phase_rad: rng.random::<f64>() * std::f64::consts::TAU, seed })
}

/// A warm-up time constant: 5 to 26 % of the session, at least 10 s, drawn again (at most 100 times) while
/// the largest size would pass the plausible limit of a warm-up's amplitude (a short time constant leaves
/// little of the exponential in the blocks, and its standard error is large).
fn warmup_tau(b: &Baseline, target: &Target, rng: &mut ChaCha8Rng) -> Result<f64, String> {
    let largest = SIZES.iter().fold(0.0f64, |m, &k| m.max(k));
    let limit =
        EffectKind::BiasWarmup.plausible_limit(target.sensor, &target.axes, b.span_s, 0.0).unwrap_or(f64::INFINITY);
    let ch = target.channel.unwrap_or(0);
    for _ in 0..100 {
        let tau = rng.random_range(b.warmup_taus_s());
        if largest * b.warmup_unit(ch, tau) <= limit {
            return Ok(tau);
        }
    }
    Err(format!("bias_warmup:{}: no time constant keeps {largest} standard errors within {limit}", target.text()))
}

/// How one trial came out.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The truth.
    pub hidden: Hidden,
    /// Size, standard errors.
    pub size: f64,
    /// The planted effect is found (see the module's documentation).
    pub found: bool,
    /// ... and the analysis marks it uncertain.
    pub uncertain: bool,
    /// The effects of the planted kind, sensor, axes and position named: "label estimate +- se".
    pub named: Vec<String>,
    /// The planted value over the standard error of the effect named at the planted place (the first).
    pub own_se_ratio: Option<f64>,
    /// Effects named that are neither planted nor the baseline's: label, and whether uncertain.
    pub false_alarms: Vec<(String, bool)>,
    /// Why it was not found (None when found): "estimate off", "not determined apart from its aliases" (off,
    /// and the analysis says the data fix only its combination with an alias), "the baseline's value",
    /// "another line", "instead: LABEL", "named as its alias: LABEL" (an effect of another kind or place
    /// that the analysis names as indistinguishable from the planted one), "named as its rival: LABEL" (one
    /// that names the planted one as nearly as good), "nothing new".
    pub miss: Option<String>,
}

/// Whether `e` is an effect of the planted kind, sensor, axes (or alias) and position.
fn at_planted_place(e: &Effect, h: &Hidden) -> bool {
    e.effect == h.effect.name()
        && e.sensor == h.sensor.name()
        && e.pos == h.pos
        && e.pair_pos.is_none()
        && (e.axes == h.axes || e.aliases.iter().any(|a| *a == candidate_name(h)))
}

/// The analysis's candidate name of the effect `e` ("accel_misalignment:xz", "position_error:e:pos1+pos2",
/// "bias_drift:x (gyro)"), as its aliases name candidates.
fn candidate_of(e: &Effect) -> String {
    match (e.pos, e.pair_pos) {
        (Some(p), Some(q)) => format!("{}:{}:pos{p}+pos{q}", e.effect, e.axes),
        (Some(p), None) => format!("{}:{}:pos{p}", e.effect, e.axes),
        (None, _) if e.effect.parse::<EffectKind>().is_ok_and(|k| k.sensor().is_none()) => {
            format!("{}:{} ({})", e.effect, e.axes, e.sensor)
        }
        (None, _) => format!("{}:{}", e.effect, e.axes),
    }
}

/// `u` and `e` are the same candidate: the same label, or the same effect with either among the other's
/// aliases (the two halves of a misalignment that gravity alone sees as one, which rounding names either
/// way), at the same line.
fn same_candidate(u: &Effect, e: &Effect) -> bool {
    let alias = u.effect == e.effect && (u.aliases.contains(&candidate_of(e)) || e.aliases.contains(&candidate_of(u)));
    (label(u) == label(e) || alias) && same_line(u.frequency_hz, e.frequency_hz)
}

/// The baseline's effect that `e` is ([`same_candidate`]), if any.
fn baseline_twin<'a>(baseline: &'a Analysis, e: &Effect) -> Option<&'a Effect> {
    baseline.effects.iter().find(|u| same_candidate(u, e))
}

/// `e` is no false alarm: the baseline's own effect ([`baseline_twin`]), or named as indistinguishable or
/// nearly as good (an alias or a rival either way, of any kind) as a baseline effect, or with the planted
/// candidate as an alias or a rival: the analysis says that the data cannot tell them apart, given the rest
/// of its model, or that they favour one over the other by a Bayes factor below 20 ([`names_planted`]). A
/// weak effect of the record itself can come back under another name: the imu_tk accelerometer z's uncertain
/// warm-up as a drift of y, its rival.
fn explained(e: &Effect, baseline: &Analysis, h: &Hidden) -> bool {
    let named = |by: &Effect, of: &Effect| {
        let c = candidate_of(of);
        by.aliases.contains(&c) || by.rivals.contains(&c)
    };
    let aliased = |u: &Effect| (named(u, e) || named(e, u)) && same_line(u.frequency_hz, e.frequency_hz);
    baseline_twin(baseline, e).is_some() || baseline.effects.iter().any(aliased) || names_planted(e, h)
}

/// `e` names the planted candidate among its aliases or its rivals.
fn names_planted(e: &Effect, h: &Hidden) -> bool {
    e.aliases.iter().chain(&e.rivals).any(|a| *a == candidate_name(h))
}

/// `a` agrees with `b` within 30 % of `b`.
fn within_30(a: f64, b: f64) -> bool {
    (a - b).abs() <= 0.3 * b.abs()
}

/// Whether `e`, at the planted place, carries the planted value and is not the baseline's own.
fn carries_planted(e: &Effect, twin: Option<&Effect>, h: &Hidden) -> Result<(), &'static str> {
    let linear = !matches!(
        h.effect,
        EffectKind::BiasWarmup
            | EffectKind::Vibration
            | EffectKind::CorrelatedNoise
            | EffectKind::NoiseWarmup
            | EffectKind::Quantization
    );
    if !same_line(h.frequency_hz, e.frequency_hz) {
        return Err("another line");
    }
    if linear {
        if twin.is_some_and(|u| (e.estimate - u.estimate).abs() <= 3.0 * e.std_error) {
            return Err("the baseline's value");
        }
        let expected = h.value + twin.map_or(0.0, |u| u.estimate);
        // The standard error the analysis gives the estimate across the models its aliases allow; none when it
        // determines only their combination (then its own standard error judges, and a miss says why).
        let off = |std_error: f64| (e.estimate - expected).abs() > 3.0 * std_error;
        match e.std_error_across_models() {
            None if off(e.std_error) => return Err("not determined apart from its aliases"),
            across if off(across.unwrap_or(e.std_error)) => return Err("estimate off"),
            _ => {}
        }
    } else {
        let same_tau = |u: &Effect| match (u.tau_s, e.tau_s) {
            (Some(a), Some(b)) => within_30(b, a),
            _ => true,
        };
        match (h.effect, twin) {
            // A process planted beside the baseline's own on the channel: independent processes add their
            // variances, and the analysis reads the channel's one process. Added in quadrature, it moves the
            // estimate less than its own size: it counts when it moved the estimate by more than 3 of its
            // standard errors, as a linear term does.
            (EffectKind::CorrelatedNoise, Some(u)) => {
                if (e.estimate - u.estimate).abs() <= 3.0 * e.std_error {
                    return Err("the baseline's value");
                }
                if !within_30(e.estimate, h.value.hypot(u.estimate)) {
                    return Err("estimate off");
                }
            }
            _ => {
                if twin.is_some_and(|u| within_30(e.estimate, u.estimate) && same_tau(u)) {
                    return Err("the baseline's value");
                }
                if !within_30(e.estimate, h.value) {
                    return Err("estimate off");
                }
            }
        }
    }
    Ok(())
}

/// Judges the `analysis` of a recording with `h` planted at `size` standard errors against the `baseline`.
pub fn judge(analysis: &Analysis, baseline: &Analysis, h: &Hidden, size: f64) -> Outcome {
    let placed: Vec<&Effect> = analysis.effects.iter().filter(|e| at_planted_place(e, h)).collect();
    let verdicts: Vec<Result<(), &str>> =
        placed.iter().map(|e| carries_planted(e, baseline_twin(baseline, e), h)).collect();
    let hit = placed.iter().zip(&verdicts).find(|(_, v)| v.is_ok()).map(|(e, _)| *e);
    let false_alarms: Vec<(String, bool)> = analysis
        .effects
        .iter()
        .filter(|e| !at_planted_place(e, h) && !explained(e, baseline, h))
        .map(|e| (label(e), is_uncertain(e)))
        .collect();
    // An effect of another kind or place that names the planted candidate among its aliases or rivals: the
    // data cannot tell the two apart in this schedule (a gyro's warm-up and drift seen in one up/down pair),
    // or favour the other one only weakly.
    let as_alias = || analysis.effects.iter().find(|e| !at_planted_place(e, h) && names_planted(e, h));
    let miss = match (hit, verdicts.first()) {
        (Some(_), _) => None,
        (None, Some(Err(why))) => Some(why.to_string()),
        (None, _) => Some(match (false_alarms.first(), as_alias()) {
            (Some((l, _)), _) => format!("instead: {l}"),
            (None, Some(e)) if e.aliases.iter().any(|a| *a == candidate_name(h)) => {
                format!("named as its alias: {}", label(e))
            }
            (None, Some(e)) => format!("named as its rival: {}", label(e)),
            (None, None) => "nothing new".to_string(),
        }),
    };
    Outcome {
        hidden: h.clone(),
        size,
        found: hit.is_some(),
        uncertain: hit.is_some_and(is_uncertain),
        named: placed.iter().map(|e| format!("{} {:+.3e} +- {:.2e}", label(e), e.estimate, e.std_error)).collect(),
        own_se_ratio: placed.first().filter(|e| e.std_error > 0.0).map(|e| (h.value / e.std_error).abs()),
        false_alarms,
        miss,
    }
}

/// One trial: draw, plant, analyse, judge.
pub fn trial(b: &Baseline, effect: EffectKind, size: f64, seed: u64) -> Result<Outcome, String> {
    let planted = draw(b, effect, size, seed)?;
    let rec = plant_into(&b.base(), &planted);
    let analysis = analyze_recording(&rec).map_err(|e| e.to_string())?;
    Ok(judge(&analysis, &b.analysis, &planted.hidden, size))
}

/// The trials of one data set: per effect and size, the outcomes.
#[derive(Clone, Debug)]
pub struct Campaign {
    /// The baseline's summary line.
    pub summary: String,
    /// Per effect, per size (in the order given): the outcomes.
    pub rows: Vec<(EffectKind, Vec<Vec<Outcome>>)>,
    /// The sizes, standard errors.
    pub sizes: Vec<f64>,
    /// Wall time of the trials (not the import or the baseline), s.
    pub seconds: f64,
}

/// Runs `runs` trials (seeds 100 onwards) of every plantable effect of `b` in `effects` (all when empty) at
/// every size of `sizes`, on `threads` threads.
pub fn campaign(b: &Baseline, effects: &[EffectKind], sizes: &[f64], runs: usize, threads: usize) -> Campaign {
    let start = Instant::now();
    let kinds: Vec<EffectKind> =
        b.plantable.iter().map(|(e, _)| *e).filter(|e| effects.is_empty() || effects.contains(e)).collect();
    let jobs: Vec<(usize, usize, u64)> = (0..kinds.len())
        .flat_map(|k| (0..sizes.len()).flat_map(move |s| (0..runs as u64).map(move |r| (k, s, 100 + r))))
        .collect();
    let outcomes = parallel(&jobs, threads.max(1), |&(k, s, seed)| {
        trial(b, kinds[k], sizes[s], seed).unwrap_or_else(|e| panic!("{}: {e}", b.set.name()))
    });
    let mut rows: Vec<(EffectKind, Vec<Vec<Outcome>>)> =
        kinds.iter().map(|&e| (e, vec![Vec::new(); sizes.len()])).collect();
    for (&(k, s, _), o) in jobs.iter().zip(outcomes) {
        rows[k].1[s].push(o);
    }
    Campaign { summary: b.summary(), rows, sizes: sizes.to_vec(), seconds: start.elapsed().as_secs_f64() }
}

/// `f` of every job on `threads` threads, in the jobs' order.
fn parallel<J: Sync, T: Send>(jobs: &[J], threads: usize, f: impl Fn(&J) -> T + Sync) -> Vec<T> {
    let mut out: Vec<(usize, T)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|w| {
                let f = &f;
                s.spawn(move || {
                    jobs.iter().enumerate().skip(w).step_by(threads).map(|(i, j)| (i, f(j))).collect::<Vec<_>>()
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().expect("trial thread")).collect()
    });
    out.sort_by_key(|(i, _)| *i);
    out.into_iter().map(|(_, t)| t).collect()
}

/// The most frequent of `items` with its count, "-" when there is none.
fn most_frequent<'a>(items: impl Iterator<Item = &'a str>) -> String {
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    items.for_each(|i| *counts.entry(i).or_default() += 1);
    counts.iter().max_by_key(|(_, k)| **k).map_or("-".to_string(), |(i, k)| format!("{i} ({k})"))
}

/// `k/n (p %)`.
fn share(k: usize, n: usize) -> String {
    format!("{k}/{n} ({:.0} %)", 100.0 * k as f64 / n.max(1) as f64)
}

/// The campaign's tables: per effect and size found/trials (with how many of those found are uncertain),
/// the targets, the median planted value in standard errors of the effect named at the planted place
/// (largest size), the most frequent reason of a miss, the trials with a false alarm (with a certain one);
/// then the false alarms per size and the most frequent, and the run time.
pub fn table(c: &Campaign, b: &Baseline) -> String {
    let sizes: Vec<String> = c.sizes.iter().map(|k| format!("{k} SE")).collect();
    let mut out = format!(
        "### {}\n\n| planted effect | targets | distinct draws per size | {} | largest size in the named effect's own SE (median) | why missed (most often) | trials with a false alarm (certain) |\n|---|---|---|{}---|---|---|\n",
        c.summary,
        sizes.join(" | "),
        "---|".repeat(sizes.len())
    );
    for (effect, per_size) in &c.rows {
        let targets: Vec<String> = b.targets(*effect).iter().map(Target::text).collect();
        let distinct = per_size
            .iter()
            .map(|o| o.iter().map(|o| format!("{:?}", o.hidden)).collect::<std::collections::BTreeSet<_>>().len())
            .max()
            .unwrap_or(0);
        out.push_str(&format!("| {effect} | {} | {distinct} |", targets.join(" ")));
        for outcomes in per_size {
            let found = outcomes.iter().filter(|o| o.found).count();
            let uncertain = outcomes.iter().filter(|o| o.found && o.uncertain).count();
            let note = if uncertain > 0 { format!(", {uncertain} uncertain") } else { String::new() };
            out.push_str(&format!(" {found}/{}{note} |", outcomes.len()));
        }
        let mut ratios: Vec<f64> = per_size.last().into_iter().flatten().filter_map(|o| o.own_se_ratio).collect();
        ratios.sort_by(f64::total_cmp);
        let ratio = ratios.get(ratios.len() / 2).map_or("-".to_string(), |r| format!("{r:.3}"));
        let why = most_frequent(per_size.iter().flatten().filter_map(|o| o.miss.as_deref()));
        let all: Vec<&Outcome> = per_size.iter().flatten().collect();
        let alarms = all.iter().filter(|o| !o.false_alarms.is_empty()).count();
        let certain = all.iter().filter(|o| o.false_alarms.iter().any(|(_, u)| !u)).count();
        out.push_str(&format!(" {ratio} | {why} | {alarms}/{} ({certain}) |\n", all.len()));
    }
    out.push_str(&false_alarm_lines(c));
    out.push_str(&format!("\ntrials: {:.0} s\n", c.seconds));
    out
}

/// False alarms per size (trials naming an effect neither planted nor the baseline's; in brackets: a certain
/// one) and the most frequent.
fn false_alarm_lines(c: &Campaign) -> String {
    let mut out =
        String::from("\nfalse alarms (trials naming an effect neither planted nor in the baseline; certain ones):");
    let (mut all, mut any, mut certain) = (0, 0, 0);
    for (s, k) in c.sizes.iter().enumerate() {
        let outcomes: Vec<&Outcome> = c.rows.iter().flat_map(|(_, per)| per[s].iter()).collect();
        let a = outcomes.iter().filter(|o| !o.false_alarms.is_empty()).count();
        let cert = outcomes.iter().filter(|o| o.false_alarms.iter().any(|(_, u)| !u)).count();
        out.push_str(&format!(" {k} SE {}, certain {};", share(a, outcomes.len()), share(cert, outcomes.len())));
        all += outcomes.len();
        any += a;
        certain += cert;
    }
    out.push_str(&format!(" all {}, certain {}\n", share(any, all), share(certain, all)));
    let labels = c
        .rows
        .iter()
        .flat_map(|(_, per)| per.iter().flatten())
        .flat_map(|o| o.false_alarms.iter().map(|(l, _)| l.as_str()));
    out.push_str(&format!("most frequent false alarm: {}\n", most_frequent(labels)));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_process_planted_at_k_standard_errors_has_an_expected_ratio_of_k_squared() {
        // Many weak frequencies: the small-signal value, k over the root of the information at zero.
        let weak = vec![0.01; 1_000_000];
        let v = variance_for_ratio(&weak, 100.0);
        assert!((v - 1.0).abs() < 0.02, "{v}");
        // Few strong ones: the information at zero promises more than the process gives; the variance that
        // gives the ratio is larger, and gives it.
        let strong = vec![1.0; 20];
        let v = variance_for_ratio(&strong, 100.0);
        assert!(v > 10.0 / 20f64.sqrt() * 1.5, "{v}");
        assert!((expected_ratio(&strong, v) - 100.0).abs() < 1e-6, "{}", expected_ratio(&strong, v));
    }

    #[test]
    fn candidates_parse_into_targets() {
        let t = parse_candidate("position_error:e:pos3", EffectKind::PositionError, 1e-3).expect("a target");
        assert_eq!((t.sensor, t.axes.as_str(), t.pos, t.channel), (Sensor::Reference, "e", Some(3), None));
        assert!(parse_candidate("position_error:n:pos1+pos2", EffectKind::PositionError, 1e-3).is_none());
        let d = parse_candidate("bias_drift:y (accel)", EffectKind::BiasDrift, 1e-6).expect("a target");
        assert_eq!((d.sensor, d.axes.as_str(), d.channel), (Sensor::Accel, "y", Some(4)));
        assert!(parse_candidate("bias_warmup:y (accel)", EffectKind::BiasDrift, 1e-6).is_none());
        let m = parse_candidate("accel_misalignment:xz", EffectKind::AccelMisalignment, 1e-4).expect("a target");
        assert_eq!((m.sensor, m.axes.as_str(), m.channel), (Sensor::Accel, "xz", None));
    }

    #[test]
    fn the_remainder_after_the_base_columns_is_what_they_cannot_fit() {
        // A constant column is fitted completely by the constant; a line keeps its centred norm.
        assert!(remainder_norm(&[vec![1.0; 4]], &[2.0; 4]) < 1e-12);
        let line = [0.0, 1.0, 2.0, 3.0];
        assert!((remainder_norm(&[vec![1.0; 4]], &line) - 5.0f64.sqrt()).abs() < 1e-12);
        // Two base columns that span the column leave nothing.
        assert!(remainder_norm(&[vec![1.0; 4], line.to_vec()], &[1.0, 3.0, 5.0, 7.0]) < 1e-12);
    }
}
