//! A scene file, loaded and built (no render): any input may fail, none may panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let source = lightpath::Source {
        name: "fuzz.toml".into(),
        text: text.into(),
        dir: std::env::temp_dir(),
    };
    if let Ok(mut desc) = source.parse() {
        desc.render.resolution = [4, 4];
        let mut specs = vec![lightpath::aov::AovSpec::new("beauty", "lpe:beauty")];
        specs.extend(
            desc.aovs
                .iter()
                .map(|(n, d)| lightpath::aov::AovSpec::new(n.clone(), d.definition.clone())),
        );
        let _ = lightpath::Scene::build(&desc, &specs);
    }
});
