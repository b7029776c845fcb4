//! Cryptomatte layers as the Psyop specification stores them: for a layer `<name>`,
//! channels `<name>00.R/G/B/A`, `<name>01.…`, each holding two (id, coverage) ranks
//! (R, G and B, A), ids as the float32 whose bits are the object's 32-bit hash; header
//! attributes `cryptomatte/<key>/name` (the layer's name) and `cryptomatte/<key>/manifest`
//! (a JSON object from object name to its id as 8 hex digits).

use crate::output::ExrContents;

/// The attribute prefix of every Cryptomatte header entry.
const PREFIX: &str = "cryptomatte/";

/// One Cryptomatte layer of an EXR.
pub struct CryptoLayer {
    pub name: String,
    /// The 7-hex-digit key of its attributes.
    pub key: String,
    /// Channel names of each `<name>NN` set: R, G, B, A.
    pub channels: Vec<[String; 4]>,
    /// Object ids and names from the manifest (empty if it is missing or unreadable).
    pub manifest: Vec<(u32, String)>,
}

/// The Cryptomatte layers the header names (`post::cryptomatte::layers_in`) whose
/// `<name>00` set of channels exists.
pub fn layers(exr: &ExrContents) -> Vec<CryptoLayer> {
    let named = crate::post::cryptomatte::layers_in(&exr.attributes);
    let mut out: Vec<CryptoLayer> = exr
        .attributes
        .iter()
        .filter(|(_, name)| named.contains(name))
        .filter_map(|(k, name)| {
            let key = k.strip_prefix(PREFIX)?.strip_suffix("/name")?;
            let channels: Vec<[String; 4]> = (0..100)
                .map(|n| ["R", "G", "B", "A"].map(|c| format!("{name}{n:02}.{c}")))
                .take_while(|set| set.iter().all(|c| exr.channel(c).is_some()))
                .collect();
            if channels.is_empty() {
                return None;
            }
            let manifest = exr
                .attributes
                .iter()
                .find(|(k, _)| *k == format!("{PREFIX}{key}/manifest"))
                .map(|(_, m)| parse_manifest(m))
                .unwrap_or_default();
            Some(CryptoLayer {
                name: name.clone(),
                key: key.to_string(),
                channels,
                manifest,
            })
        })
        .collect();
    out.sort_by(|a, b| a.name.cmp(&b.name));
    out
}

/// `{"name": "3f800000", …}` → (id, name) pairs; entries that are not 8 hex digits are
/// skipped, and a manifest that is not a JSON object gives none.
pub fn parse_manifest(text: &str) -> Vec<(u32, String)> {
    let Ok(serde_json::Value::Object(map)) = serde_json::from_str(text) else {
        return Vec::new();
    };
    let mut out: Vec<(u32, String)> = map
        .iter()
        .filter_map(|(name, hex)| {
            let hex = hex.as_str()?;
            (hex.len() == 8)
                .then(|| u32::from_str_radix(hex, 16).ok())
                .flatten()
                .map(|id| (id, name.clone()))
        })
        .collect();
    out.sort();
    out
}

impl CryptoLayer {
    /// The (id, coverage) ranks at pixel index `i`, in the file's order.
    fn ranks<'a>(
        &'a self,
        exr: &'a ExrContents,
        i: usize,
    ) -> impl Iterator<Item = (u32, f32)> + 'a {
        self.channels.iter().flat_map(move |set| {
            let v = |c: &String| exr.channel(c).map_or(0.0, |p| p[i]);
            [(v(&set[0]), v(&set[1])), (v(&set[2]), v(&set[3]))]
                .map(|(id, cov)| (id.to_bits(), cov))
        })
    }

    /// The object covering most of pixel `i`: its id and its coverage.
    pub fn top(&self, exr: &ExrContents, i: usize) -> Option<(u32, f32)> {
        let mut totals: Vec<(u32, f32)> = Vec::new();
        for (id, cov) in self.ranks(exr, i).filter(|r| r.1 > 0.0) {
            match totals.iter_mut().find(|t| t.0 == id) {
                Some(t) => t.1 += cov,
                None => totals.push((id, cov)),
            }
        }
        totals.into_iter().max_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// An object's name from the manifest; `None` for an id it does not list.
    pub fn object_name(&self, id: u32) -> Option<&str> {
        self.manifest
            .binary_search_by_key(&id, |m| m.0)
            .ok()
            .map(|k| self.manifest[k].1.as_str())
    }

    /// The matte of object `id`: its coverage summed over the ranks, per pixel.
    pub fn matte(&self, exr: &ExrContents, id: u32) -> Vec<f32> {
        let mut matte = vec![0.0f32; exr.width * exr.height];
        for set in &self.channels {
            for (id_c, cov_c) in [(&set[0], &set[1]), (&set[2], &set[3])] {
                let (Some(ids), Some(cov)) = (exr.channel(id_c), exr.channel(cov_c)) else {
                    continue;
                };
                for ((m, i), c) in matte.iter_mut().zip(ids).zip(cov) {
                    if i.to_bits() == id {
                        *m += c;
                    }
                }
            }
        }
        matte
    }

    /// A colour per object (from its id's bits), weighted by coverage: what the layer
    /// looks like as an image.
    pub fn false_colours(&self, exr: &ExrContents) -> [Vec<f32>; 3] {
        let n = exr.width * exr.height;
        let mut rgb = [vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]];
        for i in 0..n {
            for (id, cov) in self.ranks(exr, i).filter(|r| r.1 > 0.0) {
                for (c, plane) in rgb.iter_mut().enumerate() {
                    let byte = (id >> (8 * c)) & 0xff;
                    plane[i] += cov * (0.15 + 0.85 * byte as f32 / 255.0);
                }
            }
        }
        rgb
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manifests_keep_valid_entries_and_survive_garbage() {
        let m = parse_manifest(r#"{"floor": "3f800000", "bad": "xyz", "short": "12", "n": 5}"#);
        assert_eq!(m, vec![(0x3f80_0000, "floor".to_string())]);
        assert!(parse_manifest("not json").is_empty());
        assert!(parse_manifest("[1, 2]").is_empty());
    }
}
