//! The render settings, each declared once in the table below: its TOML key and section,
//! command-line flag, type, default, valid range, help text, role (does it change what a
//! pixel converges to?) and EXR header attribute. The TOML loader, the command line
//! (clap's options and their help), the overrides, the EXR header, the checkpoint and
//! `merge` all read the table, so the command line accepts exactly the values a scene
//! file accepts, with the same messages. Adding a setting is one entry here
//! (docs/architecture.md, "Add a render setting").

use crate::aov::naming::{setting_attribute, SEED_ATTRIBUTE, SPP_ATTRIBUTE};
use crate::camera::FilterKind;
use crate::error::SettingError;
use crate::guiding::GuidingMode;
use crate::integrator::connect::LightConnections;
use crate::integrator::glints::GlintSampling;
use crate::light::select::LightSelection;
use crate::media::VolumeSampling;
use crate::sampler::SamplerKind;

/// Samples a pixel takes before adaptive sampling may stop it, unless `min_spp` says
/// otherwise (fewer if `spp` is fewer).
pub const DEFAULT_MIN_SPP: u32 = 16;

/// Declares the settings: the `RenderDesc` struct and its defaults, the command line's
/// `SettingOverrides`, and the table `SETTINGS` that every reader walks.
macro_rules! settings {
    (@show $field:ident) => { |r: &RenderDesc| Value::show(&r.$field) };
    (@show $field:ident $show:expr) => { $show };
    ($(
        $field:ident: $ty:ty = $default:expr, {
            section: $section:ident,
            flag: $flag:literal,
            range: $range:expr,
            role: $role:ident,
            header: $header:expr,
            $(show: $show:expr,)?
            help: $help:literal $(,)?
        }
    )*) => {
        /// A render's settings (docs/scene-format.md: `[render]` and `[film]`), as the
        /// scene and then the command line set them. Declared in `settings.rs`'s table.
        #[derive(Clone, Debug, PartialEq)]
        pub struct RenderDesc {
            $(#[doc = $help] pub $field: $ty,)*
        }

        impl Default for RenderDesc {
            fn default() -> Self {
                RenderDesc { $($field: $default,)* }
            }
        }

        /// The settings the command line overrides; `None` keeps the scene's value.
        #[derive(Clone, Debug, Default, PartialEq)]
        pub struct SettingOverrides {
            $(pub $field: Option<$ty>,)*
        }

        impl SettingOverrides {
            /// Writes every overridden setting into `render`.
            pub fn apply(&self, render: &mut RenderDesc) {
                $(if let Some(v) = &self.$field {
                    render.$field = v.clone();
                })*
            }
        }

        /// Every render setting, in the order `lightpath render --help` lists them.
        pub static SETTINGS: &[Setting] = &[$(
            Setting {
                key: stringify!($field),
                section: Section::$section,
                flag: $flag,
                value_name: <$ty as Value>::VALUE_NAME,
                help: $help,
                range: $range,
                role: Role::$role,
                header: $header,
                read_flag: |text, overrides| {
                    let v: $ty = from_flag(stringify!($field), $range, text)?;
                    overrides.$field = Some(v);
                    Ok(())
                },
                read_toml: |value, render| {
                    render.$field = from_toml(stringify!($field), $range, value)?;
                    Ok(())
                },
                check: |render| check_value(stringify!($field), $range, &render.$field),
                show: settings!(@show $field $($show)?),
            },
        )*];
    };
}

settings! {
    spp: u32 = 16, {
        section: Render,
        flag: "spp",
        range: Range::AtLeast(1.0),
        role: PerPart,
        header: Header::Named(SPP_ATTRIBUTE),
        help: "Samples per pixel (with --noise-threshold: the most a pixel takes).",
    }
    max_depth: u32 = 8, {
        section: Render,
        flag: "max-depth",
        range: Range::AtLeast(1.0),
        role: Identity,
        header: Header::Setting,
        help: "Path segments, as Mitsuba counts them (1: emitters seen directly, \
               2: + direct light, 8: up to seven scattering events).",
    }
    max_diffuse_depth: Option<u32> = None, {
        section: Render,
        flag: "max-diffuse-depth",
        range: Range::Any,
        role: Identity,
        header: Header::Setting,
        help: "Diffuse scattering events a path may take (default: only max_depth limits \
               them).",
    }
    max_specular_depth: Option<u32> = None, {
        section: Render,
        flag: "max-specular-depth",
        range: Range::Any,
        role: Identity,
        header: Header::Setting,
        help: "Specular and glossy scattering events a path may take (default: only \
               max_depth limits them).",
    }
    rr_depth: u32 = 5, {
        section: Render,
        flag: "rr-depth",
        range: Range::Any,
        role: Shared,
        header: Header::Setting,
        help: "Russian roulette may end paths from this depth on (Mitsuba's rule).",
    }
    clamp_direct: f32 = 0.0, {
        section: Render,
        flag: "clamp-direct",
        range: Range::AtLeast(0.0),
        role: Identity,
        header: Header::Setting,
        help: "Largest luminance of one contribution of direct light (0: off).",
    }
    clamp_indirect: f32 = 0.0, {
        section: Render,
        flag: "clamp-indirect",
        range: Range::AtLeast(0.0),
        role: Identity,
        header: Header::Setting,
        help: "Largest luminance of one contribution of indirect light (0: off).",
    }
    seed: u64 = 0, {
        section: Render,
        flag: "seed",
        range: Range::Any,
        role: Shared,
        header: Header::Named(SEED_ATTRIBUTE),
        help: "Seed of every sample's numbers.",
    }
    sampler: SamplerKind = SamplerKind::default(), {
        section: Render,
        flag: "sampler",
        range: Range::Any,
        role: Shared,
        header: Header::Setting,
        help: "Sample numbers: sobol (Owen-scrambled Sobol points) or independent.",
    }
    light_selection: LightSelection = LightSelection::default(), {
        section: Render,
        flag: "light-selection",
        range: Range::Any,
        role: Shared,
        header: Header::Setting,
        help: "How lights are chosen for light sampling: tree (power, distance and \
               orientation), power, or uniform (with clamps off, relighting from AOVs \
               then equals re-rendering up to float rounding; docs/aovs.md).",
    }
    light_candidates: u32 = 1, {
        section: Render,
        flag: "light-candidates",
        range: Range::Between(1.0, 64.0),
        role: Shared,
        header: Header::Setting,
        help: "Direct light: candidates drawn per shading point, one kept by resampled \
               importance sampling on its unshadowed contribution (1: the light \
               selection's choice alone; a few help with many lights).",
    }
    light_samples: u32 = 1, {
        section: Render,
        flag: "light-samples",
        range: Range::Between(1.0, 64.0),
        role: Shared,
        header: Header::Setting,
        help: "Direct light at a camera path's first rough vertex (seen directly or through \
               mirrors and smooth glass): light samples taken there, their choices \
               stratified over the light selection (RenderMan's numLightSamples); \
               deeper vertices take one.",
    }
    volume_sampling: VolumeSampling = VolumeSampling::Mis, {
        section: Render,
        flag: "volume-sampling",
        range: Range::Any,
        role: Shared,
        header: Header::Setting,
        help: "Single scattering in media: mis (free-flight distances, and equiangular ones \
               towards point, spot and small sphere lights, weighed by MIS), mis-area \
               (also towards small rect, quad and disk lights) or distance (free-flight \
               distances alone).",
    }
    noise_threshold: f32 = 0.0, {
        section: Render,
        flag: "noise-threshold",
        range: Range::Between(0.0, 1e6),
        role: Shared,
        header: Header::Setting,
        help: "Adaptive sampling: after a pilot pass of --min-spp samples, a pixel takes \
               the most samples its eight neighbours predict for a standard error of its \
               beauty of this times the square root of its brightness (e.g. 0.1); --spp is \
               then the most (0: off).",
    }
    min_spp: Option<u32> = None, {
        section: Render,
        flag: "min-spp",
        range: Range::AtLeast(1.0),
        role: Shared,
        header: Header::Setting,
        show: |r: &RenderDesc| r.min_spp.unwrap_or(DEFAULT_MIN_SPP).to_string(),
        help: "Adaptive sampling: samples every pixel takes first (the pilot pass), at \
               most --spp (default: 16, or --spp if fewer).",
    }
    regularize: f32 = 0.0, {
        section: Render,
        flag: "regularize",
        range: Range::Between(0.0, 1.0),
        role: Identity,
        header: Header::Setting,
        help: "Path regularisation: after a diffuse bounce, specular lobes are at least \
               this rough (e.g. 0.3; 0: off). Tames caustic fireflies at the cost of sharp \
               caustics.",
    }
    guiding: GuidingMode = GuidingMode::Auto, {
        section: Render,
        flag: "guiding",
        range: Range::Any,
        role: Shared,
        header: Header::Setting,
        help: "Path guiding (Müller et al. 2017's SD-tree): on, off, or auto (train a pilot \
               on a sixteenth of the pixels and guide only if it measured that guiding pays). \
               Every farm part trains the same guide.",
    }
    guiding_passes: u32 = 4, {
        section: Render,
        flag: "guiding-passes",
        range: Range::Between(0.0, 12.0),
        role: Shared,
        header: Header::Setting,
        help: "Path guiding's training passes before the render: 1 and 2 samples on a \
               sixteenth of the pixels, then 4, 8, … on all (0: no guiding).",
    }
    light_connections: LightConnections = LightConnections::Off, {
        section: Render,
        flag: "light-connections",
        range: Range::Any,
        role: Shared,
        header: Header::Setting,
        help: "Bidirectional path tracing (Veach and Guibas): each camera sample also traces \
               a light subpath from an area, point or spot light, joins every camera \
               vertex to every light vertex and light vertices to a pinhole camera (light \
               tracing), weighted by MIS over every way to make the path; for rooms lit \
               by light off a ceiling or baffle or through a door (integrator/connect.rs). \
               on or off.",
    }
    glint_sampling: GlintSampling = GlintSampling::On, {
        section: Render,
        flag: "glint-sampling",
        range: Range::Any,
        role: Shared,
        header: Header::Setting,
        help: "Sun glints: where a pinhole camera sees a smooth mirror, each camera sample \
               also samples a film position whose reflection meets a distant light's \
               disc (Newton's method in film space), weighed by MIS against the pixel \
               filter's samples (integrator/glints.rs). on or off.",
    }
    frame: Option<f32> = None, {
        section: Render,
        flag: "frame",
        // Time codes may be negative; a million frames bounds a typo.
        range: Range::Between(-1e6, 1e6),
        role: Identity,
        header: Header::Setting,
        help: "The time code a USD stage's time samples are read at (default: the stage's \
               start time code).",
    }
    render_settings: Option<String> = None, {
        section: Render,
        flag: "render-settings",
        range: Range::Any,
        role: Identity,
        header: Header::Setting,
        help: "The RenderSettings prim of a USD stage to render with, by path (default: the \
               stage's renderSettingsPrimPath, else its first RenderSettings).",
    }
    resolution: [u32; 2] = [256, 256], {
        section: Film,
        flag: "resolution",
        // How many pixels a film may have is `limits.rs`'s (LIGHTPATH_MAX_PIXELS).
        range: Range::AtLeast(1.0),
        role: Identity,
        header: Header::Setting,
        help: "Film size in pixels, WIDTHxHEIGHT ([width, height] in a scene file).",
    }
    filter: FilterKind = FilterKind::Box, {
        section: Film,
        flag: "filter",
        range: Range::Any,
        role: Identity,
        header: Header::Setting,
        show: |r: &RenderDesc| match r.filter {
            FilterKind::Box => "box".to_string(),
            FilterKind::Gaussian => format!("gaussian {}", r.filter_stddev),
            FilterKind::BlackmanHarris => format!("blackman-harris {}", r.filter_width),
        },
        help: "Pixel filter: box (each sample counts for its own pixel), gaussian \
               (samples offset by a Gaussian of --filter-stddev pixels) or blackman-harris \
               (by a Blackman-Harris window reaching --filter-width pixels, Cycles' default).",
    }
    filter_stddev: f32 = 0.5, {
        section: Film,
        flag: "filter-stddev",
        range: Range::Above(0.0),
        role: Identity,
        header: Header::Within("filter"),
        help: "Standard deviation of the gaussian filter, in pixels.",
    }
    filter_width: f32 = 1.5, {
        section: Film,
        flag: "filter-width",
        range: Range::Above(0.0),
        role: Identity,
        header: Header::Within("filter"),
        help: "Half-width of the blackman-harris filter in pixels (Cycles' Filter Width: \
               its default 1.5 reaches 1.5 pixels either side of the pixel centre).",
    }
}

/// Where a setting sits in a TOML scene file: `[render]` or `[film]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Section {
    Render,
    Film,
}

impl Section {
    pub fn name(self) -> &'static str {
        match self {
            Section::Render => "render",
            Section::Film => "film",
        }
    }
}

/// What a setting means for the identity of a scene and for the parts of a farm frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// Changes what a pixel converges to: part of the scene's identity.
    Identity,
    /// Leaves what a pixel converges to, but the parts of one frame must share it to
    /// merge exactly (the seed and the sampler decide which numbers a sample index gets).
    Shared,
    /// Differs between the parts of one frame by design (the sample count).
    PerPart,
}

/// Where a setting's value is written in the EXR header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Header {
    /// `lightpath/setting/<key>`.
    Setting,
    /// An attribute of its own name.
    Named(&'static str),
    /// Inside the attribute of the setting of this key.
    Within(&'static str),
}

/// The values a number accepts (integers are whole by their type, every number finite).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    Any,
    AtLeast(f64),
    Above(f64),
    Between(f64, f64),
}

impl Range {
    fn contains(self, x: f64) -> bool {
        x.is_finite()
            && match self {
                Range::Any => true,
                Range::AtLeast(lo) => x >= lo,
                Range::Above(lo) => x > lo,
                Range::Between(lo, hi) => (lo..=hi).contains(&x),
            }
    }

    /// `at least 1`, `between 0 and 1`; empty for any value.
    pub fn describe(self) -> String {
        match self {
            Range::Any => String::new(),
            Range::AtLeast(lo) => format!("at least {lo}"),
            Range::Above(lo) => format!("above {lo}"),
            Range::Between(lo, hi) => format!("between {lo} and {hi}"),
        }
    }
}

/// One render setting: everything that reads settings learns it here.
pub struct Setting {
    /// The name: the TOML key, and the field of [`RenderDesc`].
    pub key: &'static str,
    pub section: Section,
    /// The long command-line flag, without its `--`.
    pub flag: &'static str,
    /// What `--help` shows as the value: `N`, `NUMBER`, `WxH`, `NAME`.
    pub value_name: &'static str,
    pub help: &'static str,
    pub range: Range,
    pub role: Role,
    pub header: Header,
    /// Reads the flag's value into the overrides (or says why it cannot).
    pub read_flag: fn(&str, &mut SettingOverrides) -> Result<(), SettingError>,
    /// Reads the TOML value into the settings (or says why it cannot).
    pub read_toml: fn(&toml::Value, &mut RenderDesc) -> Result<(), SettingError>,
    /// Says why the setting's value is out of range, if it is.
    pub check: fn(&RenderDesc) -> Result<(), SettingError>,
    /// The value as the header, the identity and the checkpoint write it.
    pub show: fn(&RenderDesc) -> String,
}

impl Setting {
    /// The header attribute this setting is written to, unless another setting's
    /// attribute holds it.
    pub fn attribute(&self) -> Option<String> {
        match self.header {
            Header::Setting => Some(setting_attribute(self.key)),
            Header::Named(name) => Some(name.to_string()),
            Header::Within(_) => None,
        }
    }

    /// `--help`'s text: the help, the valid values and the default.
    pub fn help_line(&self) -> String {
        let range = match self.range {
            Range::Any => String::new(),
            r => format!(" Must be {}.", r.describe()),
        };
        let default = (self.show)(&RenderDesc::default());
        format!(
            "{}{range} [scene default: {default}; [{}] {}]",
            self.help,
            self.section.name(),
            self.key
        )
    }
}

/// The setting of TOML key `key` in `section`.
pub fn find(section: Section, key: &str) -> Option<&'static Setting> {
    SETTINGS
        .iter()
        .find(|s| s.section == section && s.key == key)
}

/// Why `key` is no key of `section`: the keys it has, and the one meant if it is a typo.
pub fn unknown_key(section: Section, key: &str) -> String {
    let keys: Vec<&str> = SETTINGS
        .iter()
        .filter(|s| s.section == section)
        .map(|s| s.key)
        .collect();
    format!(
        "unknown key '{key}' in [{}]: expected one of {}{}",
        section.name(),
        keys.join(", "),
        crate::suggest::did_you_mean(key, keys.iter().copied())
    )
}

/// Every setting in range, and the settings agreeing with each other.
pub fn check(render: &RenderDesc) -> Result<(), SettingError> {
    for s in SETTINGS {
        (s.check)(render)?;
    }
    check_together(render)
}

/// What one setting's range cannot say: the settings that must agree with each other.
pub fn check_together(render: &RenderDesc) -> Result<(), SettingError> {
    if let Some(min_spp) = render.min_spp {
        if min_spp > render.spp {
            return Err(SettingError::MinSppAboveSpp {
                min_spp,
                spp: render.spp,
            });
        }
    }
    Ok(())
}

/// The settings that change what a pixel converges to, with their values: what a
/// scene's identity includes besides its files.
pub fn identity_pairs(render: &RenderDesc) -> Vec<(&'static str, String)> {
    SETTINGS
        .iter()
        .filter(|s| s.role == Role::Identity)
        .map(|s| (s.key, (s.show)(render)))
        .collect()
}

/// Every setting with its value, for what must match exactly (a checkpoint).
pub fn all_pairs(render: &RenderDesc) -> Vec<(&'static str, String)> {
    SETTINGS.iter().map(|s| (s.key, (s.show)(render))).collect()
}

/// The header attributes of the settings.
pub fn header_attributes(render: &RenderDesc) -> Vec<(String, String)> {
    SETTINGS
        .iter()
        .filter_map(|s| Some((s.attribute()?, (s.show)(render))))
        .collect()
}

/// The command-line flag (without `--`) of the setting a header attribute records, for
/// messages that name an attribute a user did not write.
pub fn flag_of_attribute(attribute: &str) -> Option<&'static str> {
    SETTINGS
        .iter()
        .find(|s| s.attribute().as_deref() == Some(attribute))
        .map(|s| s.flag)
}

/// The header attributes of settings in which the parts of one frame differ by design.
pub fn per_part_attributes() -> impl Iterator<Item = String> {
    SETTINGS
        .iter()
        .filter(|s| s.role == Role::PerPart)
        .filter_map(Setting::attribute)
}

/// A type a setting can have: how the command line and TOML write its values.
pub trait Value: Sized {
    /// What a value is, in messages: `a whole number`.
    const EXPECTED: &'static str;
    /// The same for the command line, where a value may be written differently.
    const EXPECTED_FLAG: &'static str = Self::EXPECTED;
    const VALUE_NAME: &'static str;
    /// The names a choice accepts (none for numbers).
    const CHOICES: &'static [&'static str] = &[];
    fn from_text(text: &str) -> Option<Self>;
    fn from_toml(value: &toml::Value) -> Option<Self>;
    fn show(&self) -> String;
    /// The numbers a range applies to.
    fn numbers(&self) -> Vec<f64>;
}

fn from_flag<T: Value>(key: &'static str, range: Range, text: &str) -> Result<T, SettingError> {
    let value = T::from_text(text.trim())
        .ok_or_else(|| unreadable::<T>(key, range, T::EXPECTED_FLAG, text))?;
    check_value(key, range, &value)?;
    Ok(value)
}

fn from_toml<T: Value>(
    key: &'static str,
    range: Range,
    value: &toml::Value,
) -> Result<T, SettingError> {
    let written = match value {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    };
    let v =
        T::from_toml(value).ok_or_else(|| unreadable::<T>(key, range, T::EXPECTED, &written))?;
    check_value(key, range, &v)?;
    Ok(v)
}

/// A value that is not of the setting's type: a choice names its choices, a number what
/// it must be.
fn unreadable<T: Value>(
    key: &'static str,
    range: Range,
    expected: &'static str,
    written: &str,
) -> SettingError {
    if !T::CHOICES.is_empty() {
        return SettingError::UnknownChoice {
            key,
            written: written.to_string(),
            choices: T::CHOICES,
            suggestion: crate::suggest::did_you_mean(written, T::CHOICES.iter().copied()),
        };
    }
    SettingError::NotOfType {
        key,
        expected,
        range: range.describe(),
        written: written.to_string(),
    }
}

fn check_value<T: Value>(key: &'static str, range: Range, value: &T) -> Result<(), SettingError> {
    let numbers = value.numbers();
    if numbers.iter().any(|x| !x.is_finite()) {
        return Err(SettingError::NotFinite {
            key,
            value: value.show(),
        });
    }
    if numbers.iter().all(|&x| range.contains(x)) {
        Ok(())
    } else {
        Err(SettingError::OutOfRange {
            key,
            range: range.describe(),
            value: value.show(),
        })
    }
}

/// A TOML integer as any integer type it fits.
fn toml_integer<T: TryFrom<i64>>(value: &toml::Value) -> Option<T> {
    value.as_integer().and_then(|i| T::try_from(i).ok())
}

impl Value for u32 {
    const EXPECTED: &'static str = "a whole number";
    const VALUE_NAME: &'static str = "N";
    fn from_text(text: &str) -> Option<Self> {
        text.parse().ok()
    }
    fn from_toml(value: &toml::Value) -> Option<Self> {
        toml_integer(value)
    }
    fn show(&self) -> String {
        self.to_string()
    }
    fn numbers(&self) -> Vec<f64> {
        vec![*self as f64]
    }
}

impl Value for u64 {
    const EXPECTED: &'static str = "a whole number";
    const VALUE_NAME: &'static str = "N";
    fn from_text(text: &str) -> Option<Self> {
        text.parse().ok()
    }
    fn from_toml(value: &toml::Value) -> Option<Self> {
        toml_integer(value)
    }
    fn show(&self) -> String {
        self.to_string()
    }
    fn numbers(&self) -> Vec<f64> {
        // Any u64 is a seed; ranges of u64 settings are not checked.
        Vec::new()
    }
}

/// A count with no limit unless set (`none` in the header).
impl Value for Option<u32> {
    const EXPECTED: &'static str = "a whole number";
    const VALUE_NAME: &'static str = "N";
    fn from_text(text: &str) -> Option<Self> {
        text.parse().ok().map(Some)
    }
    fn from_toml(value: &toml::Value) -> Option<Self> {
        toml_integer(value).map(Some)
    }
    fn show(&self) -> String {
        self.map_or("none".to_string(), |v| v.to_string())
    }
    fn numbers(&self) -> Vec<f64> {
        self.iter().map(|&v| v as f64).collect()
    }
}

impl Value for f32 {
    const EXPECTED: &'static str = "a number";
    const VALUE_NAME: &'static str = "NUMBER";
    fn from_text(text: &str) -> Option<Self> {
        text.parse().ok()
    }
    fn from_toml(value: &toml::Value) -> Option<Self> {
        match value {
            toml::Value::Float(f) => Some(*f as f32),
            toml::Value::Integer(i) => Some(*i as f32),
            _ => None,
        }
    }
    fn show(&self) -> String {
        self.to_string()
    }
    fn numbers(&self) -> Vec<f64> {
        vec![*self as f64]
    }
}

/// A number that may be unset (`none` in the header).
impl Value for Option<f32> {
    const EXPECTED: &'static str = "a number";
    const VALUE_NAME: &'static str = "NUMBER";
    fn from_text(text: &str) -> Option<Self> {
        text.parse().ok().map(Some)
    }
    fn from_toml(value: &toml::Value) -> Option<Self> {
        <f32 as Value>::from_toml(value).map(Some)
    }
    fn show(&self) -> String {
        self.map_or("none".to_string(), |v| v.to_string())
    }
    fn numbers(&self) -> Vec<f64> {
        self.iter().map(|&v| v as f64).collect()
    }
}

/// A USD prim path that may be unset (`none` in the header).
impl Value for Option<String> {
    const EXPECTED: &'static str = "an absolute prim path (e.g. /Render/Settings)";
    const VALUE_NAME: &'static str = "PATH";
    fn from_text(text: &str) -> Option<Self> {
        text.starts_with('/').then(|| Some(text.to_string()))
    }
    fn from_toml(value: &toml::Value) -> Option<Self> {
        Self::from_text(value.as_str()?)
    }
    fn show(&self) -> String {
        self.clone().unwrap_or_else(|| "none".to_string())
    }
    fn numbers(&self) -> Vec<f64> {
        Vec::new()
    }
}

/// A film size: `WxH` on the command line, `[w, h]` in TOML.
impl Value for [u32; 2] {
    const EXPECTED: &'static str = "[width, height] in whole numbers";
    const EXPECTED_FLAG: &'static str = "WIDTHxHEIGHT in whole numbers (e.g. 640x480)";
    const VALUE_NAME: &'static str = "WxH";
    fn from_text(text: &str) -> Option<Self> {
        let (w, h) = text.split_once(['x', 'X'])?;
        Some([w.trim().parse().ok()?, h.trim().parse().ok()?])
    }
    fn from_toml(value: &toml::Value) -> Option<Self> {
        match value.as_array()?.as_slice() {
            [w, h] => Some([toml_integer(w)?, toml_integer(h)?]),
            _ => None,
        }
    }
    fn show(&self) -> String {
        format!("{}x{}", self[0], self[1])
    }
    fn numbers(&self) -> Vec<f64> {
        self.iter().map(|&v| v as f64).collect()
    }
}

/// A setting that is one of a few names.
macro_rules! choice {
    ($ty:ty) => {
        impl Value for $ty {
            const EXPECTED: &'static str = "a name";
            const VALUE_NAME: &'static str = "NAME";
            const CHOICES: &'static [&'static str] = &<$ty>::NAMES;
            fn from_text(text: &str) -> Option<Self> {
                <$ty>::parse(text)
            }
            fn from_toml(value: &toml::Value) -> Option<Self> {
                <$ty>::parse(value.as_str()?)
            }
            fn show(&self) -> String {
                self.name().to_string()
            }
            fn numbers(&self) -> Vec<f64> {
                Vec::new()
            }
        }
    };
}

choice!(SamplerKind);
choice!(LightSelection);
choice!(FilterKind);
choice!(GuidingMode);
choice!(VolumeSampling);
choice!(LightConnections);
choice!(GlintSampling);

#[cfg(test)]
mod tests;
