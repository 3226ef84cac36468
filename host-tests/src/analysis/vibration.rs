//! Vibration on the samples: the lines of the periodogram summed over dwells (each dwell's mean and trend
//! removed) and of the record's coherent periodogram, the one that stands highest over the spectrum's level
//! first, each against the median of its neighbourhood (a line, not a coloured background), its frequency
//! refined within a bin, one amplitude and a phase per dwell or one phase in the record's time. A dwell
//! longer than the longest transform is searched in consecutive pieces, every sample in one; the frequency
//! and the line are then fitted on the whole dwells.

use crate::stats::noise::FftPlan;

use super::MIN_DWELL_SAMPLES;

/// A spectral line found.
pub(super) struct VibrationResult {
    /// Its frequency, Hz.
    pub frequency_hz: f64,
    /// Amplitude as the samples show it (before the interval-averaging correction).
    pub amplitude_seen: f64,
    /// Its standard error.
    pub amplitude_std: f64,
    /// Likelihood-ratio statistic, in units of the background variance.
    pub lr: f64,
    /// Independent frequencies searched (the Bonferroni factor of the search).
    pub independent_frequencies: f64,
    /// Per dwell: complex amplitude (re, im) of the line, `x_i ~ re cos(w i) - im sin(w i)`.
    pub per_dwell: Vec<(f64, f64)>,
    /// The background variance about the line (the samples' unit squared).
    pub background: f64,
    /// A line whose phase holds across the dwells (one phase in the record's time): each dwell's first
    /// sample, counted in samples from the first dwell's first. `None`: a phase per dwell.
    pub starts_samples: Option<Vec<f64>>,
    /// A line with one phase whose frequency the dwells' spacing leaves ambiguous ([`ambiguous_frequency`]):
    /// the other frequency, Hz.
    pub ambiguous_hz: Option<f64>,
}

/// A second frequency fits a coherent line nearly as well when its coherent power is at least this share of
/// the best's ([`ambiguous_frequency`]).
const AMBIGUOUS_POWER: f64 = 0.5;

/// The other frequency (Hz) that the coherent line `v` of `dwells` (first samples `starts`) fits nearly as
/// well, if any: dwells that repeat with a period `T` leave sidelobes at `f +- k/T` of `sinc(k d)` of the
/// line's amplitude (`d` the dwell's share of `T`), and noise can put the line on one of them. The coherent
/// power is scanned as [`refine_coherent`] scans it, over one bin of the longest dwell on either side; the
/// highest local maximum outside the main lobe (`1 / span` from the line) is the candidate, named when its
/// power is at least [`AMBIGUOUS_POWER`] of the line's. `None` for a line with a phase per dwell, or beyond
/// [`COHERENT_BUDGET`].
pub(super) fn ambiguous_frequency(dwells: &[Vec<f64>], v: &VibrationResult, dt: f64) -> Option<f64> {
    let starts = v.starts_samples.as_deref()?;
    let f = v.frequency_hz * dt;
    let (scan, _) = coherent_scan(dwells, starts, f)?;
    if scan.len() < 4 {
        return None;
    }
    let main_lobe = 1.0 / span_samples(dwells, starts)?;
    let best = coherent_power(dwells, starts, f);
    scan.windows(3)
        .filter(|w| w[1].1 > w[0].1 && w[1].1 >= w[2].1 && (w[1].0 - f).abs() > main_lobe)
        .map(|w| w[1])
        .max_by(|x, y| x.1.total_cmp(&y.1))
        .filter(|&(_, p)| p >= AMBIGUOUS_POWER * best)
        .map(|(x, _)| x / dt)
}

/// The fits of a step of the line search: one phase per dwell, and (two dwells or more) one phase in the
/// record's time, at the coherent periodogram's candidate and (within [`COHERENT_BUDGET`]) at the per-dwell
/// candidate's frequency.
pub(super) struct LineFits {
    /// Common amplitude, a phase per dwell.
    pub per_dwell: VibrationResult,
    /// Common amplitude and phase in the record's time, at the coherent spectrum's candidate.
    pub coherent: Option<VibrationResult>,
    /// The same at the per-dwell candidate's frequency.
    pub coherent_here: Option<VibrationResult>,
}

/// Most frequencies times samples that the scan of a coherent line's frequency may take (its direct DFTs):
/// the scan needs a quarter of `1 / span` steps over two bins of the longest dwell. Beyond (many short dwells
/// spread over a long record, or few very long ones), only the phase per dwell is tried.
const COHERENT_BUDGET: f64 = 1e8;

/// `sin(pi x) / (pi x)`: the response of an integrating sensor's interval average at `x = f dt`.
pub(super) fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-12 {
        1.0
    } else {
        (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
    }
}

/// Samples between exact evaluations of the phasor in [`dft_at`] (a recurrence in between).
const PHASOR_BLOCK: usize = 256;
/// Blocks of [`dft_at`] summed in lock step (independent chains for the processor).
const DFT_LANES: usize = 4;

/// Direct DFT of `x` at `cycles_per_sample`: sum x_i e^{-i w i}. The phasor is evaluated exactly at every
/// [`PHASOR_BLOCK`]-th sample and rotated by a recurrence in between; [`DFT_LANES`] blocks are summed side by
/// side, so the sum is that of the block-by-block order up to its rounding.
fn dft_at(x: &[f64], cycles_per_sample: f64) -> (f64, f64) {
    let w = std::f64::consts::TAU * cycles_per_sample;
    let (c, s) = (w.cos(), w.sin());
    let phasor = |i: usize| {
        let ph = w * i as f64;
        (ph.cos(), -ph.sin())
    };
    let (mut re, mut im) = ([0.0f64; DFT_LANES], [0.0f64; DFT_LANES]);
    let chunks = x.chunks_exact(PHASOR_BLOCK * DFT_LANES);
    let tail_start = x.len() - chunks.remainder().len();
    for (n, chunk) in chunks.enumerate() {
        let start = n * PHASOR_BLOCK * DFT_LANES;
        let (mut cr, mut ci) = ([0.0f64; DFT_LANES], [0.0f64; DFT_LANES]);
        for l in 0..DFT_LANES {
            (cr[l], ci[l]) = phasor(start + l * PHASOR_BLOCK);
        }
        let blocks: [&[f64]; DFT_LANES] = std::array::from_fn(|l| &chunk[l * PHASOR_BLOCK..(l + 1) * PHASOR_BLOCK]);
        for i in 0..PHASOR_BLOCK {
            for l in 0..DFT_LANES {
                let v = blocks[l][i];
                re[l] += v * cr[l];
                im[l] += v * ci[l];
                let nr = cr[l] * c + ci[l] * s;
                let ni = ci[l] * c - cr[l] * s;
                cr[l] = nr;
                ci[l] = ni;
            }
        }
    }
    let (mut tr, mut ti) = (0.0, 0.0);
    let (mut cr, mut ci) = (1.0f64, 0.0f64);
    for (i, v) in x.iter().enumerate().skip(tail_start) {
        if i % PHASOR_BLOCK == 0 {
            (cr, ci) = phasor(i);
        }
        tr += v * cr;
        ti += v * ci;
        let nr = cr * c + ci * s;
        let ni = ci * c - cr * s;
        cr = nr;
        ci = ni;
    }
    (re.iter().sum::<f64>() + tr, im.iter().sum::<f64>() + ti)
}

/// Most spectral lines found per channel (a line whose frequency wanders counted once).
pub(super) const MAX_LINES: usize = 8;

/// Most components of lines found per channel: a mains line that wanders by +-0.02 Hz over 300 s shows as
/// 15 sidebands 1/300 Hz apart, each found and removed in turn.
pub(super) const MAX_COMPONENTS: usize = 48;

/// Bins of a line found whose power is above this many times its background are its band, not searched
/// again: the skirt of a line whose frequency wanders (a mains line), and the rest of a line removed.
const BAND_OVER_BACKGROUND: f64 = 10.0;

/// Bins on either side of a line found that are its band whatever their power: those its background leaves
/// out.
const MIN_HALF_BAND: usize = LINE_HALF_WIDTH;

/// The search for the spectral lines of the dwells' detrended samples, the one that stands highest over the
/// spectrum's level first: each call of [`LineSearch::next`] finds the next candidate outside the bands of
/// the candidates before (the caller removes each line it keeps from the samples, and says so with
/// [`LineSearch::settle`], before the next call).
pub(super) struct LineSearch {
    /// Transform length (zero-padded, a power of two).
    len: usize,
    /// Bin ranges of the candidates found.
    bands: Vec<(usize, usize)>,
    /// The summed periodogram of the samples as they are (none until computed, or after a line is removed).
    power: Option<Vec<f64>>,
    /// The search of the record's coherent periodogram (two dwells or more, a span of at most a quarter of
    /// [`MAX_PIECE`]).
    coherent: Option<Spectrum>,
    /// The candidates of the last call, not yet settled: the per-dwell one and the coherent one.
    pending: [Option<Pending>; 2],
}

/// A candidate of the search not yet settled: its frequency, Hz, its band (bins of its spectrum) and the
/// sample interval, s.
type Pending = (f64, (usize, usize), f64);

/// One spectrum of the search: its transform length, the bands of its candidates, and its periodogram as the
/// samples are (none until computed, or after a line is removed).
struct Spectrum {
    len: usize,
    bands: Vec<(usize, usize)>,
    power: Option<Vec<f64>>,
}

impl LineSearch {
    /// A search over `dwells`, whose first samples are `starts` (samples from the first dwell's first);
    /// `None` when a dwell is too short for one.
    pub fn new(dwells: &[Vec<f64>], starts: &[f64]) -> Option<LineSearch> {
        let n_min = dwells.iter().map(|d| d.len()).min()?;
        let piece_max = pieces(dwells).iter().map(|d| d.len()).max()?;
        let span = span_samples(dwells, starts)?.max(0.0).round() as usize;
        let coherent = (dwells.len() >= 2 && starts.len() == dwells.len() && span <= MAX_PIECE / 4).then(|| Spectrum {
            len: span.next_power_of_two() * 4,
            bands: Vec::new(),
            power: None,
        });
        (n_min >= MIN_DWELL_SAMPLES).then(|| LineSearch {
            len: (piece_max.next_power_of_two() * 4).min(MAX_PIECE),
            bands: Vec::new(),
            power: None,
            coherent,
            pending: [None, None],
        })
    }

    /// Settles the candidates of the last call: `kept` is the line the caller kept and removed from the
    /// samples (`None`: none passed). Every candidate is excluded from the next calls when none passed, and
    /// a candidate whose band holds the kept line's frequency (the same line, seen the other way) when one
    /// did; a candidate elsewhere stays.
    pub fn settle(&mut self, kept: Option<&VibrationResult>) {
        let pending = std::mem::take(&mut self.pending);
        let lens = [self.len, self.coherent.as_ref().map_or(1, |c| c.len)];
        for (i, entry) in pending.into_iter().enumerate() {
            let Some((f_hz, (a, b), dt)) = entry else { continue };
            let half_hz = ((b - a) as f64 / 2.0).max(MIN_HALF_BAND as f64) / lens[i] as f64 / dt;
            if kept.is_none_or(|v| (v.frequency_hz - f_hz).abs() <= half_hz) {
                match i {
                    0 => self.bands.push((a, b)),
                    _ => self.coherent.iter_mut().for_each(|c| c.bands.push((a, b))),
                }
            }
        }
        if kept.is_some() {
            self.power = None;
            if let Some(s) = self.coherent.as_mut() {
                s.power = None;
            }
        }
    }

    /// The next candidate line of `dwells` (whose first samples are `starts`): the bin highest over the level
    /// of the summed periodogram of the dwells, fitted with a phase per dwell; and the bin highest over the
    /// level of the record's coherent periodogram, fitted with one phase in the record's time (or, without
    /// that spectrum, the first candidate's frequency refined coherently). Each against its local background,
    /// outside the bands of the candidates excluded before ([`LineSearch::settle`], which the caller calls
    /// after each).
    pub fn next(&mut self, dwells: &[Vec<f64>], starts: &[f64], dt: f64) -> Option<LineFits> {
        let n_min = dwells.iter().map(|d| d.len()).min()?;
        let len = self.len;
        let pieces = pieces(dwells);
        let piece_min = pieces.iter().map(|d| d.len()).min()?;
        if self.power.is_none() {
            self.power = Some(summed_periodogram(&pieces, len)?);
        }
        let power = self.power.as_deref()?;
        let (k_hat, background) = strongest_line(power, len, piece_min, pieces.len() as f64, &self.bands)?;
        let band = line_band(power, k_hat, BAND_OVER_BACKGROUND * background * pieces.len() as f64);
        let f = refine_frequency(dwells, k_hat, len);
        self.pending = [Some((f / dt, band, dt)), None];
        let per_dwell = fit_line(dwells, f, background, n_min, dt);
        let coherent = self.coherent.as_mut().and_then(|s| {
            if s.power.is_none() {
                s.power = coherent_periodogram(dwells, starts, s.len);
            }
            let power = s.power.as_deref()?;
            let (k, background) = strongest_line(power, s.len, n_min, 1.0, &s.bands)?;
            let score = |f: f64| coherent_power(dwells, starts, f);
            let fc = golden_section_max((k as f64 - 1.0) / s.len as f64, (k as f64 + 1.0) / s.len as f64, score);
            Some((fc, line_band(power, k, BAND_OVER_BACKGROUND * background), background))
        });
        let coherent = coherent.map(|(fc, band, background)| {
            self.pending[1] = Some((fc / dt, band, dt));
            fit_coherent(dwells, starts, fc, background, dt)
        });
        // The per-dwell candidate's frequency refined coherently: a line the coherent spectrum does not put
        // first can still keep its phase.
        let coherent_here =
            refine_coherent(dwells, starts, f).map(|fc| fit_coherent(dwells, starts, fc, background, dt));
        Some(LineFits { per_dwell, coherent, coherent_here })
    }
}

/// The band of a line at bin `k_hat` of `power`: the neighbouring bins above `threshold`, and at least
/// [`MIN_HALF_BAND`] bins on either side.
fn line_band(power: &[f64], k_hat: usize, threshold: f64) -> (usize, usize) {
    let above = |k: &usize| power[*k] > threshold;
    let low = (0..k_hat).rev().find(|k| !above(k)).unwrap_or(0).min(k_hat.saturating_sub(MIN_HALF_BAND));
    let high = (k_hat..power.len()).find(|k| !above(k)).unwrap_or(power.len()).max(k_hat + MIN_HALF_BAND);
    (low, high)
}

/// The periodogram `|Z_k|^2 / N` (bins 0..len/2) of the record's time line of length `len`: every dwell's
/// samples at their place (`starts`, rounded to a sample), zero between the dwells. A line whose phase holds
/// across the dwells adds up in it; white noise of variance `s^2` has the level `s^2`, as in one dwell's.
fn coherent_periodogram(dwells: &[Vec<f64>], starts: &[f64], len: usize) -> Option<Vec<f64>> {
    let plan = FftPlan::new(len).ok()?;
    let (mut re, mut im) = (vec![0.0; len], vec![0.0; len]);
    let s0 = *starts.first()?;
    for (d, s) in dwells.iter().zip(starts) {
        let at = (s - s0).max(0.0).round() as usize;
        re.get_mut(at..at + d.len())?.copy_from_slice(d);
    }
    plan.run(&mut re, &mut im).ok()?;
    let total = dwells.iter().map(Vec::len).sum::<usize>() as f64;
    Some((0..len / 2).map(|k| (re[k] * re[k] + im[k] * im[k]) / total).collect())
}

/// Longest piece of a dwell that one periodogram takes, samples, and the longest transform (a shorter dwell
/// is zero-padded to four times its length, up to this). A longer dwell's periodogram (for the search only)
/// is the sum of those of its consecutive pieces of equal length, every sample in one of them: the transform
/// stays at most this long (8 MiB per buffer), and nothing is thinned. The frequency is then refined, and the
/// line fitted, on the whole dwells.
const MAX_PIECE: usize = 1 << 20;

/// The dwells cut into consecutive pieces of at most [`MAX_PIECE`] samples (a shorter dwell is one piece).
fn pieces(dwells: &[Vec<f64>]) -> Vec<&[f64]> {
    dwells
        .iter()
        .flat_map(|d| {
            let size = d.len().div_ceil(d.len().div_ceil(MAX_PIECE).max(1)).max(1);
            d.chunks(size)
        })
        .collect()
}

/// The periodograms of the pieces (zero-padded to `len`, each over its length), summed; bins 0..len/2. Two
/// real pieces share one complex transform (`a + i b`), separated by the symmetry of real transforms.
fn summed_periodogram(dwells: &[&[f64]], len: usize) -> Option<Vec<f64>> {
    let plan = FftPlan::new(len).ok()?;
    let mut power = vec![0.0; len / 2];
    let (mut re, mut im) = (vec![0.0; len], vec![0.0; len]);
    let fill = |out: &mut [f64], d: &[f64]| {
        out.fill(0.0);
        out[..d.len()].copy_from_slice(d);
    };
    for pair in dwells.chunks(2) {
        fill(&mut re, pair[0]);
        let n_a = pair[0].len() as f64;
        match pair.get(1) {
            None => {
                im.fill(0.0);
                plan.run(&mut re, &mut im).ok()?;
                for k in 0..len / 2 {
                    power[k] += (re[k] * re[k] + im[k] * im[k]) / n_a;
                }
            }
            Some(b) => {
                fill(&mut im, b);
                plan.run(&mut re, &mut im).ok()?;
                let n_b = b.len() as f64;
                for k in 0..len / 2 {
                    // Z_k = A_k + i B_k and Z_{L-k}^* = A_k - i B_k for real a, b.
                    let m = (len - k) % len;
                    let (a_re, a_im) = (0.5 * (re[k] + re[m]), 0.5 * (im[k] - im[m]));
                    let (b_re, b_im) = (0.5 * (im[k] + im[m]), 0.5 * (re[m] - re[k]));
                    power[k] += (a_re * a_re + a_im * a_im) / n_a;
                    power[k] += (b_re * b_re + b_im * b_im) / n_b;
                }
            }
        }
    }
    Some(power)
}

/// Bins on either side of a candidate bin that its background leaves out (the line's own leakage).
const LINE_HALF_WIDTH: usize = 12;

/// Most bins on either side of a candidate bin that its background takes.
const BACKGROUND_HALF_WIDTH: usize = 150;

/// Fewest bins on either side of a candidate bin that its background takes.
const MIN_BACKGROUND_SIDE: usize = 10;

/// Bins of each block whose median is the spectrum's level at the block's centre ([`spectrum_level`]).
const LEVEL_BLOCK: usize = 128;

/// The spectrum's level at every bin: the median of each block of [`LEVEL_BLOCK`] bins, interpolated
/// linearly between the blocks' centres (held beyond the first and last). A line is a few bins of a block and
/// leaves its median; a coloured background (a ring-laser gyro's quantised increments rise with frequency,
/// a vehicle's sway falls) is followed.
fn spectrum_level(power: &[f64]) -> impl Fn(usize) -> f64 {
    let medians: Vec<f64> = power
        .chunks(LEVEL_BLOCK)
        .map(|b| {
            let mut b = b.to_vec();
            b.sort_by(f64::total_cmp);
            b[b.len() / 2].max(f64::MIN_POSITIVE)
        })
        .collect();
    move |k: usize| {
        let x = (k as f64 - 0.5 * (LEVEL_BLOCK - 1) as f64) / LEVEL_BLOCK as f64;
        let i = (x.floor().max(0.0) as usize).min(medians.len() - 1);
        let j = (i + 1).min(medians.len() - 1);
        let w = (x - i as f64).clamp(0.0, 1.0);
        medians[i] * (1.0 - w) + medians[j] * w
    }
}

/// The bin that stands highest over the spectrum's level ([`spectrum_level`]; above three cycles per
/// shortest dwell, outside `bands`) and the background level at it:
/// the median of its neighbourhood, scaled to the mean of `p` dwells' periodograms. The neighbourhood is
/// symmetric (as many bins below as above, up to [`BACKGROUND_HALF_WIDTH`]): the median of a spectrum that
/// slopes across it is then its level at the bin. A one-sided neighbourhood at the low end, where coloured
/// noise rises, put the background below the bin's own level, and its random peaks passed for lines.
fn strongest_line(power: &[f64], len: usize, n_min: usize, p: f64, bands: &[(usize, usize)]) -> Option<(usize, f64)> {
    // Lines below three cycles per shortest dwell are too close to the removed trend.
    let k_min = ((3.0 * len as f64 / n_min as f64).ceil() as usize).max(2);
    let side = LINE_HALF_WIDTH + MIN_BACKGROUND_SIDE;
    let (low, high) = (k_min + side, (len / 2).checked_sub(1 + side)?);
    if low >= high {
        return None;
    }
    let outside = |k: &usize| !bands.iter().any(|&(a, b)| (a..b).contains(k));
    let level = spectrum_level(power);
    let over = |k: usize| power[k] / level(k);
    let k_hat = (low..high).filter(outside).max_by(|&a, &b| over(a).total_cmp(&over(b)))?;
    let half_window = BACKGROUND_HALF_WIDTH.min(k_hat - k_min).min(len / 2 - 1 - k_hat);
    let mut neighbours: Vec<f64> = (k_hat - half_window..=k_hat + half_window)
        .filter(|&k| k.abs_diff(k_hat) > LINE_HALF_WIDTH)
        .map(|k| power[k])
        .collect();
    neighbours.sort_by(f64::total_cmp);
    // Median of Gamma(P, 1): P (1 - 1/(9P))^3 (Wilson-Hilferty).
    Some((k_hat, neighbours[neighbours.len() / 2] / (p * (1.0 - 1.0 / (9.0 * p)).powi(3))))
}

/// Refines the frequency (cycles per sample) within one bin of `k_hat` (bins of `len`) on the summed
/// periodogram of the whole dwells. When no dwell is longer than the transform, a bin is at most half the
/// main lobe and a golden section over the two bins finds its peak. A dwell searched in pieces has a narrower
/// lobe than a bin: the two bins are first scanned at a quarter of the lobe's half-width (the best point is
/// then on the main lobe, whose power there is at least 0.95 of its peak, above every side lobe), and the
/// golden section runs between that point's neighbours.
fn refine_frequency(dwells: &[Vec<f64>], k_hat: usize, len: usize) -> f64 {
    let score = |f: f64| -> f64 {
        dwells
            .iter()
            .map(|d| {
                let (re, im) = dft_at(d, f);
                (re * re + im * im) / d.len() as f64
            })
            .sum()
    };
    let (a, b) = ((k_hat as f64 - 1.0) / len as f64, (k_hat as f64 + 1.0) / len as f64);
    let n_max = dwells.iter().map(Vec::len).max().unwrap_or(0);
    if len >= n_max {
        return golden_section_max(a, b, score);
    }
    let step = 0.25 / n_max as f64;
    let points = ((b - a) / step).ceil() as usize;
    let best = (0..=points)
        .map(|i| a + (b - a) * i as f64 / points as f64)
        .map(|f| (f, score(f)))
        .max_by(|x, y| x.1.total_cmp(&y.1))
        .map_or(0.5 * (a + b), |(f, _)| f);
    golden_section_max(best - step, best + step, score)
}

/// The maximum of `score` on `[a, b]` by 40 steps of golden section (a unimodal `score` assumed).
fn golden_section_max(mut a: f64, mut b: f64, score: impl Fn(f64) -> f64) -> f64 {
    let gr = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - gr * (b - a), a + gr * (b - a));
    let (mut sc, mut sd) = (score(c), score(d));
    for _ in 0..40 {
        if sc > sd {
            b = d;
            d = c;
            sd = sc;
            c = b - gr * (b - a);
            sc = score(c);
        } else {
            a = c;
            c = d;
            sc = sd;
            d = a + gr * (b - a);
            sd = score(d);
        }
    }
    0.5 * (a + b)
}

/// One amplitude, a phase per dwell, at `f` cycles per sample: RSS(A) = RSS0 - 2 A sum|X_p| + A^2 N / 2, so
/// A = 2 sum|X_p| / N and the reduction is 2 (sum|X_p|)^2 / N, in units of the background variance.
fn fit_line(dwells: &[Vec<f64>], f: f64, background: f64, n_min: usize, dt: f64) -> VibrationResult {
    let mut per_dwell = Vec::new();
    let mut sum_abs = 0.0;
    let mut total = 0.0;
    for dw in dwells {
        let n = dw.len() as f64;
        let (re, im) = dft_at(dw, f);
        sum_abs += re.hypot(im);
        total += n;
        per_dwell.push((re, im, n));
    }
    let amplitude = 2.0 * sum_abs / total;
    let lr = 2.0 * sum_abs * sum_abs / total / background;
    // The line removed from each dwell: the common amplitude at the dwell's own phase.
    let per_dwell = per_dwell
        .into_iter()
        .map(|(re, im, _)| {
            let m = re.hypot(im).max(1e-300);
            (amplitude * re / m, amplitude * im / m)
        })
        .collect();
    VibrationResult {
        frequency_hz: f / dt,
        amplitude_seen: amplitude,
        amplitude_std: (2.0 * background / total).sqrt(),
        lr,
        independent_frequencies: (n_min as f64 / 2.0).max(1.0),
        per_dwell,
        background,
        starts_samples: None,
        ambiguous_hz: None,
    }
}

/// The coherent sum `Z = sum_p X_p e^{-i w s_p}` of the dwells' DFTs `X_p` at `f` cycles per sample, each
/// turned to the record's time by its first sample `s_p` (samples).
fn coherent_sum(dwells: &[Vec<f64>], starts: &[f64], f: f64) -> (f64, f64) {
    let (mut zr, mut zi) = (0.0, 0.0);
    for (d, s) in dwells.iter().zip(starts) {
        let (re, im) = dft_at(d, f);
        let ph = std::f64::consts::TAU * f * s;
        let (c, sn) = (ph.cos(), -ph.sin());
        zr += re * c - im * sn;
        zi += re * sn + im * c;
    }
    (zr, zi)
}

/// The coherent power `|Z|^2` at `f` cycles per sample ([`coherent_sum`]).
fn coherent_power(dwells: &[Vec<f64>], starts: &[f64], f: f64) -> f64 {
    let (zr, zi) = coherent_sum(dwells, starts, f);
    zr * zr + zi * zi
}

/// Samples from the first dwell's first sample to the end of the last dwell (`starts`: the dwells' first
/// samples, counted from the first dwell's).
fn span_samples(dwells: &[Vec<f64>], starts: &[f64]) -> Option<f64> {
    Some(starts.last()? + dwells.last()?.len() as f64 - starts.first()?)
}

/// The coherent power scanned around `f` (cycles per sample): over one bin of the longest dwell on either side
/// at a quarter of `1 / span`; the points (frequency, power) and the step. `None` for fewer than two dwells or
/// when the scan passes [`COHERENT_BUDGET`].
fn coherent_scan(dwells: &[Vec<f64>], starts: &[f64], f: f64) -> Option<(Vec<(f64, f64)>, f64)> {
    if dwells.len() < 2 || starts.len() != dwells.len() {
        return None;
    }
    let n_max = dwells.iter().map(Vec::len).max()? as f64;
    let n_all = dwells.iter().map(Vec::len).sum::<usize>() as f64;
    let step = 0.25 / span_samples(dwells, starts)?;
    let points = (2.0 / n_max / step).ceil();
    if !(points.is_finite() && points >= 1.0 && points * n_all <= COHERENT_BUDGET) {
        return None;
    }
    let (a, b) = (f - 1.0 / n_max, f + 1.0 / n_max);
    let scan = (0..=points as usize)
        .map(|i| a + (b - a) * i as f64 / points)
        .map(|x| (x, coherent_power(dwells, starts, x)))
        .collect();
    Some((scan, step))
}

/// The frequency (cycles per sample) of a line whose phase holds across the dwells, near the frequency `f`
/// refined with a phase per dwell: the best point of [`coherent_scan`] (span: first to last sample of the
/// record's dwells), refined by golden section between its neighbours. `None` for one dwell (the two fits are
/// the same) or when the scan passes [`COHERENT_BUDGET`].
fn refine_coherent(dwells: &[Vec<f64>], starts: &[f64], f: f64) -> Option<f64> {
    let (scan, step) = coherent_scan(dwells, starts, f)?;
    let best = scan.iter().max_by(|x, y| x.1.total_cmp(&y.1)).map(|(f, _)| *f)?;
    Some(golden_section_max(best - step, best + step, |f| coherent_power(dwells, starts, f)))
}

/// One amplitude and one phase in the record's time at `f` cycles per sample: the reduction of the residual
/// sum of squares is `2 |Z|^2 / N` ([`coherent_sum`]), amplitude `2 |Z| / N`, and each dwell's complex
/// amplitude is `(2 Z / N) e^{i w s_p}`. The frequencies searched are those of the whole span.
fn fit_coherent(dwells: &[Vec<f64>], starts: &[f64], f: f64, background: f64, dt: f64) -> VibrationResult {
    let (zr, zi) = coherent_sum(dwells, starts, f);
    let total = dwells.iter().map(Vec::len).sum::<usize>() as f64;
    let (cr, ci) = (2.0 * zr / total, 2.0 * zi / total);
    let per_dwell = starts
        .iter()
        .map(|s| {
            let ph = std::f64::consts::TAU * f * s;
            (cr * ph.cos() - ci * ph.sin(), cr * ph.sin() + ci * ph.cos())
        })
        .collect();
    let span = span_samples(dwells, starts).unwrap_or(0.0);
    VibrationResult {
        frequency_hz: f / dt,
        amplitude_seen: cr.hypot(ci),
        amplitude_std: (2.0 * background / total).sqrt(),
        lr: 2.0 * (zr * zr + zi * zi) / total / background,
        independent_frequencies: (span / 2.0).max(1.0),
        per_dwell,
        background,
        starts_samples: Some(starts.to_vec()),
        ambiguous_hz: None,
    }
}

/// The line `v` fitted again on other samples (a window of the dwells it was found in, whose first samples
/// are `starts` in the counting of `v`'s), at its frequency, against its background and with its phases (one
/// per dwell, or one in the record's time): the amplitude seen and its standard error.
pub(super) fn line_in(dwells: &[Vec<f64>], starts: &[f64], v: &VibrationResult, dt: f64) -> (f64, f64) {
    let n_min = dwells.iter().map(Vec::len).min().unwrap_or(0);
    let refit = match v.starts_samples {
        Some(_) => fit_coherent(dwells, starts, v.frequency_hz * dt, v.background, dt),
        None => fit_line(dwells, v.frequency_hz * dt, v.background, n_min, dt),
    };
    (refit.amplitude_seen, refit.amplitude_std)
}

/// Removes the line of `v` from every dwell of `series` (sample interval `dt`).
pub(super) fn remove_line(series: &mut [Vec<f64>], v: &VibrationResult, dt: f64) {
    for (s, (re, im)) in series.iter_mut().zip(&v.per_dwell) {
        let w = std::f64::consts::TAU * v.frequency_hz * dt;
        for (i, x) in s.iter_mut().enumerate() {
            let ph = w * i as f64;
            *x -= re * ph.cos() - im * ph.sin();
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::model::simulator::normal;

    /// White noise of `sigma` plus a line of `amplitude` at `frequency_hz`, `n` samples at `dt`.
    fn dwell(n: usize, dt: f64, sigma: f64, amplitude: f64, frequency_hz: f64, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|i| {
                sigma * normal(&mut rng)
                    + amplitude * (std::f64::consts::TAU * frequency_hz * dt * i as f64 + 0.3).sin()
            })
            .collect()
    }

    #[test]
    fn the_pieces_of_the_dwells_hold_every_sample_once_in_order() {
        let dwells = vec![vec![1.0; 10], (0..MAX_PIECE * 2 + 5).map(|i| i as f64).collect::<Vec<_>>()];
        let pieces = pieces(&dwells);
        assert_eq!(pieces.len(), 1 + 3);
        assert!(pieces.iter().all(|p| p.len() <= MAX_PIECE));
        let joined: Vec<f64> = pieces[1..].iter().flat_map(|p| p.iter().copied()).collect();
        assert_eq!(joined, dwells[1]);
    }

    /// A dwell longer than one transform: its line is found at its frequency and amplitude (the periodogram
    /// once thinned such a dwell, and a line found at 1,000,000 samples was missed at 1,100,000).
    #[test]
    fn a_line_in_a_dwell_longer_than_one_transform_is_found() {
        let dt_s = 1e-3;
        for (n, seed) in [(1_000_000, 7), (1_100_000, 8)] {
            let d = vec![dwell(n, dt_s, 1e-3, 2e-4, 37.0, seed)];
            let mut search = LineSearch::new(&d, &[0.0]).expect("a search");
            let v = search.next(&d, &[0.0], dt_s).expect("a line").per_dwell;
            assert!((v.frequency_hz - 37.0).abs() < 1e-5, "{n} samples: {} Hz", v.frequency_hz);
            assert!(
                (v.amplitude_seen - 2e-4).abs() < 3.0 * v.amplitude_std,
                "{n}: {} +- {}",
                v.amplitude_seen,
                v.amplitude_std
            );
            assert!(v.lr > 10_000.0, "{n} samples: likelihood ratio {}", v.lr);
        }
    }
}
