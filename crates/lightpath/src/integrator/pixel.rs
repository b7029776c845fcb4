//! The samples of one pixel: which sampler makes their numbers, and how many to take.
//!
//! Adaptive sampling (`--noise-threshold X`, `[render] noise_threshold`): every pixel
//! takes `min_spp` samples, then stops as soon as the relative standard error of its
//! beauty's luminance — estimated from its own samples, √(s² / n) / mean — is at most
//! X, or at `spp`. It checks every [`CHECK_EVERY`] samples: Sobol points come in
//! balanced blocks of powers of two, so a pixel stops at the end of a block. Every AOV
//! of the pixel is accumulated from the same samples, so partitions still sum exactly;
//! the decision reads only the pixel's own samples, so it is the same for any thread
//! count. The film records each pixel's sample count (the `sampleCount` channel).

use super::{Sink, Tracer};
use crate::film::Film;
use crate::light::luminance;
use crate::sampler::{dim, IndependentPixel, PixelSampler, Sampler, SamplerKind, SobolPixel};
use glam::Vec2;

/// Adaptive sampling checks a pixel's noise after this many samples past `min_spp`.
pub const CHECK_EVERY: u32 = 8;

/// Where one pixel's samples go and which samples it takes.
pub(super) struct PixelJob<'p> {
    /// The pixel in the frame (its sample numbers are the frame's).
    pub x: u32,
    pub y: u32,
    /// The pixel's run of the band: RGB per AOV, then alpha.
    pub run: &'p mut [f32],
    pub first_sample: u32,
    /// Samples to take, or at most when adaptive.
    pub spp: u32,
    /// Called after each sample with what it left in the sink (Cryptomatte coverage).
    pub after_sample: &'p mut dyn FnMut(&Sink),
}

/// Running sums of a pixel's beauty luminance, for its standard error.
#[derive(Default)]
struct Moments {
    n: u32,
    sum: f64,
    sum2: f64,
}

impl Moments {
    fn add(&mut self, v: f32) {
        let v = v as f64;
        self.n += 1;
        self.sum += v;
        self.sum2 += v * v;
    }

    /// Whether the relative standard error of the mean is at most `threshold`. A pixel
    /// whose samples are all equal (black background, a clamped light) has none.
    fn converged(&self, threshold: f32) -> bool {
        let n = self.n as f64;
        let mean = self.sum / n;
        let var = ((self.sum2 - self.sum * mean) / (n - 1.0)).max(0.0);
        if var == 0.0 {
            return true;
        }
        mean > 0.0 && (var / n).sqrt() <= threshold as f64 * mean
    }
}

impl Tracer<'_> {
    /// Takes the samples of one pixel with the scene's sampler; returns how many.
    pub(super) fn render_pixel(&self, job: PixelJob, out: &mut Sink) -> u32 {
        let settings = &self.scene.settings;
        let index = job.y as u64 * self.scene.camera.width as u64 + job.x as u64;
        match settings.sampler {
            SamplerKind::Sobol => {
                self.pixel_samples(job, out, SobolPixel::new(settings.seed, index))
            }
            SamplerKind::Independent => {
                self.pixel_samples(job, out, IndependentPixel::new(settings.seed, index))
            }
        }
    }

    fn pixel_samples(&self, job: PixelJob, out: &mut Sink, mut samplers: impl PixelSampler) -> u32 {
        let scene = self.scene;
        let cam = &scene.camera;
        let settings = &scene.settings;
        let alpha_slot = Film::alpha_slot(job.run.len());
        let adaptive = settings.noise_threshold > 0.0;
        let mut moments = Moments::default();
        for s in job.first_sample..job.first_sample + job.spp {
            let mut sampler = samplers.sample(s as u64);
            let offset = scene.filter.offset(sampler.get_2d(dim::FILTER));
            let film_pos = Vec2::new(job.x as f32 + 0.5, job.y as f32 + 0.5) + offset;
            let ray = cam.ray(film_pos, sampler.get_2d(dim::LENS));
            let alpha = self.trace(ray, &mut sampler, out);
            (job.after_sample)(out);
            if adaptive {
                // The beauty is AOV 0 (aov::plan puts it first).
                moments.add(luminance(out.acc.value(0)));
            }
            out.acc.flush(job.run);
            job.run[alpha_slot] += alpha;
            if adaptive
                && moments.n >= settings.min_spp
                && (moments.n - settings.min_spp) % CHECK_EVERY == 0
                && moments.converged(settings.noise_threshold)
            {
                return moments.n;
            }
        }
        job.spp
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_standard_error_decides() {
        let mut m = Moments::default();
        for v in [1.0, 1.0, 1.0, 1.0] {
            m.add(v);
        }
        assert!(m.converged(1e-6), "no variance: nothing to estimate");
        let mut m = Moments::default();
        // Mean 1, sample standard deviation 1 over 4 samples: relative error 0.5.
        for v in [0.0, 2.0, 0.0, 2.0] {
            m.add(v);
        }
        let se = (4.0f64 / 3.0 / 4.0).sqrt();
        assert!(m.converged(se as f32 * 1.001));
        assert!(!m.converged(se as f32 * 0.999));
        let mut m = Moments::default();
        for v in [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 4.0] {
            m.add(v);
        }
        assert!(
            !m.converged(0.5),
            "a rare bright sample keeps the pixel going"
        );
    }
}
