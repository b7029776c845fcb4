//! An EXR through the reader `aovs`, `comp` and `merge` use: any input may fail, none may
//! panic or allocate beyond the limits.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("lightpath-fuzz-{}.exr", std::process::id()));
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(exr) = lightpath::output::read_exr(&path) {
        let _ = lightpath::post::partitions::check_partitions(&exr);
    }
});
