//! Every case of the shared conformance vectors (a copy lives in `tests/vectors/`), run
//! through the DFA and, for matches, checked against the NFA simulator too.

use serde_json::Value;

fn vectors() -> Vec<Value> {
    let text = include_str!("vectors/conformance.jsonl");
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str(l).expect("valid JSON line"))
        .collect()
}

#[test]
fn every_conformance_vector_passes() {
    let mut failures = Vec::new();
    let cases = vectors();
    for case in &cases {
        let expr = case["expr"].as_str().unwrap();
        if case.get("error").is_some() {
            let want: Vec<usize> = case["span"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_u64().unwrap() as usize)
                .collect();
            match lpe::compile(&[expr]) {
                Ok(_) => failures.push(format!(
                    "{expr:?}: expected an error at {want:?}, compiled fine"
                )),
                Err(e) => {
                    if [e.span.start, e.span.end] != want[..] {
                        failures.push(format!(
                            "{expr:?}: span {:?}, expected {want:?} ({})",
                            e.span, e.message
                        ));
                    }
                    if let Some(kind) = case.get("kind").and_then(Value::as_str) {
                        if e.kind.name() != kind {
                            failures.push(format!(
                                "{expr:?}: kind {}, expected {kind} ({})",
                                e.kind.name(),
                                e.message
                            ));
                        }
                    }
                }
            }
        } else {
            let path =
                lpe::parse_path(case["path"].as_str().unwrap()).expect("vector paths are valid");
            let want = case["match"].as_bool().unwrap();
            let mut c = lpe::Compiler::new();
            if let Err(e) = c.add(expr) {
                failures.push(format!(
                    "{expr:?}: unexpected error {} at {:?}",
                    e.message, e.span
                ));
                continue;
            }
            c.vocabulary(path.iter().cloned());
            let a = c.compile().expect("compiles");
            let dfa = !a
                .run(&path)
                .expect("path events are in the vocabulary")
                .is_empty();
            let nfa = !a.simulate(&path).is_empty();
            if dfa != want || nfa != want {
                failures.push(format!(
                    "{expr:?} on {}: dfa {dfa}, nfa {nfa}, expected {want}",
                    case["path"]
                ));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} vectors failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}
