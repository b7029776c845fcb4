//! `lightpath merge`: the parts of one frame — sample ranges (`--first-sample`), tiles
//! (`--crop`), or both — become the EXR of the whole.
//!
//! Every part's header is read and checked before any pixel is: the parts must show the
//! same frame (display window), the same channels and every header attribute but the
//! ones that say which part it is (`lightpath/spp`, `first_sample`, `samples`, `crop`,
//! `scene`: the path may differ between machines; the scene's identity may not, and when
//! it differs the manifests of inputs name the file that changed). Parts with
//! the same window are sample ranges of it: their ranges may not overlap (a merged file
//! lists every range it holds, so merging it again with one of its parts is refused).
//! Parts with different windows are tiles: they may not overlap, must hold the same
//! samples, and must leave no hole in the rectangle they cover.
//!
//! Variance channels (`<aov>_var`) are recomputed from each part's sums of squares, so
//! they are the variance of the merged mean. Channels are averaged with weights: each part's per-pixel `sampleCount` where the
//! parts have that channel (adaptive sampling), else its sample count. `sampleCount`
//! itself adds up, and Cryptomatte pairs are merged by id and ranked again. Parts are read
//! one at a time: the memory is one part plus the merged window's sums.

use crate::aov::naming::{
    format_ranges, parse_ranges, CROP_ATTRIBUTE, FIRST_SAMPLE_ATTRIBUTE, IDENTITY_ATTRIBUTE,
    INPUTS_ATTRIBUTE, INTERRUPTED_ATTRIBUTE, SAMPLES_ATTRIBUTE, SAMPLE_COUNT_CHANNEL,
    SCENE_ATTRIBUTE, SPP_ATTRIBUTE,
};
use crate::error::{FrameMismatch, PostError};
use crate::film::PixelWindow;
use crate::output::{read_exr, read_exr_header, write_image, ExrHeader, ExrOptions};
use crate::post::cryptomatte;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Attributes that differ from part to part of one frame by design: the settings the
/// table (`settings.rs`) says so of, and the part's own sample range, window and path.
fn per_part(attribute: &str) -> bool {
    [
        FIRST_SAMPLE_ATTRIBUTE,
        SAMPLES_ATTRIBUTE,
        CROP_ATTRIBUTE,
        SCENE_ATTRIBUTE,
    ]
    .contains(&attribute)
        || crate::settings::per_part_attributes().any(|a| a == attribute)
}

/// What `merge` wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Merged {
    /// Samples per pixel of the result.
    pub spp: u64,
    /// The sample ranges it holds.
    pub ranges: Vec<(u64, u64)>,
    /// Its data window, and how many tiles it was stitched from.
    pub window: PixelWindow,
    pub tiles: usize,
}

/// One input as its header describes it.
struct Part {
    path: PathBuf,
    frame: [u32; 2],
    window: PixelWindow,
    ranges: Vec<(u64, u64)>,
    channels: Vec<String>,
    text: BTreeMap<String, String>,
}

impl Part {
    fn read(path: &Path) -> Result<Part, PostError> {
        let layout = read_exr_header(path)?;
        let window = PixelWindow {
            x0: layout.origin[0],
            y0: layout.origin[1],
            x1: layout.origin[0] + layout.width as u32,
            y1: layout.origin[1] + layout.height as u32,
        };
        let text: BTreeMap<String, String> = layout.attributes.into_iter().collect();
        if text.contains_key(INTERRUPTED_ATTRIBUTE) {
            return Err(PostError::Interrupted {
                path: path.to_path_buf(),
            });
        }
        let ranges = match text.get(SAMPLES_ATTRIBUTE) {
            Some(s) => parse_ranges(s).filter(|r| !r.is_empty()).ok_or_else(|| {
                PostError::BadAttribute {
                    path: path.to_path_buf(),
                    attribute: SAMPLES_ATTRIBUTE,
                    value: s.clone(),
                    expected: "ranges like '0-64 64-128'",
                }
            })?,
            // Files written before sample ranges were recorded: first_sample and spp.
            None => {
                let Some(spp) = text.get(SPP_ATTRIBUTE) else {
                    return Err(PostError::NotARender {
                        path: path.to_path_buf(),
                        attribute: SPP_ATTRIBUTE,
                    });
                };
                let first = match text.get(FIRST_SAMPLE_ATTRIBUTE) {
                    Some(f) => f.parse::<u64>().ok(),
                    None => Some(0),
                };
                // A count of 0 (or one that overflows) would merge as no samples at all,
                // and its weight would divide by zero.
                match (spp.parse::<u64>(), first) {
                    (Ok(n), Some(first)) if n > 0 && first.checked_add(n).is_some() => {
                        vec![(first, first + n)]
                    }
                    _ => {
                        return Err(PostError::BadAttribute {
                            path: path.to_path_buf(),
                            attribute: SPP_ATTRIBUTE,
                            value: spp.clone(),
                            expected: "a sample count (a whole number from 1, after a valid \
                                       lightpath/first_sample)",
                        })
                    }
                }
            }
        };
        let mut channels = layout.channels;
        channels.sort();
        Ok(Part {
            path: path.to_path_buf(),
            frame: layout.frame,
            window,
            ranges,
            channels,
            text,
        })
    }

    fn spp(&self) -> u64 {
        self.ranges.iter().map(|(a, b)| b - a).sum()
    }
}

/// Checks that `b` is a part of the same frame as `a`, naming the first difference.
fn same_frame(a: &Part, b: &Part) -> Result<(), PostError> {
    if a.frame != b.frame {
        return Err(PostError::FrameSize {
            path: b.path.clone(),
            size: b.frame,
            other: a.path.clone(),
            other_size: a.frame,
        });
    }
    if a.channels != b.channels {
        let only = |x: &Part, y: &Part| -> Vec<String> {
            x.channels
                .iter()
                .filter(|c| !y.channels.contains(c))
                .cloned()
                .collect()
        };
        return Err(PostError::Channels {
            first: a.path.clone(),
            second: b.path.clone(),
            only_first: only(a, b),
            only_second: only(b, a),
        });
    }
    changed_inputs(a, b)?;
    let keys: std::collections::BTreeSet<&String> = a.text.keys().chain(b.text.keys()).collect();
    // The identity last: a setting that differs is named by its own attribute.
    let (identity, others): (Vec<&String>, Vec<&String>) = keys
        .into_iter()
        .partition(|k| [IDENTITY_ATTRIBUTE, INPUTS_ATTRIBUTE].contains(&k.as_str()));
    for k in others.into_iter().chain(identity) {
        if per_part(k) {
            continue;
        }
        let (va, vb) = (a.text.get(k), b.text.get(k));
        if va != vb {
            return Err(PostError::NotOneFrame(Box::new(FrameMismatch {
                first: a.path.clone(),
                second: b.path.clone(),
                attribute: k.clone(),
                flag: crate::settings::flag_of_attribute(k),
                in_first: va.cloned(),
                in_second: vb.cloned(),
            })));
        }
    }
    Ok(())
}

/// Parts of different scenes (`lightpath/identity` differs): the files that changed
/// between them, from their manifests (`identity.rs`). A differing setting is left to
/// the attribute that names it.
fn changed_inputs(a: &Part, b: &Part) -> Result<(), PostError> {
    if a.text.get(IDENTITY_ATTRIBUTE) == b.text.get(IDENTITY_ATTRIBUTE) {
        return Ok(());
    }
    let manifest = |p: &Part| {
        p.text
            .get(INPUTS_ATTRIBUTE)
            .and_then(|m| crate::identity::parse_manifest(m))
    };
    let (Some(ma), Some(mb)) = (manifest(a), manifest(b)) else {
        return Ok(());
    };
    let changes = crate::identity::input_changes(&ma, &mb);
    if changes.is_empty() {
        return Ok(());
    }
    Err(PostError::InputsChanged {
        first: a.path.clone(),
        second: b.path.clone(),
        changes,
    })
}

fn overlaps(a: &PixelWindow, b: &PixelWindow) -> bool {
    a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1
}

/// Merges the parts of one frame into `output` (see the module's description).
pub fn merge(inputs: &[PathBuf], output: &Path) -> Result<Merged, PostError> {
    if inputs.is_empty() {
        return Err(PostError::NothingToMerge);
    }
    crate::output::target::check_exr_name(output, None)?;
    let input_refs: Vec<&Path> = inputs.iter().map(|p| p.as_path()).collect();
    crate::output::target::check(output, &input_refs)?;
    let parts: Vec<Part> = inputs
        .iter()
        .map(|p| Part::read(p))
        .collect::<Result<_, _>>()?;
    for p in &parts[1..] {
        same_frame(&parts[0], p)?;
    }
    let (groups, tile_ranges) = group_tiles(&parts)?;
    let window = check_tiles(&groups, &tile_ranges)?;

    let first = &parts[0];
    let layers = cryptomatte::layers_in(
        &first
            .text
            .iter()
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect::<Vec<_>>(),
    );
    let (w, h) = (window.width() as usize, window.height() as usize);
    let mut out: Vec<(String, Vec<f32>)> = first
        .channels
        .iter()
        .map(|c| (c.clone(), vec![0.0; w * h]))
        .collect();
    let mut header = ExrHeader::default();
    for (g, (tile, members)) in groups.iter().enumerate() {
        let merged = merge_tile(members, &layers, g == 0, &mut header)?;
        let tw = tile.width() as usize;
        for (name, plane) in &mut out {
            let Some(values) = merged.get(name) else {
                continue;
            };
            for (row, src) in values.chunks_exact(tw).enumerate() {
                let y = (tile.y0 - window.y0) as usize + row;
                let x = (tile.x0 - window.x0) as usize;
                plane[y * w + x..y * w + x + tw].copy_from_slice(src);
            }
        }
    }
    let ranges = tile_ranges[0].clone();
    let spp: u64 = ranges.iter().map(|(a, b)| b - a).sum();
    let mut text: Vec<(String, String)> = first
        .text
        .iter()
        .filter(|(k, _)| !per_part(k) || k.as_str() == SCENE_ATTRIBUTE)
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    text.push((SPP_ATTRIBUTE.into(), spp.to_string()));
    text.push((FIRST_SAMPLE_ATTRIBUTE.into(), ranges[0].0.to_string()));
    text.push((SAMPLES_ATTRIBUTE.into(), format_ranges(&ranges)));
    text.push((CROP_ATTRIBUTE.into(), window.to_string()));
    header.text = text;
    header.frame = Some(first.frame);
    header.origin = [window.x0, window.y0];
    write_image(output, w, h, out, &header, ExrOptions::default())?;
    Ok(Merged {
        spp,
        ranges,
        window,
        tiles: groups.len(),
    })
}

/// Parts by the window they cover: each entry holds the sample ranges of one tile.
type Tiles<'a> = Vec<(PixelWindow, Vec<&'a Part>)>;

/// Sample ranges, sorted: `(first, end)` each, end exclusive.
type Ranges = Vec<(u64, u64)>;

/// The parts grouped by window (each group: the sample ranges of one tile), with each
/// tile's ranges sorted; overlapping ranges within a tile are an error.
fn group_tiles(parts: &[Part]) -> Result<(Tiles<'_>, Vec<Ranges>), PostError> {
    let mut groups: Tiles = Vec::new();
    for p in parts {
        match groups.iter_mut().find(|g| g.0 == p.window) {
            Some(g) => g.1.push(p),
            None => groups.push((p.window, vec![p])),
        }
    }
    let mut tile_ranges = Vec::new();
    for (_, members) in &groups {
        let mut held: Vec<((u64, u64), &Part)> = Vec::new();
        for p in members {
            for &r in &p.ranges {
                if let Some((o, q)) = held.iter().find(|(o, _)| r.0 < o.1 && o.0 < r.1) {
                    return Err(PostError::SamplesOverlap {
                        first: q.path.clone(),
                        first_range: *o,
                        second: p.path.clone(),
                        second_range: r,
                    });
                }
                held.push((r, p));
            }
        }
        let mut ranges: Vec<(u64, u64)> = held.iter().map(|h| h.0).collect();
        ranges.sort();
        tile_ranges.push(ranges);
    }
    Ok((groups, tile_ranges))
}

/// The window the tiles make up together: an error if two overlap, hold different
/// samples, or leave a pixel of it uncovered.
fn check_tiles(
    groups: &[(PixelWindow, Vec<&'_ Part>)],
    tile_ranges: &[Ranges],
) -> Result<PixelWindow, PostError> {
    for (i, a) in groups.iter().enumerate() {
        for (j, b) in groups.iter().enumerate().skip(i + 1) {
            if overlaps(&a.0, &b.0) {
                return Err(PostError::TilesOverlap {
                    first: a.1[0].path.clone(),
                    first_window: a.0,
                    second: b.1[0].path.clone(),
                    second_window: b.0,
                });
            }
            if tile_ranges[i] != tile_ranges[j] {
                return Err(PostError::TileSamples {
                    first_window: a.0,
                    first_samples: format_ranges(&tile_ranges[i]),
                    second_window: b.0,
                    second_samples: format_ranges(&tile_ranges[j]),
                });
            }
        }
    }
    let window = groups.iter().skip(1).fold(groups[0].0, |u, g| PixelWindow {
        x0: u.x0.min(g.0.x0),
        y0: u.y0.min(g.0.y0),
        x1: u.x1.max(g.0.x1),
        y1: u.y1.max(g.0.y1),
    });
    let covered: u64 = groups
        .iter()
        .map(|g| g.0.width() as u64 * g.0.height() as u64)
        .sum();
    let area = window.width() as u64 * window.height() as u64;
    if covered != area {
        return Err(PostError::Uncovered {
            uncovered: area - covered,
            area,
            window,
        });
    }
    Ok(window)
}

/// Merges the sample ranges of one tile, reading one part at a time; the first tile's
/// first part gives the standard attributes of the result.
fn merge_tile(
    members: &[&Part],
    layers: &[String],
    keep_header: bool,
    header: &mut ExrHeader,
) -> Result<BTreeMap<String, Vec<f32>>, PostError> {
    if let [only] = members {
        // One part: its values as they are (a tile is exactly what was rendered).
        let exr = read_exr(&only.path)?;
        if keep_header {
            header.world_to_camera = exr.world_to_camera;
            header.world_to_ndc = exr.world_to_ndc;
            header.capture_date = exr.capture_date.clone();
        }
        return Ok(exr.channels.into_iter().collect());
    }
    let matte_channels: Vec<Vec<String>> = layers
        .iter()
        .map(|l| {
            let groups = members[0]
                .channels
                .iter()
                .filter(|c| cryptomatte::is_layer_channel(l, c))
                .count()
                .div_ceil(4);
            cryptomatte::channel_names(l, 2 * groups as u32)
        })
        .collect();
    let is_matte = |c: &str| matte_channels.iter().any(|m| m.iter().any(|n| n == c));
    let counted = members[0]
        .channels
        .iter()
        .any(|c| c == SAMPLE_COUNT_CHANNEL);
    let mut sums: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut weight_sum: Vec<f64> = Vec::new();
    // Per variance channel (`<aov>_var`), per pixel: the sum of squared samples.
    let mut squares: BTreeMap<(String, String), Vec<f64>> = BTreeMap::new();
    // Per layer, per pixel: the merged (id, weighted coverage) pairs.
    let mut mattes: Vec<Vec<f32>> = Vec::new();
    for (i, part) in members.iter().enumerate() {
        let exr = read_exr(&part.path)?;
        if keep_header && i == 0 {
            header.world_to_camera = exr.world_to_camera;
            header.world_to_ndc = exr.world_to_ndc;
            header.capture_date = exr.capture_date.clone();
        }
        let n = exr.width * exr.height;
        let weights: Vec<f64> = match (counted, exr.channel(SAMPLE_COUNT_CHANNEL)) {
            (true, Some(c)) => c.iter().map(|&v| v as f64).collect(),
            _ => vec![part.spp() as f64; n],
        };
        if i == 0 {
            weight_sum = vec![0.0; n];
            mattes = matte_channels
                .iter()
                .map(|m| vec![0.0; m.len() * n])
                .collect();
        }
        for (s, w) in weight_sum.iter_mut().zip(&weights) {
            *s += w;
        }
        add_squares(&exr, &weights, &mut squares);
        for (name, values) in &exr.channels {
            if is_matte(name) {
                continue;
            }
            let sum = sums.entry(name.clone()).or_insert_with(|| vec![0.0; n]);
            if name == SAMPLE_COUNT_CHANNEL {
                for (s, v) in sum.iter_mut().zip(values) {
                    *s += *v as f64;
                }
            } else {
                for ((s, v), w) in sum.iter_mut().zip(values).zip(&weights) {
                    *s += *v as f64 * w;
                }
            }
        }
        add_mattes(&exr, &matte_channels, &weights, &mut mattes);
    }
    Ok(finish_tile(
        sums,
        &squares,
        &weight_sum,
        &matte_channels,
        &mattes,
    ))
}

/// Adds one part's Cryptomatte pairs to the tile's ranked pairs, each pixel's coverage
/// weighted by its samples (normalised by [`finish_tile`]).
fn add_mattes(
    exr: &crate::output::ExrContents,
    matte_channels: &[Vec<String>],
    weights: &[f64],
    mattes: &mut [Vec<f32>],
) {
    let n = exr.width * exr.height;
    for (names, acc) in matte_channels.iter().zip(mattes.iter_mut()) {
        let planes: Vec<&[f32]> = names
            .iter()
            .map(|c| exr.channel(c).unwrap_or(&[]))
            .collect();
        let stride = names.len();
        let mut pairs = vec![0.0f32; stride];
        let mut merged = vec![0.0f32; stride];
        for px in 0..n {
            for (k, p) in planes.iter().enumerate() {
                pairs[k] = p.get(px).copied().unwrap_or(0.0);
            }
            let here = &mut acc[px * stride..(px + 1) * stride];
            // Coverage scaled by the part's weight; normalised once all are in.
            crate::film::mattes::merge_ranked(&[(&*here, 1.0), (&pairs, weights[px])], &mut merged);
            here.copy_from_slice(&merged);
        }
    }
}

/// The tile's channels from the weighted sums: means, the sample counts as they are,
/// variances of the merged means, and the Cryptomatte pairs normalised.
fn finish_tile(
    sums: BTreeMap<String, Vec<f64>>,
    squares: &BTreeMap<(String, String), Vec<f64>>,
    weight_sum: &[f64],
    matte_channels: &[Vec<String>],
    mattes: &[Vec<f32>],
) -> BTreeMap<String, Vec<f32>> {
    // Variances are not averages: the variance of the merged mean, from every sample's
    // sum of squares and the merged sum.
    let variances: Vec<((String, String), Vec<f32>)> = squares
        .iter()
        .filter_map(|((var, mean), sq)| {
            let sum = sums.get(mean)?;
            let values = sq
                .iter()
                .zip(sum)
                .zip(weight_sum)
                .map(|((q, s), n)| {
                    if *n < 2.0 {
                        0.0
                    } else {
                        ((q - s * s / n).max(0.0) / (n - 1.0) / n) as f32
                    }
                })
                .collect();
            Some(((var.clone(), mean.clone()), values))
        })
        .collect();
    let mut out: BTreeMap<String, Vec<f32>> = sums
        .into_iter()
        .map(|(name, s)| {
            let values = if name == SAMPLE_COUNT_CHANNEL {
                s.into_iter().map(|v| v as f32).collect()
            } else {
                s.iter()
                    .zip(weight_sum)
                    .map(|(v, w)| if *w > 0.0 { (v / w) as f32 } else { 0.0 })
                    .collect()
            };
            (name, values)
        })
        .collect();
    for ((var, _), values) in variances {
        out.insert(var, values);
    }
    for (names, acc) in matte_channels.iter().zip(mattes) {
        let stride = names.len();
        let mut planes = vec![vec![0.0f32; weight_sum.len()]; stride];
        for (px, w) in weight_sum.iter().enumerate() {
            let inv = if *w > 0.0 { 1.0 / w } else { 0.0 };
            for r in 0..stride / 2 {
                planes[2 * r][px] = acc[px * stride + 2 * r];
                planes[2 * r + 1][px] = (acc[px * stride + 2 * r + 1] as f64 * inv) as f32;
            }
        }
        out.extend(names.iter().cloned().zip(planes));
    }
    out
}

/// Adds one part's sums of squared samples to `squares`, for each of its variance
/// channels (from the `lightpath/variance/<aov>_var` attributes): with `n` samples, mean
/// `m` and variance of the mean `v`, `Σx² = (n − 1)·n·v + n·m²`.
fn add_squares(
    exr: &crate::output::ExrContents,
    weights: &[f64],
    squares: &mut BTreeMap<(String, String), Vec<f64>>,
) {
    use crate::aov::naming::{channel_names, VARIANCE_ATTRIBUTE_PREFIX};
    for (k, base) in &exr.attributes {
        let Some(var) = k.strip_prefix(VARIANCE_ATTRIBUTE_PREFIX) else {
            continue;
        };
        for (vc, mc) in channel_names(var).into_iter().zip(channel_names(base)) {
            let (Some(v), Some(m)) = (exr.channel(&vc), exr.channel(&mc)) else {
                continue;
            };
            let sq = squares
                .entry((vc, mc))
                .or_insert_with(|| vec![0.0; weights.len()]);
            for (((s, v), m), n) in sq.iter_mut().zip(v).zip(m).zip(weights) {
                *s += (n - 1.0) * n * *v as f64 + n * (*m as f64).powi(2);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn part(name: &str, attributes: &[(&str, &str)]) -> Part {
        Part {
            path: PathBuf::from(name),
            frame: [4, 4],
            window: PixelWindow {
                x0: 0,
                y0: 0,
                x1: 4,
                y1: 4,
            },
            ranges: vec![(0, 4)],
            channels: vec!["R".into()],
            text: attributes
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
        }
    }

    #[test]
    fn a_differing_setting_is_named_by_its_attribute_and_its_flag() {
        let depth = crate::aov::naming::setting_attribute("max_depth");
        let a = part("a.exr", &[(&depth, "8")]);
        let b = part("b.exr", &[(&depth, "4")]);
        let e = same_frame(&a, &b).unwrap_err();
        match &e {
            PostError::NotOneFrame(m) => assert_eq!(
                (m.attribute.as_str(), m.flag),
                (depth.as_str(), Some("max-depth"))
            ),
            other => panic!("{other}"),
        }
        let text = e.to_string();
        assert!(
            text.contains("lightpath/setting/max_depth (--max-depth) is '8' in the first and '4'"),
            "{text}"
        );
        // An attribute no setting writes has no flag to name.
        let c = part(
            "c.exr",
            &[(&depth, "8"), ("lightpath/aov/key", "C<L.'key'>")],
        );
        match same_frame(&a, &c).unwrap_err() {
            PostError::NotOneFrame(m) => assert_eq!(m.flag, None),
            other => panic!("{other}"),
        }
    }
}
