//! No public function takes more than six parameters: a longer list is a problem value, a
//! settings bundle or a set of callbacks that has not been named (the growth run takes a
//! `GrowthProblem`, the integrators a span of time and their hooks). The check reads every
//! `pub` (and `pub(crate)`, `pub(super)`) function of the library and command-line sources
//! (crates/*/src, src/), outside tests, and counts its parameters, `self` aside. The Python
//! binding's functions are left out: their parameters are the Python call's keyword
//! arguments (docs/python-api.md).

use std::path::{Path, PathBuf};

use crate::support::repo;

/// The most parameters a public function may take.
const MAX_PARAMETERS: usize = 6;

/// Every `.rs` file under `dir`, tests left out (files named tests.rs, folders named tests).
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().to_string();
        if path.is_dir() {
            if name != "tests" && name != "target" {
                sources(&path, out);
            }
        } else if name.ends_with(".rs") && name != "tests.rs" {
            out.push(path);
        }
    }
}

/// The source without its `#[cfg(test)]` modules (each from its attribute to its closing
/// brace, braces counted) and without comments, so that neither counts.
fn without_tests(text: &str) -> String {
    let code: String = text
        .lines()
        .map(|l| match l.trim_start().starts_with("//") {
            true => "",
            false => l,
        })
        .collect::<Vec<_>>()
        .join("\n");
    let mut out = String::new();
    let mut rest = code.as_str();
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let after = &rest[at..];
        // Only a test module is cut; a test-only item of another kind is short.
        let Some(open) = after.find('{') else {
            rest = "";
            break;
        };
        let is_module = after[..open].contains("mod ");
        if !is_module {
            out.push_str("#[cfg(test)]");
            rest = &after["#[cfg(test)]".len()..];
            continue;
        }
        let mut depth = 0usize;
        let mut end = after.len();
        for (i, c) in after[open..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = open + i + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// The public functions of `code` with their parameter counts (`self` not counted).
fn public_functions(code: &str) -> Vec<(String, usize)> {
    let bytes = code.as_bytes();
    let mut found = vec![];
    let mut from = 0;
    while let Some(at) = code[from..].find("fn ") {
        let start = from + at;
        from = start + 3;
        // A word of its own, after a visibility that starts with `pub`.
        if start > 0 && (bytes[start - 1].is_ascii_alphanumeric() || bytes[start - 1] == b'_') {
            continue;
        }
        let line_start = code[..start].rfind('\n').map_or(0, |i| i + 1);
        let head = code[line_start..start].trim();
        if !head.starts_with("pub") {
            continue;
        }
        // A function of the Python binding (`#[pyfunction]`, or a method with a
        // `#[pyo3(signature = ...)]`) takes the Python call's keyword arguments, each named in
        // docs/python-api.md: its parameters are Python's API, not a Rust one.
        let attributes = code[..line_start]
            .lines()
            .rev()
            .take_while(|l| l.trim_start().starts_with("#["));
        if attributes
            .into_iter()
            .any(|a| a.contains("pyfunction") || a.contains("pyo3(signature"))
        {
            continue;
        }
        let name: String = code[start + 3..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let mut i = start + 3 + name.len();
        // Generic parameters: skip the balanced angle brackets (an arrow is not one).
        if code[i..].starts_with('<') {
            let mut depth = 0i32;
            while i < code.len() {
                if code[i..].starts_with("->") {
                    i += 2;
                    continue;
                }
                match bytes[i] {
                    b'<' => depth += 1,
                    b'>' => {
                        depth -= 1;
                        if depth == 0 {
                            i += 1;
                            break;
                        }
                    }
                    _ => {}
                }
                i += 1;
            }
        }
        let Some(open) = code[i..].find('(').map(|k| i + k) else {
            continue;
        };
        // The parameter list: its top-level commas, brackets of every kind counted.
        let (mut depth, mut params, mut current) = (0i32, vec![], String::new());
        let mut k = open + 1;
        while k < code.len() {
            if code[k..].starts_with("->") {
                current.push_str("->");
                k += 2;
                continue;
            }
            let c = bytes[k] as char;
            match c {
                '(' | '[' | '<' | '{' => depth += 1,
                ')' | ']' | '>' | '}' if depth > 0 => depth -= 1,
                ')' => break,
                _ => {}
            }
            if c == ',' && depth == 0 {
                params.push(std::mem::take(&mut current));
            } else {
                current.push(c);
            }
            k += 1;
        }
        params.push(current);
        let count = params
            .iter()
            .map(|p| p.trim())
            .filter(|p| !p.is_empty())
            .filter(|p| {
                let p = p.trim_start_matches('&').trim_start();
                let p = p.strip_prefix("mut ").unwrap_or(p).trim_start();
                // `&self`, `&'a mut self`, `mut self`, `self: Box<Self>`.
                let p = match p.starts_with('\'') {
                    true => p.split_once(' ').map_or(p, |(_, r)| r.trim_start()),
                    false => p,
                };
                let p = p.strip_prefix("mut ").unwrap_or(p);
                !(p == "self" || p.starts_with("self:"))
            })
            .count();
        found.push((name, count));
    }
    found
}

/// Every public function of the sources under `root` with more than [`MAX_PARAMETERS`],
/// as `path: name (count)`, and how many public functions were read.
fn long_signatures(root: &Path) -> (Vec<String>, usize) {
    let mut files = vec![];
    if let Ok(crates) = std::fs::read_dir(root.join("crates")) {
        for c in crates.flatten() {
            sources(&c.path().join("src"), &mut files);
        }
    }
    sources(&root.join("src"), &mut files);
    files.sort();
    let (mut long, mut seen) = (vec![], 0);
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        for (name, count) in public_functions(&without_tests(&text)) {
            seen += 1;
            if count > MAX_PARAMETERS {
                let shown = file
                    .strip_prefix(root)
                    .unwrap_or(&file)
                    .display()
                    .to_string();
                long.push(format!("{shown}: {name} ({count} parameters)"));
            }
        }
    }
    (long, seen)
}

/// The reader counts what a reader would: self aside, generics, closures' parameter lists,
/// arrows and nested brackets in types, and test modules cut out.
#[test]
fn the_signature_reader_counts_parameters() {
    let code = r#"
pub fn seven(a: f64, b: &[f64], c: impl Fn(f64, f64) -> f64, d: Vec<(u8, u8)>, e: [u8; 3], f: &mut dyn FnMut(&mut S, f64, &[f64]) -> Result<(), E>, g: u8) {}
pub(crate) fn generic<F: Fn(f64) -> f64, T>(x: T, f: F) -> f64 { 0.0 }
#[pyfunction]
#[pyo3(signature = (a, b = 1, c = 2, d = 3, e = 4, f = 5, g = 6))]
pub(super) fn python(a: u8, b: u8, c: u8, d: u8, e: u8, f: u8, g: u8) {}
impl S {
    pub fn method(&'a mut self, a: u8, b: u8) {}
    pub fn by_value(mut self) {}
    fn private(a: u8, b: u8, c: u8, d: u8, e: u8, f: u8, g: u8) {}
}
#[cfg(test)]
mod tests {
    pub fn in_test(a: u8, b: u8, c: u8, d: u8, e: u8, f: u8, g: u8) {}
}
"#;
    let found = public_functions(&without_tests(code));
    assert_eq!(
        found,
        [
            ("seven".to_string(), 7),
            ("generic".to_string(), 2),
            ("method".to_string(), 2),
            ("by_value".to_string(), 0),
        ]
    );
}

/// No public function of the workspace's sources takes more than six parameters.
/// `EYESHELL_SIGNATURES_ROOT=DIR` reads another tree (to see the check fail on a checkout
/// that has such functions).
#[test]
fn no_public_function_takes_more_than_six_parameters() {
    let root = std::env::var_os("EYESHELL_SIGNATURES_ROOT")
        .map_or_else(|| repo().to_path_buf(), PathBuf::from);
    let (long, seen) = long_signatures(&root);
    // The reader found the sources: the workspace has well over a thousand public functions.
    assert!(
        seen > 1000,
        "only {seen} public functions read under {}",
        root.display()
    );
    assert!(
        long.is_empty(),
        "public functions with more than {MAX_PARAMETERS} parameters (bundle them: a problem value, settings, hooks):\n{}",
        long.join("\n")
    );
}
