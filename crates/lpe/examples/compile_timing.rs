//! Prints how long each stage of compiling a production AOV set takes.
use std::time::Instant;
fn main() {
    let mut rules: Vec<String> = lpe::STANDARD_NAMES
        .iter()
        .map(|(n, _)| format!("lpe:{n}"))
        .collect();
    rules.extend((0..16).map(|g| format!("C[DS]*[<L.'group{g}'><O'group{g}'>]")));
    let t = Instant::now();
    let mut c = lpe::Compiler::new();
    for r in &rules {
        c.add(r).unwrap();
    }
    let parsed = t.elapsed();
    let a = c.compile().unwrap();
    println!(
        "parse {:?}, compile {:?}, stats {:?}",
        parsed,
        t.elapsed() - parsed,
        a.stats()
    );
}
