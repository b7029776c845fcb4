//! Every channel, part and header name Lightpath writes or reads: the one owner, so the
//! renderer, the EXR writer and the post-processing commands cannot drift apart.
//!
//! Header schema (all text attributes, written in name order):
//! - `lightpath/aov/<name>`: the AOV's definition (prose for people; never parsed).
//! - `lightpath/part/<name>`: the AOV `<name>` is a part of (its whole).
//! - `lightpath/partition/<name>`: which partition of that whole it belongs to:
//!   `standard` (docs/lpe.md#standard-aovs set), `bounces` or `lightgroups`.
//! - `lightpath/lightgroup/<name>`: for a `lightgroups` part, its light group, or
//!   `__default` for lights without a group (and glowing objects).
//! - `lightpath/expression/<name>`: the AOV's expression as compiled (a standard name
//!   expanded, prefixes included) beside what the user wrote.
//! - `lightpath/scene`, `lightpath/spp`, `lightpath/first_sample`, `lightpath/seed`.
//! - `lightpath/identity`: the hash of everything that decides the render's pixels (every
//!   file it read and its identity settings); `lightpath/inputs`: the manifest of those
//!   files, one `<hash> <path>` line each (`identity.rs`).
//! - `lightpath/samples`: the sample ranges the file holds (`0-64` or, merged,
//!   `0-64 64-128`); `lightpath/crop`: the pixel window rendered (`X0,Y0,X1,Y1`).
//! - `lightpath/setting/<name>`: every other setting of the render's identity (depth
//!   limits, clamps, sampler, filter, resolution, camera): parts of one frame must agree
//!   on all of them.
//! - Standard attributes: `software`, `chromaticities`, `worldToCamera`, `worldToNDC`,
//!   and `capDate` only with `--timestamp`; `cryptomatte/<key>/…` for Cryptomatte layers.
//! - `lightpath/kind/<name>`: what AOV `<name>` holds: `light` (radiance: what a denoiser
//!   filters), `data` (albedo, normal, depth: one value per sample, never summed),
//!   `variance` (`<aov>_var`: the variance of `<aov>`'s pixel mean) or `derived`.
//! - `lightpath/variance/<aov>_var`: the AOV whose variance it is.
//! - `lightpath/denoised`: how a denoised file was filtered; `lightpath/noisy/<aov>_noisy`:
//!   the AOV a kept noisy input belongs to.

/// The beauty AOV, stored as the plain `R, G, B` channels (plus `A`).
pub const BEAUTY: &str = "beauty";
/// The alpha channel.
pub const ALPHA: &str = "A";
/// The data AOVs a denoiser takes as auxiliary images, and the depth of the first hit.
pub const ALBEDO: &str = "albedo";
pub const NORMAL: &str = "normal";
pub const DEPTH: &str = "depth";
/// The group of lights without a group, as a split's suffix and an attribute value.
pub const DEFAULT_GROUP: &str = "__default";
/// `--gain` names the default group as channels and the viewer do, `__default`; the
/// older spelling `_default` (`beauty` + `_` + `_default`) is still accepted.
pub const DEFAULT_GROUP_ARG: &str = "_default";

/// Whether a `--gain GROUP=…` names the default group (either spelling).
pub fn is_default_group(group: &str) -> bool {
    group == DEFAULT_GROUP || group == DEFAULT_GROUP_ARG
}

/// Header attribute prefixes.
pub const AOV_ATTRIBUTE_PREFIX: &str = "lightpath/aov/";
pub const PART_ATTRIBUTE_PREFIX: &str = "lightpath/part/";
pub const PARTITION_ATTRIBUTE_PREFIX: &str = "lightpath/partition/";
pub const LIGHTGROUP_ATTRIBUTE_PREFIX: &str = "lightpath/lightgroup/";
/// Render metadata attributes.
/// The holdout pair RenderMan's shadow matte is derived from (docs/lpe.md#standard-aovs), and the matte.
pub const OCCLUDED: &str = "occluded";
pub const UNOCCLUDED: &str = "unoccluded";
pub const SHADOW: &str = "shadow";
/// The definition written for the derived shadow matte.
pub const SHADOW_DEFINITION: &str = "derived: 1 - occluded/unoccluded";

pub const SCENE_ATTRIBUTE: &str = "lightpath/scene";
pub const SPP_ATTRIBUTE: &str = "lightpath/spp";
pub const FIRST_SAMPLE_ATTRIBUTE: &str = "lightpath/first_sample";
/// Present on the EXR of a stopped render: how many rows (and samples) it holds.
pub const INTERRUPTED_ATTRIBUTE: &str = "lightpath/interrupted";
pub const SEED_ATTRIBUTE: &str = "lightpath/seed";
pub const EXPRESSION_ATTRIBUTE_PREFIX: &str = "lightpath/expression/";
pub const IDENTITY_ATTRIBUTE: &str = "lightpath/identity";
pub const INPUTS_ATTRIBUTE: &str = "lightpath/inputs";
pub const SAMPLES_ATTRIBUTE: &str = "lightpath/samples";
pub const CROP_ATTRIBUTE: &str = "lightpath/crop";
pub const SETTING_ATTRIBUTE_PREFIX: &str = "lightpath/setting/";
/// The per-pixel sample count channel of adaptive renders: merges weigh by it.
pub const SAMPLE_COUNT_CHANNEL: &str = "sampleCount";

/// Attribute name holding AOV `name`'s compiled expression.
pub fn expression_attribute(name: &str) -> String {
    format!("{EXPRESSION_ATTRIBUTE_PREFIX}{name}")
}

/// Attribute name of render setting `name`.
pub fn setting_attribute(name: &str) -> String {
    format!("{SETTING_ATTRIBUTE_PREFIX}{name}")
}

/// A sample range as `lightpath/samples` lists it: `first-end` (end exclusive).
pub fn format_ranges(ranges: &[(u64, u64)]) -> String {
    ranges
        .iter()
        .map(|(a, b)| format!("{a}-{b}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// `lightpath/samples` parsed back; `None` if malformed.
pub fn parse_ranges(s: &str) -> Option<Vec<(u64, u64)>> {
    s.split_whitespace()
        .map(|r| {
            let (a, b) = r.split_once('-')?;
            let (a, b) = (a.parse().ok()?, b.parse().ok()?);
            (a < b).then_some((a, b))
        })
        .collect()
}

pub const KIND_ATTRIBUTE_PREFIX: &str = "lightpath/kind/";
pub const VARIANCE_ATTRIBUTE_PREFIX: &str = "lightpath/variance/";
pub const NOISY_ATTRIBUTE_PREFIX: &str = "lightpath/noisy/";
pub const DENOISED_ATTRIBUTE: &str = "lightpath/denoised";

/// What an AOV holds (`lightpath/kind/<name>`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AovKind {
    /// Light: contributions summed over a path's vertices.
    Light,
    /// Data (`overwrite` or `nothruput` rules: albedo, normal, depth): one value per
    /// sample, never summed.
    Data,
    /// `<aov>_var`: the estimated variance of `<aov>`'s pixel mean.
    Variance,
    /// Computed from other AOVs after rendering (the shadow matte).
    Derived,
}

impl AovKind {
    pub fn as_str(self) -> &'static str {
        match self {
            AovKind::Light => "light",
            AovKind::Data => "data",
            AovKind::Variance => "variance",
            AovKind::Derived => "derived",
        }
    }
    pub fn parse(s: &str) -> Option<AovKind> {
        [
            AovKind::Light,
            AovKind::Data,
            AovKind::Variance,
            AovKind::Derived,
        ]
        .into_iter()
        .find(|k| k.as_str() == s)
    }
    /// A rule's kind from its prefixes: `overwrite` and `nothruput` make data.
    pub fn of_flags(flags: lpe::Flags) -> AovKind {
        if flags.contains(lpe::Prefix::Overwrite) || flags.contains(lpe::Prefix::NoThruput) {
            AovKind::Data
        } else {
            AovKind::Light
        }
    }
}

/// Attribute name holding AOV `name`'s kind.
pub fn kind_attribute(name: &str) -> String {
    format!("{KIND_ATTRIBUTE_PREFIX}{name}")
}

/// The kind a header gives AOV `name`; `None` for files written before kinds existed.
pub fn kind_of(attributes: &[(String, String)], name: &str) -> Option<AovKind> {
    let key = kind_attribute(name);
    attributes
        .iter()
        .find(|(k, _)| *k == key)
        .and_then(|(_, v)| AovKind::parse(v))
}

/// The variance AOV of `aov`: `<aov>_var` (RenderMan writes the same estimate with its
/// `mse` pixel filter, as `<aov>_mse`).
pub fn variance_name(aov: &str) -> String {
    format!("{aov}_var")
}

/// Attribute naming the AOV a variance AOV belongs to.
pub fn variance_attribute(variance_aov: &str) -> String {
    format!("{VARIANCE_ATTRIBUTE_PREFIX}{variance_aov}")
}

/// The noisy input of denoised AOV `aov`, kept by `denoise --keep-noisy`.
pub fn noisy_name(aov: &str) -> String {
    format!("{aov}_noisy")
}

/// Attribute naming the AOV a kept noisy input belongs to.
pub fn noisy_attribute(noisy_aov: &str) -> String {
    format!("{NOISY_ATTRIBUTE_PREFIX}{noisy_aov}")
}

/// RenderMan's denoiser divides these AOVs by the albedo before filtering (their names
/// start with one of these, case-insensitively) and filters the others as they are.
/// `subsurface` is Lightpath's diffuse transmission (`TD`), textured by the same albedo.
pub const ALBEDO_DIVIDED_PREFIXES: [&str; 4] =
    ["diffuse", "directdiffuse", "indirectdiffuse", "subsurface"];

/// Whether a denoiser divides AOV `name` by the albedo (RenderMan's naming convention).
pub fn is_albedo_divided(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    ALBEDO_DIVIDED_PREFIXES.iter().any(|p| lower.starts_with(p))
}

/// A kind of partition an AOV can be a part of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PartitionKind {
    Standard,
    Bounces,
    LightGroups,
}

impl PartitionKind {
    pub fn as_str(self) -> &'static str {
        match self {
            PartitionKind::Standard => "standard",
            PartitionKind::Bounces => "bounces",
            PartitionKind::LightGroups => "lightgroups",
        }
    }
    pub fn parse(s: &str) -> Option<PartitionKind> {
        [
            PartitionKind::Standard,
            PartitionKind::Bounces,
            PartitionKind::LightGroups,
        ]
        .into_iter()
        .find(|k| k.as_str() == s)
    }
}

/// The channel names of AOV `name`: beauty is plain R, G, B.
pub fn channel_names(name: &str) -> [String; 3] {
    if name == BEAUTY {
        ["R".into(), "G".into(), "B".into()]
    } else {
        ["R", "G", "B"].map(|c| format!("{name}.{c}"))
    }
}

/// The name of AOV `aov`'s part for light group `group` (`None`: the default group).
pub fn split_name(aov: &str, group: Option<&str>) -> String {
    match group {
        Some(g) => format!("{aov}_{g}"),
        None => format!("{aov}{DEFAULT_GROUP}"),
    }
}

/// The light group of part `part` of split AOV `whole` (`Some(None)`: the default group);
/// `None` if `part` is not named as a part of `whole`.
pub fn split_group<'a>(whole: &str, part: &'a str) -> Option<Option<&'a str>> {
    let rest = part.strip_prefix(whole)?;
    if rest == DEFAULT_GROUP {
        return Some(None);
    }
    rest.strip_prefix('_').filter(|g| !g.is_empty()).map(Some)
}

/// The human-readable definition of a light-group part (prose: nothing parses it).
pub fn split_definition(definition: &str, group: Option<&str>) -> String {
    match group {
        Some(g) => format!("{definition} (light group '{g}')"),
        None => format!("{definition} (lights without a group)"),
    }
}

/// The part named by `--gain GROUP=…` for split AOV `base`.
pub fn gain_part(base: &str, group: &str) -> String {
    if is_default_group(group) {
        split_name(base, None)
    } else {
        split_name(base, Some(group))
    }
}

/// Bounce AOV `bounce<i>`.
pub fn bounce_name(i: u32) -> String {
    format!("bounce{i}")
}

/// The last bounce AOV, `bounce<k>plus`: k or more scattering events.
pub fn bounce_plus_name(k: u32) -> String {
    format!("bounce{k}plus")
}

/// The definition the renderer gives bounce AOV `bounce<i>` (`plus`: `bounce<i>plus`):
/// `bounce0` is emission seen directly, `bounce<i>` exactly i scattering events.
pub fn bounce_definition(i: u32, plus: bool) -> String {
    match (i, plus) {
        (0, false) => "C[<L.>O]".to_string(),
        (i, false) => format!("C[DSV]{{{i}}}[<L.>O]"),
        (k, true) => format!("C[DSV]{{{k},}}[<L.>O]"),
    }
}

/// Whether an AOV's definition is what its name means to the renderer: `lpe:<name>` for a
/// standard name, the generated rule for a bounce name. A user's own definition under such
/// a name (`--aov "directDiffuse=C<RD>L"`, a USD render var named `diffuse`) is not, so the
/// header does not claim the partition that name belongs to.
pub fn is_own_definition(name: &str, definition: &str) -> bool {
    definition.strip_prefix("lpe:") == Some(name)
        || parse_bounce(name).is_some_and(|(i, plus)| definition == bounce_definition(i, plus))
}

/// A bounce AOV's name parsed back: `(i, false)` for `bounce<i>`, `(k, true)` for
/// `bounce<k>plus`.
pub fn parse_bounce(name: &str) -> Option<(u32, bool)> {
    let rest = name.strip_prefix("bounce")?;
    let (digits, plus) = match rest.strip_suffix("plus") {
        Some(d) => (d, true),
        None => (rest, false),
    };
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok().map(|n| (n, plus))
}

/// Attribute name holding AOV `name`'s definition.
pub fn aov_attribute(name: &str) -> String {
    format!("{AOV_ATTRIBUTE_PREFIX}{name}")
}

/// An AOV as the partition attributes see it: its name, its definition and, for a
/// light-group part, the AOV it is a part of.
pub struct PartInfo<'a> {
    pub name: &'a str,
    pub definition: &'a str,
    pub split_of: Option<&'a str>,
}

/// The structured partition attributes for a render's AOVs: light-group parts always;
/// the standard set and the bounce AOVs when all their members are present with the
/// renderer's own definitions (as `check_partitions` needs every part to sum them, and a
/// redefined name is the user's, no longer a part).
pub fn partition_attributes(aovs: &[PartInfo]) -> Vec<(String, String)> {
    let has = |n: &str| {
        aovs.iter()
            .any(|a| a.name == n && is_own_definition(a.name, a.definition))
    };
    let mut out = Vec::new();
    let mut mark = |name: &str, whole: &str, kind: PartitionKind, group: Option<&str>| {
        out.push((format!("{PART_ATTRIBUTE_PREFIX}{name}"), whole.to_string()));
        out.push((
            format!("{PARTITION_ATTRIBUTE_PREFIX}{name}"),
            kind.as_str().to_string(),
        ));
        if kind == PartitionKind::LightGroups {
            out.push((
                format!("{LIGHTGROUP_ATTRIBUTE_PREFIX}{name}"),
                group.unwrap_or(DEFAULT_GROUP).to_string(),
            ));
        }
    };
    if has(BEAUTY) && lpe::BEAUTY_PARTITION.iter().all(|n| has(n)) {
        for n in lpe::BEAUTY_PARTITION {
            mark(n, BEAUTY, PartitionKind::Standard, None);
        }
    }
    // A `bounce<k>plus` with k at or above the AOV count cannot have all its parts (and
    // listing them would allocate k names: `bounce4294967295plus` aborted).
    if let Some(k) = aovs
        .iter()
        .find_map(|a| parse_bounce(a.name).filter(|b| b.1).map(|b| b.0))
        .filter(|&k| (k as usize) < aovs.len())
    {
        let mut parts: Vec<String> = (0..k).map(bounce_name).collect();
        parts.push(bounce_plus_name(k));
        if has(BEAUTY) && parts.iter().all(|p| has(p)) {
            for p in &parts {
                mark(p, BEAUTY, PartitionKind::Bounces, None);
            }
        }
    }
    for a in aovs {
        if let Some(whole) = a.split_of {
            if let Some(group) = split_group(whole, a.name) {
                mark(a.name, whole, PartitionKind::LightGroups, group);
            }
        }
    }
    out
}

/// One part as read back from a header.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartOf {
    pub name: String,
    pub whole: String,
    pub kind: PartitionKind,
    /// For a light-group part: its group, `None` for the default group.
    pub group: Option<Option<String>>,
}

/// The order parts of a partition are listed in: the standard set as docs/lpe.md#standard-aovs lists it,
/// bounces by count (`plus` last), light groups by name with the default group last.
pub fn part_order(part: &PartOf) -> (usize, u32, bool, String) {
    match part.kind {
        PartitionKind::Standard => {
            let i = lpe::BEAUTY_PARTITION.iter().position(|n| *n == part.name);
            (i.unwrap_or(usize::MAX), 0, false, part.name.clone())
        }
        PartitionKind::Bounces => {
            let (i, plus) = parse_bounce(&part.name).unwrap_or((u32::MAX, true));
            (0, i, plus, part.name.clone())
        }
        PartitionKind::LightGroups => {
            let default = matches!(part.group, Some(None));
            (0, 0, default, part.name.clone())
        }
    }
}

/// Reads the partition attributes back from a header's attributes, in name order.
pub fn parts_from_attributes(attributes: &[(String, String)]) -> Vec<PartOf> {
    let get = |key: String| attributes.iter().find(|(k, _)| *k == key).map(|(_, v)| v);
    let mut out: Vec<PartOf> = attributes
        .iter()
        .filter_map(|(k, whole)| {
            let name = k.strip_prefix(PART_ATTRIBUTE_PREFIX)?;
            let kind = PartitionKind::parse(get(format!("{PARTITION_ATTRIBUTE_PREFIX}{name}"))?)?;
            let group = get(format!("{LIGHTGROUP_ATTRIBUTE_PREFIX}{name}"))
                .map(|g| (g != DEFAULT_GROUP).then(|| g.clone()));
            Some(PartOf {
                name: name.to_string(),
                whole: whole.clone(),
                kind,
                group,
            })
        })
        .collect();
    out.sort_by(|a, b| a.name.cmp(&b.name));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_names_parse_back_to_whole_and_group() {
        for (whole, group) in [
            ("beauty", Some("key")),
            ("beauty", None),
            ("diffuse", Some("a_b")),
        ] {
            let part = split_name(whole, group);
            assert_eq!(split_group(whole, &part), Some(group), "{part}");
        }
        assert_eq!(split_group("beauty", "diffuse_key"), None);
        assert_eq!(split_group("beauty", "beauty_"), None);
        assert_eq!(gain_part("beauty", "_default"), "beauty__default");
        assert_eq!(gain_part("beauty", "__default"), "beauty__default");
        assert_eq!(gain_part("beauty", "key"), "beauty_key");
    }

    #[test]
    fn bounce_names_parse_back() {
        assert_eq!(parse_bounce(&bounce_name(3)), Some((3, false)));
        assert_eq!(parse_bounce(&bounce_plus_name(4)), Some((4, true)));
        assert_eq!(parse_bounce("bounceplus"), None);
        assert_eq!(parse_bounce("bounce1x"), None);
    }

    fn info<'a>(name: &'a str, definition: &'a str, split_of: Option<&'a str>) -> PartInfo<'a> {
        PartInfo {
            name,
            definition,
            split_of,
        }
    }

    #[test]
    fn partition_attributes_round_trip() {
        let (b0, b1) = (bounce_definition(0, false), bounce_definition(1, true));
        let aovs = [
            info("beauty", "lpe:beauty", None),
            info("bounce0", &b0, None),
            info("bounce1plus", &b1, None),
            info("beauty_key", "lpe:beauty", Some("beauty")),
            info("beauty__default", "lpe:beauty", Some("beauty")),
        ];
        let attrs = partition_attributes(&aovs);
        let parts = parts_from_attributes(&attrs);
        let find = |n: &str| parts.iter().find(|p| p.name == n).unwrap();
        assert_eq!(find("bounce0").kind, PartitionKind::Bounces);
        assert_eq!(find("bounce1plus").whole, "beauty");
        assert_eq!(find("beauty_key").group, Some(Some("key".into())));
        assert_eq!(find("beauty__default").group, Some(None));
        assert_eq!(parts.len(), 4);
        // Without beauty's full standard set, no standard partition is claimed.
        assert!(parts.iter().all(|p| p.kind != PartitionKind::Standard));
    }

    #[test]
    fn a_redefined_name_is_not_claimed_as_a_part() {
        let standard: Vec<String> = lpe::BEAUTY_PARTITION
            .iter()
            .map(|n| format!("lpe:{n}"))
            .collect();
        let mut aovs: Vec<PartInfo> = lpe::BEAUTY_PARTITION
            .iter()
            .zip(&standard)
            .map(|(n, d)| info(n, d, None))
            .collect();
        aovs.push(info(BEAUTY, "lpe:beauty", None));
        let claimed = |aovs: &[PartInfo]| {
            parts_from_attributes(&partition_attributes(aovs))
                .iter()
                .filter(|p| p.kind == PartitionKind::Standard)
                .count()
        };
        assert_eq!(claimed(&aovs), lpe::BEAUTY_PARTITION.len());
        aovs[0].definition = "C<RD>L";
        assert_eq!(claimed(&aovs), 0, "{} was redefined", aovs[0].name);
        let (b0, b1) = (bounce_definition(0, false), "C.+L");
        let bounces = [
            info("beauty", "lpe:beauty", None),
            info("bounce0", &b0, None),
            info("bounce1plus", b1, None),
        ];
        assert!(parts_from_attributes(&partition_attributes(&bounces)).is_empty());
    }
}
