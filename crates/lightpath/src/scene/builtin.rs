//! Scenes shipped inside the binary.

/// (name, TOML source) of every built-in scene; the first is the default.
pub const BUILTIN: [(&str, &str); 2] = [
    ("cornell", include_str!("../../../../scenes/cornell.toml")),
    (
        "cornell-classic",
        include_str!("../../../../scenes/cornell-classic.toml"),
    ),
];

pub fn get(name: &str) -> Option<&'static str> {
    BUILTIN.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}
