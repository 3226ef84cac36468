//! Fuzzing of every reader on stable Rust: a seeded mutation fuzzer (docs/formats.md#bad-input). Each target
//! starts from a valid input that sinscal writes itself (a recording, an angles file, a scenario, a
//! calibration JSON, a replay file, an ADIS burst, MAT-files, a layout, a labels file, the files of the four
//! importers, the data files of `import columns`' text, binary and MAT layouts and of
//! several files (sessions, side by side), the device link's frames and
//! requests, a stored calibration record), mutates it (bytes flipped, inserted, deleted or
//! repeated; lines repeated or dropped; numbers replaced by extreme ones; the end cut off), and feeds it to
//! the reader. A reader must return a value or an error: a panic is a failure, and the input that caused it
//! is written to `host-tests/fuzz-corpus/TARGET/` to be kept as a regression (every file there is replayed by
//! this test first). Values a reader accepts must be finite.
//!
//! `cargo test` runs a short campaign (`SINSCAL_FUZZ_INPUTS`, default 2000 inputs per target, a tenth of that
//! for the file reader, which writes a file per input); the opt-in
//! campaign of the size:
//!     SINSCAL_FUZZ_INPUTS=1000000 cargo test --release -p sinscal-lab --test fuzz_readers -- --nocapture
//! It reports per target the inputs run, the share accepted, the panics and the slowest input (a hang would
//! show there: every input is bounded, so the slowest is the longest reader run).

use std::path::PathBuf;
use std::time::{Duration, Instant};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sinscal_lab::fuzz::{seeds, Reader};

/// Numbers a mutation puts in place of one in the text.
const EXTREMES: [&str; 14] =
    ["0", "-0", "1e308", "-1e308", "1e-320", "nan", "inf", "-1", "65537", "4294967297", "1e15", "9", "", "0x10"];

/// One mutation of `input`.
fn mutate(input: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut v = input.to_vec();
    for _ in 0..rng.random_range(1..4) {
        if v.is_empty() {
            v.push(rng.random());
            continue;
        }
        let at = rng.random_range(0..v.len());
        match rng.random_range(0..8) {
            0 => v[at] ^= 1 << rng.random_range(0..8),
            1 => v.insert(at, rng.random()),
            2 => {
                v.remove(at);
            }
            3 => {
                let end = (at + rng.random_range(1..64)).min(v.len());
                let piece = v[at..end].to_vec();
                v.splice(at..at, piece);
            }
            4 => v.truncate(at),
            5 => {
                // Replace the number around `at` (a run of digits, signs, dots and exponents) by an extreme one.
                let is_num = |b: u8| b.is_ascii_digit() || b"+-.eE".contains(&b);
                let (mut a, mut b) = (at, at);
                while a > 0 && is_num(v[a - 1]) {
                    a -= 1;
                }
                while b < v.len() && is_num(v[b]) {
                    b += 1;
                }
                let x = EXTREMES[rng.random_range(0..EXTREMES.len())].as_bytes().to_vec();
                v.splice(a..b, x);
            }
            6 => {
                // Repeat or drop a whole line.
                let start = v[..at].iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
                let end = v[at..].iter().position(|&c| c == b'\n').map_or(v.len(), |p| at + p + 1);
                if rng.random() {
                    let line = v[start..end].to_vec();
                    v.splice(end..end, line);
                } else {
                    v.drain(start..end);
                }
            }
            _ => {
                const BYTES: &[u8] = b"\n,#:-.e0123456789 \r\"[]{}=";
                v[at] = BYTES[rng.random_range(0..BYTES.len())];
            }
        }
    }
    v
}

fn corpus_dir(target: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fuzz-corpus").join(target)
}

/// Runs `reader` on `input`; `Err` with the reason for a panic or a non-finite value accepted.
fn check(reader: Reader, input: &[u8]) -> Result<bool, String> {
    match std::panic::catch_unwind(|| reader(input)) {
        Ok(result) => result,
        Err(payload) => Err(format!(
            "panic: {}",
            payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default()
        )),
    }
}

#[test]
fn readers_survive_mutated_inputs() {
    let inputs: u64 = std::env::var("SINSCAL_FUZZ_INPUTS").ok().and_then(|v| v.parse().ok()).unwrap_or(2000);
    let seeds = seeds();
    for (target, reader, seed) in &seeds {
        assert_eq!(reader(seed), Ok(true), "{target}: the seed itself must be accepted");
    }
    // Panics print nothing while fuzzing (they are counted and kept instead).
    std::panic::set_hook(Box::new(|_| {}));
    let mut failures = Vec::new();
    for (target, reader, seed) in seeds {
        // The kept crashes first.
        if let Ok(entries) = std::fs::read_dir(corpus_dir(target)) {
            for e in entries.flatten() {
                let bytes = std::fs::read(e.path()).unwrap();
                if let Err(reason) = check(reader, &bytes) {
                    failures.push(format!("{target}: kept input {}: {reason}", e.path().display()));
                }
            }
        }
        // The file reader writes a file per input: a tenth of the inputs.
        let inputs = if target == "recording-file" { inputs.div_ceil(10) } else { inputs };
        let mut rng = ChaCha8Rng::seed_from_u64(0x5eed ^ target.len() as u64);
        let (start, mut accepted, mut slowest, mut panics) = (Instant::now(), 0u64, Duration::ZERO, 0u64);
        for i in 0..inputs {
            // Mostly one mutation of the seed; sometimes a mutation of a mutation.
            let mut input = mutate(&seed, &mut rng);
            if i % 4 == 0 {
                input = mutate(&input, &mut rng);
            }
            let t = Instant::now();
            let result = check(reader, &input);
            slowest = slowest.max(t.elapsed());
            match result {
                Ok(true) => accepted += 1,
                Ok(false) => {}
                Err(reason) => {
                    panics += 1;
                    let dir = corpus_dir(target);
                    let _ = std::fs::create_dir_all(&dir);
                    let path = dir.join(format!("crash-{i}"));
                    let _ = std::fs::write(&path, &input);
                    failures.push(format!("{target}: input {i} ({}): {reason}", path.display()));
                }
            }
        }
        println!(
            "fuzz {target}: {inputs} inputs in {:.1} s, {:.1} % accepted, {panics} failures, slowest {:.1} ms",
            start.elapsed().as_secs_f64(),
            100.0 * accepted as f64 / inputs.max(1) as f64,
            slowest.as_secs_f64() * 1e3
        );
    }
    let _ = std::panic::take_hook();
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}
