//! The `lightpath lpe …` commands as library calls: each returns what to print and
//! whether it succeeded, so the binary only prints and tests call them directly.

use serde_json::json;
use std::fmt::Write;

/// What a command prints on stdout and stderr, and its outcome.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Report {
    pub stdout: String,
    pub stderr: String,
    pub success: bool,
}

impl Report {
    fn out(&mut self, line: impl AsRef<str>) {
        self.stdout.push_str(line.as_ref());
        self.stdout.push('\n');
    }
    fn err(&mut self, line: impl AsRef<str>) {
        self.stderr.push_str(line.as_ref());
        self.stderr.push('\n');
    }
}

/// `lpe check`: every definition valid and compilable together; warnings on stderr.
pub fn check(definitions: &[String]) -> Report {
    let mut r = Report::default();
    let mut compiler = lpe::Compiler::new();
    let mut ok = true;
    for d in definitions {
        let d = crate::aov::resolve_definition(d);
        if let Err(e) = compiler.add(d) {
            ok = false;
            r.stderr.push_str(&e.render(d));
        }
    }
    if !ok {
        return r;
    }
    match compiler.compile() {
        Ok(a) => {
            for w in a.warnings() {
                r.err(format!(
                    "warning: {}: {}",
                    definitions[w.rule.0 as usize], w.message
                ));
            }
            let n = definitions.len();
            r.out(format!(
                "{n} definition{} valid",
                if n == 1 { "" } else { "s" }
            ));
            r.success = true;
        }
        Err(e) => r.err(format!("error[{}]: {}", e.kind.name(), e.message)),
    }
    r
}

/// `lpe match --path`: `match` or `no match` per definition.
pub fn match_path(definitions: &[String], path_text: &str) -> Report {
    let mut r = Report::default();
    let path = match lpe::parse_path(path_text) {
        Ok(p) => p,
        Err(e) => {
            r.stderr.push_str(&e.render(path_text));
            return r;
        }
    };
    r.success = true;
    for d in definitions {
        match lpe::matches(d, &path) {
            Ok(true) => r.out("match"),
            Ok(false) => r.out("no match"),
            Err(e) => {
                r.stderr.push_str(&e.render(d));
                r.success = false;
            }
        }
    }
    r
}

fn stats_line(s: &lpe::Stats) -> String {
    format!(
        "{} NFA states, {} DFA states before minimisation, {} after, {} event classes",
        s.nfa_states, s.dfa_states, s.min_dfa_states, s.classes
    )
}

/// `lpe explain`: each rule in plain English with its automaton's size, then all together.
pub fn explain(definitions: &[String]) -> Report {
    let mut r = Report::default();
    let mut compiler = lpe::Compiler::new();
    let mut ok = true;
    for d in definitions {
        let d = crate::aov::resolve_definition(d);
        match lpe::Rule::parse(d) {
            Ok(rule) => {
                let name = rule
                    .name
                    .clone()
                    .map(|n| format!("{n}: "))
                    .unwrap_or_default();
                r.out(format!("{name}{d}\n  {}", lpe::explain::explain(&rule)));
                if let Ok(alone) = lpe::compile(&[d]) {
                    r.out(format!("  automaton: {}", stats_line(&alone.stats())));
                }
                compiler.add_rule(rule);
            }
            Err(e) => {
                ok = false;
                r.stderr.push_str(&e.render(d));
            }
        }
    }
    if definitions.len() > 1 && ok {
        match compiler.compile() {
            Ok(a) => r.out(format!(
                "all {} rules together: {}",
                definitions.len(),
                stats_line(&a.stats())
            )),
            Err(e) => r.err(format!("error[{}]: {}", e.kind.name(), e.message)),
        }
    }
    r.success = ok;
    r
}

/// `lpe names`: the standard names and their expressions.
pub fn names() -> Report {
    let mut r = Report {
        success: true,
        ..Report::default()
    };
    for (name, expr) in lpe::STANDARD_NAMES {
        let _ = writeln!(r.stdout, "{name:<18} {expr}");
    }
    r
}

/// The conformance interface: the JSON answer to one `{"expr", "path"}` line.
pub fn answer_case(line: &str) -> serde_json::Value {
    let case: serde_json::Value = match serde_json::from_str(line) {
        Ok(v) => v,
        Err(e) => return json!({ "input_error": format!("invalid JSON: {e}") }),
    };
    let Some(expr) = case.get("expr").and_then(|v| v.as_str()) else {
        return json!({ "input_error": "expected a string field \"expr\"" });
    };
    let rule = match lpe::Rule::parse(expr) {
        Ok(r) => r,
        Err(e) => return json!({ "error": e.message, "span": [e.span.start, e.span.end] }),
    };
    let Some(path_text) = case.get("path").and_then(|v| v.as_str()) else {
        // A valid expression without a path: compile it, report a compile error if any.
        return match lpe::compile(&[expr]) {
            Ok(_) => json!({ "valid": true }),
            Err(e) => json!({ "error": e.message, "span": [e.span.start, e.span.end] }),
        };
    };
    let path = match lpe::parse_path(path_text) {
        Ok(p) => p,
        Err(e) => return json!({ "path_error": e.message }),
    };
    let mut compiler = lpe::Compiler::new();
    compiler.add_rule(rule);
    compiler.vocabulary(path.iter().cloned());
    match compiler.compile() {
        Ok(a) => json!({ "match": !a.run(&path).unwrap_or(&[]).is_empty() }),
        Err(e) => json!({ "error": e.message, "span": [e.span.start, e.span.end] }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_reports_validity_and_errors() {
        let ok = check(&["C<RD>[<L.>O]".to_string()]);
        assert!(ok.success);
        assert_eq!(ok.stdout, "1 definition valid\n");
        let bad = check(&["C<RD".to_string()]);
        assert!(!bad.success);
        assert!(bad.stderr.contains('^'), "{}", bad.stderr);
    }

    #[test]
    fn match_path_answers_per_definition() {
        let r = match_path(
            &["C<RD>[<L.>O]".to_string(), "C<RS>L".to_string()],
            "C<RD'floor'><L'key'>",
        );
        assert!(r.success);
        assert_eq!(r.stdout, "match\nno match\n");
        assert!(answer_case("not json")["input_error"].is_string());
    }
}
