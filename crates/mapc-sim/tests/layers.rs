//! mapc-sim's layers (docs/architecture.md): a module uses only the layers above its own. Every source file's
//! `crate::` paths are read (tests and comments aside) and each is checked against the table below.

use std::path::{Path, PathBuf};

/// The layers from the bottom of the table's order up: index 0 is used by all others.
const LAYERS: &[&[&str]] = &[
    &["numeric", "ids", "error", "spec"],
    &["models"],
    &["network"],
    &["demand"],
    &["measure"],
    &["sim"],
    &["runs"],
];

fn layer_of(first: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&first))
}

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The code of a file without its comments and its test module.
fn code(text: &str) -> String {
    let text = text.split("#[cfg(test)]\nmod tests").next().unwrap();
    text.lines()
        .map(|l| l.split("//").next().unwrap())
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn every_module_uses_only_the_layers_above_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    files.sort();
    let mut arrows_checked = 0;
    let mut wrong = Vec::new();
    for f in &files {
        let rel = f
            .strip_prefix(&src)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let name = rel.rsplit('/').next().unwrap();
        if rel == "lib.rs" || name.ends_with("tests.rs") {
            continue;
        }
        let own_first = rel.split(['/', '.']).next().unwrap();
        let own = layer_of(own_first).unwrap_or_else(|| panic!("{rel}: module not in the table"));
        let text = code(&std::fs::read_to_string(f).unwrap());
        for (i, _) in text.match_indices("crate::") {
            let first: String = text[i + 7..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if first == own_first || first.is_empty() || first.starts_with(char::is_uppercase) {
                continue;
            }
            let Some(used) = layer_of(&first) else {
                wrong.push(format!("{rel} uses crate::{first}, which is in no layer"));
                continue;
            };
            arrows_checked += 1;
            if used > own || (used == own && own != 0) {
                wrong.push(format!(
                    "{rel} (layer {own}) uses crate::{first} (layer {used})"
                ));
            }
        }
    }
    assert!(
        arrows_checked > 30,
        "only {arrows_checked} paths found: is the source still there?"
    );
    assert!(
        wrong.is_empty(),
        "arrows against the layers:\n{}",
        wrong.join("\n")
    );
}
