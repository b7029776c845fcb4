//! The film: one RGB accumulator per AOV per pixel, plus alpha, stored pixel by pixel so
//! a sample writes one contiguous run.

use glam::Vec3A;

#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub aovs: usize,
    /// Samples accumulated per pixel.
    pub spp: u32,
    /// `width × height` runs of `3 × aovs + 1` sums (RGB per AOV, then alpha).
    pub data: Vec<f32>,
}

impl Film {
    pub fn new(width: u32, height: u32, aovs: usize, spp: u32) -> Film {
        let stride = 3 * aovs + 1;
        Film {
            width,
            height,
            aovs,
            spp,
            data: vec![0.0; width as usize * height as usize * stride],
        }
    }

    pub fn stride(&self) -> usize {
        3 * self.aovs + 1
    }

    /// The mean value of AOV `k` at pixel (x, y).
    pub fn pixel(&self, k: usize, x: u32, y: u32) -> Vec3A {
        let i = (y as usize * self.width as usize + x as usize) * self.stride() + 3 * k;
        Vec3A::new(self.data[i], self.data[i + 1], self.data[i + 2]) / self.spp as f32
    }

    /// AOV `k` as RGB planes of means, row by row.
    pub fn channel(&self, k: usize, c: usize) -> Vec<f32> {
        let inv = 1.0 / self.spp as f32;
        self.data
            .chunks_exact(self.stride())
            .map(|px| px[3 * k + c] * inv)
            .collect()
    }

    pub fn alpha(&self) -> Vec<f32> {
        let inv = 1.0 / self.spp as f32;
        let a = 3 * self.aovs;
        self.data
            .chunks_exact(self.stride())
            .map(|px| px[a] * inv)
            .collect()
    }

    /// Merges a film of the same frame rendered with other samples (a farm's sample
    /// ranges): the result is the film of all samples.
    pub fn merge(&mut self, other: &Film) -> Result<(), String> {
        if (self.width, self.height, self.aovs) != (other.width, other.height, other.aovs) {
            return Err("films differ in size or AOV count".into());
        }
        for (a, b) in self.data.iter_mut().zip(&other.data) {
            *a += b;
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
    touched: Vec<u32>,
    is_touched: Vec<bool>,
}

impl SampleAccumulator {
    pub fn new(aovs: usize) -> SampleAccumulator {
        SampleAccumulator {
            values: vec![Vec3A::ZERO; aovs],
            touched: Vec::with_capacity(aovs),
            is_touched: vec![false; aovs],
        }
    }

    #[inline]
    pub fn add(&mut self, aov: usize, value: Vec3A, overwrite: bool) {
        if !self.is_touched[aov] {
            self.is_touched[aov] = true;
            self.touched.push(aov as u32);
            self.values[aov] = value;
        } else if overwrite {
            self.values[aov] = value;
        } else {
            self.values[aov] += value;
        }
    }

    /// Adds the sample to a pixel's run of the film and clears it.
    #[inline]
    pub fn flush(&mut self, pixel: &mut [f32]) {
        for &k in &self.touched {
            let k = k as usize;
            let v = self.values[k];
            pixel[3 * k] += v.x;
            pixel[3 * k + 1] += v.y;
            pixel[3 * k + 2] += v.z;
            self.is_touched[k] = false;
        }
        self.touched.clear();
    }
}
