//! Cryptomatte accumulation during the render: per pixel, how many camera samples first
//! hit each object, ranked into (id, coverage) pairs when the pixel's samples are done.
//! What the ids are and how the layers are named and written (the spec's hash, manifest
//! and EXR channels) is `post::cryptomatte`'s; this side only counts.
//!
//! The render loop keeps a [`PixelMatte`] per worker (fixed size: nothing is allocated
//! per sample or pixel) and writes the ranked pairs when a pixel's samples are done.

/// Distinct ids a pixel can tell apart per layer; a pixel seeing more objects than this
/// keeps the first ones met (far beyond the ranks written).
pub const PIXEL_CAPACITY: usize = 32;

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
    /// Values per pixel: per layer, an (id, coverage) pair per rank, padded to whole
    /// RGBA groups.
    pub fn stride(&self) -> usize {
        self.layers.len() * self.layer_stride()
    }

    /// Values per pixel of one layer.
    fn layer_stride(&self) -> usize {
        4 * self.ranks.div_ceil(2) as usize
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
    fn a_pixel_ranks_ids_by_coverage_and_merges_weighted() {
        let (a, b) = (f32::from_bits(0x3f00_0001), f32::from_bits(0x3f00_0002));
        let table = MatteTable {
            layers: vec!["CryptoObject".into()],
            ranks: 4,
            ids: vec![vec![Some(a.to_bits())], vec![Some(b.to_bits())], vec![None]],
            names: vec![vec!["a".into(), "b".into()]],
        };
        let mut px = PixelMatte::new(1);
        for o in [Some(1), Some(0), Some(1), Some(2), None] {
            px.add(&table, o);
        }
        let mut out = vec![9.0; table.stride()];
        px.flush(&table, &mut out);
        assert_eq!(out[0].to_bits(), b.to_bits());
        assert_eq!(out[1], 0.4);
        assert_eq!(out[2].to_bits(), a.to_bits());
        assert_eq!(out[3], 0.2);
        assert_eq!(&out[4..], &[0.0; 4]);
        // The record is clear for the next pixel.
        px.add(&table, Some(0));
        px.flush(&table, &mut out);
        assert_eq!((out[0].to_bits(), out[1]), (a.to_bits(), 1.0));

        let mut merged = [0.0; 4];
        merge_ranked(
            &[(&[a, 1.0, 0.0, 0.0], 0.25), (&[b, 0.5, a, 0.5], 0.75)],
            &mut merged,
        );
        assert_eq!(merged, [a, 0.625, b, 0.375]);
    }
}
