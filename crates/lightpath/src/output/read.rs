//! Reading EXRs: the one reader for renders read back (merge, denoise, comp, diff, the
//! viewer) and for images a scene reads (EXR textures, dome maps). Every read checks the
//! header first: a regular file within the input-size limit, whose declared pixels fit
//! the memory limit (a crafted header claiming billions of pixels was allocated, and
//! aborted the process). Images a scene reads come as bytes from `limits::read_input`,
//! so they are also inputs of the render's identity.

use super::ExrHeader;
use crate::error::{ExrFault, ExrReadError};
use ::exr::meta::attribute::{AttributeValue, Text};
use ::exr::meta::MetaData;
use ::exr::prelude::*;
use std::io::{Read, Seek};
use std::path::Path;
use std::result::Result;

/// An EXR read back: its channels by name and the header's AOV definitions.
pub struct ExrContents {
    pub width: usize,
    pub height: usize,
    pub channels: Vec<(String, Vec<f32>)>,
    pub attributes: Vec<(String, String)>,
    /// The display window's size and where the data window starts in it.
    pub frame: [u32; 2],
    pub origin: [u32; 2],
    pub world_to_camera: Option<[f32; 16]>,
    pub world_to_ndc: Option<[f32; 16]>,
    pub capture_date: Option<String>,
}

impl ExrContents {
    /// The header of a file made from this one (a comp, a denoise): the same frame and
    /// crop, camera and capture date, with `text` as its attributes.
    pub fn derived_header(&self, text: Vec<(String, String)>) -> ExrHeader {
        ExrHeader {
            frame: Some(self.frame),
            origin: self.origin,
            world_to_camera: self.world_to_camera,
            world_to_ndc: self.world_to_ndc,
            capture_date: self.capture_date.clone(),
            text,
        }
    }

    pub fn channel(&self, name: &str) -> Option<&[f32]> {
        self.channels
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }

    /// AOV names with their definitions, from the header.
    pub fn aovs(&self) -> Vec<(String, String)> {
        self.attributes
            .iter()
            .filter_map(|(k, v)| {
                k.strip_prefix(super::AOV_ATTRIBUTE_PREFIX)
                    .map(|n| (n.to_string(), v.clone()))
            })
            .collect()
    }
}

/// What a file's header says about its first layer, without its pixels: what `merge`
/// checks before it reads any.
#[derive(Clone, Debug)]
pub struct ExrLayout {
    /// The display window's size and where the data window starts in it.
    pub frame: [u32; 2],
    pub origin: [u32; 2],
    /// The data window's size.
    pub width: usize,
    pub height: usize,
    /// Channel names, as the file lists them.
    pub channels: Vec<String>,
    /// The layer's text attributes.
    pub attributes: Vec<(String, String)>,
}

/// Opens an EXR file for reading: a regular file within the input-size limit.
fn open(path: &Path) -> Result<std::fs::File, ExrFault> {
    let limits = crate::limits::Limits::current();
    let file = std::fs::File::open(path).map_err(ExrFault::Open)?;
    let meta = file.metadata().map_err(ExrFault::Open)?;
    if !meta.is_file() {
        return Err(ExrFault::NotRegular);
    }
    limits.check_file_bytes(meta.len(), "reading this file")?;
    Ok(file)
}

/// Where a layer's data window may lie.
#[derive(Clone, Copy, PartialEq, Eq)]
enum DataWindow {
    /// Inside the display window: a render or a crop of one.
    InsideDisplay,
    /// Anywhere: an image read as a texture is its data window.
    Anywhere,
}

/// The first layer's layout, after checking that every layer's declared pixels fit the
/// memory limit.
fn layout(meta: &MetaData, window: DataWindow) -> Result<ExrLayout, ExrFault> {
    let mut bytes = 0u64;
    for h in meta.headers.iter() {
        let pixels = h.layer_size.width() as u64 * h.layer_size.height() as u64;
        // Each sample as an f32, and once more while it is converted.
        bytes = bytes.saturating_add(pixels.saturating_mul(h.channels.list.len() as u64 * 8));
    }
    crate::limits::Limits::current().check_memory(bytes, "the pixels its header declares")?;
    let header = meta.headers.first().ok_or(ExrFault::NoImage)?;
    let display = header.shared_attributes.display_window;
    let position = header.own_attributes.layer_position;
    let (x0, y0) = (
        position.x() - display.position.x(),
        position.y() - display.position.y(),
    );
    let size = header.layer_size;
    if window == DataWindow::InsideDisplay
        && (x0 < 0
            || y0 < 0
            || x0 as usize + size.width() > display.size.width()
            || y0 as usize + size.height() > display.size.height())
    {
        return Err(ExrFault::DataWindow {
            data_origin: [position.x() as i64, position.y() as i64],
            data_size: [size.width(), size.height()],
            display_origin: [display.position.x() as i64, display.position.y() as i64],
            display_size: [display.size.width(), display.size.height()],
        });
    }
    Ok(ExrLayout {
        frame: [display.size.width() as u32, display.size.height() as u32],
        origin: [x0.max(0) as u32, y0.max(0) as u32],
        width: size.width(),
        height: size.height(),
        channels: header
            .channels
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect(),
        attributes: text_attributes(&header.own_attributes.other),
    })
}

fn text_attributes(
    attributes: &std::collections::HashMap<Text, AttributeValue>,
) -> Vec<(String, String)> {
    attributes
        .iter()
        .filter_map(|(k, v)| match v {
            AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect()
}

/// The header of an EXR file: its first layer's layout and text attributes.
pub fn read_exr_header(path: &Path) -> Result<ExrLayout, ExrReadError> {
    let file = open(path).map_err(|f| f.of(path))?;
    let meta = MetaData::read_from_unbuffered(file, false)
        .map_err(|e| ExrFault::Decode(e.to_string()).of(path))?;
    layout(&meta, DataWindow::InsideDisplay).map_err(|f| f.of(path))
}

/// Checks an EXR file as every read does, before reading its pixels.
pub fn check_exr_file(path: &Path) -> Result<(), ExrReadError> {
    read_exr_header(path).map(|_| ())
}

/// An EXR file's first layer: every channel (as f32) and the header.
pub fn read_exr(path: &Path) -> Result<ExrContents, ExrReadError> {
    let file = open(path).map_err(|f| f.of(path))?;
    read_first_layer(std::io::BufReader::new(file), DataWindow::InsideDisplay)
        .map_err(|f| f.of(path))
}

/// An EXR held in memory (a texture or a dome map as `limits::read_input` read it): its
/// first layer's size and its texels as RGBA (`A` is 1 where the image has none), rows
/// from the top. The data window is the image, as a texture reader takes it.
pub fn decode_exr_rgba(bytes: &[u8]) -> Result<(usize, usize, Vec<[f32; 4]>), ExrFault> {
    let image = read_first_layer(std::io::Cursor::new(bytes), DataWindow::Anywhere)?;
    let channel = |name: &'static str| image.channel(name).ok_or(ExrFault::MissingChannel(name));
    let (r, g, b) = (channel("R")?, channel("G")?, channel("B")?);
    let a = image.channel("A");
    let texels = (0..image.width * image.height)
        .map(|i| [r[i], g[i], b[i], a.map_or(1.0, |a| a[i])])
        .collect();
    Ok((image.width, image.height, texels))
}

fn read_first_layer(
    mut source: impl Read + Seek + Send,
    window: DataWindow,
) -> Result<ExrContents, ExrFault> {
    let decode = |e: ::exr::error::Error| ExrFault::Decode(e.to_string());
    let meta = MetaData::read_from_buffered(&mut source, false).map_err(decode)?;
    let layout = layout(&meta, window)?;
    source
        .seek(std::io::SeekFrom::Start(0))
        .map_err(ExrFault::Open)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(source)
        .map_err(decode)?;
    let mut layer = image.layer_data;
    // Float channels are moved, not copied (a 1080p file with 40 AOVs holds 1 GB of them).
    let channels = std::mem::take(&mut layer.channel_data.list)
        .into_iter()
        .map(|c| {
            let values = match c.sample_data {
                FlatSamples::F32(v) => v,
                other => other.values_as_f32().collect(),
            };
            (c.name.to_string(), values)
        })
        .collect();
    Ok(ExrContents {
        width: layer.size.width(),
        height: layer.size.height(),
        channels,
        attributes: text_attributes(&layer.attributes.other),
        frame: layout.frame,
        origin: layout.origin,
        world_to_camera: layer.attributes.world_to_camera,
        world_to_ndc: layer.attributes.world_to_normalized_device,
        capture_date: layer
            .attributes
            .capture_date
            .as_ref()
            .map(|t| t.to_string()),
    })
}
