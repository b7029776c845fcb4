//! `lightpath denoise`: every light AOV of an EXR filtered with Intel Open Image Denoise,
//! the partitions the file declares still adding up afterwards.
//!
//! OIDN's recommended final-frame setup: the `albedo` and `normal` AOVs are prefiltered
//! once (each by an `RT` filter of its own) and every filter then takes them as clean
//! auxiliary images (`cleanAux`), so their noise is not read as detail. Beauty is filtered
//! at `high`; every other AOV at the job's quality (`--quality`, default `fast`: 2–4× less
//! CPU than `high`, for AOVs that are comped rather than looked at whole), and
//! so are the two prefilters (see [`Filter::prefilter`]). Filters are
//! made one at a time, in the order beauty, AOVs as they are, AOVs divided by albedo, so
//! OIDN's working memory is one filter's.
//!
//! Per AOV (its kind from the header's `lightpath/kind/<name>`, see `aov::naming`):
//! - light AOVs are filtered with OIDN's `RT` filter (HDR), with the `albedo` and `normal`
//!   AOVs as auxiliary images. Following RenderMan's naming convention, AOVs whose names
//!   start with `diffuse`, `directDiffuse`, `indirectDiffuse` or `subsurface` are divided
//!   by the albedo first (textures do not smear) and multiplied back after, with a white
//!   albedo as their auxiliary image; the others (`specular…`, `emission`, light-group
//!   parts of beauty, user AOVs) are filtered as they are. Light-group parts are filtered
//!   one by one, like any AOV; an AOV split by light group (beauty excepted) is then the
//!   sum of its denoised groups, as a compositor rebuilds it, instead of a filter run of
//!   its own. Likewise `diffuse` and `specular` (and each of their light-group parts) are
//!   the sums of their denoised standard parts (`directDiffuse + indirectDiffuse +
//!   subsurface`, `lpe::STANDARD_SUMS`) where the noisy file adds up that way to
//!   [`SUM_TOLERANCE`]: they are made after reconciliation, so they stay those sums in the
//!   output. An AOV that is zero (or one constant) everywhere stays as
//!   it is (no filtering), and so does one already converged: where the file holds its
//!   variance (`<aov>_var`, `--variance`), an AOV whose noise (the root mean variance of
//!   its pixel means) is below [`CONVERGED_NOISE`] of its mean level, in every channel.
//! - emission seen directly (`emission`, `bounce0`) is kept as rendered: it has only
//!   antialiasing noise, and filtering blurs a light's HDR edges into its surroundings.
//!   Beauty is filtered without it (`beauty − emission`) and gets it back after.
//! - data (albedo, normal, depth), variance (`<aov>_var`, describing the noisy input) and
//!   alpha are kept as they are; the derived shadow matte is recomputed from the
//!   denoised `occluded` and `unoccluded`.
//! - Reconciliation: filtering each AOV alone breaks additivity. The whole of each
//!   declared partition is authoritative (beauty is the image with the most signal);
//!   its parts are scaled, per pixel and channel, by `whole / Σ parts`, so they sum to it
//!   to float rounding (emission parts keep their value and the others share the rest,
//!   wherever the whole holds it). Where the denoised parts hold (almost) nothing of a whole that is
//!   not zero (`Σ parts < 10⁻³·whole`), the whole is shared in the noisy parts'
//!   proportions (equally if those are zero too). Wholes are reconciled before their own
//!   parts (beauty, then `directDiffuse`, then `directDiffuse_<group>`), and denoised
//!   light is clamped at zero first. Parts kept as they are (emission, zero, constant or
//!   converged AOVs) keep their values exactly: where the whole is below them, or no part
//!   was filtered, what the parts cannot hold goes to an explicit remainder AOV,
//!   `<whole>__remainder_<kind>`, declared a part of the partition (written only where
//!   needed). So `lightpath aovs` passes on the result, and
//!   relighting with `comp --gain` from the denoised light groups equals the denoised
//!   beauty when every gain is 1.

use crate::aov::naming::{self, channel_names, AovKind};
use crate::error::{DenoiseFault, OidnError, PostError};
use crate::output::{read_exr, stage_image, ExrContents, ExrOptions};
use crate::progress::{Progress, Silent, Task};
use std::collections::HashMap;
use std::path::PathBuf;

/// What a build without the `denoise` feature says when asked to denoise.
pub const UNAVAILABLE: &str = "this lightpath was built without denoising (cargo feature \
`denoise`, Intel Open Image Denoise). To get it: `pip install --no-deps pyoidn==2.5.1.0`, then \
`export OIDN_DIR=\"$(python3 -c 'import importlib.util, os; \
print(os.path.dirname(importlib.util.find_spec(\"pyoidn\").origin))')/oidn\"` and \
`cargo install --path crates/lightpath --features denoise` (or `cargo run --release \
--features denoise -- …`); any Open Image Denoise 2.x install works as OIDN_DIR";

/// Whether this build can denoise.
pub const AVAILABLE: bool = cfg!(feature = "denoise");

/// The albedo below which a pixel's channel is not divided (divided by this instead):
/// dark surfaces reflect little light, and dividing by a near-zero albedo would magnify
/// their noise.
const MIN_ALBEDO: f32 = 0.01;

/// OIDN's quality setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Quality {
    /// The best images (OIDN's default for final frames): always the beauty's.
    High,
    Balanced,
    /// A smaller network: 2–4× less CPU than `high` (1080p: 2.9 against 12.7 CPU-s,
    /// docs/performance.md). The default for AOVs other than
    /// beauty (`--quality`).
    #[default]
    Fast,
}

/// The quality beauty is always filtered at, whatever `--quality` says of the AOVs.
pub const BEAUTY_QUALITY: Quality = Quality::High;

/// An AOV whose noise is below this fraction of its mean level in every channel is left
/// as it is: half a step of an 8-bit display at the AOV's mean level (1/512), noise no
/// viewer sees and a filter could only blur.
pub const CONVERGED_NOISE: f64 = 1.0 / 512.0;

/// How closely a file's noisy AOV must equal the sum of its standard parts, relative to
/// its value (at least 10⁻³), in every pixel and channel, for the denoised AOV to be made
/// as the sum of the denoised parts: thirty times the float rounding of the renderer's
/// sums (≤ 3·10⁻⁷ on a 1080p, 44-AOV frame), far below any AOV that differs from the sum.
pub const SUM_TOLERANCE: f32 = 1e-5;

impl Quality {
    pub fn parse(s: &str) -> Result<Quality, crate::error::InvalidValue> {
        match s {
            "high" => Ok(Quality::High),
            "balanced" => Ok(Quality::Balanced),
            "fast" => Ok(Quality::Fast),
            other => Err(crate::error::InvalidValue(format!(
                "unknown quality '{other}': expected high, balanced or fast"
            ))),
        }
    }
    pub fn as_str(self) -> &'static str {
        match self {
            Quality::High => "high",
            Quality::Balanced => "balanced",
            Quality::Fast => "fast",
        }
    }
}

/// One `lightpath denoise` run.
#[derive(Clone, Debug)]
pub struct DenoiseJob {
    pub input: PathBuf,
    pub output: PathBuf,
    /// Keep each filtered AOV's input as `<aov>_noisy`.
    pub keep_noisy: bool,
    /// The quality of every AOV but beauty (always [`BEAUTY_QUALITY`]).
    pub quality: Quality,
    /// Exposure of the PNG preview of the denoised beauty written beside the output, in
    /// stops.
    pub preview_exposure: f32,
}

/// How one AOV is treated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Treatment {
    /// Divided by the albedo, filtered with a white albedo, multiplied back.
    AlbedoDivided,
    /// Filtered as it is, with the albedo and normal.
    AsIs,
    /// Kept as it is (data, variance, AOVs of unknown kind…).
    Kept,
    /// Recomputed from denoised AOVs (the shadow matte).
    Recomputed,
    /// Emission seen directly (`emission`, `bounce0`): kept as it is. It has no Monte
    /// Carlo noise beyond antialiasing, and a denoiser blurs its HDR edges (a light of
    /// radiance 18 next to a wall of 0.5 lost a third of its value at 16 spp).
    Emission,
}

/// What `run` did.
#[derive(Clone, Debug, Default)]
pub struct DenoiseSummary {
    /// AOVs filtered (zero AOVs excluded).
    pub filtered: usize,
    /// Light AOVs that were zero (or one constant) everywhere, left as they are.
    pub zero: usize,
    /// Light AOVs whose variance says they are converged, left as they are.
    pub converged: usize,
    /// Wholes split by light group made as the sum of their denoised groups.
    pub summed: usize,
    /// AOVs made as the sum of their denoised standard parts (`lpe::STANDARD_SUMS`).
    pub derived: usize,
    /// Remainder AOVs written to keep partitions summing.
    pub remainders: usize,
    /// Partitions reconciled.
    pub partitions: usize,
    /// Auxiliary images used: albedo, normal.
    pub albedo: bool,
    pub normal: bool,
    pub seconds: f64,
}

impl DenoiseSummary {
    /// The line `lightpath denoise` prints.
    pub fn line(&self) -> String {
        let aux = match (self.albedo, self.normal) {
            (true, true) => "albedo and normal",
            (true, false) => "albedo only (no normal AOV)",
            _ => "no auxiliary images (no albedo AOV)",
        };
        format!(
            "denoised {} AOVs ({} more as sums of their light groups and {} as sums of their \
             standard parts; {} zero or constant and {} converged AOVs left as they are) with \
             {aux}, {} partitions reconciled ({} remainders): {:.2} s",
            self.filtered,
            self.summed,
            self.derived,
            self.zero,
            self.converged,
            self.partitions,
            self.remainders,
            self.seconds
        )
    }
}

/// The treatment of each AOV of an EXR, by name, in the header's order.
pub fn plan(exr: &ExrContents) -> Vec<(String, Treatment)> {
    let names: Vec<String> = exr.aovs().into_iter().map(|(n, _)| n).collect();
    let has = |n: &str| names.iter().any(|m| m == n);
    let albedo = has(naming::ALBEDO);
    names
        .iter()
        .map(|name| {
            let kind = naming::kind_of(&exr.attributes, name).unwrap_or_else(|| {
                // Files written before kinds were recorded: the standard data AOVs.
                if [naming::ALBEDO, naming::NORMAL, naming::DEPTH].contains(&name.as_str()) {
                    AovKind::Data
                } else {
                    AovKind::Light
                }
            });
            let t = match kind {
                AovKind::Light if is_emission(name) => Treatment::Emission,
                AovKind::Light if albedo && naming::is_albedo_divided(name) => {
                    Treatment::AlbedoDivided
                }
                AovKind::Light => Treatment::AsIs,
                AovKind::Derived
                    if name == naming::SHADOW
                        && has(naming::OCCLUDED)
                        && has(naming::UNOCCLUDED) =>
                {
                    Treatment::Recomputed
                }
                _ => Treatment::Kept,
            };
            (name.clone(), t)
        })
        .collect()
}

/// Whether AOV `name` is emission seen directly: the standard `emission` (`CO`) or the
/// bounce partition's `bounce0` (`C[<L.>O]`).
fn is_emission(name: &str) -> bool {
    name == EMISSION || name == naming::bounce_name(0)
}

/// The standard AOV of emission seen directly.
const EMISSION: &str = "emission";

/// RGB planes of one AOV.
type Planes = [Vec<f32>; 3];

/// RGB planes of one AOV of the input file, borrowed (no copy of what is only read).
type View<'a> = [&'a [f32]; 3];

/// The planes as a [`View`].
fn view(p: &Planes) -> View<'_> {
    [&p[0], &p[1], &p[2]]
}

/// An EXR's named channels.
type Channels = Vec<(String, Vec<f32>)>;

/// How one AOV is filtered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct How {
    /// The input was divided by the albedo: filter it with a white albedo.
    pub albedo_divided: bool,
    pub quality: Quality,
}

/// An image filter over interleaved RGB of the file's size: OIDN, or a stand-in in
/// tests.
pub trait Filter {
    /// Prefilters the auxiliary images in place, once, before any AOV is filtered, at
    /// the AOVs' quality: albedo and normal are noisy only where a pixel's samples see
    /// different surfaces, and at `fast` the two prefilters of a 1080p frame cost 6 CPU-s
    /// instead of 26 (the beauty's RMSE against a reference moves by under 1 %,
    /// docs/performance.md).
    fn prefilter(&mut self, aux: &mut Aux, quality: Quality) -> Result<(), DenoiseFault>;
    /// Filters one image with the (prefiltered) auxiliary images.
    fn filter(&mut self, rgb: &mut [f32], how: How, aux: &Aux) -> Result<(), OidnError>;
}

/// The auxiliary images, interleaved RGB: albedo clamped to [0, 1], normal as rendered.
pub struct Aux {
    pub albedo: Option<Vec<f32>>,
    pub normal: Option<Vec<f32>>,
}

fn interleave(p: View) -> Vec<f32> {
    let mut out = Vec::new();
    interleave_into(p, &mut out);
    out
}

/// `p` interleaved into `out` (its allocation reused: no fresh pages per AOV).
fn interleave_into(p: View, out: &mut Vec<f32>) {
    out.clear();
    out.reserve(p[0].len() * 3);
    for ((r, g), b) in p[0].iter().zip(p[1]).zip(p[2]) {
        out.extend([*r, *g, *b]);
    }
}

/// AOV `aov`'s planes in the file, if it has all three.
fn planes_in<'a>(exr: &'a ExrContents, aov: &str) -> Option<View<'a>> {
    let names = channel_names(aov);
    let get = |c: usize| exr.channel(&names[c]);
    Some([get(0)?, get(1)?, get(2)?])
}

/// The auxiliary images of an EXR: its `albedo` and `normal` AOVs.
pub fn aux_images(exr: &ExrContents) -> Aux {
    let albedo = planes_in(exr, naming::ALBEDO).map(|p| {
        let mut v = interleave(p);
        v.iter_mut().for_each(|a| {
            *a = if a.is_finite() {
                a.clamp(0.0, 1.0)
            } else {
                0.0
            }
        });
        v
    });
    let normal = albedo.as_ref().and_then(|_| {
        planes_in(exr, naming::NORMAL).map(|p| {
            let mut v = interleave(p);
            v.iter_mut().for_each(|n| {
                *n = if n.is_finite() {
                    n.clamp(-1.0, 1.0)
                } else {
                    0.0
                }
            });
            v
        })
    });
    Aux { albedo, normal }
}

/// Filters one AOV: sanitises it (non-finite → 0, negative → 0), divides by the albedo
/// if asked, filters, multiplies back and clamps at zero. `rgb` is the interleaved
/// image's buffer, reused from one AOV to the next.
fn filter_aov(
    planes: View,
    treatment: Treatment,
    quality: Quality,
    aux: &Aux,
    filter: &mut dyn Filter,
    rgb: &mut Vec<f32>,
) -> Result<Planes, OidnError> {
    interleave_into(planes, rgb);
    for v in rgb.iter_mut() {
        if !v.is_finite() || *v < 0.0 {
            *v = 0.0;
        }
    }
    let albedo = aux.albedo.as_deref();
    let divide = treatment == Treatment::AlbedoDivided && albedo.is_some();
    if let (true, Some(a)) = (divide, albedo) {
        for (v, a) in rgb.iter_mut().zip(a) {
            *v /= a.max(MIN_ALBEDO);
        }
    }
    let how = How {
        albedo_divided: divide,
        quality,
    };
    filter.filter(rgb, how, aux)?;
    if let (true, Some(a)) = (divide, albedo) {
        for (v, a) in rgb.iter_mut().zip(a) {
            *v *= a.max(MIN_ALBEDO);
        }
    }
    let n = planes[0].len();
    let mut out = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
    for (i, px) in rgb.chunks_exact(3).enumerate() {
        for c in 0..3 {
            out[c][i] = if px[c].is_finite() {
                px[c].max(0.0)
            } else {
                0.0
            };
        }
    }
    Ok(out)
}

/// `a − b`, channel by channel.
fn minus(a: View, b: View) -> Planes {
    [0, 1, 2].map(|c| a[c].iter().zip(b[c]).map(|(x, y)| x - y).collect())
}

/// One declared partition: a whole and its parts.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Partition {
    pub whole: String,
    pub kind: naming::PartitionKind,
    pub parts: Vec<String>,
}

/// The partitions an EXR's header declares, wholes before their own parts' partitions
/// (a whole that is itself a part comes after the partition it is in).
pub fn partitions(exr: &ExrContents) -> Vec<Partition> {
    let mut sorted = naming::parts_from_attributes(&exr.attributes);
    let whole_of: HashMap<String, String> = sorted
        .iter()
        .map(|p| (p.name.clone(), p.whole.clone()))
        .collect();
    // Ancestors of a name (bounded: a malformed header could hold a cycle).
    let depth = |name: &str| {
        let (mut n, mut d) = (name.to_string(), 0);
        while let Some(w) = whole_of.get(&n) {
            n = w.clone();
            d += 1;
            if d > whole_of.len() {
                break;
            }
        }
        d
    };
    let mut groups: Vec<(usize, String, naming::PartitionKind, Vec<String>)> = Vec::new();
    sorted.sort_by_key(|p| (p.whole.clone(), p.kind, naming::part_order(p)));
    for p in sorted {
        match groups.last_mut() {
            Some((_, w, k, names)) if *w == p.whole && *k == p.kind => names.push(p.name),
            _ => groups.push((depth(&p.whole), p.whole.clone(), p.kind, vec![p.name])),
        }
    }
    groups.sort_by(|a, b| (a.0, &a.1, a.2).cmp(&(b.0, &b.1, b.2)));
    groups
        .into_iter()
        .map(|(_, whole, kind, parts)| Partition { whole, kind, parts })
        .collect()
}

/// Scales `parts` so they sum to `whole`, per pixel and channel (see the module doc);
/// `noisy` are the parts before filtering, for pixels where the filtered parts are empty.
/// `fixed` parts (kept as rendered) keep their value; the others share the rest of the
/// whole. What the free parts cannot hold (the whole below the fixed parts, or no free
/// part) is returned as the remainder, `None` where it is zero everywhere.
pub fn reconcile(
    whole: &Planes,
    parts: &mut [&mut Planes],
    noisy: &[View],
    fixed: &[bool],
) -> Option<Planes> {
    let n = whole[0].len();
    let free: Vec<usize> = (0..parts.len()).filter(|k| !fixed[*k]).collect();
    let mut remainder: Option<Planes> = None;
    for c in 0..3 {
        for i in 0..n {
            let kept: f32 = (0..parts.len())
                .filter(|k| fixed[*k])
                .map(|k| parts[k][c][i])
                .sum();
            let w = whole[c][i] - kept;
            if w < 0.0 || free.is_empty() {
                free.iter().for_each(|&k| parts[k][c][i] = 0.0);
                if w != 0.0 {
                    let r = remainder.get_or_insert_with(|| [0, 1, 2].map(|_| vec![0.0; n]));
                    r[c][i] = w;
                }
                continue;
            }
            let sum: f32 = free.iter().map(|&k| parts[k][c][i]).sum();
            if sum > 0.0 && sum >= 1e-3 * w {
                let s = w / sum;
                free.iter().for_each(|&k| parts[k][c][i] *= s);
                continue;
            }
            let noisy_sum: f32 = free.iter().map(|&k| noisy[k][c][i].max(0.0)).sum();
            for &k in &free {
                parts[k][c][i] = if noisy_sum > 0.0 {
                    w * noisy[k][c][i].max(0.0) / noisy_sum
                } else {
                    w / free.len() as f32
                };
            }
        }
    }
    remainder
}

/// Denoises an EXR's contents with `filter`: the output's channels and attributes.
/// `aux` (from [`aux_images`]) is prefiltered first; `quality` is every AOV's but
/// beauty's; `progress` counts filter runs.
pub fn denoise_contents(
    exr: &ExrContents,
    mut aux: Aux,
    filter: &mut dyn Filter,
    options: ContentOptions,
    summary: &mut DenoiseSummary,
    progress: &dyn Progress,
) -> Result<(Channels, Vec<(String, String)>), DenoiseFault> {
    if exr
        .attributes
        .iter()
        .any(|(k, _)| k == naming::DENOISED_ATTRIBUTE)
    {
        return Err(DenoiseFault::AlreadyDenoised);
    }
    let plan = plan(exr);
    summary.albedo = aux.albedo.is_some();
    summary.normal = aux.normal.is_some();
    let work = work(exr, &plan, summary);
    let pixels = (exr.width * exr.height) as u64;
    let prefilters = aux.albedo.iter().chain(&aux.normal).count() as u64;
    progress.task(Task::DENOISE);
    progress.start(prefilters + work.filter.len() as u64, 0);
    filter.prefilter(&mut aux, options.quality)?;
    progress.advance(prefilters, prefilters * pixels);
    let (mut noisy, mut denoised) =
        filter_aovs(exr, &work, &aux, filter, options.quality, progress)?;
    progress.finish();
    let mut attributes = exr.attributes.clone();
    // Partitions of the derived AOVs are reconciled once those are made, from their
    // reconciled parts.
    let (mut remainders, waiting) =
        reconcile_partitions(exr, partitions(exr), &noisy, &mut denoised, &work, summary);
    insert_sums(exr, &work.derived, &mut noisy, &mut denoised);
    remainders.extend(reconcile_partitions(exr, waiting, &noisy, &mut denoised, &work, summary).0);
    for r in &mut remainders {
        attributes.extend(r.attributes());
        denoised.insert(r.name.clone(), std::mem::take(&mut r.planes));
    }
    if plan
        .iter()
        .any(|(n, t)| n == naming::SHADOW && *t == Treatment::Recomputed)
    {
        let matte = shadow_matte_of(exr, &denoised);
        denoised.insert(naming::SHADOW.into(), matte);
    }
    // Every input channel, the denoised AOVs' replaced (moved, not copied); remainders
    // after them.
    let mut replaced: HashMap<String, Vec<f32>> = HashMap::new();
    for (name, planes) in denoised {
        for (ch, v) in channel_names(&name).into_iter().zip(planes) {
            replaced.insert(ch, v);
        }
    }
    let mut channels: Vec<(String, Vec<f32>)> = exr
        .channels
        .iter()
        .map(|(n, v)| (n.clone(), replaced.remove(n).unwrap_or_else(|| v.clone())))
        .collect();
    for r in &remainders {
        for ch in channel_names(&r.name) {
            if let Some(v) = replaced.remove(&ch) {
                channels.push((ch, v));
            }
        }
    }
    if options.keep_noisy {
        keep_noisy_aovs(exr, &noisy, &mut channels, &mut attributes)?;
    }
    attributes.push((
        naming::DENOISED_ATTRIBUTE.into(),
        describe(summary, options.quality),
    ));
    Ok((channels, attributes))
}

/// What [`denoise_contents`] is asked besides the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ContentOptions {
    /// Keep each filtered AOV's input as `<aov>_noisy`.
    pub keep_noisy: bool,
    /// The quality of every AOV but beauty.
    pub quality: Quality,
}

/// Each AOV the plan filters or keeps, by name, as it goes out.
type AovPlanes = HashMap<String, Planes>;

/// The same AOVs as read (the noisy input), borrowed from the file.
type NoisyPlanes<'a> = HashMap<String, View<'a>>;

/// The light AOVs of a file, sorted by what is done with them.
struct Work {
    /// Filtered, in the order filters are made: beauty, AOVs as they are, AOVs divided
    /// by albedo (so each filter is made once).
    filter: Vec<(String, Treatment)>,
    /// Kept as rendered: emission, and AOVs zero, constant or converged everywhere.
    kept: std::collections::HashSet<String>,
    /// Wholes split by light group (beauty excepted) made as the sum of their denoised
    /// parts, with those parts.
    summed: Vec<(String, Vec<String>)>,
    /// AOVs made, after reconciliation, as the sum of their denoised standard parts
    /// (those in the file), with those parts.
    derived: Vec<(String, Vec<String>)>,
}

fn work(exr: &ExrContents, plan: &[(String, Treatment)], summary: &mut DenoiseSummary) -> Work {
    let mut filter = Vec::new();
    let mut kept = std::collections::HashSet::new();
    for (name, t) in plan {
        if !matches!(
            t,
            Treatment::AsIs | Treatment::AlbedoDivided | Treatment::Emission
        ) {
            continue;
        }
        let Some(p) = planes_in(exr, name) else {
            continue;
        };
        if *t == Treatment::Emission {
            kept.insert(name.clone());
        } else if p.iter().all(|c| c.iter().all(|v| *v == c[0])) {
            // Zero or constant everywhere: no noise to remove (and no OIDN run to pay).
            summary.zero += 1;
            kept.insert(name.clone());
        } else if converged(exr, name, p) {
            summary.converged += 1;
            kept.insert(name.clone());
        } else {
            filter.push((name.clone(), *t));
        }
    }
    // A whole split by light group is what a compositor rebuilds from its groups: the
    // sum of the denoised parts, one OIDN run fewer per split AOV. Beauty, the image
    // looked at whole, is filtered itself (at high) and stays authoritative.
    let mut summed = Vec::new();
    for p in partitions(exr) {
        let filtered = filter.iter().position(|(n, _)| *n == p.whole);
        let complete = p.parts.iter().all(|n| planes_in(exr, n).is_some());
        if p.kind != naming::PartitionKind::LightGroups || p.whole == naming::BEAUTY || !complete {
            continue;
        }
        if let Some(i) = filtered {
            filter.remove(i);
            summed.push((p.whole, p.parts));
        }
    }
    let derived = standard_sums(exr, &mut filter, &mut summed, &kept);
    filter.sort_by_key(|(name, t)| (name != naming::BEAUTY, *t == Treatment::AlbedoDivided));
    summary.filtered = filter.len();
    summary.summed = summed.len();
    summary.derived = derived.len();
    Work {
        filter,
        kept,
        summed,
        derived,
    }
}

/// The AOVs to be filtered or summed from their light groups that the file shows to be
/// the sum of their standard parts (`lpe::STANDARD_SUMS`: `diffuse`, `specular`, and
/// each of their light-group parts `diffuse_<group>` from `directDiffuse_<group>`, …),
/// taken out of `filter` and `summed`: one OIDN run fewer each. Only where every part
/// the file has is denoised or kept, and the noisy AOV equals the sum of those parts to
/// [`SUM_TOLERANCE`] everywhere (a part the file lacks then holds nothing).
fn standard_sums(
    exr: &ExrContents,
    filter: &mut Vec<(String, Treatment)>,
    summed: &mut Vec<(String, Vec<String>)>,
    kept: &std::collections::HashSet<String>,
) -> Vec<(String, Vec<String>)> {
    let mut derived = Vec::new();
    let candidates: Vec<String> = filter
        .iter()
        .map(|(n, _)| n.clone())
        .chain(summed.iter().map(|(n, _)| n.clone()))
        .collect();
    for name in candidates {
        let Some((suffix, parts)) = lpe::STANDARD_SUMS.iter().find_map(|(whole, parts)| {
            let suffix = name.strip_prefix(whole)?;
            (suffix.is_empty() || suffix.starts_with('_')).then_some((suffix, parts))
        }) else {
            continue;
        };
        let parts: Vec<String> = parts
            .iter()
            .map(|p| format!("{p}{suffix}"))
            .filter(|p| planes_in(exr, p).is_some())
            .collect();
        let denoised = |p: &String| {
            kept.contains(p)
                || filter.iter().any(|(n, _)| n == p)
                || summed.iter().any(|(n, _)| n == p)
        };
        if parts.is_empty() || !parts.iter().all(denoised) || !adds_up(exr, &name, &parts) {
            continue;
        }
        filter.retain(|(n, _)| *n != name);
        summed.retain(|(n, _)| *n != name);
        derived.push((name, parts));
    }
    // A whole summed from light groups that are made so is made after them.
    let is_derived = |p: &String| derived.iter().any(|(d, _)| d == p);
    let (late, early): (Vec<_>, Vec<_>) = std::mem::take(summed)
        .into_iter()
        .partition(|(_, parts)| parts.iter().any(is_derived));
    *summed = early;
    derived.extend(late);
    derived
}

/// Whether AOV `whole` of the file equals the sum of `parts` to [`SUM_TOLERANCE`] in
/// every pixel and channel (non-finite values never do).
fn adds_up(exr: &ExrContents, whole: &str, parts: &[String]) -> bool {
    let names = channel_names(whole);
    (0..3).all(|c| {
        let Some(w) = exr.channel(&names[c]) else {
            return false;
        };
        let ps: Option<Vec<&[f32]>> = parts
            .iter()
            .map(|p| exr.channel(&channel_names(p)[c]))
            .collect();
        let Some(ps) = ps else {
            return false;
        };
        w.iter().enumerate().all(|(i, w)| {
            let sum: f32 = ps.iter().map(|p| p[i]).sum();
            (sum - w).abs() <= SUM_TOLERANCE * w.abs().max(1e-3)
        })
    })
}

/// Each of `sums` (an AOV and its parts) as the sum of its parts' denoised planes, with
/// its noisy input from the file: wholes split by light group, and the derived AOVs.
fn insert_sums<'a>(
    exr: &'a ExrContents,
    sums: &[(String, Vec<String>)],
    noisy: &mut NoisyPlanes<'a>,
    denoised: &mut AovPlanes,
) {
    for (name, parts) in sums {
        let Some(p) = planes_in(exr, name) else {
            continue;
        };
        let n = p[0].len();
        let mut sum: Planes = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        for part in parts {
            if let Some(q) = denoised.get(part) {
                for c in 0..3 {
                    sum[c].iter_mut().zip(&q[c]).for_each(|(s, v)| *s += v);
                }
            }
        }
        denoised.insert(name.clone(), sum);
        noisy.insert(name.clone(), p);
    }
}

/// Whether the file's variance of AOV `name` (its `<name>_var`, if written) says its
/// noise is below [`CONVERGED_NOISE`] of its mean level in every channel.
fn converged(exr: &ExrContents, name: &str, planes: View) -> bool {
    let Some(variance) = planes_in(exr, &naming::variance_name(name)) else {
        return false;
    };
    (0..3).all(|c| {
        let n = planes[c].len().max(1) as f64;
        let level = planes[c].iter().map(|v| v.abs() as f64).sum::<f64>() / n;
        let noise = (variance[c].iter().map(|v| v.max(0.0) as f64).sum::<f64>() / n).sqrt();
        level.is_finite() && noise.is_finite() && noise <= CONVERGED_NOISE * level
    })
}

/// Filters the work's AOVs; the kept ones go out as read (emission with negative and
/// non-finite values zeroed).
fn filter_aovs<'a>(
    exr: &'a ExrContents,
    work: &Work,
    aux: &Aux,
    filter: &mut dyn Filter,
    quality: Quality,
    progress: &dyn Progress,
) -> Result<(NoisyPlanes<'a>, AovPlanes), DenoiseFault> {
    let mut noisy = NoisyPlanes::new();
    let mut denoised = AovPlanes::new();
    for name in &work.kept {
        let Some(p) = planes_in(exr, name) else {
            continue;
        };
        let out = p.map(|c| {
            if is_emission(name) {
                c.iter()
                    .map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 })
                    .collect()
            } else {
                c.to_vec()
            }
        });
        denoised.insert(name.clone(), out);
        noisy.insert(name.clone(), p);
    }
    // Beauty is filtered without the emission seen directly, which is added back after.
    let emission = work
        .kept
        .contains(EMISSION)
        .then(|| planes_in(exr, EMISSION))
        .flatten();
    let pixels = (exr.width * exr.height) as u64;
    let mut rgb = Vec::new();
    for (name, t) in &work.filter {
        let Some(p) = planes_in(exr, name) else {
            continue;
        };
        let is_beauty = name == naming::BEAUTY;
        let quality = if is_beauty { BEAUTY_QUALITY } else { quality };
        let emission = emission.filter(|_| is_beauty);
        let out =
            filter_lit(p, *t, quality, emission, aux, filter, &mut rgb).map_err(|source| {
                DenoiseFault::Filtering {
                    aov: name.clone(),
                    source,
                }
            })?;
        progress.advance(1, pixels);
        denoised.insert(name.clone(), out);
        noisy.insert(name.clone(), p);
    }
    insert_sums(exr, &work.summed, &mut noisy, &mut denoised);
    Ok((noisy, denoised))
}

/// One AOV filtered; with `emission` (beauty's), that is taken out before and added
/// back after, so the light seen directly is not smeared into its surroundings.
fn filter_lit(
    p: View,
    t: Treatment,
    quality: Quality,
    emission: Option<View>,
    aux: &Aux,
    filter: &mut dyn Filter,
    rgb: &mut Vec<f32>,
) -> Result<Planes, OidnError> {
    let unlit = emission.map(|e| minus(p, e));
    let input = unlit.as_ref().map_or(p, view);
    let mut out = filter_aov(input, t, quality, aux, filter, rgb)?;
    if let Some(e) = emission {
        for c in 0..3 {
            for (o, e) in out[c].iter_mut().zip(e[c]) {
                *o += e.max(0.0);
            }
        }
    }
    Ok(out)
}

/// What a partition's parts kept as rendered could not hold of its denoised whole.
struct Remainder {
    name: String,
    whole: String,
    kind: naming::PartitionKind,
    planes: Planes,
}

impl Remainder {
    /// Its definition, kind and place in the partition, as the header declares them.
    fn attributes(&self) -> Vec<(String, String)> {
        vec![
            (
                naming::aov_attribute(&self.name),
                format!(
                    "denoise remainder: '{}' minus its {} parts, where the parts kept as \
                     rendered exceed it or none was filtered",
                    self.whole,
                    self.kind.as_str()
                ),
            ),
            (
                naming::kind_attribute(&self.name),
                AovKind::Light.as_str().into(),
            ),
            (
                format!("{}{}", naming::PART_ATTRIBUTE_PREFIX, self.name),
                self.whole.clone(),
            ),
            (
                format!("{}{}", naming::PARTITION_ATTRIBUTE_PREFIX, self.name),
                self.kind.as_str().into(),
            ),
        ]
    }
}

/// Scales each of `partitions`' denoised parts to sum to its denoised whole: the
/// remainders that takes, and the partitions waiting for a derived AOV (not yet made).
fn reconcile_partitions(
    exr: &ExrContents,
    partitions: Vec<Partition>,
    noisy: &NoisyPlanes,
    denoised: &mut AovPlanes,
    work: &Work,
    summary: &mut DenoiseSummary,
) -> (Vec<Remainder>, Vec<Partition>) {
    let kept = &work.kept;
    let mut remainders = Vec::new();
    let mut waiting = Vec::new();
    for part in partitions {
        let all = std::iter::once(&part.whole).chain(&part.parts);
        if !all.clone().all(|n| denoised.contains_key(n)) {
            if all
                .clone()
                .any(|n| work.derived.iter().any(|(d, _)| d == n))
            {
                waiting.push(part);
            }
            continue;
        }
        let whole = denoised.remove(&part.whole).unwrap_or_default();
        let noisy_parts: Vec<View> = part.parts.iter().map(|p| noisy[p]).collect();
        let mut taken: Vec<Planes> = part
            .parts
            .iter()
            .map(|p| denoised.remove(p).unwrap_or_default())
            .collect();
        let mut refs: Vec<&mut Planes> = taken.iter_mut().collect();
        let fixed: Vec<bool> = part.parts.iter().map(|p| kept.contains(p)).collect();
        if let Some(planes) = reconcile(&whole, &mut refs, &noisy_parts, &fixed) {
            let name = format!("{}__remainder_{}", part.whole, part.kind.as_str());
            // A file that already has the name keeps it (its parts then sum to the whole
            // only up to this remainder, which `lightpath aovs` reports).
            if !exr.aovs().iter().any(|(n, _)| *n == name) {
                summary.remainders += 1;
                remainders.push(Remainder {
                    name,
                    whole: part.whole.clone(),
                    kind: part.kind,
                    planes,
                });
            }
        }
        for (name, planes) in part.parts.iter().zip(taken) {
            denoised.insert(name.clone(), planes);
        }
        denoised.insert(part.whole, whole);
        summary.partitions += 1;
    }
    (remainders, waiting)
}

/// The shadow matte made again from the denoised `occluded` and `unoccluded`.
fn shadow_matte_of(exr: &ExrContents, denoised: &AovPlanes) -> Planes {
    let get = |n: &str| {
        denoised
            .get(n)
            .map(view)
            .or_else(|| planes_in(exr, n))
            .unwrap_or([&[], &[], &[]])
    };
    crate::output::shadow_matte(get(naming::OCCLUDED), get(naming::UNOCCLUDED))
}

/// `--keep-noisy`: each filtered AOV's input as `<aov>_noisy`, declared as such.
fn keep_noisy_aovs(
    exr: &ExrContents,
    noisy: &NoisyPlanes,
    channels: &mut Channels,
    attributes: &mut Vec<(String, String)>,
) -> Result<(), DenoiseFault> {
    let definitions: HashMap<String, String> = exr.aovs().into_iter().collect();
    let mut names: Vec<&String> = noisy.keys().filter(|n| !is_emission(n)).collect();
    names.sort();
    for name in names {
        let kept = naming::noisy_name(name);
        if definitions.contains_key(&kept) {
            return Err(DenoiseFault::NoisyNameTaken {
                aov: name.clone(),
                name: kept,
            });
        }
        for (ch, v) in channel_names(&kept).into_iter().zip(noisy[name]) {
            channels.push((ch, v.to_vec()));
        }
        attributes.push((
            naming::aov_attribute(&kept),
            format!(
                "{} (the noisy input of '{name}')",
                definitions.get(name).map(String::as_str).unwrap_or("")
            ),
        ));
        attributes.push((naming::noisy_attribute(&kept), name.clone()));
        attributes.push((
            naming::kind_attribute(&kept),
            AovKind::Light.as_str().into(),
        ));
    }
    Ok(())
}

/// The `lightpath/denoised` attribute: how the file was filtered.
fn describe(s: &DenoiseSummary, quality: Quality) -> String {
    let aux = match (s.albedo, s.normal) {
        (true, true) => {
            "albedo and normal auxiliary images prefiltered at the AOVs' quality \
                         (cleanAux)"
        }
        (true, false) => "albedo auxiliary image prefiltered at the AOVs' quality (cleanAux)",
        _ => "no auxiliary images",
    };
    format!(
        "Intel Open Image Denoise RT filter (hdr), {aux}; beauty at {}, other AOVs at {}; \
         AOVs named diffuse*, directDiffuse*, indirectDiffuse*, subsurface* divided by \
         albedo; AOVs split by light group (beauty excepted) the sum of their denoised \
         groups; diffuse and specular (and their light groups), where the noisy file adds \
         up so, the sums of their denoised direct, indirect and transmitted parts; zero, constant and converged AOVs kept; every declared partition's \
         filtered parts scaled to sum to its denoised whole, with a remainder AOV where \
         its kept parts cannot",
        BEAUTY_QUALITY.as_str(),
        quality.as_str()
    )
}

/// Open Image Denoise's working memory per pixel for one RT filter with albedo and
/// normal, measured with OIDN 2.5.1 on the CPU: ~590 bytes at `high` (540×960: 314 MB),
/// ~350 at `fast` (1920×1080: 715 MB); rounded up.
const OIDN_BYTES_PER_PIXEL: u64 = 640;

/// The bytes a denoise of a `width`×`height` file with `channels` float channels needs
/// at most: OIDN's working memory, and each channel four times (read, noisy and
/// denoised copies, the output).
pub fn memory_needed(width: usize, height: usize, channels: usize) -> u64 {
    let pixels = (width as u64).saturating_mul(height as u64);
    pixels
        .saturating_mul(OIDN_BYTES_PER_PIXEL.saturating_add(16u64.saturating_mul(channels as u64)))
}

/// Runs a denoise: reads the input, filters, writes the output atomically.
pub fn run(job: &DenoiseJob) -> Result<DenoiseSummary, PostError> {
    run_with_progress(job, &Silent)
}

/// [`run`], reporting each filter run to `progress`.
pub fn run_with_progress(
    job: &DenoiseJob,
    progress: &dyn Progress,
) -> Result<DenoiseSummary, PostError> {
    // Said first: without the denoiser no input could be of use.
    if !AVAILABLE {
        return Err(PostError::DenoiseUnavailable);
    }
    let cannot = |fault: DenoiseFault| PostError::Denoise {
        path: job.input.clone(),
        fault,
    };
    let start = std::time::Instant::now();
    let exr = read_exr(&job.input)?;
    // Checked before Open Image Denoise allocates: the library's allocation failures
    // are not reported as errors through its Rust binding.
    crate::limits::Limits::current()
        .check_memory(
            memory_needed(exr.width, exr.height, exr.channels.len()),
            &format!(
                "denoising {} ({}×{}, {} channels)",
                job.input.display(),
                exr.width,
                exr.height,
                exr.channels.len()
            ),
        )
        .map_err(|e| cannot(e.into()))?;
    let aux = aux_images(&exr);
    let mut summary = DenoiseSummary::default();
    let options = ContentOptions {
        keep_noisy: job.keep_noisy,
        quality: job.quality,
    };
    let (channels, attributes) = with_oidn(exr.width, exr.height, |f| {
        denoise_contents(&exr, aux, f, options, &mut summary, progress)
    })
    .map_err(DenoiseFault::from)
    .and_then(|r| r)
    .map_err(cannot)?;
    // The input's header with the denoiser's attributes: a crop stays a crop of its frame.
    let header = exr.derived_header(attributes);
    let png_path = crate::output::naming::preview_path(&job.output);
    crate::output::target::check(&png_path, &[&job.input])?;
    let beauty = channel_names(naming::BEAUTY).map(|c| {
        channels
            .iter()
            .find(|(n, _)| *n == c)
            .map(|(_, v)| v.clone())
    });
    // A file without the beauty (a render product of AOVs alone) has no preview.
    let png = match beauty {
        [Some(r), Some(g), Some(b)] => Some(crate::output::stage_png_rgb(
            &png_path,
            exr.width as u32,
            exr.height as u32,
            &[r, g, b],
            job.preview_exposure,
        )?),
        _ => None,
    };
    let image = stage_image(
        &job.output,
        exr.width,
        exr.height,
        channels,
        &header,
        ExrOptions::default(),
    )?;
    match png {
        Some(png) => crate::output::atomic::commit_pair(image, png)?,
        None => image.commit()?,
    }
    summary.seconds = start.elapsed().as_secs_f64();
    Ok(summary)
}

/// Runs `body` with OIDN filters for images of this size: made when first asked for
/// and kept while the next image asks for the same (one filter's memory at a time).
#[cfg(feature = "denoise")]
fn with_oidn<R>(
    width: usize,
    height: usize,
    body: impl FnOnce(&mut dyn Filter) -> R,
) -> Result<R, OidnError> {
    use super::oidn::{Device, Filter as Rt, Inputs};
    let device = Device::new()?;
    let raw = |q: Quality| match q {
        Quality::High => super::oidn::Quality::High,
        Quality::Balanced => super::oidn::Quality::Balanced,
        Quality::Fast => super::oidn::Quality::Fast,
    };
    struct Oidn<'d> {
        device: &'d Device,
        width: usize,
        height: usize,
        current: Option<((Inputs, super::oidn::Quality), Rt<'d>)>,
        white: Vec<f32>,
    }
    impl<'d> Oidn<'d> {
        fn filter_for(
            &mut self,
            inputs: Inputs,
            quality: super::oidn::Quality,
        ) -> Result<&mut Rt<'d>, OidnError> {
            if self.current.as_ref().map(|c| c.0) != Some((inputs, quality)) {
                // The old filter's memory is freed before the new one's is taken.
                self.current = None;
                let f = Rt::new(self.device, self.width, self.height, inputs, quality)?;
                self.current = Some(((inputs, quality), f));
            }
            match &mut self.current {
                Some((_, f)) => Ok(f),
                None => Err(OidnError("no filter".into())),
            }
        }
    }
    struct Run<'d> {
        oidn: Oidn<'d>,
        raw: fn(Quality) -> super::oidn::Quality,
    }
    impl Filter for Run<'_> {
        fn prefilter(&mut self, aux: &mut Aux, quality: Quality) -> Result<(), DenoiseFault> {
            let q = (self.raw)(quality);
            if let Some(a) = aux.albedo.as_mut() {
                let f = self.oidn.filter_for(Inputs::Albedo, q);
                f.and_then(|f| f.run(a, None, None)).map_err(|source| {
                    DenoiseFault::Prefiltering {
                        aux: "albedo",
                        source,
                    }
                })?;
            }
            if let Some(n) = aux.normal.as_mut() {
                let f = self.oidn.filter_for(Inputs::Normal, q);
                f.and_then(|f| f.run(n, None, None)).map_err(|source| {
                    DenoiseFault::Prefiltering {
                        aux: "normal",
                        source,
                    }
                })?;
            }
            self.oidn.current = None;
            Ok(())
        }
        fn filter(&mut self, rgb: &mut [f32], how: How, aux: &Aux) -> Result<(), OidnError> {
            let inputs = Inputs::Color {
                albedo: aux.albedo.is_some(),
                normal: aux.normal.is_some(),
            };
            let q = (self.raw)(how.quality);
            if how.albedo_divided && self.oidn.white.len() != rgb.len() {
                self.oidn.white = vec![1.0; rgb.len()];
            }
            // Divided by the albedo, an AOV is filtered with a white one.
            let white = std::mem::take(&mut self.oidn.white);
            let albedo = if how.albedo_divided {
                Some(white.as_slice())
            } else {
                aux.albedo.as_deref()
            };
            let result = self
                .oidn
                .filter_for(inputs, q)
                .and_then(|f| f.run(rgb, albedo, aux.normal.as_deref()));
            self.oidn.white = white;
            result
        }
    }
    let mut run = Run {
        oidn: Oidn {
            device: &device,
            width,
            height,
            current: None,
            white: Vec::new(),
        },
        raw,
    };
    Ok(body(&mut run))
}

#[cfg(not(feature = "denoise"))]
fn with_oidn<R>(
    _width: usize,
    _height: usize,
    _body: impl FnOnce(&mut dyn Filter) -> R,
) -> Result<R, OidnError> {
    Err(OidnError(UNAVAILABLE.into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planes_of(exr: &ExrContents, aov: &str) -> Option<Planes> {
        planes_in(exr, aov).map(|p| p.map(<[f32]>::to_vec))
    }

    /// A 3×3 box blur: a real (if crude) denoiser with OIDN's interface.
    struct BoxBlur {
        width: usize,
        height: usize,
        divided_calls: usize,
        /// The quality of each call, in order.
        qualities: Vec<Quality>,
        /// The quality the auxiliary images were prefiltered at, once they are.
        prefiltered: Option<Quality>,
    }

    impl BoxBlur {
        fn new() -> BoxBlur {
            BoxBlur {
                width: 6,
                height: 5,
                divided_calls: 0,
                qualities: Vec::new(),
                prefiltered: None,
            }
        }

        fn blur(&self, rgb: &mut [f32]) {
            let src = rgb.to_vec();
            let (w, h) = (self.width as i64, self.height as i64);
            for y in 0..h {
                for x in 0..w {
                    for c in 0..3 {
                        let (mut s, mut n) = (0.0, 0.0);
                        for dy in -1..=1 {
                            for dx in -1..=1 {
                                let (xx, yy) = (x + dx, y + dy);
                                if xx >= 0 && yy >= 0 && xx < w && yy < h {
                                    s += src[((yy * w + xx) * 3 + c) as usize];
                                    n += 1.0;
                                }
                            }
                        }
                        rgb[((y * w + x) * 3 + c) as usize] = s / n;
                    }
                }
            }
        }
    }

    impl Filter for BoxBlur {
        fn prefilter(&mut self, aux: &mut Aux, quality: Quality) -> Result<(), DenoiseFault> {
            assert!(
                self.prefiltered.is_none(),
                "the auxiliary images are prefiltered once"
            );
            self.prefiltered = Some(quality);
            for image in aux.albedo.iter_mut().chain(aux.normal.iter_mut()) {
                self.blur(image);
            }
            Ok(())
        }
        fn filter(&mut self, rgb: &mut [f32], how: How, aux: &Aux) -> Result<(), OidnError> {
            assert!(
                self.prefiltered.is_some(),
                "every filter runs with prefiltered auxiliary images"
            );
            assert!(aux.albedo.is_some());
            self.divided_calls += how.albedo_divided as usize;
            self.qualities.push(how.quality);
            self.blur(rgb);
            Ok(())
        }
    }

    fn noise(seed: u32, n: usize) -> Vec<f32> {
        let mut s = seed.wrapping_mul(747_796_405).wrapping_add(1);
        (0..n)
            .map(|_| {
                s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (s >> 8) as f32 / 16_777_216.0
            })
            .collect()
    }

    /// A 6×5 file: beauty = emission + directDiffuse + … (only two non-zero parts), a
    /// light-group split of beauty, albedo, normal and a depth.
    fn file() -> ExrContents {
        let n = 30;
        let dd = [noise(1, n), noise(2, n), noise(3, n)];
        let ds = [noise(4, n), noise(5, n), noise(6, n)];
        let key = [noise(7, n), noise(8, n), noise(9, n)];
        let beauty: Planes =
            [0, 1, 2].map(|c| dd[c].iter().zip(&ds[c]).map(|(a, b)| a + b).collect());
        let rest: Planes =
            [0, 1, 2].map(|c| beauty[c].iter().zip(&key[c]).map(|(b, k)| b * k).collect());
        let keyp: Planes =
            [0, 1, 2].map(|c| beauty[c].iter().zip(&rest[c]).map(|(b, r)| b - r).collect());
        let zero = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let albedo = [vec![0.5; n], noise(10, n), vec![0.005; n]];
        let normal = [vec![0.0; n], vec![0.0; n], vec![1.0; n]];
        let mut aovs: Vec<(&str, Planes, AovKind)> = vec![
            ("beauty", beauty, AovKind::Light),
            ("directDiffuse", dd, AovKind::Light),
            ("directSpecular", ds, AovKind::Light),
            ("beauty_key", keyp, AovKind::Light),
            ("beauty__default", rest, AovKind::Light),
            ("albedo", albedo, AovKind::Data),
            ("normal", normal, AovKind::Data),
            (
                "depth",
                [vec![2.0; n], vec![2.0; n], vec![2.0; n]],
                AovKind::Data,
            ),
        ];
        for z in lpe::BEAUTY_PARTITION {
            if z != "directDiffuse" && z != "directSpecular" {
                aovs.push((z, zero.clone(), AovKind::Light));
            }
        }
        let mut channels = Vec::new();
        let mut attributes = Vec::new();
        let definitions: Vec<String> = aovs.iter().map(|a| format!("lpe:{}", a.0)).collect();
        let mut infos = Vec::new();
        for ((name, planes, kind), definition) in aovs.iter().zip(&definitions) {
            for (ch, v) in channel_names(name).into_iter().zip(planes.clone()) {
                channels.push((ch, v));
            }
            attributes.push((naming::aov_attribute(name), definition.clone()));
            attributes.push((naming::kind_attribute(name), kind.as_str().to_string()));
            infos.push(naming::PartInfo {
                name,
                definition,
                split_of: name.starts_with("beauty_").then_some("beauty"),
            });
        }
        attributes.extend(naming::partition_attributes(&infos));
        channels.push(("A".into(), vec![1.0; n]));
        ExrContents {
            width: 6,
            height: 5,
            channels,
            attributes,
            frame: [6, 5],
            origin: [0, 0],
            world_to_camera: None,
            world_to_ndc: None,
            capture_date: None,
        }
    }

    fn options(keep_noisy: bool) -> ContentOptions {
        ContentOptions {
            keep_noisy,
            quality: Quality::Fast,
        }
    }

    fn run_box(exr: &ExrContents, keep: bool) -> (ExrContents, DenoiseSummary, BoxBlur) {
        let aux = aux_images(exr);
        let mut f = BoxBlur::new();
        let mut s = DenoiseSummary::default();
        let (channels, attributes) =
            denoise_contents(exr, aux, &mut f, options(keep), &mut s, &Silent).unwrap();
        let out = ExrContents {
            width: exr.width,
            height: exr.height,
            channels,
            attributes,
            frame: exr.frame,
            origin: exr.origin,
            world_to_camera: None,
            world_to_ndc: None,
            capture_date: None,
        };
        (out, s, f)
    }

    #[test]
    fn plan_follows_the_naming_convention_and_kinds() {
        let exr = file();
        let plan: HashMap<String, Treatment> = plan(&exr).into_iter().collect();
        assert_eq!(plan["directDiffuse"], Treatment::AlbedoDivided);
        assert_eq!(plan["subsurface"], Treatment::AlbedoDivided);
        assert_eq!(plan["directSpecular"], Treatment::AsIs);
        assert_eq!(plan["beauty_key"], Treatment::AsIs);
        assert_eq!(plan["albedo"], Treatment::Kept);
        assert_eq!(plan["depth"], Treatment::Kept);
    }

    #[test]
    fn partitions_sum_after_filtering_and_data_is_kept() {
        let exr = file();
        let (out, s, f) = run_box(&exr, false);
        // beauty, directDiffuse, directSpecular and the two light-group parts; six zero
        // members of the standard set (including the two volume ones) are left alone, and emission is kept as it is.
        assert_eq!((s.filtered, s.zero, s.partitions), (5, 6, 2));
        assert_eq!((s.converged, s.remainders), (0, 0));
        assert_eq!(f.divided_calls, 1);
        // Beauty first, at high; the other AOVs at the job's quality.
        assert_eq!(f.qualities[0], BEAUTY_QUALITY);
        assert!(f.qualities[1..].iter().all(|q| *q == Quality::Fast));
        // The auxiliary images at the AOVs' quality.
        assert_eq!(f.prefiltered, Some(Quality::Fast));
        let checks = crate::post::check_partitions(&out);
        assert_eq!(checks.len(), 2);
        for c in &checks {
            assert!(c.max_relative_error < 1e-5, "{c:?}");
        }
        // Filtering did something, data did not change.
        assert_ne!(out.channel("R"), exr.channel("R"));
        assert_eq!(out.channel("depth.R"), exr.channel("depth.R"));
        assert_eq!(out.channel("albedo.G"), exr.channel("albedo.G"));
        assert_eq!(out.channel("A"), exr.channel("A"));
        // The box blur keeps a constant image constant: the mean is preserved to
        // within the blur's edge effects.
        let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
        let (a, b) = (
            mean(out.channel("R").unwrap()),
            mean(exr.channel("R").unwrap()),
        );
        assert!((a - b).abs() < 0.1 * b, "{a} vs {b}");
    }

    #[test]
    fn albedo_division_round_trips_where_filtering_is_the_identity() {
        struct Identity;
        impl Filter for Identity {
            fn prefilter(&mut self, _: &mut Aux, _: Quality) -> Result<(), DenoiseFault> {
                Ok(())
            }
            fn filter(&mut self, _: &mut [f32], _: How, _: &Aux) -> Result<(), OidnError> {
                Ok(())
            }
        }
        let exr = file();
        let aux = aux_images(&exr);
        let p = planes_of(&exr, "directDiffuse").unwrap();
        let out = filter_aov(
            view(&p),
            Treatment::AlbedoDivided,
            Quality::Fast,
            &aux,
            &mut Identity,
            &mut Vec::new(),
        )
        .unwrap();
        for c in 0..3 {
            for (a, b) in out[c].iter().zip(&p[c]) {
                assert!((a - b).abs() <= 1e-6 * b.abs().max(1.0), "{a} vs {b}");
            }
        }
    }

    #[test]
    fn keep_noisy_adds_the_inputs_and_a_second_denoise_is_refused() {
        let exr = file();
        let (out, _, _) = run_box(&exr, true);
        assert_eq!(out.channel("beauty_noisy.R"), exr.channel("R"));
        assert_eq!(
            out.channel("directDiffuse_noisy.G"),
            exr.channel("directDiffuse.G")
        );
        // The noisy copies are in no partition: the checks are the same two.
        assert_eq!(crate::post::check_partitions(&out).len(), 2);
        let aux = aux_images(&out);
        let mut f = BoxBlur::new();
        let mut s = DenoiseSummary::default();
        let err = denoise_contents(&out, aux, &mut f, options(false), &mut s, &Silent).unwrap_err();
        assert!(matches!(err, DenoiseFault::AlreadyDenoised), "{err}");
    }

    #[test]
    fn reconcile_shares_a_whole_the_filtered_parts_lost() {
        let whole: Planes = [vec![2.0, 1.0], vec![0.0, 0.0], vec![1.0, 1.0]];
        let mut a: Planes = [vec![1.0, 0.0], vec![0.5, 0.0], vec![0.0, 0.0]];
        let mut b: Planes = [vec![3.0, 0.0], vec![0.5, 0.0], vec![0.0, 0.0]];
        let na: Planes = [vec![0.0, 1.0], vec![0.0, 0.0], vec![0.0, 0.0]];
        let nb: Planes = [vec![0.0, 3.0], vec![0.0, 0.0], vec![0.0, 0.0]];
        let rest = reconcile(
            &whole,
            &mut [&mut a, &mut b],
            &[view(&na), view(&nb)],
            &[false, false],
        );
        assert!(rest.is_none());
        // Scaled: 1 and 3 of 2 → 0.5 and 1.5.
        assert_eq!((a[0][0], b[0][0]), (0.5, 1.5));
        // The filtered parts are empty: the noisy proportions, 1:3.
        assert_eq!((a[0][1], b[0][1]), (0.25, 0.75));
        // A zero whole empties its parts.
        assert_eq!((a[1][0], b[1][0]), (0.0, 0.0));
        // Nothing anywhere: shared equally.
        assert_eq!((a[2][1], b[2][1]), (0.5, 0.5));
    }

    #[test]
    fn reconcile_keeps_fixed_emission_and_shares_the_rest() {
        let whole: Planes = [vec![5.0, 1.0], vec![0.0; 2], vec![0.0; 2]];
        let mut e: Planes = [vec![4.0, 2.0], vec![0.0; 2], vec![0.0; 2]];
        let mut a: Planes = [vec![3.0, 1.0], vec![0.0; 2], vec![0.0; 2]];
        let ne = e.clone();
        let na = a.clone();
        let rest = reconcile(
            &whole,
            &mut [&mut e, &mut a],
            &[view(&ne), view(&na)],
            &[true, false],
        );
        // Emission 4 kept, the other part takes 5 − 4.
        assert_eq!((e[0][0], a[0][0]), (4.0, 1.0));
        // A whole below its emission: the emission is kept exactly, the free part
        // empties and the remainder holds the difference, 1 − 2.
        assert_eq!((e[0][1], a[0][1]), (2.0, 0.0));
        let rest = rest.unwrap();
        assert_eq!((rest[0][0], rest[0][1], rest[1][1]), (0.0, -1.0, 0.0));
        // Every part kept: the remainder is all of the difference.
        let mut k: Planes = [vec![0.5, 3.0], vec![0.0; 2], vec![0.0; 2]];
        let nk = k.clone();
        let rest = reconcile(&whole, &mut [&mut k], &[view(&nk)], &[true]).unwrap();
        assert_eq!((k[0][0], rest[0][0], rest[0][1]), (0.5, 4.5, -2.0));
    }

    #[test]
    fn partitions_order_wholes_before_their_parts() {
        let names = [
            "beauty",
            "directDiffuse",
            "directDiffuse_key",
            "directDiffuse__default",
        ];
        let infos: Vec<naming::PartInfo> = names
            .iter()
            .map(|n| naming::PartInfo {
                name: n,
                definition: "lpe:directDiffuse",
                split_of: n.starts_with("directDiffuse_").then_some("directDiffuse"),
            })
            .collect();
        let mut attributes = naming::partition_attributes(&infos);
        attributes.push((
            format!("{}directDiffuse", naming::PART_ATTRIBUTE_PREFIX),
            "beauty".into(),
        ));
        attributes.push((
            format!("{}directDiffuse", naming::PARTITION_ATTRIBUTE_PREFIX),
            "standard".into(),
        ));
        let exr = ExrContents {
            width: 1,
            height: 1,
            channels: vec![],
            attributes,
            frame: [1, 1],
            origin: [0, 0],
            world_to_camera: None,
            world_to_ndc: None,
            capture_date: None,
        };
        let p = partitions(&exr);
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].whole, "beauty");
        assert_eq!(p[1].whole, "directDiffuse");
    }

    #[test]
    fn a_converged_aov_is_kept_and_the_partition_still_sums_with_a_remainder() {
        let mut exr = file();
        // directSpecular's variance: far below 1/512 of its level, so it is converged;
        // directDiffuse's: large, so it is filtered.
        for (aov, v) in [("directSpecular", 1e-12f32), ("directDiffuse", 1.0)] {
            let name = naming::variance_name(aov);
            for ch in channel_names(&name) {
                exr.channels.push((ch, vec![v; 30]));
            }
            exr.attributes.push((
                naming::kind_attribute(&name),
                AovKind::Variance.as_str().into(),
            ));
            exr.attributes
                .push((naming::aov_attribute(&name), format!("variance of {aov}")));
        }
        let (out, s, _) = run_box(&exr, false);
        assert_eq!(s.converged, 1);
        assert_eq!(
            out.channel("directSpecular.R"),
            exr.channel("directSpecular.R")
        );
        assert_eq!(s.filtered, 4);
        for c in crate::post::check_partitions(&out) {
            assert!(c.max_relative_error < 1e-5, "{c:?}");
        }
    }

    #[test]
    fn a_remainder_is_declared_a_part_and_makes_the_sum_exact() {
        let mut exr = file();
        // A part kept as it is (constant) brighter than beauty: the standard partition
        // needs a remainder.
        for ch in channel_names("subsurface") {
            exr.channels.iter_mut().find(|(n, _)| *n == ch).unwrap().1 = vec![100.0; 30];
        }
        let (out, s, _) = run_box(&exr, false);
        assert_eq!(s.remainders, 1);
        let name = "beauty__remainder_standard";
        assert_eq!(out.channel("subsurface.G"), Some(&[100.0f32; 30][..]));
        assert!(out.channel(&format!("{name}.R")).unwrap()[0] < 0.0);
        let checks = crate::post::check_partitions(&out);
        let standard = checks
            .iter()
            .find(|c| c.parts.iter().any(|p| p == name))
            .expect("the remainder is a part of the standard partition");
        assert!(standard.max_relative_error < 1e-5, "{standard:?}");
    }

    #[test]
    fn a_whole_split_by_light_group_is_the_sum_of_its_denoised_groups() {
        let mut exr = file();
        let dd = planes_of(&exr, "directDiffuse").unwrap();
        let infos = [
            ("directDiffuse_key", 0.3f32),
            ("directDiffuse__default", 0.7),
        ];
        for (name, share) in infos {
            for (ch, v) in channel_names(name).into_iter().zip(&dd) {
                exr.channels
                    .push((ch, v.iter().map(|x| x * share).collect()));
            }
            exr.attributes
                .push((naming::kind_attribute(name), AovKind::Light.as_str().into()));
            exr.attributes
                .push((naming::aov_attribute(name), "lpe:directDiffuse".into()));
        }
        let parts: Vec<naming::PartInfo> = infos
            .iter()
            .map(|(name, _)| naming::PartInfo {
                name,
                definition: "lpe:directDiffuse",
                split_of: Some("directDiffuse"),
            })
            .collect();
        exr.attributes.extend(naming::partition_attributes(&parts));
        let (out, s, f) = run_box(&exr, false);
        // directDiffuse is not filtered itself; its two groups are.
        assert_eq!((s.summed, s.filtered), (1, 6));
        assert_eq!(f.qualities.len(), 6);
        let checks = crate::post::check_partitions(&out);
        assert_eq!(checks.len(), 3);
        for c in &checks {
            assert!(c.max_relative_error < 1e-5, "{c:?}");
        }
    }

    /// `file()` with a `diffuse` AOV: `directDiffuse` times `scale`.
    fn with_diffuse(scale: f32) -> ExrContents {
        let mut exr = file();
        let dd = planes_of(&exr, "directDiffuse").unwrap();
        for (ch, v) in channel_names("diffuse").into_iter().zip(&dd) {
            exr.channels
                .push((ch, v.iter().map(|x| x * scale).collect()));
        }
        exr.attributes.push((
            naming::kind_attribute("diffuse"),
            AovKind::Light.as_str().into(),
        ));
        exr.attributes
            .push((naming::aov_attribute("diffuse"), "lpe:diffuse".into()));
        exr
    }

    #[test]
    fn diffuse_is_the_sum_of_its_denoised_parts_where_the_file_adds_up() {
        // directDiffuse + the zero indirectDiffuse and subsurface: no filter run of its
        // own, and afterwards the sum of the reconciled parts.
        let (out, s, f) = run_box(&with_diffuse(1.0), false);
        assert_eq!((s.derived, s.filtered, f.qualities.len()), (1, 5, 5));
        for c in ["R", "G", "B"] {
            let sum: Vec<f32> = ["directDiffuse", "indirectDiffuse", "subsurface"]
                .iter()
                .map(|p| out.channel(&format!("{p}.{c}")).unwrap())
                .fold(vec![0.0; 30], |mut s, p| {
                    s.iter_mut().zip(p).for_each(|(s, v)| *s += v);
                    s
                });
            assert_eq!(out.channel(&format!("diffuse.{c}")).unwrap(), &sum[..]);
        }
        assert_ne!(
            out.channel("diffuse.R"),
            with_diffuse(1.0).channel("diffuse.R")
        );
        // A diffuse that is not that sum is filtered itself.
        let (out, s, _) = run_box(&with_diffuse(1.01), false);
        assert_eq!((s.derived, s.filtered), (0, 6));
        assert_ne!(out.channel("diffuse.R"), out.channel("directDiffuse.R"));
    }

    #[test]
    fn light_groups_of_diffuse_are_sums_and_their_partition_sums() {
        let mut exr = with_diffuse(1.0);
        let dd = planes_of(&exr, "directDiffuse").unwrap();
        let mut infos = Vec::new();
        for (group, share) in [("_key", 0.3f32), ("__default", 0.7)] {
            for whole in ["directDiffuse", "diffuse"] {
                let name = format!("{whole}{group}");
                for (ch, v) in channel_names(&name).into_iter().zip(&dd) {
                    exr.channels
                        .push((ch, v.iter().map(|x| x * share).collect()));
                }
                exr.attributes.push((
                    naming::kind_attribute(&name),
                    AovKind::Light.as_str().into(),
                ));
                exr.attributes
                    .push((naming::aov_attribute(&name), format!("lpe:{whole}")));
                infos.push((name, whole));
            }
        }
        let parts: Vec<naming::PartInfo> = infos
            .iter()
            .map(|(name, whole)| naming::PartInfo {
                name,
                definition: "lpe:diffuse",
                split_of: Some(whole),
            })
            .collect();
        exr.attributes.extend(naming::partition_attributes(&parts));
        let (out, s, f) = run_box(&exr, false);
        // The two directDiffuse groups are filtered; directDiffuse is their sum, diffuse
        // and its groups are sums of those.
        assert_eq!((s.filtered, s.summed, s.derived), (6, 1, 3));
        assert_eq!(f.qualities.len(), 6);
        // Reconciling diffuse's groups to it moves them by float rounding at most.
        let (d, dd) = (
            out.channel("diffuse_key.G").unwrap(),
            out.channel("directDiffuse_key.G").unwrap(),
        );
        for (a, b) in d.iter().zip(dd) {
            assert!((a - b).abs() <= 1e-6 * b.abs().max(1e-3), "{a} vs {b}");
        }
        let checks = crate::post::check_partitions(&out);
        assert_eq!(checks.len(), 4);
        for c in &checks {
            assert!(c.max_relative_error < 1e-5, "{c:?}");
        }
    }

    #[test]
    fn memory_is_checked_against_oidns_needs_and_every_channel() {
        // 1080p with 40 RGB AOVs: OIDN's ~1.3 GB and 120 channels four times over.
        let b = memory_needed(1920, 1080, 120);
        assert_eq!(b, 1920 * 1080 * (640 + 16 * 120));
        // A header claiming a huge frame does not overflow.
        assert_eq!(memory_needed(usize::MAX, usize::MAX, usize::MAX), u64::MAX);
        assert!(crate::limits::Limits::default()
            .check_memory(memory_needed(1 << 16, 1 << 16, 400), "denoising")
            .is_err());
    }

    #[test]
    fn quality_parses() {
        assert_eq!(Quality::parse("fast"), Ok(Quality::Fast));
        assert!(Quality::parse("best").is_err());
    }
}
