//! The prefixes of docs/lpe.md#prefixes and the standard names of §7.

/// A prefix changes how the renderer routes contributions to the AOV carrying it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Prefix {
    Unoccluded,
    Shadows,
    Holdouts,
    NoThruput,
    Overwrite,
    NoClamp,
    NoInfiniteCheck,
}

impl Prefix {
    pub const ALL: [Prefix; 7] = [
        Prefix::Unoccluded,
        Prefix::Shadows,
        Prefix::Holdouts,
        Prefix::NoThruput,
        Prefix::Overwrite,
        Prefix::NoClamp,
        Prefix::NoInfiniteCheck,
    ];

    pub fn word(self) -> &'static str {
        match self {
            Prefix::Unoccluded => "unoccluded",
            Prefix::Shadows => "shadows",
            Prefix::Holdouts => "holdouts",
            Prefix::NoThruput => "nothruput",
            Prefix::Overwrite => "overwrite",
            Prefix::NoClamp => "noclamp",
            Prefix::NoInfiniteCheck => "noinfinitecheck",
        }
    }

    pub fn from_word(word: &str) -> Option<Prefix> {
        Prefix::ALL.into_iter().find(|p| p.word() == word)
    }

    pub fn describe(self) -> &'static str {
        match self {
            Prefix::Unoccluded => "light counts as if nothing blocked it",
            Prefix::Shadows => "collects the light that occluders removed",
            Prefix::Holdouts => "only paths that touch a holdout object",
            Prefix::NoThruput => "not multiplied by the path throughput",
            Prefix::Overwrite => "the last matching value of a sample replaces the others",
            Prefix::NoClamp => "exempt from sample clamping",
            Prefix::NoInfiniteCheck => "NaN and infinite samples are kept",
        }
    }
}

/// A set of prefixes, one bit each.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Flags(u8);

impl Flags {
    pub fn contains(self, p: Prefix) -> bool {
        self.0 & (1 << p as u8) != 0
    }
    pub fn insert(&mut self, p: Prefix) {
        self.0 |= 1 << p as u8;
    }
    pub fn iter(self) -> impl Iterator<Item = Prefix> {
        Prefix::ALL.into_iter().filter(move |p| self.contains(*p))
    }
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }
}

impl FromIterator<Prefix> for Flags {
    fn from_iter<I: IntoIterator<Item = Prefix>>(iter: I) -> Flags {
        let mut f = Flags::default();
        for p in iter {
            f.insert(p);
        }
        f
    }
}

/// The standard names of docs/lpe.md#standard-aovs, with their definitions (prefixes included).
pub const STANDARD_NAMES: [(&str, &str); 13] = [
    ("beauty", "C[DSV]*[<L.>O]"),
    ("emission", "CO"),
    ("diffuse", "C<.D>[DSV]*[<L.>O]"),
    ("specular", "C<.S>[DSV]*[<L.>O]"),
    ("directDiffuse", "C<RD>[<L.>O]"),
    ("indirectDiffuse", "C<RD>[DSV]+[<L.>O]"),
    ("directSpecular", "C<RS>[<L.>O]"),
    ("indirectSpecular", "C<RS>[DSV]+[<L.>O]"),
    ("subsurface", "C<TD>[DSV]*[<L.>O]"),
    ("transmissive", "C<TS>[DSV]*[<L.>O]"),
    ("volumeDirect", "CV[<L.>O]"),
    ("volumeIndirect", "CV[DSV]+[<L.>O]"),
    (
        "albedo",
        "nothruput;noinfinitecheck;noclamp;unoccluded;overwrite;C<.S'passthru'>*((U2L)|O)",
    ),
];

/// The names whose AOVs partition `beauty` (their sum equals it).
pub const BEAUTY_PARTITION: [&str; 9] = [
    "emission",
    "directDiffuse",
    "indirectDiffuse",
    "directSpecular",
    "indirectSpecular",
    "subsurface",
    "transmissive",
    "volumeDirect",
    "volumeIndirect",
];

/// Standard AOVs that are the sum of others, by their definitions: the first event after
/// the camera is diffuse (or specular) either by reflection or by transmission, and a
/// reflection is followed by no more scattering (direct) or by some (indirect); so
/// `diffuse = directDiffuse + indirectDiffuse + subsurface`, and the same for `specular`.
/// Each light-group part of a whole is the sum of its parts' same light-group parts.
pub const STANDARD_SUMS: [(&str, [&str; 3]); 2] = [
    (
        "diffuse",
        ["directDiffuse", "indirectDiffuse", "subsurface"],
    ),
    (
        "specular",
        ["directSpecular", "indirectSpecular", "transmissive"],
    ),
];

/// Looks up a standard name in its exact or all-lowercase spelling; returns the canonical
/// name and its definition.
pub fn standard_name(word: &str) -> Option<(&'static str, &'static str)> {
    STANDARD_NAMES
        .iter()
        .find(|(name, _)| *name == word || name.to_lowercase() == word)
        .copied()
}

/// The candidate closest to `word` by edit distance, if it is plausibly a typo.
pub(crate) fn closest<'a>(
    word: &str,
    candidates: impl IntoIterator<Item = &'a str>,
) -> Option<&'a str> {
    let lower = word.to_lowercase();
    candidates
        .into_iter()
        .map(|c| (edit_distance(&lower, &c.to_lowercase()), c))
        .filter(|(d, c)| *d <= (c.len() / 3).max(2))
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + (ca != *cb) as usize).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typos_suggest_the_intended_prefix() {
        let words = Prefix::ALL.map(Prefix::word);
        assert_eq!(closest("unocluded", words), Some("unoccluded"));
        assert_eq!(closest("holdout", words), Some("holdouts"));
        assert_eq!(closest("Unoccluded", words), Some("unoccluded"));
        assert_eq!(closest("C", words), None);
    }

    #[test]
    fn standard_sums_hold_on_every_short_path() {
        // Every path of up to three scattering events, lit or seen as emission: it is in
        // a sum's whole exactly when it is in one of its parts.
        let steps = ["<RD>", "<TD>", "<RS>", "<TS>", "V"];
        let mut paths: Vec<String> = vec!["C".into()];
        let mut all = Vec::new();
        for _ in 0..=3 {
            all.extend(
                paths
                    .iter()
                    .flat_map(|p| [format!("{p}<L'key'>"), format!("{p}O")]),
            );
            paths = paths
                .iter()
                .flat_map(|p| steps.map(|s| format!("{p}{s}")))
                .collect();
        }
        for (whole, parts) in STANDARD_SUMS {
            let definition = |n: &str| standard_name(n).unwrap().1;
            let mut compiler = crate::Compiler::new();
            let w = compiler.add(definition(whole)).unwrap();
            let ps = parts.map(|p| compiler.add(definition(p)).unwrap());
            let automaton = compiler.compile().unwrap();
            let mut lit = 0;
            for text in &all {
                let path = crate::parse_path(text).unwrap();
                let rules = automaton.run(&path).unwrap_or(&[]);
                let in_parts = ps.iter().filter(|p| rules.contains(p)).count();
                assert_eq!(in_parts, rules.contains(&w) as usize, "{whole}: {text}");
                lit += in_parts;
            }
            assert!(lit > 20, "{whole}: only {lit} paths");
        }
    }

    #[test]
    fn standard_names_accept_the_lowercase_spelling_only() {
        assert_eq!(standard_name("directdiffuse").unwrap().0, "directDiffuse");
        assert!(standard_name("Directdiffuse").is_none());
        assert!(standard_name("DIRECTDIFFUSE").is_none());
    }
}
