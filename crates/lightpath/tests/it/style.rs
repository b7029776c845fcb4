//! The code's shape: no function of the workspace's sources is over ~120 lines of body,
//! except those allowed below by name, each with its reason (docs/architecture.md: small
//! named steps; the exception is the BVH's traversal loop, docs/performance.md).

use std::path::{Path, PathBuf};

/// Longest body allowed, in lines between the opening and the closing brace.
const MAX_BODY_LINES: usize = 120;

/// (file under the workspace, function name): allowed to be longer.
const ALLOWED: &[(&str, &str)] = &[
    // The closest-hit traversal: one body on purpose, inlined into each lane width's
    // `#[target_feature]` entry point; split, it was slower (its doc comment says why).
    ("crates/lightpath/src/geometry/bvh.rs", "closest"),
];

/// Every function in `text` (rustfmt's layout: a body closes with `}` at the indentation
/// of its `fn` line) whose body is over `max` lines: (name, first line, body lines).
fn long_functions(text: &str, max: usize) -> Vec<(String, usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let Some((indent, name)) = fn_name(line) else {
            continue;
        };
        // The signature ends at the first line ending in `{` (a body) or `;` (none).
        let Some(open) = (i..lines.len()).find(|&j| {
            let l = lines[j].trim_end();
            l.ends_with('{') || l.ends_with(';') || l.ends_with('}')
        }) else {
            continue;
        };
        if !lines[open].trim_end().ends_with('{') {
            continue;
        }
        let close_line = format!("{indent}}}");
        let Some(close) = (open + 1..lines.len()).find(|&j| lines[j] == close_line) else {
            continue;
        };
        let body = close - open - 1;
        if body > max {
            found.push((name.to_string(), i + 1, body));
        }
    }
    found
}

/// The indentation and name of a line that starts a function (`pub(crate) unsafe fn x`).
fn fn_name(line: &str) -> Option<(&str, &str)> {
    let rest = line.trim_start();
    let indent = &line[..line.len() - rest.len()];
    let mut words = rest.split_whitespace();
    loop {
        let w = words.next()?;
        if w == "fn" {
            let name = words.next()?;
            let end = name
                .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                .unwrap_or(name.len());
            return (end > 0).then(|| (indent, &name[..end]));
        }
        let qualifier = w.starts_with("pub")
            || matches!(
                w,
                "const" | "async" | "unsafe" | "extern" | "\"C\"" | "default"
            );
        if !qualifier {
            return None;
        }
    }
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn no_function_is_over_120_lines_but_the_traversal_loop() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = Vec::new();
    for krate in std::fs::read_dir(root.join("crates")).unwrap() {
        let src = krate.unwrap().path().join("src");
        if src.is_dir() {
            rust_files(&src, &mut files);
        }
    }
    assert!(files.len() > 50, "found only {} files", files.len());
    let mut over = Vec::new();
    for file in &files {
        let rel = file
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let text = std::fs::read_to_string(file).unwrap();
        for (name, line, body) in long_functions(&text, MAX_BODY_LINES) {
            if !ALLOWED.contains(&(rel.as_str(), name.as_str())) {
                over.push(format!("{rel}:{line}: fn {name} has {body} lines"));
            }
        }
    }
    assert!(
        over.is_empty(),
        "functions over {MAX_BODY_LINES} lines (split them, or allow one with its reason):\n{}",
        over.join("\n")
    );
}

#[test]
fn the_length_check_counts_body_lines() {
    let body = |n: usize| "    x();\n".repeat(n);
    let text = format!(
        "pub(crate) fn short(\n    a: u32,\n) -> u32 {{\n{}}}\n\nimpl A {{\n    unsafe fn long(&self) {{\n{}    }}\n    fn decl();\n}}\n",
        body(MAX_BODY_LINES),
        format!("    {}", body(MAX_BODY_LINES + 1).replace('\n', "\n    ")).trim_end_matches(' '),
    );
    let found = long_functions(&text, MAX_BODY_LINES);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].0, "long");
    assert_eq!(found[0].2, MAX_BODY_LINES + 1);
}
