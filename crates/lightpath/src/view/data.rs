//! What the page shows of an EXR: its AOVs and what its header declares about them
//! (partitions, light groups, Cryptomatte layers, `_noisy` twins), images as half floats,
//! the values of one pixel in every AOV. Every name comes from `aov::naming` and the
//! structured partition attributes; no definition's prose is read.

use super::crypto;
use crate::aov::naming::{self, channel_names, PartitionKind};
use crate::output::ExrContents;
use crate::post::partitions::{check_partitions, PartitionCheck};
use half::f16;
use half::slice::{HalfBitsSliceExt, HalfFloatSliceExt};
use rayon::prelude::*;
use serde_json::{json, Value};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// The suffix of an AOV's pre-denoise twin (`beauty_noisy` beside a denoised `beauty`).
pub const NOISY_SUFFIX: &str = "_noisy";

/// How wide the page draws thumbnails (it reads this from `/api/info`).
pub const THUMBNAIL_WIDTH: usize = 160;

/// Reduced images (thumbnails) of one generation, by name and reduction factor: each is
/// made once, by whichever thread asks first (another asking meanwhile waits for it).
#[derive(Default)]
struct Reduced {
    generation: u64,
    images: HashMap<(String, usize), Arc<OnceLock<Option<HalfImage>>>>,
}

/// An EXR as the viewer holds it: the file's channels and header, or a live render's.
pub struct ViewData {
    pub exr: ExrContents,
    /// Bumped whenever pixels change (a live render's bands): the page reloads on a change.
    pub generation: u64,
    /// A render is still filling the channels.
    pub live: bool,
    /// What the page calls the image (the file name, or the scene of a live render).
    pub title: String,
    /// Partition checks of the current generation (measured once, not per request).
    checks: Option<(u64, Vec<PartitionCheck>)>,
    reduced: Mutex<Reduced>,
}

/// An image to send: `channels` half floats per pixel, rows top to bottom.
#[derive(Clone)]
pub struct HalfImage {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    /// Little-endian IEEE half floats.
    pub bytes: Vec<u8>,
}

impl ViewData {
    pub fn new(exr: ExrContents, title: impl Into<String>) -> ViewData {
        ViewData {
            exr,
            generation: 0,
            live: false,
            title: title.into(),
            checks: None,
            reduced: Mutex::default(),
        }
    }

    /// AOV names with their definitions, in name order.
    pub fn aovs(&self) -> Vec<(String, String)> {
        let mut aovs = self.exr.aovs();
        aovs.sort();
        aovs
    }

    fn has_aov(&self, name: &str) -> bool {
        channel_names(name)
            .iter()
            .all(|c| self.exr.channel(c).is_some())
    }

    /// The generation whose partition checks are still to be measured, if any (none while
    /// a render runs: rows not rendered yet are zero in every AOV).
    pub fn unmeasured(&self) -> Option<u64> {
        let measured = matches!(&self.checks, Some((g, _)) if *g == self.generation);
        (!self.live && !measured).then_some(self.generation)
    }

    /// Measures the partition checks (a pass over every part: seconds on a 1 GB file,
    /// so the server runs it on its own thread under a read lock).
    pub fn measure(&self) -> Vec<PartitionCheck> {
        check_partitions(&self.exr)
    }

    /// Keeps the checks measured for `generation`.
    pub fn set_checks(&mut self, generation: u64, checks: Vec<PartitionCheck>) {
        if generation == self.generation {
            self.checks = Some((generation, checks));
        }
    }

    fn checks(&self) -> &[PartitionCheck] {
        match &self.checks {
            Some((g, c)) if *g == self.generation => c,
            _ => &[],
        }
    }

    /// Everything the page lays out: the AOVs with their expressions, grouped by the
    /// partitions the header declares with each one's measured error, the light-group
    /// mixers, the Cryptomatte layers and the `_noisy` twins.
    pub fn info(&self) -> Value {
        let aovs = self.aovs();
        let parts = naming::parts_from_attributes(&self.exr.attributes);
        let checks = self.checks();
        let mut partitions: Vec<(String, PartitionKind, Vec<String>)> = Vec::new();
        let mut sorted = parts.clone();
        sorted.sort_by_key(|p| (p.whole.clone(), p.kind, naming::part_order(p)));
        for p in &sorted {
            match partitions.last_mut() {
                Some((w, k, names)) if *w == p.whole && *k == p.kind => names.push(p.name.clone()),
                _ => partitions.push((p.whole.clone(), p.kind, vec![p.name.clone()])),
            }
        }
        let partitions: Vec<Value> = partitions
            .into_iter()
            .map(|(whole, kind, names)| {
                let error = checks
                    .iter()
                    .find(|c| c.whole == whole && c.parts == names)
                    .map(|c| c.max_relative_error);
                json!({
                    "whole": whole,
                    "kind": kind.as_str(),
                    "parts": names,
                    "max_relative_error": error,
                })
            })
            .collect();
        let mixers: Vec<Value> = {
            let mut wholes: Vec<&str> = sorted
                .iter()
                .filter(|p| p.kind == PartitionKind::LightGroups)
                .map(|p| p.whole.as_str())
                .collect();
            wholes.dedup();
            wholes
                .into_iter()
                .filter(|w| self.has_aov(w))
                .map(|whole| {
                    let groups: Vec<Value> = sorted
                        .iter()
                        .filter(|p| p.whole == whole && p.kind == PartitionKind::LightGroups)
                        .filter(|p| self.has_aov(&p.name))
                        .map(|p| {
                            let group = p.group.clone().flatten();
                            json!({
                                "part": p.name,
                                "group": group.clone().unwrap_or_else(|| naming::DEFAULT_GROUP.into()),
                                "arg": group.unwrap_or_else(|| naming::DEFAULT_GROUP.into()),
                            })
                        })
                        .collect();
                    json!({ "base": whole, "groups": groups })
                })
                .collect()
        };
        let noisy: Vec<Value> = aovs
            .iter()
            .filter(|(n, _)| !n.ends_with(NOISY_SUFFIX))
            .filter_map(|(n, _)| {
                let twin = format!("{n}{NOISY_SUFFIX}");
                self.has_aov(&twin)
                    .then(|| json!({ "aov": n, "noisy": twin }))
            })
            .collect();
        let crypto: Vec<Value> = crypto::layers(&self.exr)
            .iter()
            .map(|l| json!({ "name": l.name, "key": l.key, "ranks": 2 * l.channels.len(), "objects": l.manifest.len() }))
            .collect();
        let aovs: Vec<Value> = aovs
            .iter()
            .map(|(name, definition)| {
                let part = parts.iter().find(|p| p.name == *name);
                json!({
                    "name": name,
                    "definition": definition,
                    "whole": part.map(|p| p.whole.clone()),
                    "partition": part.map(|p| p.kind.as_str()),
                    "present": self.has_aov(name),
                })
            })
            .collect();
        json!({
            "title": self.title,
            "width": self.exr.width,
            "height": self.exr.height,
            "generation": self.generation,
            "live": self.live,
            "beauty": naming::BEAUTY,
            "aovs": aovs,
            "partitions": partitions,
            "tolerance": crate::post::partitions::DEFAULT_TOLERANCE,
            "thumbnail_width": THUMBNAIL_WIDTH,
            "mixers": mixers,
            "relight_caveat": crate::post::comp::relight_caveat(&self.exr.attributes),
            "noisy": noisy,
            "cryptomatte": crypto,
        })
    }

    /// AOV `name` (or a Cryptomatte layer's false colours) as half floats, box-filtered
    /// down by a whole factor to at most `max_width` pixels across. Reduced images are
    /// kept until the pixels change (a thumbnail is made once, see [`Self::thumbnails`]);
    /// full-size ones are made per request.
    pub fn image(&self, name: &str, max_width: usize) -> Option<HalfImage> {
        let factor = self.exr.width.div_ceil(max_width.max(1)).max(1);
        if factor == 1 {
            return self.make_image(name, max_width);
        }
        let cell = {
            let mut reduced = self.reduced.lock().unwrap_or_else(|e| e.into_inner());
            if reduced.generation != self.generation {
                *reduced = Reduced {
                    generation: self.generation,
                    images: HashMap::new(),
                };
            }
            let key = (name.to_string(), factor);
            Arc::clone(reduced.images.entry(key).or_default())
        };
        cell.get_or_init(|| self.make_image(name, max_width))
            .clone()
    }

    /// Makes every thumbnail the page will ask for (AOVs and Cryptomatte layers, several
    /// at once): the server does this as soon as a file is shown, while the browser
    /// starts.
    pub fn thumbnails(&self) {
        let mut names: Vec<String> = self
            .aovs()
            .into_iter()
            .map(|(n, _)| n)
            .filter(|n| self.has_aov(n))
            .collect();
        names.extend(crypto::layers(&self.exr).into_iter().map(|l| l.name));
        names.par_iter().for_each(|n| {
            self.image(n, THUMBNAIL_WIDTH);
        });
    }

    fn make_image(&self, name: &str, max_width: usize) -> Option<HalfImage> {
        let planes: Vec<std::borrow::Cow<[f32]>> = if self.has_aov(name) {
            channel_names(name)
                .iter()
                .map(|c| self.exr.channel(c).map(std::borrow::Cow::Borrowed))
                .collect::<Option<_>>()?
        } else {
            let layer = crypto::layers(&self.exr)
                .into_iter()
                .find(|l| l.name == name)?;
            layer
                .false_colours(&self.exr)
                .into_iter()
                .map(std::borrow::Cow::Owned)
                .collect()
        };
        let planes: Vec<&[f32]> = planes.iter().map(|p| p.as_ref()).collect();
        Some(downsample(
            &planes,
            self.exr.width,
            self.exr.height,
            max_width,
        ))
    }

    /// The matte of object `id` in Cryptomatte layer `layer`: one half-float channel.
    pub fn matte(&self, layer: &str, id: u32) -> Option<HalfImage> {
        let layer = crypto::layers(&self.exr)
            .into_iter()
            .find(|l| l.name == layer)?;
        let matte = layer.matte(&self.exr, id);
        Some(downsample(
            &[&matte],
            self.exr.width,
            self.exr.height,
            usize::MAX,
        ))
    }

    /// The values at pixel (x, y) of every AOV and of alpha, and the object each
    /// Cryptomatte layer sees there.
    pub fn pixel(&self, x: usize, y: usize) -> Option<Value> {
        if x >= self.exr.width || y >= self.exr.height {
            return None;
        }
        let i = y * self.exr.width + x;
        let values: Vec<Value> = self
            .aovs()
            .iter()
            .filter(|(n, _)| self.has_aov(n))
            .map(|(n, _)| {
                let rgb: Vec<f32> = channel_names(n)
                    .iter()
                    .map(|c| self.exr.channel(c).map_or(0.0, |p| p[i]))
                    .collect();
                json!({ "name": n, "rgb": rgb })
            })
            .collect();
        let crypto: Vec<Value> = crypto::layers(&self.exr)
            .iter()
            .filter_map(|l| {
                let (id, coverage) = l.top(&self.exr, i)?;
                Some(json!({
                    "layer": l.name,
                    "id": format!("{id:08x}"),
                    "name": l.object_name(id),
                    "coverage": coverage,
                }))
            })
            .collect();
        Some(json!({
            "x": x,
            "y": y,
            "alpha": self.exr.channel(naming::ALPHA).map(|a| a[i]),
            "values": values,
            "cryptomatte": crypto,
        }))
    }
}

/// Box-filters planes by the whole factor that brings the width to at most `max_width`
/// (partial boxes at the right and bottom edges average what they cover) and packs them
/// interleaved as little-endian half floats. Output rows are made in parallel, each
/// summing its input rows in one sequential pass per plane and converted to half floats
/// a row at a time.
pub fn downsample(planes: &[&[f32]], width: usize, height: usize, max_width: usize) -> HalfImage {
    let f = width.div_ceil(max_width.max(1)).max(1);
    let (w, h) = (width.div_ceil(f), height.div_ceil(f));
    let channels = planes.len();
    let mut bytes = vec![0u8; w * h * channels * 2];
    let row_bytes = (w * channels * 2).max(1);
    bytes.par_chunks_mut(row_bytes).enumerate().for_each_init(
        // Per worker: the row's floats (interleaved), one plane's box sums, the halves.
        || {
            (
                vec![0f32; w * channels],
                vec![0f32; w],
                vec![0u16; w * channels],
            )
        },
        |(values, sums, halves), (oy, row)| {
            let ys = oy * f..((oy + 1) * f).min(height);
            for (c, plane) in planes.iter().enumerate() {
                if f == 1 {
                    let src = &plane[oy * width..(oy + 1) * width];
                    for (v, s) in values.iter_mut().skip(c).step_by(channels).zip(src) {
                        *v = *s;
                    }
                    continue;
                }
                sums.fill(0.0);
                for y in ys.clone() {
                    let src = &plane[y * width..(y + 1) * width];
                    for (sum, chunk) in sums.iter_mut().zip(src.chunks(f)) {
                        *sum += chunk.iter().sum::<f32>();
                    }
                }
                for (ox, (v, sum)) in values
                    .iter_mut()
                    .skip(c)
                    .step_by(channels)
                    .zip(sums.iter())
                    .enumerate()
                {
                    *v = sum / (ys.len() * f.min(width - ox * f)) as f32;
                }
            }
            halves
                .reinterpret_cast_mut::<f16>()
                .convert_from_f32_slice(values);
            for (out, half) in row.chunks_exact_mut(2).zip(halves.iter()) {
                out.copy_from_slice(&half.to_le_bytes());
            }
        },
    );
    HalfImage {
        width: w,
        height: h,
        channels,
        bytes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn half(bytes: &[u8], i: usize) -> f32 {
        f16::from_bits(u16::from_le_bytes([bytes[2 * i], bytes[2 * i + 1]])).to_f32()
    }

    #[test]
    fn thumbnails_are_kept_until_the_pixels_change() {
        let (w, h) = (8, 4);
        let channels = channel_names("glow")
            .into_iter()
            .map(|c| (c, vec![1.0f32; w * h]))
            .collect();
        let exr = ExrContents {
            width: w,
            height: h,
            channels,
            attributes: vec![(naming::aov_attribute("glow"), "CO".into())],
            frame: [w as u32, h as u32],
            origin: [0, 0],
            world_to_camera: None,
            world_to_ndc: None,
            capture_date: None,
        };
        let mut data = ViewData::new(exr, "t");
        data.thumbnails();
        let small = |d: &ViewData| d.image("glow", 4).map(|i| (i.width, half(&i.bytes, 0)));
        assert_eq!(small(&data), Some((4, 1.0)));
        // A live render's band: new pixels, a new generation, a new thumbnail.
        data.exr.channels[0].1.fill(3.0);
        assert_eq!(small(&data), Some((4, 1.0)), "kept within a generation");
        data.generation += 1;
        assert_eq!(small(&data), Some((4, 3.0)));
        assert_eq!(data.image("glow", 8).map(|i| half(&i.bytes, 0)), Some(3.0));
        assert!(data.image("nothing", 4).is_none());
    }

    #[test]
    fn downsampling_averages_whole_boxes_and_partial_edges() {
        // 5×3, factor 2 (max width 3): boxes 2×2, the right column and bottom row partial.
        let plane: Vec<f32> = (0..15).map(|v| v as f32).collect();
        let img = downsample(&[&plane], 5, 3, 3);
        assert_eq!((img.width, img.height, img.channels), (3, 2, 1));
        assert_eq!(half(&img.bytes, 0), (0.0 + 1.0 + 5.0 + 6.0) / 4.0);
        assert_eq!(half(&img.bytes, 2), (4.0 + 9.0) / 2.0);
        assert_eq!(half(&img.bytes, 3), (10.0 + 11.0) / 2.0);
        assert_eq!(half(&img.bytes, 5), 14.0);
        let full = downsample(&[&plane, &plane], 5, 3, usize::MAX);
        assert_eq!((full.width, full.height), (5, 3));
        assert_eq!(half(&full.bytes, 2 * 7 + 1), 7.0);
    }
}
