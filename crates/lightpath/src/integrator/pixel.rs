//! The samples of one pixel: which sampler makes their numbers, and how many to take.
//!
//! A pixel takes the samples `first_sample + taken ..` of its job, up to `spp` in all.
//! Under adaptive sampling (`adaptive.rs`) its second pass takes it to its target count,
//! which its neighbourhood's pilot samples set, and no further. Every AOV of the pixel is
//! accumulated from the same samples, so partitions still sum exactly; the film records
//! each pixel's sample count (the `sampleCount` channel).

use super::adaptive::Moments;
use super::glints::GlintSample;
use super::{Sink, Tracer};
use crate::film::Film;
use crate::light::luminance;
use crate::sampler::{IndependentPixel, PixelSampler, Sampler, SamplerKind, SobolPixel};
use glam::Vec2;

/// Where one pixel's samples go and which samples it takes.
pub(super) struct PixelJob<'p> {
    /// The pixel in the frame (its sample numbers are the frame's).
    pub x: u32,
    pub y: u32,
    /// The pixel's run of the band: RGB per AOV, then alpha.
    pub run: &'p mut [f32],
    pub first_sample: u32,
    /// Samples `run` already holds (an adaptive pilot's): the pixel goes on from sample
    /// `first_sample + taken`.
    pub taken: u32,
    /// Samples to have in all (under adaptive sampling: the pass's, or the pixel's target).
    pub spp: u32,
    /// Called after each sample with what it left in the sink (Cryptomatte coverage).
    pub after_sample: &'p mut dyn FnMut(&Sink),
    /// The pilot's moments of the pixel's beauty, which the samples add to (adaptive
    /// sampling's pilot pass); `None`: none kept.
    pub moments: Option<&'p mut Moments>,
}

impl Tracer<'_> {
    /// Takes the samples of one pixel with the scene's sampler; returns how many the
    /// pixel holds in all (`job.taken` and this call's).
    pub(super) fn render_pixel(&self, job: PixelJob, out: &mut Sink) -> u32 {
        let settings = &self.scene.settings;
        let index = job.y as u64 * self.scene.camera.width as u64 + job.x as u64;
        match settings.sampler {
            SamplerKind::Sobol => {
                let mut pixel = self.sobol_pixel(out, index);
                let held = self.pixel_samples(job, out, &mut *pixel);
                out.sobol = Some(pixel);
                held
            }
            SamplerKind::Independent => {
                self.pixel_samples(job, out, &mut IndependentPixel::new(self.seed, index))
            }
        }
    }

    /// The Sobol sampler of frame pixel `index`: the worker's, made over (`Sink::sobol`),
    /// or a new one.
    fn sobol_pixel(&self, out: &mut Sink, index: u64) -> Box<SobolPixel> {
        match out.sobol.take() {
            Some(mut pixel) => {
                pixel.reset(self.seed, index);
                pixel
            }
            None => Box::new(SobolPixel::new(self.seed, index)),
        }
    }

    /// Traces the light subpaths of samples `samples` of frame pixel (`x`, `y`) and
    /// joins them to the camera, with no camera paths (a pixel outside the window:
    /// connect/light_tracing.rs). Their numbers are those the pixel's own samples use.
    pub(super) fn splat_pixel(
        &self,
        x: u32,
        y: u32,
        samples: std::ops::Range<u32>,
        out: &mut Sink,
    ) {
        let index = y as u64 * self.scene.camera.width as u64 + x as u64;
        match self.scene.settings.sampler {
            SamplerKind::Sobol => {
                let mut pixel = self.sobol_pixel(out, index);
                for s in samples {
                    out.light_path.reset();
                    self.splat(out, &mut pixel.sample(s as u64));
                }
                out.sobol = Some(pixel);
            }
            SamplerKind::Independent => {
                let mut pixel = IndependentPixel::new(self.seed, index);
                for s in samples {
                    out.light_path.reset();
                    self.splat(out, &mut pixel.sample(s as u64));
                }
            }
        }
    }

    fn pixel_samples(
        &self,
        job: PixelJob,
        out: &mut Sink,
        samplers: &mut impl PixelSampler,
    ) -> u32 {
        let scene = self.scene;
        let cam = &scene.camera;
        let alpha_slot = Film::alpha_slot(job.run.len());
        let mut moments = job.moments;
        let glints = match self.glint_pixel(job.x, job.y) {
            Some(pixel) => {
                out.glint_pixel = pixel;
                true
            }
            None => false,
        };
        let index = job.y as u64 * cam.width as u64 + job.x as u64;
        for s in job.first_sample + job.taken..job.first_sample + job.spp {
            let mut sampler = samplers.sample(s as u64);
            let (u_filter, u_lens) = sampler.camera_2d();
            let offset = scene.filter.offset(u_filter);
            let film_pos = Vec2::new(job.x as f32 + 0.5, job.y as f32 + 0.5) + offset;
            let ray = cam.ray(film_pos, u_lens);
            // The filter's density of the offset: only light tracing's weights use it.
            let film_pdf = if self.splats.is_some() {
                scene.filter.pdf(offset)
            } else {
                0.0
            };
            out.glint = glints.then_some(GlintSample {
                film: film_pos,
                lens: u_lens,
            });
            let alpha = self.trace(ray, film_pdf, &mut sampler, out);
            if let Some(g) = out.glint {
                self.sample_glint(out, g, index, s as u64);
            }
            (job.after_sample)(out);
            if let Some(m) = &mut moments {
                // The beauty is AOV 0 (aov::plan puts it first).
                m.add(luminance(out.acc.value(0)));
            }
            out.acc.flush(job.run);
            job.run[alpha_slot] += alpha;
        }
        out.glint = None;
        job.spp.max(job.taken)
    }
}
