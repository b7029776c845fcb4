//! An OBJ file through the loader and the mesh build: any input may fail, none may panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("lightpath-fuzz-{}.obj", std::process::id()));
    if std::fs::write(&path, data).is_err() {
        return;
    }
    let scene = format!(
        "[[objects]]\nshape = \"obj\"\nfile = {:?}\n",
        path.display().to_string()
    );
    let source = lightpath::Source {
        name: "fuzz.toml".into(),
        text: scene,
        dir: std::env::temp_dir(),
    };
    if let Ok(desc) = source.parse() {
        let specs = vec![lightpath::aov::AovSpec::new("beauty", "lpe:beauty")];
        let _ = lightpath::Scene::build(&desc, &specs);
    }
});
