//! Build script: for bare-metal targets with QEMU's board (feature `mps2-an386`) only, put `memory.x` on the
//! linker search path and link with the cortex-m-rt and defmt scripts.
//! Host builds (tests, the `sinscal` tool) are left untouched.
use std::{env, fs, path::PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=build.rs");
    // Another board's package links with its own memory.x (it depends on `sinscal` without the feature): this
    // one, on the search path of every package that depends on the core, must not shadow it.
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") || env::var_os("CARGO_FEATURE_MPS2_AN386").is_none() {
        return;
    }
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    fs::copy("memory.x", out.join("memory.x")).expect("memory.x is at the package root");
    println!("cargo:rustc-link-search={}", out.display());
    // cortex-m-rt's and defmt's linker scripts, for every linked artefact (binaries and on-target tests).
    println!("cargo:rustc-link-arg=-Tlink.x");
    println!("cargo:rustc-link-arg=-Tdefmt.x");
}
