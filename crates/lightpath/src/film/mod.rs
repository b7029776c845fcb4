//! The film: one RGB accumulator per AOV per pixel, plus alpha. Rendering fills a band
//! of rows stored pixel by pixel (a sample writes one contiguous run); the film keeps one
//! plane per channel, so output hands the planes to the EXR writer without copying and
//! the peak memory stays about one film.

pub mod mattes;
pub mod splats;

use crate::error::InvalidValue;

/// Two films that cannot be merged: not of the same frame and AOVs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("films differ in size, window, AOV count or variance AOVs")]
pub struct FilmMismatch;

use glam::Vec3A;

#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub aovs: usize,
    /// Samples accumulated per pixel.
    pub spp: u32,
    /// `3 × (aovs + squared) + 1` planes of `width × height` sums: R, G, B of each AOV,
    /// then of the squared samples of each AOV in `squared`, then alpha.
    pub planes: Vec<Vec<f32>>,
    /// Samples each pixel took, when adaptive sampling let pixels stop early (`None`:
    /// every pixel took `spp`). Every AOV and alpha of a pixel share its count.
    pub sample_counts: Option<Vec<u32>>,
    /// AOVs whose squared samples are summed too, for their variance (`--variance`).
    pub squared: Vec<u32>,
    /// The pixels of the frame this film holds (a `--crop` window; else the whole frame).
    pub window: PixelWindow,
    /// The whole frame's size (the EXR's display window).
    pub frame: [u32; 2],
    /// Cryptomatte layers, if the render asked for them: ranked (id, coverage) values,
    /// `table.stride()` planes of `width × height` (final values, not sums).
    pub mattes: Option<Mattes>,
}

/// Cryptomatte output of a render: the table it was made with and its planes.
#[derive(Clone, Debug)]
pub struct Mattes {
    pub table: mattes::MatteTable,
    pub planes: Vec<Vec<f32>>,
}

/// A rectangle of a frame's pixels, end exclusive: what a render covers (`--crop
/// X0,Y0,X1,Y1`). Pixel (x, y) of a window is pixel (x0 + x, y0 + y) of the frame, with
/// the frame's sample numbers, so tiles of a frame join into exactly the whole render.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PixelWindow {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl PixelWindow {
    /// The whole of a `width × height` frame.
    pub fn full(width: u32, height: u32) -> PixelWindow {
        PixelWindow {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    pub fn width(&self) -> u32 {
        self.x1.saturating_sub(self.x0)
    }

    pub fn height(&self) -> u32 {
        self.y1.saturating_sub(self.y0)
    }

    /// Parses `X0,Y0,X1,Y1`.
    pub fn parse(s: &str) -> Result<PixelWindow, InvalidValue> {
        let v: Vec<&str> = s.split(',').map(str::trim).collect();
        let bad = || {
            InvalidValue(format!(
                "expected X0,Y0,X1,Y1 (pixels, end exclusive), got '{s}'"
            ))
        };
        if v.len() != 4 {
            return Err(bad());
        }
        let mut n = [0u32; 4];
        for (slot, text) in n.iter_mut().zip(&v) {
            *slot = text.parse().map_err(|_| bad())?;
        }
        let w = PixelWindow {
            x0: n[0],
            y0: n[1],
            x1: n[2],
            y1: n[3],
        };
        if w.x1 <= w.x0 || w.y1 <= w.y0 {
            return Err(InvalidValue(format!(
                "crop {s} is empty: X1 must exceed X0 and Y1 must exceed Y0"
            )));
        }
        Ok(w)
    }

    /// Checks that the window lies in a `width × height` frame and is not empty.
    pub fn check(&self, width: u32, height: u32) -> Result<(), InvalidValue> {
        if self.width() == 0 || self.height() == 0 || self.x1 > width || self.y1 > height {
            return Err(InvalidValue(format!(
                "crop {self} is not a non-empty window of the {width}x{height} frame"
            )));
        }
        Ok(())
    }
}

impl std::fmt::Display for PixelWindow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

impl Film {
    /// Values per pixel in a row buffer: RGB per AOV, then alpha.
    pub fn stride_for(aovs: usize) -> usize {
        3 * aovs + 1
    }

    /// Values per pixel in a row buffer when `squared` AOVs also sum their squares.
    pub fn stride_with(aovs: usize, squared: usize) -> usize {
        3 * (aovs + squared) + 1
    }

    /// Where alpha sits in a pixel's run of `stride` values (after every AOV's RGB).
    #[inline(always)]
    pub fn alpha_slot(stride: usize) -> usize {
        stride - 1
    }

    /// An empty film (planes are allocated zeroed, so untouched pages cost nothing).
    pub fn new(width: u32, height: u32, aovs: usize, spp: u32) -> Film {
        Film::with_squares(width, height, aovs, spp, Vec::new())
    }

    /// An empty film that also sums the squared samples of the `squared` AOVs.
    pub fn with_squares(width: u32, height: u32, aovs: usize, spp: u32, squared: Vec<u32>) -> Film {
        let n = width as usize * height as usize;
        let planes = (0..Film::stride_with(aovs, squared.len()))
            .map(|_| vec![0.0; n])
            .collect();
        Film {
            width,
            height,
            aovs,
            spp,
            planes,
            sample_counts: None,
            squared,
            window: PixelWindow::full(width, height),
            frame: [width, height],
            mattes: None,
        }
    }

    /// The same empty film, also summing the squared samples of the `squared` AOVs.
    pub fn summing_squares(self, squared: Vec<u32>) -> Film {
        Film {
            window: self.window,
            frame: self.frame,
            ..Film::with_squares(self.width, self.height, self.aovs, self.spp, squared)
        }
    }

    /// An empty film for `window` of a `frame`-sized frame.
    pub fn for_window(window: PixelWindow, frame: [u32; 2], aovs: usize, spp: u32) -> Film {
        Film {
            window,
            frame,
            ..Film::new(window.width(), window.height(), aovs, spp)
        }
    }

    /// Stores the sample counts of rows starting at `first_row` (adaptive sampling).
    pub fn store_counts(&mut self, first_row: usize, rows: &[u32]) {
        if let Some(counts) = &mut self.sample_counts {
            let start = first_row * self.width as usize;
            counts[start..start + rows.len()].copy_from_slice(rows);
        }
    }

    /// The samples pixel `i` (row by row) took.
    #[inline]
    pub fn samples_at(&self, i: usize) -> u32 {
        self.sample_counts.as_ref().map_or(self.spp, |c| c[i])
    }

    /// 1 / samples of each pixel, row by row.
    fn inverse_counts(&self) -> impl Iterator<Item = f32> + '_ {
        (0..self.width as usize * self.height as usize)
            .map(|i| 1.0 / self.samples_at(i).max(1) as f32)
    }

    /// Moves rendered rows (each `width × stride` interleaved sums) starting at row
    /// `first_row` into the planes, one plane per thread.
    pub fn store_rows(&mut self, first_row: usize, rows: &[f32]) {
        use rayon::prelude::*;
        let stride = Film::stride_with(self.aovs, self.squared.len());
        let start = first_row * self.width as usize;
        let pixels = rows.len() / stride;
        self.planes
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, plane)| {
                for (d, px) in plane[start..start + pixels]
                    .iter_mut()
                    .zip(rows.chunks_exact(stride))
                {
                    *d = px[c];
                }
            });
    }

    /// The inverse of [`Film::store_rows`]: copies rows starting at `first_row` from the
    /// planes into an interleaved band (`width × stride` per row).
    pub fn load_rows(&self, first_row: usize, rows: &mut [f32]) {
        let stride = Film::stride_with(self.aovs, self.squared.len());
        let start = first_row * self.width as usize;
        for (c, plane) in self.planes.iter().enumerate() {
            for (px, s) in rows.chunks_exact_mut(stride).zip(&plane[start..]) {
                px[c] = *s;
            }
        }
    }

    /// The mean value of AOV `k` at pixel (x, y).
    pub fn pixel(&self, k: usize, x: u32, y: u32) -> Vec3A {
        let i = y as usize * self.width as usize + x as usize;
        Vec3A::new(
            self.planes[3 * k][i],
            self.planes[3 * k + 1][i],
            self.planes[3 * k + 2][i],
        ) / self.samples_at(i).max(1) as f32
    }

    /// Channel `c` of AOV `k` as a plane of means, row by row.
    pub fn channel(&self, k: usize, c: usize) -> Vec<f32> {
        self.planes[3 * k + c]
            .iter()
            .zip(self.inverse_counts())
            .map(|(v, inv)| v * inv)
            .collect()
    }

    pub fn alpha(&self) -> Vec<f32> {
        self.planes[Film::alpha_slot(self.planes.len())]
            .iter()
            .zip(self.inverse_counts())
            .map(|(v, inv)| v * inv)
            .collect()
    }

    /// All planes as means, consuming the film (no copy): R, G, B per AOV, the mean
    /// squares of the `squared` AOVs, then alpha.
    pub fn into_means(self) -> Vec<Vec<f32>> {
        let inverse: Option<Vec<f32>> = self
            .sample_counts
            .is_some()
            .then(|| self.inverse_counts().collect());
        let inv = 1.0 / self.spp as f32;
        let mut planes = self.planes;
        for p in &mut planes {
            match &inverse {
                Some(inverse) => p.iter_mut().zip(inverse).for_each(|(v, i)| *v *= i),
                None => p.iter_mut().for_each(|v| *v *= inv),
            }
        }
        planes
    }

    /// Merges a film of the same frame rendered with other samples (a farm's sample
    /// ranges): the result is the film of all samples.
    pub fn merge(&mut self, other: &Film) -> Result<(), FilmMismatch> {
        if (self.width, self.height, self.aovs, &self.squared)
            != (other.width, other.height, other.aovs, &other.squared)
            || (self.window, self.frame) != (other.window, other.frame)
        {
            return Err(FilmMismatch);
        }
        for (a, b) in self.planes.iter_mut().zip(&other.planes) {
            for (x, y) in a.iter_mut().zip(b) {
                *x += y;
            }
        }
        if self.sample_counts.is_some() || other.sample_counts.is_some() {
            let counts = (0..self.width as usize * self.height as usize)
                .map(|i| self.samples_at(i) + other.samples_at(i))
                .collect();
            self.sample_counts = Some(counts);
        }
        if let (Some(m), Some(o)) = (&mut self.mattes, &other.mattes) {
            let total = (self.spp + other.spp).max(1) as f64;
            let (wa, wb) = (self.spp as f64 / total, other.spp as f64 / total);
            let per_layer = m.table.stride() / m.table.layers.len().max(1);
            let mut a = vec![0.0; per_layer];
            let mut b = vec![0.0; per_layer];
            let mut out = vec![0.0; per_layer];
            for layer in 0..m.table.layers.len() {
                let planes = layer * per_layer..(layer + 1) * per_layer;
                for i in 0..(self.width as usize * self.height as usize) {
                    for (k, p) in planes.clone().enumerate() {
                        a[k] = m.planes[p][i];
                        b[k] = o.planes[p][i];
                    }
                    mattes::merge_ranked(&[(&a, wa), (&b, wb)], &mut out);
                    for (k, p) in planes.clone().enumerate() {
                        m.planes[p][i] = out[k];
                    }
                }
            }
        }
        self.spp += other.spp;
        Ok(())
    }
}

/// What one camera sample adds to each AOV, before it reaches the film (so `overwrite`
/// can replace within the sample). Allocated once per worker: the hot loop allocates
/// nothing.
pub struct SampleAccumulator {
    values: Vec<Vec3A>,
    /// AOVs whose squared sample is added too, after every AOV's RGB in the pixel run.
    squared: Vec<u32>,
    /// A bit per AOV: has this sample touched it? (A list of touched AOVs cost a push
    /// with its capacity check per first touch.)
    touched: Vec<u64>,
}

impl SampleAccumulator {
    pub fn new(aovs: usize) -> SampleAccumulator {
        SampleAccumulator::with_squares(aovs, Vec::new())
    }

    /// An accumulator that also adds the squared samples of the `squared` AOVs.
    pub fn with_squares(aovs: usize, squared: Vec<u32>) -> SampleAccumulator {
        SampleAccumulator {
            values: vec![Vec3A::ZERO; aovs],
            squared,
            touched: vec![0; aovs.div_ceil(64)],
        }
    }

    #[inline(always)]
    pub fn add(&mut self, aov: usize, value: Vec3A, overwrite: bool) {
        let bit = 1u64 << (aov & 63);
        let word = &mut self.touched[aov >> 6];
        if *word & bit == 0 || overwrite {
            *word |= bit;
            self.values[aov] = value;
        } else {
            self.values[aov] += value;
        }
    }

    /// What the sample has added to AOV `k` so far.
    #[inline]
    pub fn value(&self, k: usize) -> Vec3A {
        if self.touched[k >> 6] & (1u64 << (k & 63)) != 0 {
            self.values[k]
        } else {
            Vec3A::ZERO
        }
    }

    /// The number of AOVs it holds.
    pub fn aovs(&self) -> usize {
        self.values.len()
    }

    /// Hands each AOV the sample touched and its value to `f`, and clears the sample
    /// (squares are not kept: light tracing's splats, film/splats.rs).
    #[inline]
    pub fn drain(&mut self, mut f: impl FnMut(usize, Vec3A)) {
        for (w, word) in self.touched.iter_mut().enumerate() {
            let mut bits = std::mem::take(word);
            while bits != 0 {
                let k = w * 64 + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                f(k, self.values[k]);
            }
        }
    }

    /// Adds the sample to a pixel's run of the film and clears it.
    #[inline]
    pub fn flush(&mut self, pixel: &mut [f32]) {
        let base = 3 * self.values.len();
        for (j, &k) in self.squared.iter().enumerate() {
            let k = k as usize;
            if self.touched[k >> 6] & (1u64 << (k & 63)) != 0 {
                let v = self.values[k] * self.values[k];
                let p = &mut pixel[base + 3 * j..base + 3 * j + 3];
                p[0] += v.x;
                p[1] += v.y;
                p[2] += v.z;
            }
        }
        for (w, word) in self.touched.iter_mut().enumerate() {
            let mut bits = std::mem::take(word);
            while bits != 0 {
                let k = w * 64 + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let v = self.values[k];
                let p = &mut pixel[3 * k..3 * k + 3];
                p[0] += v.x;
                p[1] += v.y;
                p[2] += v.z;
            }
        }
    }
}

/// The estimated variance of a pixel mean from `n` samples with mean `mean` and mean
/// square `mean_square`: the sample variance over `n`, `(E[x²] − E[x]²) / (n − 1)`; zero
/// with fewer than two samples, where it cannot be estimated.
#[inline]
pub fn variance_of_mean(mean: f32, mean_square: f32, n: u32) -> f32 {
    if n < 2 {
        return 0.0;
    }
    ((mean_square as f64 - mean as f64 * mean as f64).max(0.0) / (n - 1) as f64) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn squared_samples_give_the_variance_of_the_mean() {
        // Two AOVs, the second with squares; four samples of 1, 2, 3, 6 (mean 3, sample
        // variance 14/3, variance of the mean 14/12).
        let mut acc = SampleAccumulator::with_squares(2, vec![1]);
        let stride = Film::stride_with(2, 1);
        let mut pixel = vec![0.0; stride];
        for x in [1.0f32, 2.0, 3.0, 6.0] {
            acc.add(1, Vec3A::splat(x), false);
            acc.add(0, Vec3A::ONE, false);
            acc.flush(&mut pixel);
        }
        let mut film = Film::with_squares(1, 1, 2, 4, vec![1]);
        film.store_rows(0, &pixel);
        let planes = film.into_means();
        assert_eq!(planes.len(), stride);
        let (mean, msq) = (planes[3][0], planes[6][0]);
        assert_eq!((mean, msq), (3.0, 12.5));
        let v = variance_of_mean(mean, msq, 4);
        assert!((v - 14.0 / 12.0).abs() < 1e-6, "{v}");
        assert_eq!(variance_of_mean(1.0, 1.0, 1), 0.0);
    }
}
