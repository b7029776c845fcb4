//! Any input must give a diagnostic or an automaton: never a panic, never a hang.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        // Definitions separated by newlines compile together, as AOV sets do.
        let defs: Vec<&str> = text.split('\n').take(8).collect();
        match lpe::compile(&defs) {
            Ok(a) => {
                let _ = a.warnings();
            }
            Err(e) => {
                assert!(e.span.start <= e.span.end);
                let _ = e.render(defs.last().copied().unwrap_or(""));
            }
        }
        let _ = lpe::parse_path(text);
    }
});
