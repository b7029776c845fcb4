//! Cryptomatte (Psyop's specification 1.2): per pixel, the ids of the objects, materials
//! and assets the camera sees, ranked by coverage, so Nuke's and Blender's Cryptomatte
//! nodes pick a matte for any of them by name.
//!
//! - An id is `MurmurHash3_32(name, seed 0)` turned into a float by the spec's
//!   `uint32_to_float32`: a hash whose exponent bits are all 0 or all 1 (a denormal,
//!   an infinity or a NaN) has bit 23 flipped.
//! - Layer `CryptoObject` with `ranks` = 6 is stored as `CryptoObject00.R/G/B/A`
//!   (id, coverage of rank 0, id, coverage of rank 1), `CryptoObject01` (ranks 2, 3), …
//! - The header holds `cryptomatte/<key>/name|hash|conversion|manifest`, the key being the
//!   first 7 hex digits of the layer name's hash; the manifest maps names to ids as
//!   8-digit hex of the float's bits (JSON).
//!
//! Coverage is the fraction of the pixel's camera samples whose first hit is the object:
//! samples are placed by the pixel filter (filter importance sampling), so coverage
//! follows the filter exactly as the beauty does. A holdout, and an object the camera
//! does not see (`visible_camera = false`), has no id: where the camera sees geometry
//! the coverages of `CryptoObject` sum to the pixel's alpha.
//!
//! The render loop keeps a [`PixelMatte`] per worker (fixed size: nothing is allocated
//! per sample or pixel) and writes the ranked pairs when a pixel's samples are done.

use std::collections::BTreeMap;

/// The layers Lightpath writes, in channel order.
pub const OBJECT: &str = "CryptoObject";
pub const MATERIAL: &str = "CryptoMaterial";
pub const ASSET: &str = "CryptoAsset";
/// The number of ranks written by default (the spec's and Nuke's usual depth).
pub const DEFAULT_RANKS: u32 = 6;
/// Largest rank count `--cryptomatte-ranks` accepts.
pub const MAX_RANKS: u32 = 16;
/// Distinct ids a pixel can tell apart per layer; a pixel seeing more objects than this
/// keeps the first ones met (far beyond the ranks written).
pub const PIXEL_CAPACITY: usize = 32;

/// The spec's hash attribute value and conversion.
pub const HASH_NAME: &str = "MurmurHash3_32";
pub const CONVERSION: &str = "uint32_to_float32";

/// MurmurHash3, x86 32-bit variant.
pub fn murmur3_32(data: &[u8], seed: u32) -> u32 {
    const C1: u32 = 0xcc9e_2d51;
    const C2: u32 = 0x1b87_3593;
    let mut h = seed;
    let mut blocks = data.chunks_exact(4);
    for b in &mut blocks {
        let mut k = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        k = k.wrapping_mul(C1).rotate_left(15).wrapping_mul(C2);
        h ^= k;
        h = h.rotate_left(13).wrapping_mul(5).wrapping_add(0xe654_6b64);
    }
    let tail = blocks.remainder();
    let mut k = 0u32;
    for (i, &b) in tail.iter().enumerate() {
        k |= (b as u32) << (8 * i);
    }
    if !tail.is_empty() {
        k = k.wrapping_mul(C1).rotate_left(15).wrapping_mul(C2);
        h ^= k;
    }
    h ^= data.len() as u32;
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^= h >> 16;
    h
}

/// The id of `name` as float bits: the hash with bit 23 flipped when its exponent is 0
/// or 255 (`uint32_to_float32`), so every id is a finite, normal float.
pub fn id_bits(name: &str) -> u32 {
    let mut h = murmur3_32(name.as_bytes(), 0);
    let exp = (h >> 23) & 0xff;
    if exp == 0 || exp == 0xff {
        h ^= 1 << 23;
    }
    h
}

/// The id of `name` as the float the channels store.
pub fn id(name: &str) -> f32 {
    f32::from_bits(id_bits(name))
}

/// The layer's key in the header: the first 7 hex digits of its name's hash.
pub fn key(layer: &str) -> String {
    format!("{:08x}", murmur3_32(layer.as_bytes(), 0))[..7].to_string()
}

/// Channel names of a layer with `ranks` ranks: `<layer>00.R`, `.G`, `.B`, `.A`, `<layer>01.R`…
/// (two ranks per RGBA group).
pub fn channel_names(layer: &str, ranks: u32) -> Vec<String> {
    (0..ranks.div_ceil(2))
        .flat_map(|g| ["R", "G", "B", "A"].map(|c| format!("{layer}{g:02}.{c}")))
        .collect()
}

/// The header attributes of a layer: name, hash, conversion and its manifest (JSON, names
/// in sorted order).
pub fn attributes(layer: &str, names: &[String]) -> Vec<(String, String)> {
    let k = key(layer);
    let manifest: BTreeMap<&str, String> = names
        .iter()
        .map(|n| (n.as_str(), format!("{:08x}", id_bits(n))))
        .collect();
    let manifest = serde_json::to_string(&manifest).unwrap_or_else(|_| "{}".into());
    vec![
        (format!("cryptomatte/{k}/conversion"), CONVERSION.into()),
        (format!("cryptomatte/{k}/hash"), HASH_NAME.into()),
        (format!("cryptomatte/{k}/manifest"), manifest),
        (format!("cryptomatte/{k}/name"), layer.into()),
    ]
}

/// The layers found in a header: (layer name, its channel-name prefix) from the
/// `cryptomatte/<key>/name` attributes.
pub fn layers_in(attributes: &[(String, String)]) -> Vec<String> {
    let mut out: Vec<String> = attributes
        .iter()
        .filter_map(|(k, v)| {
            let rest = k.strip_prefix("cryptomatte/")?;
            (rest.strip_suffix("/name")?.len() == 7).then(|| v.clone())
        })
        .collect();
    out.sort();
    out
}

/// Whether channel `name` belongs to Cryptomatte layer `layer` (`<layer>NN.X`).
pub fn is_layer_channel(layer: &str, name: &str) -> bool {
    name.strip_prefix(layer)
        .and_then(|r| r.split_once('.'))
        .is_some_and(|(n, c)| n.len() == 2 && n.bytes().all(|b| b.is_ascii_digit()) && c.len() == 1)
}

/// What a render's Cryptomatte layers know of the scene: per object, its id in each
/// layer (`None`: it has no name there, e.g. no material), and each layer's names.
#[derive(Clone, Debug)]
pub struct MatteTable {
    /// Layer names, in order (`CryptoObject`, `CryptoMaterial`, `CryptoAsset`).
    pub layers: Vec<String>,
    pub ranks: u32,
    /// Per scene object, per layer: the id's float bits.
    pub ids: Vec<Vec<Option<u32>>>,
    /// Per layer: the names its manifest lists.
    pub names: Vec<Vec<String>>,
}

impl MatteTable {
    /// A table from each object's name in each layer (`None`: nothing in that layer).
    /// Holdout objects should be given no names: they are not in the image.
    pub fn new(layers: Vec<String>, ranks: u32, object_names: &[Vec<Option<String>>]) -> Self {
        let mut names: Vec<Vec<String>> = vec![Vec::new(); layers.len()];
        let ids = object_names
            .iter()
            .map(|per_layer| {
                per_layer
                    .iter()
                    .enumerate()
                    .map(|(l, n)| {
                        let n = n.as_ref()?;
                        if !names[l].contains(n) {
                            names[l].push(n.clone());
                        }
                        Some(id_bits(n))
                    })
                    .collect()
            })
            .collect();
        for n in &mut names {
            n.sort();
        }
        MatteTable {
            layers,
            ranks: ranks.clamp(1, MAX_RANKS),
            ids,
            names,
        }
    }

    /// Values per pixel: per layer, an (id, coverage) pair per rank, padded to whole
    /// RGBA groups.
    pub fn stride(&self) -> usize {
        self.layers.len() * self.layer_stride()
    }

    fn layer_stride(&self) -> usize {
        4 * self.ranks.div_ceil(2) as usize
    }

    /// Header attributes of every layer.
    pub fn attributes(&self) -> Vec<(String, String)> {
        self.layers
            .iter()
            .zip(&self.names)
            .flat_map(|(l, n)| attributes(l, n))
            .collect()
    }

    /// Channel names in the order of a pixel's values.
    pub fn channel_names(&self) -> Vec<String> {
        self.layers
            .iter()
            .flat_map(|l| channel_names(l, self.ranks))
            .collect()
    }
}

/// One pixel's ids and their sample counts, per layer: fixed size, reused pixel after
/// pixel by a render worker.
pub struct PixelMatte {
    entries: Vec<[(u32, u32); PIXEL_CAPACITY]>,
    len: Vec<usize>,
    samples: u32,
}

impl PixelMatte {
    pub fn new(layers: usize) -> PixelMatte {
        PixelMatte {
            entries: vec![[(0, 0); PIXEL_CAPACITY]; layers],
            len: vec![0; layers],
            samples: 0,
        }
    }

    /// One camera sample whose first visible hit is `object` (`None`: nothing, a holdout
    /// or the background).
    #[inline]
    pub fn add(&mut self, table: &MatteTable, object: Option<u32>) {
        self.samples += 1;
        let Some(ids) = object.and_then(|o| table.ids.get(o as usize)) else {
            return;
        };
        for (l, id) in ids.iter().enumerate() {
            let Some(id) = *id else { continue };
            let entries = &mut self.entries[l][..];
            let len = &mut self.len[l];
            match entries[..*len].iter_mut().find(|e| e.0 == id) {
                Some(e) => e.1 += 1,
                None if *len < PIXEL_CAPACITY => {
                    entries[*len] = (id, 1);
                    *len += 1;
                }
                None => {}
            }
        }
    }

    /// Starts the pixel's record from ranked pairs [`PixelMatte::flush`] wrote after
    /// `samples` samples (an adaptive render's pilot), so that the samples added next
    /// count on top of them. Ids ranked below `table.ranks` were dropped by that flush.
    pub fn resume(&mut self, table: &MatteTable, pairs: &[f32], samples: u32) {
        self.samples = samples;
        for (l, chunk) in pairs.chunks_exact(table.layer_stride()).enumerate() {
            let mut len = 0;
            for p in chunk
                .chunks_exact(2)
                .filter(|p| p[1] > 0.0)
                .take(PIXEL_CAPACITY)
            {
                // A coverage is count / samples in f32: exact back to the count for any
                // pilot under 2^22 samples.
                let count = (p[1] * samples as f32).round() as u32;
                self.entries[l][len] = (p[0].to_bits(), count);
                len += 1;
            }
            self.len[l] = len;
        }
    }

    /// Writes the pixel's ranked (id, coverage) pairs into `out` (`table.stride()`
    /// values) and clears the record for the next pixel. Ranks by coverage, then by id
    /// so that ties are ordered the same in every render.
    pub fn flush(&mut self, table: &MatteTable, out: &mut [f32]) {
        let stride = table.layer_stride();
        let total = self.samples.max(1) as f32;
        for (l, chunk) in out.chunks_exact_mut(stride).enumerate() {
            let entries = &mut self.entries[l][..self.len[l]];
            entries.sort_unstable_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
            chunk.fill(0.0);
            for (r, e) in entries.iter().take(table.ranks as usize).enumerate() {
                chunk[2 * r] = f32::from_bits(e.0);
                chunk[2 * r + 1] = e.1 as f32 / total;
            }
            self.len[l] = 0;
        }
        self.samples = 0;
    }
}

/// Merges one layer's ranked pairs of the same pixel from several renders of it (sample
/// ranges), each weighted by its share of the samples: the same ids' coverages add, and
/// the result is ranked again. `parts` gives each part's pairs and weight; `out` gets
/// `ranks` pairs.
pub fn merge_ranked(parts: &[(&[f32], f64)], out: &mut [f32]) {
    let mut acc: Vec<(u32, f64)> = Vec::new();
    for (pairs, w) in parts {
        for p in pairs.chunks_exact(2) {
            if p[1] <= 0.0 {
                continue;
            }
            let id = p[0].to_bits();
            match acc.iter_mut().find(|e| e.0 == id) {
                Some(e) => e.1 += p[1] as f64 * w,
                None => acc.push((id, p[1] as f64 * w)),
            }
        }
    }
    acc.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    out.fill(0.0);
    for (slot, e) in out.chunks_exact_mut(2).zip(&acc) {
        slot[0] = f32::from_bits(e.0);
        slot[1] = e.1 as f32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn murmur3_matches_the_reference_vectors() {
        // SMHasher's published values for MurmurHash3_x86_32.
        assert_eq!(murmur3_32(b"", 0), 0);
        assert_eq!(murmur3_32(b"", 1), 0x514e_28b7);
        assert_eq!(murmur3_32(b"", 0xffff_ffff), 0x81f1_6f39);
        assert_eq!(murmur3_32(&[0, 0, 0, 0], 0), 0x2362_f9de);
        assert_eq!(murmur3_32(b"aaaa", 0x9747_b28c), 0x5a97_808a);
        assert_eq!(murmur3_32(b"abc", 0), 0xb3dd_93fa);
        assert_eq!(murmur3_32(b"Hello, world!", 0x9747_b28c), 0x2488_4cba);
        assert_eq!(
            murmur3_32(b"The quick brown fox jumps over the lazy dog", 0x9747_b28c),
            0x2fa8_26cd
        );
    }

    #[test]
    fn ids_are_normal_floats_and_keys_are_seven_hex_digits() {
        for name in ["", "a", "floor", "CryptoObject", "light0", "sphere.001"] {
            let f = id(name);
            assert!(f.is_finite() && (f == 0.0 || f.is_normal()), "{name}: {f}");
        }
        // The keys Blender and Arnold files carry for these layer names.
        assert_eq!(key(OBJECT), "3ae39a5");
        assert_eq!(key(MATERIAL), "be359d6");
    }

    #[test]
    fn a_pixel_ranks_ids_by_coverage_and_merges_weighted() {
        let table = MatteTable::new(
            vec![OBJECT.into()],
            4,
            &[vec![Some("a".into())], vec![Some("b".into())], vec![None]],
        );
        let mut px = PixelMatte::new(1);
        for o in [Some(1), Some(0), Some(1), Some(2), None] {
            px.add(&table, o);
        }
        let mut out = vec![9.0; table.stride()];
        px.flush(&table, &mut out);
        assert_eq!(out[0].to_bits(), id_bits("b"));
        assert_eq!(out[1], 0.4);
        assert_eq!(out[2].to_bits(), id_bits("a"));
        assert_eq!(out[3], 0.2);
        assert_eq!(&out[4..], &[0.0; 4]);
        // The record is clear for the next pixel.
        px.add(&table, Some(0));
        px.flush(&table, &mut out);
        assert_eq!((out[0].to_bits(), out[1]), (id_bits("a"), 1.0));

        let (a, b) = (id("a"), id("b"));
        let mut merged = [0.0; 4];
        merge_ranked(
            &[(&[a, 1.0, 0.0, 0.0], 0.25), (&[b, 0.5, a, 0.5], 0.75)],
            &mut merged,
        );
        assert_eq!(merged, [a, 0.625, b, 0.375]);
    }

    #[test]
    fn channel_names_pair_two_ranks_per_rgba_group() {
        assert_eq!(
            channel_names(OBJECT, 3),
            [
                "CryptoObject00.R",
                "CryptoObject00.G",
                "CryptoObject00.B",
                "CryptoObject00.A",
                "CryptoObject01.R",
                "CryptoObject01.G",
                "CryptoObject01.B",
                "CryptoObject01.A"
            ]
        );
        assert!(is_layer_channel(OBJECT, "CryptoObject01.A"));
        assert!(!is_layer_channel(OBJECT, "CryptoObject.R"));
        assert!(!is_layer_channel(OBJECT, "CryptoObjectX1.R"));
    }
}
