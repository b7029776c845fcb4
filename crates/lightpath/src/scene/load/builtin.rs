//! Scenes shipped inside the binary (TOML sources, loaded like files).

/// (name, TOML source) of every built-in scene; the first is the default.
pub const BUILTIN: [(&str, &str); 3] = [
    (
        "cornell",
        include_str!("../../../../../scenes/cornell.toml"),
    ),
    (
        "cornell-classic",
        include_str!("../../../../../scenes/cornell-classic.toml"),
    ),
    (
        "materials",
        include_str!("../../../../../scenes/materials.toml"),
    ),
];

pub fn get(name: &str) -> Option<&'static str> {
    BUILTIN.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}

/// The source of a built-in scene, named `builtin:<name>`; read from the binary, it is
/// an input of the render's identity like a scene file.
pub fn source(name: &str) -> Option<super::Source> {
    get(name).map(|text| {
        let name = format!("builtin:{name}");
        crate::identity::note_read(std::path::Path::new(&name), text.as_bytes());
        super::Source {
            name,
            text: text.to_string(),
            dir: std::path::PathBuf::new(),
        }
    })
}
