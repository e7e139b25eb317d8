//! Rooms of one job, read from the sources (ARCHITECTURE.md): no Rust file over
//! [`MAX_FILE_LINES`] lines, no function outside the tests over [`MAX_FN_LINES`] lines, and
//! no cycle between the top-level modules of a crate. A file or a function that long holds
//! several jobs, and a cycle ties two rooms into one; each check prints every offender.
//!
//! The sources are read with a small lexer of Rust (comments, strings, raw strings and
//! character literals are blanked, so that a brace or a `crate::` inside them counts for
//! nothing) rather than a parser: the checks count lines and braces and read paths, which
//! the lexer gives exactly.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::support::repo;

/// The most lines a Rust file may have.
const MAX_FILE_LINES: usize = 1_100;

/// The most lines a function outside the tests may have, from its `fn` line to its closing
/// brace.
const MAX_FN_LINES: usize = 150;

/// Every Rust file of the workspace, outside target/ and hidden directories, relative to the
/// repository.
fn workspace_rust_files() -> Vec<PathBuf> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        for path in entries {
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if path.is_dir() {
                if name != "target" && !name.starts_with('.') {
                    walk(root, &path, out);
                }
            } else if name.ends_with(".rs") {
                out.push(path.strip_prefix(root).unwrap().to_path_buf());
            }
        }
    }
    let root = repo();
    let mut files = Vec::new();
    walk(root, root, &mut files);
    files
}

/// `text` with every comment, string literal and character literal replaced by spaces
/// (line breaks kept), so that lines, braces and paths of the code read as they are.
fn code_only(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let blank = |out: &mut String, ch: char| out.push(if ch == '\n' { '\n' } else { ' ' });
    let mut i = 0;
    while i < c.len() {
        let at = |k: usize| c.get(k).copied().unwrap_or('\0');
        // A raw string: r"…", r#"…"#, br#"…"# (not an identifier ending in r or br).
        let raw_start = if at(i) == 'r' {
            Some(i + 1)
        } else if at(i) == 'b' && at(i + 1) == 'r' {
            Some(i + 2)
        } else {
            None
        };
        let ident_before = i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_');
        if let (Some(mut j), false) = (raw_start, ident_before) {
            let mut hashes = 0;
            while at(j) == '#' {
                hashes += 1;
                j += 1;
            }
            if at(j) == '"' {
                j += 1;
                loop {
                    if j >= c.len() {
                        break;
                    }
                    if c[j] == '"' && (0..hashes).all(|h| at(j + 1 + h) == '#') {
                        j += 1 + hashes;
                        break;
                    }
                    j += 1;
                }
                for &ch in &c[i..j.min(c.len())] {
                    blank(&mut out, ch);
                }
                i = j;
                continue;
            }
        }
        match at(i) {
            '/' if at(i + 1) == '/' => {
                while i < c.len() && c[i] != '\n' {
                    out.push(' ');
                    i += 1;
                }
            }
            '/' if at(i + 1) == '*' => {
                // Block comments nest in Rust.
                let mut depth = 0;
                while i < c.len() {
                    if at(i) == '/' && at(i + 1) == '*' {
                        depth += 1;
                        out.push_str("  ");
                        i += 2;
                    } else if at(i) == '*' && at(i + 1) == '/' {
                        depth -= 1;
                        out.push_str("  ");
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        blank(&mut out, c[i]);
                        i += 1;
                    }
                }
            }
            '"' => {
                blank(&mut out, '"');
                i += 1;
                while i < c.len() && c[i] != '"' {
                    if c[i] == '\\' && i + 1 < c.len() {
                        blank(&mut out, c[i]);
                        i += 1;
                    }
                    blank(&mut out, c[i]);
                    i += 1;
                }
                if i < c.len() {
                    blank(&mut out, '"');
                    i += 1;
                }
            }
            '\'' => {
                // A character literal ('x', '\n', '\u{7b}', '{'), else a lifetime ('a).
                let end = if at(i + 1) == '\\' {
                    (i + 2..c.len()).find(|&k| c[k] == '\'')
                } else if at(i + 2) == '\'' {
                    Some(i + 2)
                } else {
                    None
                };
                match end {
                    Some(e) => {
                        for &ch in &c[i..=e] {
                            blank(&mut out, ch);
                        }
                        i = e + 1;
                    }
                    None => {
                        out.push('\'');
                        i += 1;
                    }
                }
            }
            ch => {
                out.push(ch);
                i += 1;
            }
        }
    }
    out
}

/// The index of the brace closing the one at `open` in `code` (comments and literals
/// blanked), or the end.
fn closing_brace(code: &[u8], open: usize) -> usize {
    let mut depth = 0usize;
    for (k, &b) in code.iter().enumerate().skip(open) {
        match b {
            b'{' => depth += 1,
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return k;
                }
            }
            _ => {}
        }
    }
    code.len()
}

fn is_ident(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

/// The byte ranges of `code` that are test code: each item under `#[cfg(test)]` (a test
/// module's braces, a test helper's body).
fn test_ranges(code: &str) -> Vec<(usize, usize)> {
    let bytes = code.as_bytes();
    let mut ranges = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find("#[cfg(test)]") {
        let at = from + k;
        // The item ends at its first `;` (`mod tests;`) or its first block's closing brace.
        let rest = &bytes[at..];
        let semi = rest.iter().position(|&b| b == b';');
        let open = rest.iter().position(|&b| b == b'{');
        let end = match (semi, open) {
            (Some(s), Some(o)) if s < o => at + s,
            (_, Some(o)) => closing_brace(bytes, at + o),
            (Some(s), None) => at + s,
            (None, None) => bytes.len(),
        };
        ranges.push((at, end));
        from = end.max(at + 1);
    }
    ranges
}

/// A source file of tests: under a tests/ directory, or a test module of its own
/// (`tests.rs`, or a file under a `tests` module directory).
fn is_test_file(path: &Path) -> bool {
    path.components()
        .any(|c| c.as_os_str() == "tests" || c.as_os_str() == "tests.rs")
}

/// Every function of `code` with a body: (its name, the line of `fn`, its lines from the
/// `fn` line to its closing brace), outside `skip`.
fn functions(code: &str, skip: &[(usize, usize)]) -> Vec<(String, usize, usize)> {
    let bytes = code.as_bytes();
    let line_of = |at: usize| bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find("fn ") {
        let at = from + k;
        from = at + 3;
        if at > 0 && is_ident(bytes[at - 1]) {
            continue;
        }
        if skip.iter().any(|&(s, e)| at >= s && at <= e) {
            continue;
        }
        let name: String = code[at + 3..]
            .trim_start()
            .chars()
            .take_while(|&ch| ch.is_alphanumeric() || ch == '_')
            .collect();
        if name.is_empty() {
            continue; // a function pointer type: fn(f64) -> f64
        }
        // The body is the first `{` outside parentheses and brackets, unless a `;` ends the
        // declaration first (a trait's method without a default).
        let (mut parens, mut open) = (0i32, None);
        for (j, &b) in bytes.iter().enumerate().skip(at) {
            match b {
                b'(' | b'[' => parens += 1,
                b')' | b']' => parens -= 1,
                b';' if parens == 0 => break,
                b'{' if parens == 0 => {
                    open = Some(j);
                    break;
                }
                _ => {}
            }
        }
        let Some(open) = open else { continue };
        let close = closing_brace(bytes, open);
        let (first, last) = (line_of(at), line_of(close.min(bytes.len() - 1)));
        found.push((name, first, last - first + 1));
    }
    found
}

/// The files over [`MAX_FILE_LINES`] lines, as `path: N lines`.
fn long_files() -> Vec<String> {
    let root = repo();
    workspace_rust_files()
        .iter()
        .filter_map(|f| {
            let n = std::fs::read_to_string(root.join(f))
                .unwrap()
                .lines()
                .count();
            (n > MAX_FILE_LINES).then(|| format!("{}: {n} lines", f.display()))
        })
        .collect()
}

/// The functions over [`MAX_FN_LINES`] lines outside the tests, as `path:line fn name: N lines`.
fn long_functions() -> Vec<String> {
    let root = repo();
    let mut long = Vec::new();
    for f in workspace_rust_files() {
        if is_test_file(&f) {
            continue;
        }
        let code = code_only(&std::fs::read_to_string(root.join(&f)).unwrap());
        for (name, line, n) in functions(&code, &test_ranges(&code)) {
            if n > MAX_FN_LINES {
                long.push(format!("{}:{line} fn {name}: {n} lines", f.display()));
            }
        }
    }
    long
}

/// The source directories of the workspace's crates: src/, vendor-check/src and crates/*/src.
fn crate_sources() -> Vec<PathBuf> {
    let root = repo();
    let mut dirs = vec![root.join("src"), root.join("vendor-check/src")];
    let mut crates: Vec<PathBuf> = std::fs::read_dir(root.join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path().join("src"))
        .filter(|p| p.is_dir())
        .collect();
    crates.sort();
    dirs.extend(crates);
    dirs
}

/// The top-level modules each top-level module of the crate in `src` names by a
/// `crate::` path (in a `use` or in code): module → (module it names → the first place it
/// names it, `file:line`).
fn module_graph(src: &Path) -> BTreeMap<String, BTreeMap<String, String>> {
    let root = repo();
    let mut graph: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
    let mut files = Vec::new();
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    walk(src, &mut files);
    files.sort();
    for f in files {
        let rel = f.strip_prefix(src).unwrap();
        let first = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let module = first.trim_end_matches(".rs").to_string();
        if module == "lib" || module == "main" {
            continue;
        }
        let code = code_only(&std::fs::read_to_string(&f).unwrap());
        let skip = test_ranges(&code);
        let bytes = code.as_bytes();
        let mut from = 0;
        while let Some(k) = code[from..].find("crate::") {
            let at = from + k;
            from = at + 7;
            if at > 0 && (is_ident(bytes[at - 1]) || bytes[at - 1] == b'$') {
                continue; // eyeshell_crate::, $crate::
            }
            if skip.iter().any(|&(s, e)| at >= s && at <= e) || is_test_file(rel) {
                continue;
            }
            let after = &code[at + 7..];
            // `crate::a::…`, or a group `crate::{a::…, b}`: the first segment of each.
            let mut names = Vec::new();
            if let Some(group) = after.strip_prefix('{') {
                let mut depth = 0;
                let mut segment_start = true;
                for (j, ch) in group.char_indices() {
                    match ch {
                        '{' => depth += 1,
                        '}' if depth == 0 => break,
                        '}' => depth -= 1,
                        ',' if depth == 0 => segment_start = true,
                        c if segment_start && (c.is_alphanumeric() || c == '_') => {
                            let name: String = group[j..]
                                .chars()
                                .take_while(|&c| c.is_alphanumeric() || c == '_')
                                .collect();
                            names.push(name);
                            segment_start = false;
                        }
                        _ => {}
                    }
                }
            } else {
                names.push(
                    after
                        .chars()
                        .take_while(|&c| c.is_alphanumeric() || c == '_')
                        .collect(),
                );
            }
            let line = bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
            let place = format!("{}:{line}", f.strip_prefix(root).unwrap().display());
            for name in names {
                if !name.is_empty() && name != module && name != "self" {
                    graph
                        .entry(module.clone())
                        .or_default()
                        .entry(name)
                        .or_insert_with(|| place.clone());
                }
            }
        }
    }
    graph
}

/// The cycles of `graph`: its strongly connected components of more than one module
/// (Tarjan's algorithm), each sorted.
fn cycles(graph: &BTreeMap<String, BTreeMap<String, String>>) -> Vec<Vec<String>> {
    struct Tarjan<'g> {
        graph: &'g BTreeMap<String, BTreeMap<String, String>>,
        index: BTreeMap<&'g str, usize>,
        low: BTreeMap<&'g str, usize>,
        stack: Vec<&'g str>,
        on_stack: BTreeSet<&'g str>,
        found: Vec<Vec<String>>,
    }
    impl<'g> Tarjan<'g> {
        fn visit(&mut self, v: &'g str) {
            let n = self.index.len();
            self.index.insert(v, n);
            self.low.insert(v, n);
            self.stack.push(v);
            self.on_stack.insert(v);
            for w in self.graph.get(v).into_iter().flat_map(|e| e.keys()) {
                let w = w.as_str();
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let lw = self.low[w];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(lw);
                } else if self.on_stack.contains(w) {
                    let iw = self.index[w];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(iw);
                }
            }
            if self.low[v] == self.index[v] {
                let mut component = Vec::new();
                loop {
                    let w = self.stack.pop().unwrap();
                    self.on_stack.remove(w);
                    component.push(w.to_string());
                    if w == v {
                        break;
                    }
                }
                if component.len() > 1 {
                    component.sort();
                    self.found.push(component);
                }
            }
        }
    }
    let mut t = Tarjan {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        found: Vec::new(),
    };
    for v in graph.keys() {
        if !t.index.contains_key(v.as_str()) {
            t.visit(v);
        }
    }
    t.found
}

/// Each cycle between the top-level modules of a crate, with the edges inside it and where
/// each is taken.
fn module_cycles() -> Vec<String> {
    let mut out = Vec::new();
    for src in crate_sources() {
        let graph = module_graph(&src);
        for component in cycles(&graph) {
            let edges: Vec<String> = component
                .iter()
                .flat_map(|a| {
                    graph[a]
                        .iter()
                        .filter(|(b, _)| component.contains(b))
                        .map(move |(b, place)| format!("{a} → {b} ({place})"))
                })
                .collect();
            out.push(format!(
                "{}: {}: {}",
                src.strip_prefix(repo()).unwrap().display(),
                component.join(" ↔ "),
                edges.join("; ")
            ));
        }
    }
    out
}

#[test]
fn no_rust_file_is_over_1100_lines() {
    let files = workspace_rust_files();
    // Not vacuous: the walk found the workspace's sources, the tests' among them.
    assert!(files.len() > 200, "{} Rust files", files.len());
    assert!(files.iter().any(|f| f.ends_with("tests/cli/rooms.rs")));
    let long = long_files();
    assert!(
        long.is_empty(),
        "{} files over {MAX_FILE_LINES} lines (split them by job):\n{}",
        long.len(),
        long.join("\n")
    );
}

#[test]
fn no_function_outside_the_tests_is_over_150_lines() {
    let long = long_functions();
    assert!(
        long.is_empty(),
        "{} functions over {MAX_FN_LINES} lines outside the tests (split them by job):\n{}",
        long.len(),
        long.join("\n")
    );
}

#[test]
fn no_module_cycle_inside_a_crate() {
    let found = module_cycles();
    assert!(
        found.is_empty(),
        "{} module cycles:\n{}",
        found.len(),
        found.join("\n")
    );
}

/// The lexer and the counts on known text, so that the checks above cannot pass by
/// reading nothing: braces in strings, characters and comments count for nothing, a
/// lifetime is not a character, a test module is skipped, a cycle is found.
#[test]
fn the_checks_count_what_they_claim() {
    let text = "fn a<'x>(s: &'x str) -> char {\n    let b = '{';\n    let s = \"}}\";\n    \
                let r = r#\"}\"#; // }\n    /* } /* } */ } */\n    b\n}\n\
                trait T { fn m(&self); fn n(&self) {} }\n\
                type F = fn(f64) -> f64;\n\
                #[cfg(test)]\nmod tests {\n    fn hidden() {\n    }\n}\n\
                fn last() { let x = [0u8; 4]; }\n";
    let code = code_only(text);
    assert_eq!(code.lines().count(), text.lines().count());
    let found = functions(&code, &test_ranges(&code));
    let names: Vec<(&str, usize, usize)> =
        found.iter().map(|(n, l, k)| (n.as_str(), *l, *k)).collect();
    assert_eq!(names, [("a", 1, 7), ("n", 8, 1), ("last", 15, 1)], "{code}");
    let mut graph: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
    for (a, b) in [
        ("scene", "rundir"),
        ("rundir", "text"),
        ("text", "scene"),
        ("x", "text"),
    ] {
        graph
            .entry(a.into())
            .or_default()
            .insert(b.into(), String::new());
    }
    assert_eq!(cycles(&graph), [["rundir", "scene", "text"]]);
    // The graph of a real crate holds its edges: the files crate's scene reads its keys'
    // table from its own module and the numerics from the core crate's re-exports.
    let files = module_graph(&repo().join("crates/eyeshell/src"));
    assert!(
        files.get("scene").is_some_and(|e| e.contains_key("model")),
        "{files:?}"
    );
}
