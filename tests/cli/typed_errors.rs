//! The middle floors speak in types: no public function, type or field of a library crate
//! (core, optics, linalg, plot, sundials, eyeshell) has a `Result<_, String>`, and the
//! numerics name no scene key (a key is the scene layer's word for a parameter; core names
//! parameters by identifiers). Both read the sources as text, outside test modules and
//! comments: a test may name the key it checks, and a comment may say which key a value
//! comes from, without the shipped code holding it.

use std::path::{Path, PathBuf};

use crate::support::repo;

/// The library crates whose public API is checked.
const LIBRARY_CRATES: [&str; 6] = ["core", "optics", "linalg", "plot", "sundials", "eyeshell"];

/// Public signatures that still return a string error, each with why it is not typed yet.
/// The list must be exactly what the scan finds: fixing one means deleting its line.
const NOT_YET_TYPED: [(&str, &str); 0] = [];

/// Every .rs file under `dir`.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut out = vec![];
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// The lines of `src` that ship: up to the first `#[cfg(test)]` (test modules come last in
/// this code base), without comment lines; each with its line number.
fn shipped_lines(src: &str) -> Vec<(usize, &str)> {
    src.lines()
        .enumerate()
        .take_while(|(_, l)| l.trim() != "#[cfg(test)]")
        .filter(|(_, l)| !l.trim_start().starts_with("//"))
        .map(|(i, l)| (i + 1, l))
        .collect()
}

/// Whether `sig` holds a `Result<…, String>`: the last type argument of a `Result<` at
/// nesting depth zero inside it is `String`.
fn has_string_error(sig: &str) -> bool {
    let mut rest = sig;
    while let Some(at) = rest.find("Result<") {
        let inner = &rest[at + "Result<".len()..];
        let (mut depth, mut last_comma, mut end) = (0i32, None, None);
        for (i, c) in inner.char_indices() {
            match c {
                '<' | '(' | '[' => depth += 1,
                '>' | ')' | ']' if depth == 0 => {
                    end = Some(i);
                    break;
                }
                '>' | ')' | ']' => depth -= 1,
                ',' if depth == 0 => last_comma = Some(i),
                _ => {}
            }
        }
        if let (Some(comma), Some(end)) = (last_comma, end) {
            if inner[comma + 1..end].trim() == "String" {
                return true;
            }
        }
        rest = inner;
    }
    false
}

/// The public signatures of `src` with a string error: `pub fn` and `pub type` items
/// (joined over lines up to their body or `;`), `pub` fields, and the methods of a
/// `pub trait`. Returns (line, the item's first words).
fn string_errors_in(src: &str) -> Vec<(usize, String)> {
    let lines = shipped_lines(src);
    let mut found = vec![];
    let mut trait_depth: Option<i32> = None;
    let mut depth = 0i32;
    for (k, &(n, line)) in lines.iter().enumerate() {
        let s = line.trim();
        if s.starts_with("pub trait ") {
            trait_depth = Some(depth);
        }
        let in_pub_trait = trait_depth.is_some_and(|d| depth == d + 1);
        let item = s.starts_with("pub fn ")
            || s.starts_with("pub const fn ")
            || s.starts_with("pub unsafe fn ")
            || s.starts_with("pub type ")
            || (in_pub_trait && s.starts_with("fn "));
        let field = !item
            && s.starts_with("pub ")
            && s[4..].split_once(':').is_some_and(|(name, _)| {
                !name.is_empty() && name.chars().all(|c| c.is_alphanumeric() || c == '_')
            });
        let sig = if item {
            let mut sig = String::new();
            for &(_, l) in lines[k..].iter().take(20) {
                sig.push_str(l.trim());
                sig.push(' ');
                if l.trim_end().ends_with('{') || l.trim_end().ends_with(';') {
                    break;
                }
            }
            Some(sig)
        } else if field {
            Some(s.to_string())
        } else {
            None
        };
        if let Some(sig) = sig {
            if has_string_error(&sig) {
                let head: String = s.split('(').next().unwrap_or(s).chars().take(60).collect();
                found.push((n, head));
            }
        }
        depth += line.matches('{').count() as i32 - line.matches('}').count() as i32;
        if trait_depth.is_some_and(|d| depth <= d) {
            trait_depth = None;
        }
    }
    found
}

#[test]
fn the_scan_finds_string_errors_in_every_form_of_public_signature() {
    let src = r#"
pub fn one(x: f64) -> Result<f64, String> {
pub fn multi(
    x: f64,
) -> Result<Vec<(usize, f64)>, String> {
pub type Callback<'a> = dyn FnMut(f64) -> Result<(), String> + 'a;
pub struct S {
    pub field: Option<Result<f64, String>>,
}
pub trait T {
    fn method(&self) -> Result<(), String>;
}
pub fn typed() -> Result<String, std::io::Error> {
fn private() -> Result<(), String> {
pub(crate) fn in_crate() -> Result<(), String> {
// pub fn commented() -> Result<(), String> {
#[cfg(test)]
pub fn in_tests() -> Result<(), String> {
"#;
    let found: Vec<String> = string_errors_in(src).into_iter().map(|(_, h)| h).collect();
    assert_eq!(
        found,
        [
            "pub fn one",
            "pub fn multi",
            "pub type Callback<'a> = dyn FnMut",
            "pub field: Option<Result<f64, String>>,",
            "fn method",
        ]
    );
}

#[test]
fn no_public_signature_of_a_library_crate_has_a_string_error() {
    let mut found: Vec<(String, String)> = vec![];
    let mut files = 0;
    for krate in LIBRARY_CRATES {
        for path in sources(&repo().join("crates").join(krate).join("src")) {
            files += 1;
            let src = std::fs::read_to_string(&path).unwrap();
            let rel = path.strip_prefix(repo()).unwrap().display().to_string();
            for (n, head) in string_errors_in(&src) {
                found.push((rel.clone(), format!("{n}: {head}")));
            }
        }
    }
    assert!(files > 100, "only {files} source files read");
    let unexpected: Vec<&(String, String)> = found
        .iter()
        .filter(|(file, head)| {
            !NOT_YET_TYPED
                .iter()
                .any(|(f, h)| f == file && head.split_once(": ").is_some_and(|(_, x)| x == *h))
        })
        .collect();
    assert!(
        unexpected.is_empty(),
        "public signatures with a string error (give them an error type): {unexpected:#?}"
    );
    for (f, h) in NOT_YET_TYPED {
        assert!(
            found
                .iter()
                .any(|(file, head)| file == f && head.ends_with(&format!(": {h}"))),
            "{f}: {h} is typed now: delete it from NOT_YET_TYPED"
        );
    }
}

/// Every scene key of the key table (crates/eyeshell/src/scene/keys.rs): the `key: "…"`
/// of each entry.
fn scene_keys() -> Vec<String> {
    let table = std::fs::read_to_string(repo().join("crates/eyeshell/src/scene/keys.rs")).unwrap();
    let mut keys: Vec<String> = table
        .split("key: \"")
        .skip(1)
        .filter_map(|rest| rest.split_once('"').map(|(k, _)| k.to_string()))
        .filter(|k| k.contains('.'))
        .collect();
    keys.sort();
    keys.dedup();
    keys
}

/// The string literals of one line of code (escapes kept as written), up to a comment.
fn literals(line: &str) -> Vec<&str> {
    let mut out = vec![];
    let (mut start, mut escaped) = (None, false);
    let bytes = line.as_bytes();
    for (i, &c) in bytes.iter().enumerate() {
        match (start, c) {
            (None, b'/') if bytes.get(i + 1) == Some(&b'/') => break,
            (None, b'"') => start = Some(i + 1),
            (Some(_), b'\\') if !escaped => {
                escaped = true;
                continue;
            }
            (Some(s), b'"') if !escaped => {
                out.push(&line[s..i]);
                start = None;
            }
            _ => {}
        }
        escaped = false;
    }
    out
}

/// Whether `key` occurs in `text` as a whole key (not inside a longer one).
fn names_key(text: &str, key: &str) -> bool {
    let word = |c: char| c.is_alphanumeric() || c == '_' || c == '.';
    text.match_indices(key).any(|(at, _)| {
        let before = text[..at].chars().next_back();
        let after = text[at + key.len()..].chars().next();
        !before.is_some_and(word) && !after.is_some_and(|c| c.is_alphanumeric() || c == '_')
    })
}

/// The scene keys `src`'s shipped code names in string literals, of `keys`: (line, key).
fn key_literals_in(src: &str, keys: &[String]) -> Vec<(usize, String)> {
    let mut found = vec![];
    for (n, line) in shipped_lines(src) {
        for lit in literals(line) {
            for key in keys.iter().filter(|k| names_key(lit, k)) {
                found.push((n, key.clone()));
            }
        }
    }
    found
}

/// Whether a literal gives command-line advice: a long option (`--set`, `--force`) or an
/// `eyeshell` command line. Which advice to give is the command line's, not the numerics'.
fn is_command_line_advice(lit: &str) -> bool {
    let option = lit.match_indices("--").any(|(at, _)| {
        lit[at + 2..]
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_lowercase())
    });
    option || lit.contains("eyeshell ")
}

/// What core's shipped code says in the scene's or the command line's words: (file:line,
/// the key or the advice).
fn scene_words_in_core() -> Vec<(String, String)> {
    let keys = scene_keys();
    assert!(
        keys.len() > 60,
        "{} keys read from the key table",
        keys.len()
    );
    let mut found = vec![];
    let mut files = 0;
    for path in sources(&repo().join("crates/core/src")) {
        files += 1;
        let src = std::fs::read_to_string(&path).unwrap();
        let rel = path.strip_prefix(repo()).unwrap().display().to_string();
        for (n, key) in key_literals_in(&src, &keys) {
            found.push((format!("{rel}:{n}"), key));
        }
        for (n, line) in shipped_lines(&src) {
            for lit in literals(line)
                .into_iter()
                .filter(|l| is_command_line_advice(l))
            {
                found.push((format!("{rel}:{n}"), lit.to_string()));
            }
        }
    }
    assert!(files > 40, "only {files} files of crates/core/src read");
    found
}

#[test]
fn the_key_scan_reads_keys_in_literals_not_in_names() {
    let line =
        r#"let x = format!("solver.tol = {} and {}", a, "optics.pupil_position"); // "material.C""#;
    assert_eq!(
        literals(line),
        ["solver.tol = {} and {}", "optics.pupil_position"]
    );
    assert!(names_key("solver.tol = {}", "solver.tol"));
    assert!(!names_key("optics.pupil_position", "optics.pupil"));
    assert!(!names_key("xsolver.tol", "solver.tol"));
    assert!(names_key("optics.surfaces[{i}].radius", "optics.surfaces"));
    // A literal coming back is found, on its line; a name, a comment or a test is not.
    let keys: Vec<String> = ["solver.tol", "growth.eta0", "optics.surfaces"]
        .map(String::from)
        .to_vec();
    let src = r#"use crate::names::Quantity;
/// solver.tol in a doc comment.
fn f(tol: f64) -> String {
    let solver = Quantity::Tolerance; // "growth.eta0"
    format!("{} = {tol} (solver.tol)", solver)
}
const WHERE: &str = "optics.surfaces[{i}]";
#[cfg(test)]
mod tests { const K: &str = "growth.eta0"; }
"#;
    assert_eq!(
        key_literals_in(src, &keys),
        [
            (5, "solver.tol".to_string()),
            (7, "optics.surfaces".to_string())
        ]
    );
    assert!(is_command_line_advice("give it with --set growth.eta0=1"));
    assert!(is_command_line_advice("run eyeshell sweep again"));
    assert!(!is_command_line_advice("x -- y, t = --1"));
}

/// Core names parameters by identifiers (`eyeshell_core::names::Quantity`, `SensParam`) and
/// the scene layer maps each to its key (crates/eyeshell/src/scene/names.rs): no string
/// literal of core's shipped code names a scene key or gives the command line's advice.
#[test]
fn core_names_no_scene_key() {
    let found = scene_words_in_core();
    println!("{} scene-key literals in crates/core/src", found.len());
    assert!(
        found.is_empty(),
        "{} scene-key or command-line literals in crates/core/src: name the parameter by an identifier (a Quantity) the scene layer maps to its key; first: {:?}",
        found.len(),
        &found[..found.len().min(10)]
    );
}
