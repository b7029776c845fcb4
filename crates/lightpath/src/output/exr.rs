//! The single-part EXR: writing a film with its AOVs and header, reading one back.

use super::atomic::{stage, Staged};
use crate::aov::naming::{self, channel_names};
use crate::error::OutputError;
use crate::film::Film;
use crate::scene::Aov;
use ::exr::prelude::*;
use std::path::Path;

/// How EXR channels are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct ExrOptions {
    /// Half floats instead of float32.
    pub half: bool,
    pub compression: ExrCompression,
}

/// EXR compression (all lossless).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ExrCompression {
    None,
    Rle,
    /// ZIP one scan line at a time: the default. As compact as `zip` on renders (85.46 vs
    /// 85.42 MB for 1080p with 37 AOVs), faster to write and to read a line at a time
    /// (Nuke), and its blocks in flight are small: with 16-line blocks and ~110 channels
    /// the parallel writer held ~120 MB of blocks at once.
    #[default]
    Zips,
    /// ZIP over 16 scan lines.
    Zip,
    /// Wavelet: the usual choice for noisy float renders in VFX pipelines.
    Piz,
}

impl ExrCompression {
    pub fn parse(s: &str) -> std::result::Result<ExrCompression, crate::error::InvalidValue> {
        Ok(match s {
            "none" => ExrCompression::None,
            "rle" => ExrCompression::Rle,
            "zips" => ExrCompression::Zips,
            "zip" => ExrCompression::Zip,
            "piz" => ExrCompression::Piz,
            other => {
                return Err(crate::error::InvalidValue(format!(
                    "unknown compression '{other}': expected none, rle, zips, zip or piz"
                )))
            }
        })
    }

    fn encoding(self) -> Encoding {
        let compression = match self {
            ExrCompression::None => Compression::Uncompressed,
            ExrCompression::Rle => Compression::RLE,
            ExrCompression::Zips => Compression::ZIP1,
            ExrCompression::Zip => Compression::ZIP16,
            ExrCompression::Piz => Compression::PIZ,
        };
        Encoding {
            compression,
            ..Encoding::SMALL_LOSSLESS
        }
    }
}

/// An AOV computed from others after rendering (not an LPE).
pub struct DerivedAov {
    pub name: String,
    pub definition: String,
    pub rgb: [Vec<f32>; 3],
}

/// The derived AOVs a render's AOVs allow: `shadow = 1 - occluded/unoccluded` (where
/// unoccluded > 0, else 0) when both holdout AOVs `occluded` and `unoccluded` are there —
/// the matte a compositor multiplies a background plate by.
pub fn derived_aovs(film: &Film, aovs: &[Aov]) -> Vec<DerivedAov> {
    let find = |n: &str| aovs.iter().position(|a| a.name == n);
    let (Some(occ), Some(unocc)) = (find(naming::OCCLUDED), find(naming::UNOCCLUDED)) else {
        return Vec::new();
    };
    if find(naming::SHADOW).is_some() {
        return Vec::new();
    }
    let o = [0, 1, 2].map(|c| film.channel(occ, c));
    let u = [0, 1, 2].map(|c| film.channel(unocc, c));
    let rgb = shadow_matte([&o[0], &o[1], &o[2]], [&u[0], &u[1], &u[2]]);
    vec![DerivedAov {
        name: naming::SHADOW.into(),
        definition: naming::SHADOW_DEFINITION.into(),
        rgb,
    }]
}

/// The shadow matte `1 - occluded/unoccluded` (where unoccluded > 0, else 0), clamped to
/// [0, 1], channel by channel.
pub fn shadow_matte(occluded: [&[f32]; 3], unoccluded: [&[f32]; 3]) -> [Vec<f32>; 3] {
    [0, 1, 2].map(|c| {
        occluded[c]
            .iter()
            .zip(unoccluded[c])
            .map(|(o, u)| {
                if *u > 0.0 {
                    (1.0 - o / u).clamp(0.0, 1.0)
                } else {
                    0.0
                }
            })
            .collect()
    })
}

/// Writes the film (consumed: its planes become the EXR's channels without a copy).
pub fn write_exr(
    path: &Path,
    film: Film,
    aovs: &[Aov],
    derived: Vec<DerivedAov>,
    options: ExrOptions,
    extra: &[(String, String)],
) -> std::result::Result<(), OutputError> {
    let header = ExrHeader {
        text: extra.to_vec(),
        ..ExrHeader::default()
    };
    write_film(path, film, aovs, derived, options, header)
}

/// Writes the film with a header: a film of a window of the frame gets the frame as its
/// display window and the window as its data window; Cryptomatte layers, if rendered,
/// their channels and manifests.
pub fn write_film(
    path: &Path,
    film: Film,
    aovs: &[Aov],
    derived: Vec<DerivedAov>,
    options: ExrOptions,
    header: ExrHeader,
) -> std::result::Result<(), OutputError> {
    stage_film(path, film, aovs, derived, options, header)?.commit()
}

/// [`write_film`] up to the rename: the file written and synced beside `path`.
pub fn stage_film(
    path: &Path,
    film: Film,
    aovs: &[Aov],
    derived: Vec<DerivedAov>,
    options: ExrOptions,
    mut header: ExrHeader,
) -> std::result::Result<Staged, OutputError> {
    let (width, height) = (film.width as usize, film.height as usize);
    let counts = film
        .sample_counts
        .as_ref()
        .map(|c| c.iter().map(|&n| n as f32).collect::<Vec<f32>>());
    header.frame = Some(film.frame);
    header.origin = [film.window.x0, film.window.y0];
    let mattes = film.mattes.clone();
    let squared = film.squared.clone();
    // Each pixel's sample count: its own under adaptive sampling, else the film's.
    let samples: Vec<u32> = (0..width * height).map(|i| film.samples_at(i)).collect();
    let mut planes = film.into_means().into_iter();
    let mut channels = Vec::new();
    let mut attributes = aov_attributes(aovs);
    for aov in aovs {
        for name in channel_names(&aov.name) {
            channels.push((name, planes.next().unwrap_or_default()));
        }
    }
    for &k in &squared {
        let Some(aov) = aovs.get(k as usize) else {
            continue;
        };
        let name = naming::variance_name(&aov.name);
        for (c, ch) in channel_names(&name).into_iter().enumerate() {
            let mut v = planes.next().unwrap_or_default();
            let mean = &channels[3 * k as usize + c].1;
            for ((v, m), n) in v.iter_mut().zip(mean).zip(&samples) {
                *v = crate::film::variance_of_mean(*m, *v, *n);
            }
            channels.push((ch, v));
        }
        attributes.push((
            naming::aov_attribute(&name),
            format!(
                "variance of the pixel mean of '{}' (RenderMan's mse, {}_mse)",
                aov.name, aov.name
            ),
        ));
        attributes.push((
            naming::kind_attribute(&name),
            naming::AovKind::Variance.as_str().into(),
        ));
        attributes.push((naming::variance_attribute(&name), aov.name.clone()));
    }
    // Alpha goes with the beauty: a file of other AOVs (a render product without it)
    // has none.
    let alpha = planes.next().unwrap_or_default();
    if aovs.iter().any(|a| a.name == naming::BEAUTY) {
        channels.push((naming::ALPHA.into(), alpha));
    }
    if let Some(counts) = counts {
        channels.push((naming::SAMPLE_COUNT_CHANNEL.into(), counts));
    }
    for d in derived {
        for (name, values) in channel_names(&d.name).into_iter().zip(d.rgb) {
            channels.push((name, values));
        }
        attributes.push((
            naming::kind_attribute(&d.name),
            naming::AovKind::Derived.as_str().into(),
        ));
        attributes.push((naming::aov_attribute(&d.name), d.definition));
    }
    if let Some(m) = mattes {
        attributes.extend(crate::post::cryptomatte::table_attributes(&m.table));
        channels.extend(
            crate::post::cryptomatte::table_channel_names(&m.table)
                .into_iter()
                .zip(m.planes),
        );
    }
    attributes.append(&mut header.text);
    header.text = attributes;
    stage_image(path, width, height, channels, &header, options)
}

/// The header attributes describing a render's AOVs: each one's definition and compiled
/// expression, and the structured partition attributes.
pub fn aov_attributes(aovs: &[Aov]) -> Vec<(String, String)> {
    let mut attributes = Vec::new();
    for aov in aovs {
        attributes.push((naming::aov_attribute(&aov.name), aov.definition.clone()));
        attributes.push((
            naming::expression_attribute(&aov.name),
            aov.expression.clone(),
        ));
        attributes.push((
            naming::kind_attribute(&aov.name),
            naming::AovKind::of_flags(aov.flags).as_str().into(),
        ));
    }
    let parts: Vec<naming::PartInfo> = aovs
        .iter()
        .map(|a| naming::PartInfo {
            name: &a.name,
            definition: &a.definition,
            split_of: a
                .part_of
                .and_then(|k| aovs.get(k as usize))
                .map(|w| w.name.as_str()),
        })
        .collect();
    attributes.extend(naming::partition_attributes(&parts));
    attributes
}

/// What an EXR's header says besides its channels and their definitions.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExrHeader {
    /// The whole frame's size (display window); `None`: the data's own size.
    pub frame: Option<[u32; 2]>,
    /// Where the data window starts in the frame (a crop's corner).
    pub origin: [u32; 2],
    /// `worldToCamera` and `worldToNDC`, as OpenEXR lays them out (row vectors: a point
    /// times the matrix).
    pub world_to_camera: Option<[f32; 16]>,
    pub world_to_ndc: Option<[f32; 16]>,
    /// `capDate` (`YYYY:MM:DD hh:mm:ss`, UTC, with `utcOffset` 0): only when asked, so
    /// identical renders stay identical files.
    pub capture_date: Option<String>,
    /// Text attributes (`lightpath/…`, `cryptomatte/…`).
    pub text: Vec<(String, String)>,
}

/// The `software` attribute of every file Lightpath writes.
pub fn software() -> String {
    format!("Lightpath {}", env!("CARGO_PKG_VERSION"))
}

/// Writes named float channels and text attributes as one single-part EXR, atomically.
pub fn write_channels(
    path: &Path,
    width: usize,
    height: usize,
    channels: Vec<(String, Vec<f32>)>,
    attributes: &[(String, String)],
    options: ExrOptions,
) -> std::result::Result<(), OutputError> {
    let header = ExrHeader {
        text: attributes.to_vec(),
        ..ExrHeader::default()
    };
    write_image(path, width, height, channels, &header, options)
}

/// Writes named float channels (a `width × height` data window) with a header, as one
/// single-part EXR, atomically. Every file gets `software` and Rec.709/D65
/// `chromaticities`; every channel `pLinear` 0 (OpenEXR's default, and right for
/// scene-linear light: the `exr` crate's guess gave `R` 0 but `diffuse.R` 1). Cryptomatte
/// channels stay 32-bit floats under `--half`: their ids are hashes.
pub fn write_image(
    path: &Path,
    width: usize,
    height: usize,
    channels: Vec<(String, Vec<f32>)>,
    header: &ExrHeader,
    options: ExrOptions,
) -> std::result::Result<(), OutputError> {
    stage_image(path, width, height, channels, header, options)?.commit()
}

/// [`write_image`] up to the rename.
pub fn stage_image(
    path: &Path,
    width: usize,
    height: usize,
    channels: Vec<(String, Vec<f32>)>,
    header: &ExrHeader,
    options: ExrOptions,
) -> std::result::Result<Staged, OutputError> {
    let layers = crate::post::cryptomatte::layers_in(&header.text);
    let channels: Vec<AnyChannel<FlatSamples>> = channels
        .into_iter()
        .map(|(name, v)| {
            let is_id = layers
                .iter()
                .any(|l| crate::post::cryptomatte::is_layer_channel(l, &name));
            let samples = if options.half && !is_id {
                FlatSamples::F16(v.into_iter().map(f16::from_f32).collect())
            } else {
                FlatSamples::F32(v)
            };
            AnyChannel {
                quantize_linearly: false,
                ..AnyChannel::new(name.as_str(), samples)
            }
        })
        .collect();
    let mut layer_attributes = LayerAttributes {
        software_name: Some(Text::from(software().as_str())),
        world_to_camera: header.world_to_camera,
        world_to_normalized_device: header.world_to_ndc,
        capture_date: header.capture_date.as_deref().map(Text::from),
        utc_offset: header.capture_date.as_ref().map(|_| 0.0),
        layer_position: Vec2(header.origin[0] as i32, header.origin[1] as i32),
        ..LayerAttributes::default()
    };
    for (k, v) in &header.text {
        layer_attributes.other.insert(
            Text::from(k.as_str()),
            AttributeValue::Text(Text::from(v.as_str())),
        );
    }
    let layer = Layer::new(
        (width, height),
        layer_attributes,
        options.compression.encoding(),
        AnyChannels::sort(SmallVec::from_vec(channels)),
    );
    let frame = header
        .frame
        .map_or((width, height), |f| (f[0] as usize, f[1] as usize));
    let mut image_attributes = ImageAttributes::new(IntegerBounds::from_dimensions(frame));
    image_attributes.chromaticities = Some(::exr::meta::attribute::Chromaticities {
        red: Vec2(0.64, 0.33),
        green: Vec2(0.30, 0.60),
        blue: Vec2(0.15, 0.06),
        white: Vec2(0.3127, 0.3290),
    });
    let image = Image::new(image_attributes, layer);
    stage(path, |file| {
        image
            .write()
            .to_unbuffered(&mut *file)
            .and_then(|()| sort_header_attributes(file).map_err(exr::error::Error::from))
            .map_err(|e| match e {
                exr::error::Error::Io(source) => OutputError::Write {
                    path: path.to_path_buf(),
                    source,
                },
                other => OutputError::Encode {
                    path: path.to_path_buf(),
                    reason: other.to_string(),
                },
            })
    })
}

/// Rewrites a single-part EXR's header with its attributes in name order. The `exr` crate
/// keeps them in a `HashMap`, so two identical renders wrote the same attributes in a
/// different order: a farm could not compare outputs by checksum. The set of attributes
/// is the same either way, so the header keeps its length and nothing after it moves.
fn sort_header_attributes(file: &mut std::fs::File) -> std::io::Result<()> {
    use std::io::{Read, Seek, SeekFrom, Write};
    file.seek(SeekFrom::Start(0))?;
    // Headers are small; one that does not end within this much is left as it is.
    let mut head = Vec::new();
    (&mut *file).take(1 << 22).read_to_end(&mut head)?;
    let multipart = head.len() >= 8 && head[5] & 0x10 != 0;
    if head.len() < 8 || head[..4] != [0x76, 0x2f, 0x31, 0x01] || multipart {
        return Ok(());
    }
    // Attributes: name\0 type\0 size (i32 LE) value; an empty name ends the header.
    let mut attributes: Vec<(&[u8], &[u8])> = Vec::new();
    let mut at = 8;
    loop {
        let Some(name_len) = head[at..].iter().position(|&b| b == 0) else {
            return Ok(());
        };
        if name_len == 0 {
            break;
        }
        let name = &head[at..at + name_len];
        let Some(type_len) = head[at + name_len + 1..].iter().position(|&b| b == 0) else {
            return Ok(());
        };
        let size_at = at + name_len + 1 + type_len + 1;
        let Some(size) = head.get(size_at..size_at + 4) else {
            return Ok(());
        };
        let size = i32::from_le_bytes([size[0], size[1], size[2], size[3]]);
        let end = size_at + 4 + size.max(0) as usize;
        if end > head.len() {
            return Ok(());
        }
        attributes.push((name, &head[at..end]));
        at = end;
    }
    attributes.sort_by(|a, b| a.0.cmp(b.0));
    let sorted: Vec<u8> = attributes
        .iter()
        .flat_map(|a| a.1.iter().copied())
        .collect();
    debug_assert_eq!(sorted.len(), at - 8);
    file.seek(SeekFrom::Start(8))?;
    file.write_all(&sorted)
}
