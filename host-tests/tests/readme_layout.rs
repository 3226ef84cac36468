//! The README's layout section names every source file of the repository under its folder: a file added,
//! moved or renamed without the README following fails here. It reads the source tree; it runs no code.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

/// The workspace root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("host-tests is inside the workspace").to_path_buf()
}

/// The folders that hold the project's Rust sources, relative to the root.
const SOURCE_ROOTS: [&str; 4] = ["src", "host-tests/src", "host-tests/lab/src", "boards/stm32f405/src"];

/// Every `.rs` file under `dir`, relative to the root.
fn rust_files(root: &Path, dir: &Path, out: &mut Vec<String>) {
    let Ok(entries) = fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(root, &p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/"));
        }
    }
}

/// The README's layout block: each entry (a line that starts with a path, and its indented continuation lines)
/// by its path.
fn layout_entries(readme: &str) -> BTreeMap<String, String> {
    let section = readme.split("\n## Layout").nth(1).expect("README has a '## Layout' section");
    let block = section.split("```").nth(1).expect("the layout section has a code block");
    let mut entries = BTreeMap::new();
    let mut current: Option<String> = None;
    for line in block.lines() {
        if line.starts_with(' ') {
            if let Some(path) = &current {
                entries.entry(path.clone()).and_modify(|t: &mut String| t.push_str(line));
            }
            continue;
        }
        let Some(first) = line.split_whitespace().next() else { continue };
        let path = first.trim_end_matches(',').to_string();
        entries.insert(path.clone(), line[first.len()..].to_string());
        current = Some(path);
    }
    entries
}

/// Whether `text` names `word` as a whole word (letters, digits and `_` around it are not part of it).
fn names(text: &str, word: &str) -> bool {
    text.match_indices(word).any(|(at, _)| {
        let before = text[..at].chars().next_back();
        let after = text[at + word.len()..].chars().next();
        let part = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
        !part(before) && !part(after)
    })
}

#[test]
fn the_readme_layout_names_every_source_file_under_its_folder() {
    let root = root();
    let readme = fs::read_to_string(root.join("README.md")).unwrap();
    let entries = layout_entries(&readme);
    let mut sources = Vec::new();
    for dir in SOURCE_ROOTS {
        rust_files(&root, &root.join(dir), &mut sources);
    }
    assert!(sources.len() > 100, "only {} source files found: the scan is not reading the tree", sources.len());
    let mut missing = Vec::new();
    for file in &sources {
        let (folder, name) = file.rsplit_once('/').unwrap();
        let stem = name.trim_end_matches(".rs");
        // The file itself as an entry (src/lib.rs, host-tests/src/main.rs), or its stem in the entry of its
        // folder or of a folder above it (where a subfolder is described as `sub/ (a, b)`).
        let named = entries.contains_key(file.as_str())
            || folder.match_indices('/').map(|(i, _)| &folder[..i]).chain([folder]).any(|f| {
                let text = entries.get(&format!("{f}/")).map(String::as_str).unwrap_or("");
                let sub = &folder[f.len()..].trim_start_matches('/');
                let in_sub = sub.is_empty() || names(text, sub.rsplit('/').next().unwrap_or(sub));
                in_sub && (names(text, stem) || ["mod", "lib", "main"].contains(&stem))
            });
        if !named {
            missing.push(file.clone());
        }
    }
    println!("README layout: {} entries, {} source files, {} not named", entries.len(), sources.len(), missing.len());
    assert!(
        missing.is_empty(),
        "source files the README's layout does not name under their folder:\n{}",
        missing.join("\n")
    );
    // An entry for a folder or a file that does not exist is stale.
    let stale: Vec<_> =
        entries.keys().filter(|p| p.contains('/') && !root.join(p.trim_end_matches('/')).exists()).collect();
    assert!(stale.is_empty(), "README layout entries for paths that do not exist: {stale:?}");
}
