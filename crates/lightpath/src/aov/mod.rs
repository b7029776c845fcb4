//! Which AOVs a render produces: beauty first, then the standard set, the scene's own,
//! the command line's, and light-group splits. One owner for AOV names.

pub mod naming;
pub mod plan;

use lpe::STANDARD_NAMES;
use naming::{bounce_definition, bounce_name, bounce_plus_name, BEAUTY, DEPTH, NORMAL};

/// An AOV to render: its channel name and its LPE definition.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AovSpec {
    pub name: String,
    pub definition: String,
    /// Also split this AOV per light group: `<name>_<group>` and `<name>__default`.
    pub split_light_groups: bool,
}

impl AovSpec {
    pub fn new(name: impl Into<String>, definition: impl Into<String>) -> AovSpec {
        AovSpec {
            name: name.into(),
            definition: definition.into(),
            split_light_groups: false,
        }
    }

    /// The same AOV, also split per light group.
    pub fn split(mut self) -> AovSpec {
        self.split_light_groups = true;
        self
    }

    /// Parses `NAME=DEF` (as `--aov` takes it); a bare standard name is its own name.
    pub fn parse(arg: &str) -> Result<AovSpec, crate::error::InvalidValue> {
        if let Some((name, def)) = arg.split_once('=') {
            let name = name.trim();
            if !name.is_empty()
                && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                && !name.starts_with(|c: char| c.is_ascii_digit())
            {
                return Ok(AovSpec::new(name, def.trim()));
            }
        }
        let word = arg.trim().trim_start_matches("lpe:");
        if let Some((name, def)) = STANDARD_DATA.iter().find(|(n, _)| *n == word) {
            return Ok(AovSpec::new(*name, *def));
        }
        if let Some((name, _)) = STANDARD_LOBES.iter().find(|(n, _)| *n == word) {
            return Ok(AovSpec::new(*name, format!("lpe:{name}")));
        }
        match lpe::standard_name(word) {
            Some((name, _)) => Ok(AovSpec::new(name, format!("lpe:{name}"))),
            None => Err(crate::error::InvalidValue(format!(
                "expected NAME=DEFINITION or a standard name, got '{arg}'"
            ))),
        }
    }
}

/// The data AOVs Lightpath adds to docs/lpe.md#standard-aovs's set: the first hit's world-space shading
/// normal (`U6`) and camera-space depth (`U7`), one value per sample like `albedo`. With
/// `albedo` they are what a denoiser takes as auxiliary images.
pub const STANDARD_DATA: [(&str, &str); 2] = [
    (
        NORMAL,
        "nothruput;noinfinitecheck;noclamp;unoccluded;overwrite;CU6L",
    ),
    (
        DEPTH,
        "nothruput;noinfinitecheck;noclamp;unoccluded;overwrite;CU7L",
    ),
];

/// Lightpath's standard AOVs beside the partition (docs/lpe.md#standard-aovs): light
/// that left the camera's first surface by a single specular lobe (they overlap
/// `directSpecular` and `indirectSpecular`; `sheen` is `fuzz`), and `volume`, light
/// first scattered by a medium (`volumeDirect` + `volumeIndirect`).
pub const STANDARD_LOBES: [(&str, &str); 5] = [
    ("coat", "C<RS4>[DSV]*[<L.>O]"),
    ("iridescence", "C<RS5>[DSV]*[<L.>O]"),
    ("fuzz", "C<RS6>[DSV]*[<L.>O]"),
    ("sheen", "C<RS6>[DSV]*[<L.>O]"),
    ("volume", "CV[DSV]*[<L.>O]"),
];

/// A definition with Lightpath's own standard names resolved: `lpe:normal` and
/// `lpe:depth` name the renderer's data AOVs, `lpe:coat`, `lpe:iridescence` and
/// `lpe:fuzz` its lobe AOVs, which the language (and so the `lpe` crate) does not know;
/// every other definition is returned as written.
pub fn resolve_definition(definition: &str) -> &str {
    let word = definition.trim().strip_prefix("lpe:").unwrap_or("");
    STANDARD_DATA
        .iter()
        .chain(&STANDARD_LOBES)
        .find(|(n, _)| n.eq_ignore_ascii_case(word))
        .map_or(definition, |(_, d)| d)
}

/// The standard AOVs of docs/lpe.md#standard-aovs other than beauty, then the lobe AOVs
/// `coat`, `iridescence` and `fuzz`, then `normal` and `depth`.
pub fn standard() -> Vec<AovSpec> {
    STANDARD_NAMES
        .iter()
        .filter(|(n, _)| *n != BEAUTY)
        .map(|(n, _)| AovSpec::new(*n, format!("lpe:{n}")))
        .chain(
            STANDARD_LOBES
                .iter()
                .filter(|(n, _)| *n != "sheen")
                .map(|(n, _)| AovSpec::new(*n, format!("lpe:{n}"))),
        )
        .chain(STANDARD_DATA.iter().map(|(n, d)| AovSpec::new(*n, *d)))
        .collect()
}

/// Beauty plus the given AOVs, in order, without duplicate names (a later definition
/// replaces an earlier one; an AOV named `beauty` replaces the default beauty).
pub fn assemble(extra: impl IntoIterator<Item = AovSpec>) -> Vec<AovSpec> {
    let mut out = vec![AovSpec::new(BEAUTY, format!("lpe:{BEAUTY}"))];
    for a in extra {
        match out.iter_mut().find(|o| o.name == a.name) {
            Some(existing) => *existing = a,
            None => out.push(a),
        }
    }
    out
}

/// Bounce AOVs that partition beauty: `bounce0` (emission seen directly), `bounce<i>`
/// (exactly i scattering events) up to `bounce<k-1>`, and `bounce<k>plus`.
pub fn bounces(k: u32) -> Vec<AovSpec> {
    let k = k.clamp(1, 63);
    let mut out: Vec<AovSpec> = (0..k)
        .map(|i| AovSpec::new(bounce_name(i), bounce_definition(i, false)))
        .collect();
    out.push(AovSpec::new(
        bounce_plus_name(k),
        bounce_definition(k, true),
    ));
    out
}

/// The name of AOV `aov`'s part for light group `group` (`None`: the default group of
/// lights without a group, and glowing objects).
pub fn split_name(aov: &str, group: Option<&str>) -> String {
    naming::split_name(aov, group)
}

/// Beauty split per light group as LPEs: `beauty_<group>` for each group, and
/// `beauty__default` for lights without a group (and glowing objects). The renderer's
/// own split (`AovSpec::split`) routes by light instead and needs no extra rules; this
/// form is for other renderers and for checking one against the other.
pub fn light_group_split(groups: &[String]) -> Vec<AovSpec> {
    let mut out: Vec<AovSpec> = groups
        .iter()
        .map(|g| {
            AovSpec::new(
                split_name(BEAUTY, Some(g)),
                format!("C[DSV]*[<L.'{g}'><O'{g}'>]"),
            )
        })
        .collect();
    let all: String = groups
        .iter()
        .map(|g| format!("'{g}'"))
        .collect::<Vec<_>>()
        .join(" ");
    let default = if groups.is_empty() {
        "C[DSV]*[<L.>O]".to_string()
    } else {
        format!("C[DSV]*[<L.[^{all}]><O[^{all}]>]")
    };
    out.push(AovSpec::new(split_name(BEAUTY, None), default));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aov_arguments_parse() {
        assert_eq!(
            AovSpec::parse("key=C<.>*<L.'key'>").unwrap(),
            AovSpec::new("key", "C<.>*<L.'key'>")
        );
        assert_eq!(
            AovSpec::parse("directdiffuse").unwrap(),
            AovSpec::new("directDiffuse", "lpe:directDiffuse")
        );
        assert!(AovSpec::parse("C<RD>L").is_err());
    }

    #[test]
    fn the_renderers_own_standard_names_resolve() {
        assert_eq!(resolve_definition("lpe:normal"), STANDARD_DATA[0].1);
        assert_eq!(resolve_definition(" lpe:depth"), STANDARD_DATA[1].1);
        assert_eq!(resolve_definition("lpe:diffuse"), "lpe:diffuse");
        assert_eq!(
            resolve_definition("lpe:sheen"),
            resolve_definition("lpe:fuzz")
        );
        assert_eq!(resolve_definition("lpe:coat"), "C<RS4>[DSV]*[<L.>O]");
        let coat = AovSpec::parse("coat").unwrap();
        assert_eq!(
            (coat.name.as_str(), coat.definition.as_str()),
            ("coat", "lpe:coat")
        );
        assert_eq!(resolve_definition("normal"), "normal");
        let mut compiler = lpe::Compiler::new().profile(crate::events::profile());
        for (name, _) in STANDARD_DATA {
            compiler
                .add(resolve_definition(&format!("lpe:{name}")))
                .unwrap();
        }
    }

    #[test]
    fn a_named_beauty_replaces_the_default() {
        let a = assemble([AovSpec::new("beauty", "C<RD>L"), AovSpec::new("x", "CO")]);
        assert_eq!(a.len(), 2);
        assert_eq!(a[0].definition, "C<RD>L");
    }
}
