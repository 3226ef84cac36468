//! The speed and memory of the MAT-file reader on a long matrix (docs/formats.md#mat-files): writes a MAT-file
//! of ROWS x COLS doubles (SIMULATION: a smooth signal plus a counter, no meaning), or reads one and prints the
//! time of `read_mat`. Run the two steps as two processes so that the peak memory of the read is its own:
//!
//!     cargo run --release -p sinscal-host --example mat_speed -- write FILE 3600000 7 [--compress]
//!     /usr/bin/time -v target/release/examples/mat_speed read FILE
use std::time::Instant;

use sinscal_host::io::import::mat::{read_mat, write_mat, ByteOrder};

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: mat_speed write FILE ROWS COLS [--compress] | mat_speed read FILE";
    match args.iter().map(String::as_str).collect::<Vec<_>>().as_slice() {
        ["write", file, rows, cols, rest @ ..] => {
            let rows: usize = rows.parse().map_err(|_| usage.to_string())?;
            let cols: usize = cols.parse().map_err(|_| usage.to_string())?;
            let data: Vec<f64> = (0..rows * cols)
                .map(|i| if i < rows { i as f64 * 1e-3 } else { (i as f64 * 1e-4).sin() * 9.81 + (i % 17) as f64 })
                .collect();
            let compress = rest == ["--compress"];
            let start = Instant::now();
            let bytes = write_mat(&[("imu", rows, cols, &data)], ByteOrder::Little, compress)?;
            std::fs::write(file, &bytes).map_err(|e| e.to_string())?;
            println!("wrote {file}: {rows}x{cols}, {} bytes in {:.3} s", bytes.len(), start.elapsed().as_secs_f64());
        }
        ["read", file] => {
            let start = Instant::now();
            let bytes = std::fs::read(file).map_err(|e| e.to_string())?;
            let loaded_s = start.elapsed().as_secs_f64();
            let matrices = read_mat(&bytes, file).map_err(|e| e.to_string())?;
            let total_s = start.elapsed().as_secs_f64();
            for m in &matrices {
                let sum: f64 = m.data.iter().sum();
                println!("'{}' {}x{}, sum {sum:.6e}", m.name, m.rows, m.cols);
            }
            println!("file read in {loaded_s:.3} s, read_mat in {:.3} s, {:.3} s in all", total_s - loaded_s, total_s);
        }
        _ => return Err(usage.to_string()),
    }
    Ok(())
}
