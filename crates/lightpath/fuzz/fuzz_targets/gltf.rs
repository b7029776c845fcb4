//! A glTF file (binary or JSON: the loader reads both) through the loader and the scene
//! build: any input may fail, none may panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("lightpath-fuzz-{}.glb", std::process::id()));
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(desc) = lightpath::load_scene(&path.display().to_string()) {
        let specs = vec![lightpath::aov::AovSpec::new("beauty", "lpe:beauty")];
        let _ = lightpath::Scene::build(&desc, &specs);
    }
});
