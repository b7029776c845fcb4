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
//! Counting coverage during the render is the film's (`film::mattes`); this module names,
//! hashes and writes what it counted.

use std::collections::BTreeMap;

use crate::film::mattes::MatteTable;

/// The layers Lightpath writes, in channel order.
pub const OBJECT: &str = "CryptoObject";
pub const MATERIAL: &str = "CryptoMaterial";
pub const ASSET: &str = "CryptoAsset";
/// The number of ranks written by default (the spec's and Nuke's usual depth).
pub const DEFAULT_RANKS: u32 = 6;
/// Largest rank count `--cryptomatte-ranks` accepts.
pub const MAX_RANKS: u32 = 16;

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

/// The table of a render's Cryptomatte layers from each object's name in each layer
/// (`None`: nothing in that layer): the ids the film accumulates and the names the
/// manifests list. Holdout objects should be given no names: they are not in the image.
pub fn table(layers: Vec<String>, ranks: u32, object_names: &[Vec<Option<String>>]) -> MatteTable {
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

/// Header attributes of every layer of a table.
pub fn table_attributes(table: &MatteTable) -> Vec<(String, String)> {
    table
        .layers
        .iter()
        .zip(&table.names)
        .flat_map(|(l, n)| attributes(l, n))
        .collect()
}

/// A table's channel names, in the order of a pixel's values.
pub fn table_channel_names(table: &MatteTable) -> Vec<String> {
    table
        .layers
        .iter()
        .flat_map(|l| channel_names(l, table.ranks))
        .collect()
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
    fn a_table_hashes_each_name_and_lists_it_once_per_layer() {
        let table = table(
            vec![OBJECT.into()],
            40,
            &[
                vec![Some("b".into())],
                vec![Some("a".into())],
                vec![Some("b".into())],
                vec![None],
            ],
        );
        assert_eq!(table.ranks, MAX_RANKS);
        assert_eq!(table.names, [["a", "b"]]);
        assert_eq!(table.ids[0], [Some(id_bits("b"))]);
        assert_eq!(table.ids[3], [None]);
        assert_eq!(table_channel_names(&table).len(), table.stride());
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
