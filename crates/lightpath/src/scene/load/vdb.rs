//! OpenVDB files (`.vdb`): one float grid, chosen by name, as its active voxels (leaf
//! nodes and constant tiles) and its index-to-world transform. This is what a
//! heterogeneous medium's `density = "smoke.vdb"`, `grid = "density"` reads
//! (docs/scene-format.md); `media::grid::DensityGrid` turns it into a lookup.
//!
//! Why our own reader and not the `vdb-rs` crate (0.6): that crate panics on input it
//! does not expect (`panic!` on any map but the scale ones, so every rotated grid;
//! `todo!`/`assert!` on older versions, duplicate names and multi-buffer trees),
//! allocates whatever sizes a file claims (a process abort, which `catch_unwind` cannot
//! catch), and hands unchecked buffers to C Blosc (`blosc_cbuffer_sizes` reads 16 bytes
//! from a shorter buffer): a garbled file could crash or read out of bounds. It also drops
//! root-level tiles. This reader is safe Rust, checks every length against the bytes
//! that are there and every allocation against `limits`, and returns an error naming
//! what was expected.
//!
//! Supported, which is what OpenVDB 3 and later (Houdini, Blender, EmberGen) write:
//! format versions 222 to 224; trees `Tree_float_5_4_3`, stored as 32- or 16-bit floats
//! (`_HalfFloat`, `is_saved_as_half_float`); Blosc (LZ4 or zlib codec, byte shuffle),
//! zlib or no compression, with or without active-mask compression; the linear maps
//! (uniform/non-uniform scale, translation, affine, unitary); instanced grids. Not
//! supported, each a clear error: vector, double and other grid types, level sets,
//! frustum maps, Blosc's BloscLZ/Snappy/Zstd codecs and bit shuffle, formats before 222.
//!
//! The layout follows OpenVDB's own writer (`io/Archive.cc`, `io/Compression.h`,
//! `tree/RootNode.h`, `InternalNode.h`, `LeafNode.h`) and c-blosc 1's frame format.

use crate::limits::Limits;
use crate::scene::desc::Origin;
use crate::scene::SceneError;
use glam::{DAffine3, DMat3, DVec3, IVec3};
use std::path::Path;

/// Voxels along one edge of a leaf node.
pub const LEAF_DIM: i32 = 8;
/// Voxels of a leaf node.
pub const LEAF_VOXELS: usize = 512;

/// One float grid of a `.vdb` file.
#[derive(Clone, Debug)]
pub struct VdbGrid {
    pub name: String,
    /// Index space (voxel centres at integer coordinates) to world space.
    pub index_to_world: DAffine3,
    /// The grid's background value (the value of voxels no node stores). Only active
    /// voxels carry density; the background is kept for information.
    pub background: f32,
    pub leaves: Vec<VdbLeaf>,
    /// Active tiles: cubes of constant value above the leaf level.
    pub tiles: Vec<VdbTile>,
    /// Whether the file stored the values as 16-bit floats.
    pub half: bool,
}

/// A leaf node: 8³ voxels from `origin`, x slowest (`(x << 6) | (y << 3) | z`).
#[derive(Clone, Debug)]
pub struct VdbLeaf {
    pub origin: IVec3,
    pub values: Box<[f32; LEAF_VOXELS]>,
    /// Bit `n` of `active[n / 64]`: voxel `n` is active.
    pub active: [u64; 8],
}

/// An active tile: `edge`³ voxels of one value from `origin` (edge 8, 128 or 4096).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VdbTile {
    pub origin: IVec3,
    pub edge: i32,
    pub value: f32,
}

impl VdbLeaf {
    pub fn is_active(&self, n: usize) -> bool {
        self.active[n / 64] >> (n % 64) & 1 == 1
    }
}

impl VdbGrid {
    /// Every active voxel with its value, tiles expanded (for tests and small grids).
    pub fn active_voxels(&self) -> impl Iterator<Item = (IVec3, f32)> + '_ {
        let leaves = self.leaves.iter().flat_map(|leaf| {
            (0..LEAF_VOXELS)
                .filter(|&n| leaf.is_active(n))
                .map(|n| (leaf.origin + leaf_offset(n), leaf.values[n]))
        });
        let tiles = self.tiles.iter().flat_map(|t| {
            let e = t.edge;
            (0..e * e * e).map(move |n| {
                (
                    t.origin + IVec3::new(n / (e * e), (n / e) % e, n % e),
                    t.value,
                )
            })
        });
        leaves.chain(tiles)
    }

    /// Active voxels, tiles counted voxel by voxel.
    pub fn active_voxel_count(&self) -> u64 {
        let leaves: u64 = self
            .leaves
            .iter()
            .map(|l| l.active.iter().map(|w| w.count_ones() as u64).sum::<u64>())
            .sum();
        let tiles: u64 = self.tiles.iter().map(|t| (t.edge as u64).pow(3)).sum();
        leaves + tiles
    }
}

/// Position of voxel `n` within its leaf.
pub fn leaf_offset(n: usize) -> IVec3 {
    let n = n as i32;
    IVec3::new(n >> 6, (n >> 3) & 7, n & 7)
}

/// Reads grid `grid` of the `.vdb` file `path`, named at `at` (errors point there and
/// name the file).
pub fn load(path: &Path, grid: &str, at: &Origin) -> Result<VdbGrid, SceneError> {
    let file = path.display().to_string();
    let bytes = crate::limits::read_input(path)
        .map_err(|e| at.error(format!("cannot read OpenVDB file {file}: {e}")))?;
    parse(&bytes, grid).map_err(|e| at.error(format!("OpenVDB file {file}: {e}")))
}

/// The names and tree types of the grids in a `.vdb` file's bytes.
pub fn grid_names(bytes: &[u8]) -> Result<Vec<(String, String)>, String> {
    let header = Header::read(bytes)?;
    Ok(header
        .grids
        .into_iter()
        .map(|g| (g.name, g.tree_type))
        .collect())
}

/// Grid `grid` of a `.vdb` file's bytes.
pub fn parse(bytes: &[u8], grid: &str) -> Result<VdbGrid, String> {
    let header = Header::read(bytes)?;
    let listed = || {
        header
            .grids
            .iter()
            .map(|g| format!("'{}' ({})", g.name, g.tree_type))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let Some(desc) = header.grids.iter().find(|g| g.name == grid) else {
        return Err(format!(
            "no grid named '{grid}'; the file has {}",
            if header.grids.is_empty() {
                "no grids".to_string()
            } else {
                listed()
            }
        ));
    };
    let base_type = desc.tree_type.trim_end_matches("_HalfFloat");
    if base_type != "Tree_float_5_4_3" {
        let kind = match base_type {
            t if t.starts_with("Tree_vec3") => "a vector grid",
            "Tree_double_5_4_3" => "a double-precision grid",
            "Tree_bool_5_4_3" | "Tree_mask_5_4_3" => "a mask grid",
            t if t.starts_with("Tree_int") => "an integer grid",
            t if t.starts_with("ptdataidx") || t.starts_with("ptidx") => "a point grid",
            _ => "not a float grid",
        };
        return Err(format!(
            "grid '{grid}' is {kind} ({}); a density must be a float grid (Tree_float_5_4_3)",
            desc.tree_type
        ));
    }
    let mut r = Reader::at(bytes, desc.grid_pos)?;
    let compression = r.u32("the grid's compression flags")?;
    if compression & !(ZIP | ACTIVE_MASK | BLOSC) != 0 {
        return Err(format!(
            "grid '{grid}': unknown compression flags {compression:#x} (known: zlib 0x1, active mask 0x2, Blosc 0x4)"
        ));
    }
    let meta = read_metadata(&mut r)?;
    let half = desc.tree_type.ends_with("_HalfFloat")
        || meta
            .iter()
            .any(|(k, v)| k == "is_saved_as_half_float" && matches!(v, Meta::Bool(true)));
    if let Some((_, Meta::String(class))) = meta.iter().find(|(k, _)| k == "class") {
        if class == "level set" {
            return Err(format!(
                "grid '{grid}' is a level set (signed distances), not a density; convert it to a fog volume first"
            ));
        }
    }
    let index_to_world = read_transform(&mut r, grid)?;
    // An instanced grid shares the tree of the grid it names (written before it).
    if !desc.instance_parent.is_empty() {
        let parent = header
            .grids
            .iter()
            .find(|g| g.name == desc.instance_parent)
            .ok_or_else(|| {
                format!(
                    "grid '{grid}' is an instance of '{}', which the file does not have",
                    desc.instance_parent
                )
            })?;
        let mut parent_grid = parse(bytes, &parent.name.clone())?;
        parent_grid.name = grid.to_string();
        parent_grid.index_to_world = index_to_world;
        return Ok(parent_grid);
    }
    let mut tree = TreeReader {
        r,
        half,
        compression,
        background: 0.0,
        leaves: Vec::new(),
        tiles: Vec::new(),
        scratch: Vec::new(),
        limits: Limits::current(),
        grid,
    };
    tree.read_topology()?;
    tree.r.pos = usize::try_from(desc.block_pos)
        .ok()
        .filter(|&p| p <= bytes.len())
        .ok_or_else(|| {
            format!(
                "grid '{grid}': its voxel data starts at byte {}, past the end of the file ({} bytes)",
                desc.block_pos,
                bytes.len()
            )
        })?;
    tree.read_buffers()?;
    Ok(VdbGrid {
        name: grid.to_string(),
        index_to_world,
        background: tree.background,
        leaves: tree.leaves,
        tiles: tree.tiles,
        half,
    })
}

const ZIP: u32 = 0x1;
const ACTIVE_MASK: u32 = 0x2;
const BLOSC: u32 = 0x4;

/// Format versions read (OpenVDB's `OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION` to
/// `..._MULTIPASS_IO`).
const MIN_VERSION: u32 = 222;
const MAX_VERSION: u32 = 224;

/// Bytes a leaf takes once read (values, mask, origin, box).
const LEAF_BYTES: u64 = (LEAF_VOXELS * 4 + 64 + 12 + 16) as u64;

/// Bounds-checked little-endian reading.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn at(bytes: &'a [u8], pos: u64) -> Result<Reader<'a>, String> {
        let pos = usize::try_from(pos)
            .ok()
            .filter(|&p| p <= bytes.len())
            .ok_or_else(|| {
                format!(
                    "a grid starts at byte {pos}, past the end of the file ({} bytes): truncated?",
                    bytes.len()
                )
            })?;
        Ok(Reader { bytes, pos })
    }

    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(format!(
                "truncated: {what} needs {n} bytes at byte {}, the file has {}",
                self.pos,
                self.bytes.len()
            ));
        };
        let s = &self.bytes[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], String> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N, what)?);
        Ok(a)
    }
    fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.array::<1>(what)?[0])
    }
    fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }
    fn i32(&mut self, what: &str) -> Result<i32, String> {
        Ok(i32::from_le_bytes(self.array(what)?))
    }
    fn u64(&mut self, what: &str) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.array(what)?))
    }
    fn i64(&mut self, what: &str) -> Result<i64, String> {
        Ok(i64::from_le_bytes(self.array(what)?))
    }
    fn f32(&mut self, what: &str) -> Result<f32, String> {
        Ok(f32::from_le_bytes(self.array(what)?))
    }
    fn f64(&mut self, what: &str) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.array(what)?))
    }
    fn dvec3(&mut self, what: &str) -> Result<DVec3, String> {
        Ok(DVec3::new(
            self.f64(what)?,
            self.f64(what)?,
            self.f64(what)?,
        ))
    }
    fn ivec3(&mut self, what: &str) -> Result<IVec3, String> {
        Ok(IVec3::new(
            self.i32(what)?,
            self.i32(what)?,
            self.i32(what)?,
        ))
    }
    /// A length-prefixed string (the length is checked against the bytes left).
    fn string(&mut self, what: &str) -> Result<String, String> {
        let n = self.u32(what)? as usize;
        Ok(String::from_utf8_lossy(self.take(n, what)?).into_owned())
    }
    /// A node mask of `bits` bits as 64-bit words.
    fn mask(&mut self, bits: usize, what: &str) -> Result<Vec<u64>, String> {
        let raw = self.take(bits / 8, what)?;
        Ok(raw
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap_or_default()))
            .collect())
    }
}

/// A grid's entry in the file header.
struct Descriptor {
    name: String,
    tree_type: String,
    instance_parent: String,
    grid_pos: u64,
    block_pos: u64,
}

struct Header {
    grids: Vec<Descriptor>,
}

impl Header {
    fn read(bytes: &[u8]) -> Result<Header, String> {
        let mut r = Reader { bytes, pos: 0 };
        let magic = r
            .take(8, "the OpenVDB magic number")
            .map_err(|_| "not an OpenVDB file: shorter than its 8-byte magic number".to_string())?;
        if magic != [0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0] {
            return Err(
                "not an OpenVDB file: it does not start with the magic number ' BDV'".into(),
            );
        }
        let version = r.u32("the format version")?;
        if version < MIN_VERSION {
            return Err(format!(
                "format version {version} predates {MIN_VERSION} (OpenVDB 3); re-save the file with a newer OpenVDB"
            ));
        }
        if version > MAX_VERSION {
            return Err(format!(
                "format version {version} is newer than this reader knows ({MIN_VERSION} to {MAX_VERSION})"
            ));
        }
        let _library_version = (r.u32("the library version")?, r.u32("the library version")?);
        if r.u8("the grid-offsets flag")? == 0 {
            return Err("written as a stream without grid offsets; save it as a file".into());
        }
        r.take(36, "the file's UUID")?;
        read_metadata(&mut r)?;
        let count = r.u32("the grid count")?;
        let mut grids = Vec::new();
        for _ in 0..count {
            let name = r.string("a grid name")?;
            let tree_type = r.string("a grid type")?;
            let instance_parent = r.string("a grid's instance parent")?;
            let grid_pos = r.u64("a grid's offset")?;
            let block_pos = r.u64("a grid's offset")?;
            let end_pos = r.u64("a grid's offset")?;
            // Names made unique by the writer carry a suffix after an ASCII record separator.
            let name = name.split('\u{1e}').next().unwrap_or_default().to_string();
            let instance_parent = instance_parent
                .split('\u{1e}')
                .next()
                .unwrap_or_default()
                .to_string();
            grids.push(Descriptor {
                name,
                tree_type,
                instance_parent,
                grid_pos,
                block_pos,
            });
            // The next descriptor follows this grid's data.
            r = Reader::at(bytes, end_pos)?;
        }
        Ok(Header { grids })
    }
}

/// A metadata value the reader looks at; others are skipped by their stored size.
enum Meta {
    String(String),
    Bool(bool),
    Other,
}

fn read_metadata(r: &mut Reader) -> Result<Vec<(String, Meta)>, String> {
    let count = r.u32("a metadata count")?;
    let mut out = Vec::new();
    for _ in 0..count {
        let name = r.string("a metadata name")?;
        let kind = r.string("a metadata type")?;
        let size = r.u32("a metadata size")? as usize;
        let data = r.take(size, "a metadata value")?;
        let value = match kind.as_str() {
            "string" => Meta::String(String::from_utf8_lossy(data).into_owned()),
            "bool" => Meta::Bool(data.first().is_some_and(|&b| b != 0)),
            _ => Meta::Other,
        };
        out.push((name, value));
    }
    Ok(out)
}

/// A grid's map from index to world space; OpenVDB's matrices act on row vectors.
fn read_transform(r: &mut Reader, grid: &str) -> Result<DAffine3, String> {
    let kind = r.string("the grid's transform")?;
    let what = "the grid's transform";
    let affine = match kind.as_str() {
        "UniformScaleMap" | "ScaleMap" => {
            let scale = r.dvec3(what)?;
            r.take(4 * 24, what)?;
            DAffine3::from_scale(scale)
        }
        "UniformScaleTranslateMap" | "ScaleTranslateMap" => {
            let translation = r.dvec3(what)?;
            let scale = r.dvec3(what)?;
            r.take(4 * 24, what)?;
            DAffine3::from_scale_rotation_translation(scale, Default::default(), translation)
        }
        "TranslationMap" => DAffine3::from_translation(r.dvec3(what)?),
        "AffineMap" | "UnitaryMap" => {
            let mut m = [0.0f64; 16];
            for v in &mut m {
                *v = r.f64(what)?;
            }
            // Row i of the stored matrix is the image of axis i; row 3 the translation.
            DAffine3 {
                matrix3: DMat3::from_cols(
                    DVec3::new(m[0], m[1], m[2]),
                    DVec3::new(m[4], m[5], m[6]),
                    DVec3::new(m[8], m[9], m[10]),
                ),
                translation: DVec3::new(m[12], m[13], m[14]),
            }
        }
        "NonlinearFrustumMap" => {
            return Err(format!(
                "grid '{grid}' has a frustum transform; only linear transforms are supported"
            ))
        }
        other => return Err(format!("grid '{grid}' has an unknown transform '{other}'")),
    };
    let det = affine.matrix3.determinant();
    if !affine.matrix3.is_finite() || !affine.translation.is_finite() || det.abs() < 1e-300 {
        return Err(format!(
            "grid '{grid}' has a degenerate transform ({kind} with determinant {det:e})"
        ));
    }
    Ok(affine)
}

struct TreeReader<'a, 'g> {
    r: Reader<'a>,
    half: bool,
    compression: u32,
    background: f32,
    leaves: Vec<VdbLeaf>,
    tiles: Vec<VdbTile>,
    /// Internal nodes' values, reused.
    scratch: Vec<f32>,
    limits: Limits,
    grid: &'g str,
}

impl TreeReader<'_, '_> {
    fn read_topology(&mut self) -> Result<(), String> {
        let buffers = self.r.u32("the tree's buffer count")?;
        if buffers != 1 {
            return Err(format!(
                "grid '{}' has {buffers} buffers per leaf; only 1 is supported",
                self.grid
            ));
        }
        // The background is stored as a full float even in half-float files.
        self.background = self.r.f32("the background value")?;
        let tiles = self.r.u32("the root's tile count")?;
        let children = self.r.u32("the root's child count")?;
        for _ in 0..tiles {
            let origin = self.r.ivec3("a root tile")?;
            let value = self.r.f32("a root tile")?;
            let active = self.r.u8("a root tile")? != 0;
            self.tile(origin, 4096, value, active)?;
        }
        for _ in 0..children {
            let origin = self.r.ivec3("a root child's origin")?;
            if origin.to_array().iter().any(|c| c & 4095 != 0) {
                return Err(format!(
                    "grid '{}': a top-level node at {origin} is not aligned to 4096 voxels",
                    self.grid
                ));
            }
            self.internal(origin, 5)?;
        }
        Ok(())
    }

    /// An internal node of `2^log2`³ children: 5 (children of 128³) or 4 (leaves).
    fn internal(&mut self, origin: IVec3, log2: u32) -> Result<(), String> {
        let n = 1usize << (3 * log2);
        let child_mask = self.r.mask(n, "an internal node's child mask")?;
        let value_mask = self.r.mask(n, "an internal node's value mask")?;
        let mut values = std::mem::take(&mut self.scratch);
        values.resize(n, 0.0);
        self.values(&value_mask, &mut values)?;
        let child_shift = if log2 == 5 { 7 } else { 3 };
        let at = |i: usize| {
            let i = i as i32;
            let l = log2 as i32;
            origin
                + IVec3::new(i >> (2 * l), (i >> l) & ((1 << l) - 1), i & ((1 << l) - 1))
                    * (1 << child_shift)
        };
        let on = |mask: &[u64], i: usize| mask[i / 64] >> (i % 64) & 1 == 1;
        for (i, &value) in values.iter().enumerate() {
            if !on(&child_mask, i) {
                self.tile(at(i), 1 << child_shift, value, on(&value_mask, i))?;
            }
        }
        self.scratch = values;
        for i in 0..n {
            if !on(&child_mask, i) {
                continue;
            }
            if log2 == 5 {
                self.internal(at(i), 4)?;
            } else {
                let mask = self.r.mask(LEAF_VOXELS, "a leaf's value mask")?;
                let count = self.leaves.len() as u64 + 1;
                self.limits.check_memory(
                    count * LEAF_BYTES,
                    &format!("the leaves of grid '{}'", self.grid),
                )?;
                self.leaves.push(VdbLeaf {
                    origin: at(i),
                    values: Box::new([0.0; LEAF_VOXELS]),
                    active: mask.try_into().unwrap_or_default(),
                });
            }
        }
        Ok(())
    }

    fn tile(&mut self, origin: IVec3, edge: i32, value: f32, active: bool) -> Result<(), String> {
        if !active {
            return Ok(());
        }
        if !value.is_finite() {
            return Err(format!(
                "grid '{}': a tile at {origin} has the value {value}",
                self.grid
            ));
        }
        self.limits.check_memory(
            (self.tiles.len() as u64 + 1) * 32,
            &format!("the tiles of grid '{}'", self.grid),
        )?;
        self.tiles.push(VdbTile {
            origin,
            edge,
            value,
        });
        Ok(())
    }

    fn read_buffers(&mut self) -> Result<(), String> {
        let mut leaves = std::mem::take(&mut self.leaves);
        for leaf in &mut leaves {
            let mask = self.r.mask(LEAF_VOXELS, "a leaf's value mask")?;
            leaf.active = mask.try_into().unwrap_or_default();
            let active = leaf.active;
            self.values(&active, &mut leaf.values[..])?;
            for (n, &v) in leaf.values.iter().enumerate() {
                if leaf.is_active(n) && !v.is_finite() {
                    return Err(format!(
                        "grid '{}': voxel {} has the value {v}",
                        self.grid,
                        leaf.origin + leaf_offset(n)
                    ));
                }
            }
        }
        self.leaves = leaves;
        Ok(())
    }

    /// A node's values (OpenVDB's `readCompressedValues`): a byte saying which
    /// inactive values are stored, then the active (or all) values, compressed.
    fn values(&mut self, value_mask: &[u64], out: &mut [f32]) -> Result<(), String> {
        let n = out.len();
        let meta = self.r.u8("a node's compression metadata")?;
        if meta > 6 {
            return Err(format!(
                "grid '{}': unknown node metadata {meta} at byte {} (expected 0 to 6)",
                self.grid,
                self.r.pos - 1
            ));
        }
        let bg = self.background;
        let mut inactive = [if meta == 0 { bg } else { -bg }, bg];
        if matches!(meta, 2 | 4 | 5) {
            inactive[0] = self.r.f32("an inactive value")?;
            if meta == 5 {
                inactive[1] = self.r.f32("an inactive value")?;
            }
        }
        let selection = if matches!(meta, 3..=5) {
            Some(self.r.mask(n, "a node's selection mask")?)
        } else {
            None
        };
        let on = |mask: &[u64], i: usize| mask[i / 64] >> (i % 64) & 1 == 1;
        let active: usize = value_mask.iter().map(|w| w.count_ones() as usize).sum();
        let count = if self.compression & ACTIVE_MASK != 0 && meta != 6 {
            active
        } else {
            n
        };
        let width = if self.half { 2 } else { 4 };
        let mut raw = vec![0u8; count * width];
        // OpenVDB's HalfWriter writes nothing at all for no values; the float path
        // writes an empty block.
        if !(self.half && count == 0) {
            self.data(&mut raw)?;
        }
        let value = |i: usize| {
            let b = &raw[i * width..];
            if width == 2 {
                half::f16::from_le_bytes([b[0], b[1]]).to_f32()
            } else {
                f32::from_le_bytes([b[0], b[1], b[2], b[3]])
            }
        };
        if count == n {
            for (i, o) in out.iter_mut().enumerate() {
                *o = value(i);
            }
        } else {
            let mut next = 0;
            for (i, o) in out.iter_mut().enumerate() {
                *o = if on(value_mask, i) {
                    next += 1;
                    value(next - 1)
                } else if selection.as_ref().is_some_and(|s| on(s, i)) {
                    inactive[1]
                } else {
                    inactive[0]
                };
            }
        }
        Ok(())
    }

    /// `out.len()` bytes of values, as `io::readData` stores them.
    fn data(&mut self, out: &mut [u8]) -> Result<(), String> {
        if self.compression & (BLOSC | ZIP) == 0 {
            out.copy_from_slice(self.r.take(out.len(), "a node's values")?);
            return Ok(());
        }
        let stored = self.r.i64("a compressed block's size")?;
        // A negative size: the writer stored the bytes uncompressed.
        if stored <= 0 {
            let len = stored.unsigned_abs();
            if len != out.len() as u64 {
                return Err(format!(
                    "grid '{}': an uncompressed block of {len} bytes at byte {} where {} were expected",
                    self.grid,
                    self.r.pos,
                    out.len()
                ));
            }
            out.copy_from_slice(self.r.take(out.len(), "a node's values")?);
            return Ok(());
        }
        let at = self.r.pos;
        let len = usize::try_from(stored).unwrap_or(usize::MAX);
        let block = self.r.take(len, "a compressed block")?;
        let result = if self.compression & BLOSC != 0 {
            blosc_decode(block, out)
        } else {
            zlib_decode(block, out)
        };
        result.map_err(|e| format!("grid '{}': at byte {at}: {e}", self.grid))
    }
}

fn zlib_decode(src: &[u8], out: &mut [u8]) -> Result<(), String> {
    use std::io::Read;
    let mut z = flate2::read::ZlibDecoder::new(src);
    z.read_exact(out)
        .map_err(|e| format!("zlib data does not inflate to {} bytes: {e}", out.len()))?;
    let mut extra = [0u8; 1];
    if matches!(z.read(&mut extra), Ok(1)) {
        return Err(format!(
            "zlib data inflates to more than the {} bytes expected",
            out.len()
        ));
    }
    Ok(())
}

/// A c-blosc 1 frame (`blosc_decompress`): a 16-byte header (version, codec version,
/// flags, type size, sizes), block offsets, then each block as one stream or one per
/// byte of the type, each LZ4 or zlib compressed (or stored), byte-shuffled.
pub fn blosc_decode(src: &[u8], out: &mut [u8]) -> Result<(), String> {
    if src.len() < 16 {
        return Err(format!(
            "a Blosc block of {} bytes, shorter than its header",
            src.len()
        ));
    }
    let word = |at: usize| u32::from_le_bytes([src[at], src[at + 1], src[at + 2], src[at + 3]]);
    let (version, flags, typesize) = (src[0], src[2], src[3] as usize);
    let (nbytes, blocksize, cbytes) = (word(4) as usize, word(8) as usize, word(12) as usize);
    if !(1..=2).contains(&version) || flags & 0x08 != 0 {
        return Err(format!(
            "Blosc format version {version}, flags {flags:#x}: not a c-blosc 1 frame"
        ));
    }
    if nbytes != out.len() {
        return Err(format!(
            "Blosc block holds {nbytes} bytes where {} were expected",
            out.len()
        ));
    }
    if cbytes > src.len() {
        return Err(format!(
            "Blosc block claims {cbytes} bytes but {} are stored",
            src.len()
        ));
    }
    let src = &src[..cbytes];
    if nbytes == 0 {
        return Ok(());
    }
    if flags & 0x02 != 0 {
        // Stored uncompressed after the header.
        let body = src
            .get(16..16 + nbytes)
            .ok_or("truncated uncompressed Blosc block")?;
        out.copy_from_slice(body);
        return Ok(());
    }
    if flags & 0x04 != 0 {
        return Err("Blosc bit shuffle is not supported (OpenVDB writes byte shuffle)".into());
    }
    let codec = flags >> 5;
    if codec != 1 && codec != 3 {
        let name = ["BloscLZ", "LZ4", "Snappy", "zlib", "Zstd"]
            .get(codec as usize)
            .unwrap_or(&"an unknown codec");
        return Err(format!(
            "Blosc codec {name} is not supported (LZ4, OpenVDB's, and zlib are)"
        ));
    }
    if blocksize == 0 || typesize == 0 {
        return Err("Blosc block with a zero block or type size".into());
    }
    let shuffle = flags & 0x01 != 0 && typesize > 1;
    let dont_split = flags & 0x10 != 0;
    let nblocks = nbytes.div_ceil(blocksize);
    let starts_end = 16 + 4 * nblocks;
    if starts_end > src.len() {
        return Err("truncated Blosc block offsets".into());
    }
    let mut tmp = vec![0u8; if shuffle { blocksize.min(nbytes) } else { 0 }];
    for j in 0..nblocks {
        let leftover = j == nblocks - 1 && nbytes % blocksize != 0;
        let bsize = if leftover {
            nbytes % blocksize
        } else {
            blocksize
        };
        let splits = if !dont_split && typesize <= 16 && blocksize / typesize >= 128 && !leftover {
            typesize
        } else {
            1
        };
        if bsize % splits != 0 {
            return Err("Blosc block size is not a multiple of its type size".into());
        }
        let per = bsize / splits;
        let dest = &mut out[j * blocksize..j * blocksize + bsize];
        let target: &mut [u8] = if shuffle { &mut tmp[..bsize] } else { dest };
        let mut at = word(16 + 4 * j) as usize;
        for s in 0..splits {
            let size = src
                .get(at..at + 4)
                .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .ok_or("a Blosc stream offset past the block")?;
            at += 4;
            let size = usize::try_from(size).map_err(|_| "a negative Blosc stream size")?;
            let stream = src
                .get(at..at.saturating_add(size))
                .ok_or("a Blosc stream past the block")?;
            at += size;
            let part = &mut target[s * per..(s + 1) * per];
            if size == per {
                part.copy_from_slice(stream);
            } else if codec == 1 {
                let got = lz4_flex::block::decompress_into(stream, part)
                    .map_err(|e| format!("LZ4 stream in a Blosc block: {e}"))?;
                if got != per {
                    return Err(format!(
                        "LZ4 stream gave {got} bytes where {per} were expected"
                    ));
                }
            } else {
                zlib_decode(stream, part)?;
            }
        }
        if shuffle {
            // Byte b of element i was stored at b * elements + i.
            let elements = bsize / typesize;
            let dest = &mut out[j * blocksize..j * blocksize + bsize];
            for i in 0..elements {
                for b in 0..typesize {
                    dest[i * typesize + b] = tmp[b * elements + i];
                }
            }
            let rest = elements * typesize;
            dest[rest..].copy_from_slice(&tmp[rest..bsize]);
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn data(name: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/vdb")
            .join(name)
    }

    fn bytes(name: &str) -> Vec<u8> {
        std::fs::read(data(name)).expect("test grid (tests/data/vdb/make.sh writes them)")
    }

    /// The density make_vdb.cpp writes, active on [-4,11]x[0,9]x[2,9].
    pub(crate) fn ramp(p: IVec3) -> f32 {
        2.0 + p.x as f32 / 4.0 + p.y as f32 / 8.0 + p.z as f32 / 16.0
    }

    pub(crate) fn in_ramp_box(p: IVec3) -> bool {
        p.cmpge(IVec3::new(-4, 0, 2)).all() && p.cmple(IVec3::new(11, 9, 9)).all()
    }

    #[test]
    fn every_encoding_of_the_ramp_reads_its_exact_voxels_and_transform() {
        // Voxel (3, 4, 5) in world space as OpenVDB 10 maps it (pyopenvdb's indexToWorld).
        let cases = [
            ("ramp.vdb", DVec3::new(1.3, 2.4, 3.5), false),
            ("ramp_zip.vdb", DVec3::new(-0.7, 1.3, 1.25), false),
            (
                "ramp_half.vdb",
                DVec3::new(0.6196152422706633, 0.742820323027551, 3.0),
                true,
            ),
        ];
        for (file, world, half) in cases {
            let g = parse(&bytes(file), "density").unwrap_or_else(|e| panic!("{file}: {e}"));
            assert_eq!(g.half, half, "{file}");
            assert_eq!(g.leaves.len(), 12, "{file}: leaves");
            assert!(g.tiles.is_empty(), "{file}");
            assert_eq!(g.active_voxel_count(), 16 * 10 * 8, "{file}");
            for (p, v) in g.active_voxels() {
                assert!(in_ramp_box(p), "{file}: active voxel {p} outside the ramp");
                assert_eq!(v, ramp(p), "{file}: voxel {p}");
            }
            let w = g.index_to_world.transform_point3(DVec3::new(3.0, 4.0, 5.0));
            assert!((w - world).length() < 1e-12, "{file}: {w} vs {world}");
        }
    }

    #[test]
    fn tiles_of_both_internal_levels_are_read_beside_leaf_voxels() {
        let g = parse(&bytes("tiles.vdb"), "density").unwrap();
        let mut tiles = g.tiles.clone();
        tiles.sort_by_key(|t| t.edge);
        assert_eq!(
            tiles,
            [
                VdbTile {
                    origin: IVec3::new(128, 0, 0),
                    edge: 8,
                    value: 3.0
                },
                VdbTile {
                    origin: IVec3::ZERO,
                    edge: 128,
                    value: 1.5
                }
            ]
        );
        let voxels: Vec<_> = g
            .leaves
            .iter()
            .flat_map(|l| {
                (0..LEAF_VOXELS)
                    .filter(|&n| l.is_active(n))
                    .map(|n| (l.origin + leaf_offset(n), l.values[n]))
            })
            .collect();
        assert_eq!(
            voxels,
            [(IVec3::new(136, 0, 0), 4.0), (IVec3::new(137, 1, 2), 4.0)]
        );
        // As pyopenvdb counts them: 128³ + 8³ + 2.
        assert_eq!(g.active_voxel_count(), 2_097_666);
    }

    #[test]
    fn a_grid_is_chosen_by_name_and_other_types_are_refused_by_name() {
        let b = bytes("grids.vdb");
        let names: Vec<String> = grid_names(&b).unwrap().into_iter().map(|g| g.0).collect();
        assert_eq!(
            names,
            ["density", "temperature", "velocity", "surface", "double"]
        );
        let t = parse(&b, "temperature").unwrap();
        assert_eq!(
            t.active_voxels().collect::<Vec<_>>(),
            [(IVec3::new(1, 2, 3), 300.0)]
        );
        let d = parse(&b, "density").unwrap();
        assert_eq!(d.active_voxels().collect::<Vec<_>>(), [(IVec3::ONE, 0.75)]);
        for (grid, says) in [
            ("velocity", "is a vector grid (Tree_vec3s_5_4_3)"),
            ("double", "is a double-precision grid"),
            ("surface", "is a level set"),
            (
                "smoke",
                "no grid named 'smoke'; the file has 'density' (Tree_float_5_4_3)",
            ),
        ] {
            let e = parse(&b, grid).unwrap_err();
            assert!(e.contains(says), "{grid}: {e}");
        }
    }

    #[test]
    fn load_errors_name_the_file_and_where_it_was_named() {
        let at = Origin {
            file: "scene.toml".into(),
            line: 7,
            col: 11,
        };
        let missing = data("missing.vdb");
        let e = load(&missing, "density", &at).unwrap_err().to_string();
        assert!(
            e.starts_with("scene.toml:7:11: cannot read OpenVDB file"),
            "{e}"
        );
        assert!(e.contains("missing.vdb"), "{e}");
        let not_vdb = data("make.sh");
        let e = load(&not_vdb, "density", &at).unwrap_err().to_string();
        assert!(e.contains("make.sh: not an OpenVDB file"), "{e}");
        let e = load(&data("grids.vdb"), "velocity", &at)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("grids.vdb: grid 'velocity' is a vector grid"),
            "{e}"
        );
        assert_eq!(
            load(&data("ramp.vdb"), "density", &at)
                .unwrap()
                .leaves
                .len(),
            12
        );
    }

    /// SplitMix64: deterministic bytes for the fuzz tests.
    fn splitmix(state: &mut u64) -> u64 {
        *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    #[test]
    fn truncated_files_are_errors_never_panics() {
        for file in ["ramp.vdb", "ramp_zip.vdb", "ramp_half.vdb", "tiles.vdb"] {
            let b = bytes(file);
            // Every cut in the header and first nodes, then every 5th byte.
            for len in (0..b.len()).filter(|&l| l < 12_000 || l % 5 == 0) {
                let r = parse(&b[..len], "density");
                assert!(r.is_err(), "{file} cut at {len} bytes read as a grid");
            }
        }
    }

    #[test]
    fn garbled_files_are_errors_or_grids_never_panics() {
        let mut state = 27;
        for file in [
            "ramp.vdb",
            "ramp_zip.vdb",
            "ramp_half.vdb",
            "tiles.vdb",
            "grids.vdb",
        ] {
            let b = bytes(file);
            for _ in 0..400 {
                let mut g = b.clone();
                let edits = 1 + splitmix(&mut state) % 8;
                for _ in 0..edits {
                    let at = (splitmix(&mut state) % g.len() as u64) as usize;
                    let r = splitmix(&mut state);
                    // Random bytes, or sizes pushed to extremes.
                    g[at] = match r % 4 {
                        0 => 0xff,
                        1 => 0x00,
                        2 => 0x80,
                        _ => (r >> 8) as u8,
                    };
                }
                let _ = parse(&g, "density");
                let _ = parse(&g, "temperature");
            }
        }
    }

    #[test]
    fn garbled_blosc_frames_are_errors_never_panics() {
        let mut state = 5;
        let mut out = vec![0u8; 2048];
        for _ in 0..20_000 {
            let len = (splitmix(&mut state) % 200) as usize;
            let mut frame: Vec<u8> = (0..len).map(|_| splitmix(&mut state) as u8).collect();
            // A plausible header half of the time, so the block loop is reached.
            if len >= 16 && splitmix(&mut state) % 2 == 0 {
                frame[0] = 2;
                frame[2] = 0x21 | (splitmix(&mut state) as u8 & 0x10);
                frame[3] = 4;
                frame[4..8].copy_from_slice(&2048u32.to_le_bytes());
                frame[12..16].copy_from_slice(&(len as u32).to_le_bytes());
            }
            let _ = blosc_decode(&frame, &mut out);
        }
    }
}
