//! The repository's own rules, checked on its files: the core's layers and the host's use only the layers below
//! them, the host's product library never names the laboratory crate, nothing cites a file outside the
//! repository, every citation of `docs/` names a page and a heading that exist, and the command line's figures
//! need no C font library. These read the source tree; they run no code of the project.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

/// The workspace root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("host-tests is inside the workspace").to_path_buf()
}

/// Every file under `dir` (recursively) whose name ends with one of `exts`, skipping build output and what
/// cargo-fuzz generates (git ignores both; libFuzzer changes its corpus while it runs).
fn files(dir: &Path, exts: &[&str], out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if p.is_dir() {
            if !["target", "corpus", "artifacts", "coverage"].contains(&name) && !name.starts_with('.') {
                files(&p, exts, out);
            }
        } else if exts.iter().any(|x| name.ends_with(x)) {
            out.push(p);
        }
    }
}

/// The core's layers, lowest first: a module may use only layers listed before it (and itself).
const LAYERS: [&str; 8] = ["math", "nav", "sensor", "calib", "run", "instrument", "rig", "board"];

#[test]
fn core_layers_use_only_the_layers_below_them() {
    let src = root().join("src");
    let mut violations = Vec::new();
    let mut checked = 0;
    for (rank, layer) in LAYERS.iter().enumerate() {
        let mut rs = Vec::new();
        files(&src.join(layer), &[".rs"], &mut rs);
        assert!(!rs.is_empty(), "layer {layer} has no files under src/{layer}");
        for file in rs {
            let text = fs::read_to_string(&file).unwrap();
            for (n, line) in text.lines().enumerate() {
                for (i, _) in line.match_indices("crate::") {
                    let used = line[i + "crate::".len()..].split(|c: char| !c.is_alphanumeric() && c != '_').next();
                    let Some(used_rank) = used.and_then(|u| LAYERS.iter().position(|l| *l == u)) else { continue };
                    checked += 1;
                    if used_rank > rank {
                        violations.push(format!("{}:{}: {layer} uses {}", file.display(), n + 1, LAYERS[used_rank]));
                    }
                }
            }
        }
    }
    println!("layers: {checked} cross-layer paths checked, {} violations", violations.len());
    assert!(checked > 20, "only {checked} cross-module paths found: the scan is not reading the layers");
    assert!(violations.is_empty(), "a layer uses a layer above it:\n{}", violations.join("\n"));
    // Nothing of the core lives outside the layers but the crate root and the firmware entry points.
    let top: BTreeSet<String> = fs::read_dir(&src)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| !LAYERS.contains(&n.as_str()))
        .collect();
    assert_eq!(top, BTreeSet::from(["bin".to_string(), "lib.rs".to_string()]), "files beside the layers in src/");
}

/// The host's layers (sinscal-host's top-level modules), lowest first, with their rank: a module may use only
/// modules of a lower rank (and itself); modules of the same rank do not use each other. io/ is the lowest.
const HOST_LAYERS: [(&str, usize); 10] = [
    ("io", 0),
    ("model", 1),
    ("stats", 1),
    ("calibration", 2),
    ("navigation", 3),
    ("device", 3),
    ("plot", 4),
    ("analysis", 5),
    ("study", 5),
    ("cmd", 6),
];

/// The `crate::` paths of the host file `text` that name a host layer: (line, layer, rank).
fn host_layer_uses(text: &str) -> Vec<(usize, &'static str, usize)> {
    let mut uses = Vec::new();
    for (n, line) in text.lines().enumerate() {
        for (i, _) in line.match_indices("crate::") {
            let used = line[i + "crate::".len()..].split(|c: char| !c.is_alphanumeric() && c != '_').next();
            if let Some(&(layer, rank)) = used.and_then(|u| HOST_LAYERS.iter().find(|(l, _)| *l == u)) {
                uses.push((n + 1, layer, rank));
            }
        }
    }
    uses
}

#[test]
fn host_layers_use_only_the_layers_below_them() {
    let src = root().join("host-tests").join("src");
    let mut violations = Vec::new();
    let mut checked = 0;
    for (layer, rank) in HOST_LAYERS {
        let mut rs = Vec::new();
        let file = src.join(format!("{layer}.rs"));
        if file.is_file() {
            rs.push(file);
        }
        files(&src.join(layer), &[".rs"], &mut rs);
        assert!(!rs.is_empty(), "host layer {layer} has no files under host-tests/src");
        for file in rs {
            let text = fs::read_to_string(&file).unwrap();
            for (n, used, used_rank) in host_layer_uses(&text) {
                if used == layer {
                    continue;
                }
                checked += 1;
                if used_rank >= rank {
                    violations.push(format!("{}:{n}: {layer} uses {used}", file.display()));
                }
            }
        }
    }
    println!("host layers: {checked} cross-layer paths checked, {} violations", violations.len());
    assert!(checked > 50, "only {checked} cross-module paths found: the scan is not reading the host's layers");
    assert!(violations.is_empty(), "a host layer uses a layer above it (or beside it):\n{}", violations.join("\n"));
    // Nothing of the host's library lives outside the layers but the crate root and the binary's entry point.
    let top: BTreeSet<String> = fs::read_dir(&src)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| !HOST_LAYERS.iter().any(|(l, _)| *l == n.as_str() || format!("{l}.rs") == *n))
        .collect();
    assert_eq!(
        top,
        BTreeSet::from(["lib.rs".to_string(), "main.rs".to_string()]),
        "files beside the layers in host-tests/src"
    );
}

/// The product (sinscal-host) never uses the laboratory (sinscal-lab, host-tests/lab): the laboratory depends on
/// the product, not the other way round (only its own tests may name it, and today none does).
#[test]
fn the_product_never_names_the_laboratory() {
    let host = root().join("host-tests");
    let mut rs = Vec::new();
    files(&host.join("src"), &[".rs"], &mut rs);
    assert!(rs.len() > 50, "only {} files of host-tests/src read", rs.len());
    let mut hits = Vec::new();
    for file in rs {
        let text = fs::read_to_string(&file).unwrap();
        for (n, line) in text.lines().enumerate() {
            if line.contains(["sinscal", "_lab"].concat().as_str()) {
                hits.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
            }
        }
    }
    let manifest = fs::read_to_string(host.join("Cargo.toml")).unwrap();
    for (n, line) in manifest.lines().enumerate() {
        if line.contains(["sinscal", "-lab"].concat().as_str()) {
            hits.push(format!("host-tests/Cargo.toml:{}: {}", n + 1, line.trim()));
        }
    }
    assert!(hits.is_empty(), "the product names the laboratory:\n{}", hits.join("\n"));
}

/// The general estimator (calib/general, the default) stands alone: it uses nothing of the paper's angle method
/// (calib/angles), which may use it (its capacity is the general estimator's).
#[test]
fn the_general_estimator_does_not_use_the_angle_method() {
    let mut rs = Vec::new();
    files(&root().join("src/calib/general"), &[".rs"], &mut rs);
    assert!(rs.len() > 3, "only {} files under src/calib/general", rs.len());
    let mut uses = Vec::new();
    for file in &rs {
        for (n, line) in fs::read_to_string(file).unwrap().lines().enumerate() {
            if line.contains("calib::angles") {
                uses.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
            }
        }
    }
    assert!(uses.is_empty(), "the general estimator uses the angle method:\n{}", uses.join("\n"));
}

/// A real board is a package of its own (boards/): no code of the core names a board's crates (its HAL, its
/// framework, its chip), so that every board runs the same core. QEMU's board (src/board, register level, no crate
/// of its own) is the one board inside the core package.
#[test]
fn nothing_board_specific_leaks_into_the_core() {
    let mut rs = Vec::new();
    files(&root().join("src"), &[".rs"], &mut rs);
    let board_crates = ["stm32", "rtic", "embassy", "probe_rs", "defmt_rtt", "panic_probe"];
    let mut leaks = Vec::new();
    for file in &rs {
        let text = fs::read_to_string(file).unwrap();
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("").to_lowercase();
            let mut words = code.split(|c: char| !c.is_alphanumeric() && c != '_');
            if words.any(|w| board_crates.iter().any(|c| w == *c || (w.starts_with(c) && !c.contains('_')))) {
                leaks.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
            }
        }
    }
    println!("board crates: {} core files checked, {} leaks", rs.len(), leaks.len());
    assert!(rs.len() > 40, "only {} files under src/: the scan is not reading the core", rs.len());
    assert!(leaks.is_empty(), "the core names a board's crate:\n{}", leaks.join("\n"));
    // And the core's manifest depends on none of them.
    let manifest = fs::read_to_string(root().join("Cargo.toml")).unwrap();
    let deps: Vec<&str> = manifest.lines().filter(|l| !l.trim_start().starts_with('#')).collect();
    for c in ["stm32", "rtic", "embassy", "defmt-rtt", "panic-probe"] {
        assert!(!deps.iter().any(|l| l.contains(c)), "the core's Cargo.toml depends on {c}");
    }
}

/// The files whose text users and developers read: code, scripts, manifests, README and docs. (`.ci/run`, the
/// CI wiring, is left out: it names where CI puts the measured data, beside the clone.)
fn project_texts() -> Vec<PathBuf> {
    let r = root();
    let mut out = Vec::new();
    for dir in ["src", "host-tests", "scripts", "docs", ".cargo", "boards"] {
        files(&r.join(dir), &[".rs", ".md", ".toml", ""], &mut out);
    }
    for f in ["README.md", "Cargo.toml", "build.rs", "memory.x"] {
        out.push(r.join(f));
    }
    out.retain(|p| p.is_file() && fs::read_to_string(p).is_ok());
    out
}

#[test]
fn nothing_cites_a_file_outside_the_repository() {
    // Written in pieces so that this file does not match itself.
    let outside =
        [["SPEC", ".md"].concat(), ["METHOD", ".md"].concat(), ["PROVEN", "ANCE"].concat(), ["shared", "/"].concat()];
    let mut hits = Vec::new();
    let texts = project_texts();
    println!("outside citations: {} files read", texts.len());
    assert!(texts.len() > 50, "only {} files read", texts.len());
    for file in texts {
        let text = fs::read_to_string(&file).unwrap();
        for (n, line) in text.lines().enumerate() {
            for o in &outside {
                if line.contains(o.as_str()) {
                    hits.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
                }
            }
        }
    }
    assert!(hits.is_empty(), "citations of files outside the repository:\n{}", hits.join("\n"));
}

/// GitHub's anchor of a Markdown heading: lower case, punctuation dropped, spaces to hyphens.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

#[test]
fn every_docs_citation_names_an_existing_page_and_heading() {
    let docs = root().join("docs");
    let mut cited = 0;
    let mut broken = Vec::new();
    for file in project_texts() {
        let text = fs::read_to_string(&file).unwrap();
        let in_docs = file.parent() == Some(docs.as_path());
        for (n, line) in text.lines().enumerate() {
            // `docs/<page>.md#<anchor>` anywhere, and `(<page>.md#<anchor>)` links inside docs/.
            let mut targets: Vec<String> = line
                .match_indices("docs/")
                .map(|(i, _)| {
                    line[i + 5..]
                        .split(|c: char| !(c.is_alphanumeric() || "-_.#".contains(c)))
                        .next()
                        .unwrap_or("")
                        .to_string()
                })
                .collect();
            if in_docs {
                targets.extend(
                    line.match_indices("](")
                        .map(|(i, _)| line[i + 2..].split(')').next().unwrap_or("").to_string())
                        .filter(|t| !t.contains("://") && !t.starts_with('#') && t.contains(".md")),
                );
            }
            for t in targets {
                let t = t.trim_end_matches('.');
                let (page, frag) = t.split_once('#').unwrap_or((t, ""));
                if !page.ends_with(".md") {
                    continue;
                }
                cited += 1;
                let Ok(page_text) = fs::read_to_string(docs.join(page)) else {
                    broken.push(format!("{}:{}: no page docs/{page}", file.display(), n + 1));
                    continue;
                };
                let anchors: BTreeSet<String> = page_text
                    .lines()
                    .filter(|l| l.starts_with('#'))
                    .map(|l| anchor(l.trim_start_matches('#')))
                    .collect();
                if !frag.is_empty() && !anchors.contains(frag) {
                    broken.push(format!("{}:{}: docs/{page} has no heading #{frag}", file.display(), n + 1));
                }
            }
        }
    }
    println!("docs citations: {cited} checked, {} broken", broken.len());
    assert!(cited > 30, "only {cited} citations of docs/ found: the scan is not reading them");
    assert!(broken.is_empty(), "broken citations:\n{}", broken.join("\n"));
}

#[test]
fn anchors_follow_the_heading_rule() {
    assert_eq!(anchor(" Step 4: angles and biases"), "step-4-angles-and-biases");
    assert_eq!(anchor(" Replay file (\"SSRP\", version 1)"), "replay-file-ssrp-version-1");
    assert_eq!(anchor(" `psins`"), "psins");
}

/// The packages of Cargo.lock reached from `from` through their dependencies (every target and kind: what
/// the lock file can bring into a build), by name.
fn locked_dependencies(from: &str) -> BTreeSet<String> {
    let lock = fs::read_to_string(root().join("Cargo.lock")).unwrap();
    let mut deps: std::collections::BTreeMap<String, BTreeSet<String>> = Default::default();
    let (mut name, mut in_deps) = (String::new(), false);
    for line in lock.lines().map(str::trim) {
        if let Some(n) = line.strip_prefix("name = ") {
            name = n.trim_matches('"').to_string();
            deps.entry(name.clone()).or_default();
        } else if line == "dependencies = [" {
            in_deps = true;
        } else if in_deps && line == "]" {
            in_deps = false;
        } else if in_deps {
            // `"name"`, `"name version"` or `"name version (source)"`.
            let dep = line.trim_end_matches(',').trim_matches('"').split(' ').next().unwrap_or("").to_string();
            deps.entry(name.clone()).or_default().insert(dep);
        } else if line.starts_with('[') {
            in_deps = false;
        }
    }
    let mut reached = BTreeSet::new();
    let mut todo = vec![from.to_string()];
    while let Some(p) = todo.pop() {
        if reached.insert(p.clone()) {
            todo.extend(deps.get(&p).into_iter().flatten().cloned());
        }
    }
    reached
}

/// The figures (plotters) draw their text with a font of the program's own through pure-Rust crates: no font
/// crate that links a C library (font-kit, which reaches fontconfig and FreeType, or their bindings) is in
/// the command line's dependency tree, as plotters' default features would put them there.
#[test]
fn the_figures_link_no_c_font_library() {
    let reached = locked_dependencies("sinscal-host");
    println!("font libraries: {} packages reached from sinscal-host", reached.len());
    assert!(
        reached.len() > 50 && reached.contains("plotters") && reached.contains("clap"),
        "plotters and clap are not reached from sinscal-host: the Cargo.lock scan is not reading it"
    );
    let c_fonts = [
        "font-kit",
        "freetype",
        "freetype-rs",
        "freetype-sys",
        "fontconfig",
        "fontconfig-sys",
        "servo-fontconfig",
        "servo-fontconfig-sys",
        "yeslogic-fontconfig",
        "yeslogic-fontconfig-sys",
        "expat-sys",
        "servo-freetype-sys",
        "core-text",
        "dwrote",
    ];
    let found: Vec<&str> = c_fonts.iter().copied().filter(|c| reached.contains(*c)).collect();
    assert!(found.is_empty(), "sinscal-host depends (Cargo.lock) on font crates that link C libraries: {found:?}");
}

mod common;

/// A missing prerequisite is a failure where prerequisites are required (`.ci/run` sets the variable), and a skip
/// written to the stderr handle elsewhere; `.ci/run` sets the variable.
#[test]
fn a_missing_prerequisite_fails_in_ci_and_is_reported_elsewhere() {
    let mut out = Vec::new();
    common::report_skip("a QEMU test", "qemu-system-arm not found", false, &mut out);
    assert_eq!(String::from_utf8(out).unwrap(), "SKIPPED a QEMU test: qemu-system-arm not found\n");
    let required = std::panic::catch_unwind(|| {
        common::report_skip("a QEMU test", "qemu-system-arm not found", true, &mut Vec::new());
    });
    let message = *required.expect_err("a required prerequisite that is missing fails").downcast::<String>().unwrap();
    assert!(message.contains("qemu-system-arm not found") && message.contains(common::REQUIRE_ALL), "{message}");
    let ci = fs::read_to_string(root().join(".ci/run")).unwrap();
    assert!(ci.contains(&format!("export {}=1", common::REQUIRE_ALL)), ".ci/run must require every prerequisite");
}
