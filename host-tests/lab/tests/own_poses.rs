//! Planted effects in the three measured data sets WITH THEIR OWN POSES AND TIME BASE
//! (`sinscal_lab::own_poses`): each record as imported is analysed once (the baseline), one effect of the
//! catalogue is planted at 3, 5 and 10 standard errors by the sensor model of `sinscal_lab::planted`, and
//! `sinscal analyze` is judged on whether it names it (FOUND) and on what else it names (FALSE ALARMS).
//!
//! The fast test plants two kinds twice at 10 standard errors in the imucal Ferraris and imu_tk records and
//! asserts that every one is found (what else the analysis names is printed, not asserted: on the Ferraris
//! faces a planted effect moves the record's own tilts between equivalent parametrisations). The campaign is opt-in:
//!     SINSCAL_DATA=DIR SINSCAL_OWN_RUNS=20 cargo test --release -p sinscal-lab --test own_poses -- --ignored --nocapture
//! (20 trials per effect and size by default; SINSCAL_OWN_SETS=ferraris,imutk,psins picks the sets,
//! SINSCAL_OWN_SIZES=3,5,10 the sizes, SINSCAL_OWN_KINDS=vibration,... the effects; the trials run on the
//! machine's cores).

#[path = "../../tests/common/mod.rs"]
mod common;

use std::time::Instant;

use sinscal_host::analysis::analyze_recording;
use sinscal_host::model::catalogue::EffectKind;
use sinscal_lab::own_poses::{campaign, draw, table, Baseline, DataSet, Outcome, SIZES};
use sinscal_lab::planted::plant_into;

/// The set's baseline, imported from the data directory.
fn baseline(dir: &std::path::Path, set: DataSet) -> Baseline {
    let record = set.import(dir).unwrap_or_else(|e| panic!("{}: {e}", set.name()));
    Baseline::new(set, record).unwrap_or_else(|e| panic!("{}: the untouched record analyses: {e}", set.name()))
}

/// One line on a trial.
fn describe(o: &Outcome) -> String {
    let h = &o.hidden;
    format!(
        "{} SE: planted {} {} {} {:?} {:+.4e} (tau {:?}, f {:?}); named there {:?}; miss {:?}; false alarms {:?}",
        o.size, h.effect, h.sensor, h.axes, h.pos, h.value, h.tau_s, h.frequency_hz, o.named, o.miss, o.false_alarms
    )
}

/// The kinds the fast test plants per set: a static term and sample-level or time terms (ones the campaign
/// finds in every trial, or nine of ten for the imu_tk lines, at 10 standard errors).
const FAST: [(DataSet, &[EffectKind]); 2] = [
    (DataSet::Ferraris, &[EffectKind::AccelScaleFactor, EffectKind::Quantization]),
    (DataSet::Imutk, &[EffectKind::AccelMisalignment, EffectKind::BiasWarmup, EffectKind::Vibration]),
];

#[test]
fn planted_effects_at_ten_standard_errors_are_found_in_the_records_own_poses() {
    let Some(dir) = common::data_dir() else { return };
    let start = Instant::now();
    for (set, kinds) in FAST {
        let b = baseline(&dir, set);
        for &kind in kinds {
            assert!(!b.targets(kind).is_empty(), "{}: {kind} cannot be planted", set.name());
        }
        let c = campaign(&b, kinds, &[10.0], 2, 2);
        println!("{}", table(&c, &b));
        for (kind, per_size) in &c.rows {
            assert_eq!(per_size[0].len(), 2, "{}: {kind}", set.name());
            for o in &per_size[0] {
                assert!(o.found, "{}: {kind} at 10 SE not found: {}", set.name(), describe(o));
            }
        }
    }
    println!("fast test: {:.1} s", start.elapsed().as_secs_f64());
}

/// REAL DATA with a planted effect: a warm-up of the accelerometer y at 5 standard errors in the imu_tk record
/// (seed 100: -0.274 m/s^2 at 96.0 s, the campaign's draw). The block model finds it with its time constant
/// within 10 % (it chose 116 s and added a drift of the same channel when the time constant was not profiled
/// again once the scale factors were in), and the correlated-noise test, which takes the block model's warm-up
/// off the samples, names no process on that channel (it named one at the slow end of its range, the warm-up's
/// bend within the 52-s first dwell).
#[test]
fn a_planted_warm_up_leaves_no_drift_and_no_correlated_noise_beside_it() {
    let Some(dir) = common::data_dir() else { return };
    let b = baseline(&dir, DataSet::Imutk);
    let planted = draw(&b, EffectKind::BiasWarmup, 5.0, 100).expect("a warm-up can be planted");
    let h = &planted.hidden;
    assert_eq!((h.sensor.name(), h.axes.as_str()), ("accel", "y"), "the campaign's draw changed: {h:?}");
    let analysis = analyze_recording(&plant_into(&b.base(), &planted)).expect("the analysis runs");
    let on_y = |kind: EffectKind| {
        analysis.effects.iter().find(|e| e.effect == kind.name() && e.sensor == "accel" && e.axes == "y")
    };
    let warmup = on_y(EffectKind::BiasWarmup).expect("the warm-up is named");
    let (tau, tau_planted) = (warmup.tau_s.unwrap_or(f64::NAN), h.tau_s.unwrap_or(f64::NAN));
    assert!((tau / tau_planted - 1.0).abs() < 0.1, "tau {tau} s, planted {tau_planted} s");
    assert!((warmup.estimate / h.value - 1.0).abs() < 0.1, "{} vs {}", warmup.estimate, h.value);
    assert!(on_y(EffectKind::BiasDrift).is_none(), "a drift beside the warm-up");
    assert!(on_y(EffectKind::CorrelatedNoise).is_none(), "a correlated noise beside the warm-up");
}

/// An environment variable's comma-separated list, parsed by `parse`, or `default`.
fn env_list<T>(name: &str, default: Vec<T>, parse: impl Fn(&str) -> Option<T>) -> Vec<T> {
    match std::env::var(name) {
        Ok(v) if !v.trim().is_empty() => {
            v.split(',').map(|s| parse(s.trim()).unwrap_or_else(|| panic!("{name}: cannot read {s:?}"))).collect()
        }
        _ => default,
    }
}

/// The campaign: `SINSCAL_OWN_RUNS` trials (default 20) of every plantable effect (`SINSCAL_OWN_KINDS`) of
/// every set (`SINSCAL_OWN_SETS`) at every size (`SINSCAL_OWN_SIZES`), seeds 100 onwards; one table per set,
/// the trials not found or with a false alarm on stderr.
#[test]
#[ignore]
fn campaign_in_the_records_own_poses() {
    let Some(dir) = common::data_dir() else { return };
    let runs: usize = std::env::var("SINSCAL_OWN_RUNS").ok().and_then(|v| v.parse().ok()).unwrap_or(20);
    let sets = env_list("SINSCAL_OWN_SETS", DataSet::ALL.to_vec(), DataSet::parse);
    let sizes = env_list("SINSCAL_OWN_SIZES", SIZES.to_vec(), |s| s.parse().ok());
    let kinds = env_list("SINSCAL_OWN_KINDS", Vec::new(), |s| s.parse::<EffectKind>().ok());
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let start = Instant::now();
    for set in sets {
        let b = baseline(&dir, set);
        let c = campaign(&b, &kinds, &sizes, runs, threads);
        for o in c.rows.iter().flat_map(|(_, per)| per.iter().flatten()) {
            if !o.found || !o.false_alarms.is_empty() {
                eprintln!("  {}: {}{}", set.name(), if o.found { "found, " } else { "" }, describe(o));
            }
        }
        println!("\n{}", table(&c, &b));
        assert!(c.rows.iter().all(|(_, per)| per.iter().all(|o| o.len() == runs)));
    }
    println!("campaign: {:.0} s", start.elapsed().as_secs_f64());
}
