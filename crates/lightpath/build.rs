//! With the `denoise` feature, puts `$OIDN_DIR/lib` on the run-time search path of the
//! package's binaries and tests, so they find Open Image Denoise where the build found
//! it (the `oidn` crate links it from there) without LD_LIBRARY_PATH.

fn main() {
    println!("cargo:rerun-if-env-changed=OIDN_DIR");
    if std::env::var_os("CARGO_FEATURE_DENOISE").is_none() {
        return;
    }
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if let (Some(dir), true) = (
        std::env::var_os("OIDN_DIR"),
        matches!(os.as_str(), "linux" | "macos"),
    ) {
        let lib = std::path::Path::new(&dir).join("lib");
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", lib.display());
    }
}
