//! Adaptive sampling (`--noise-threshold X --min-spp N --spp MAX`, `[render]
//! noise_threshold`) in two passes over the frame, so that a pixel's count can depend on
//! its neighbours, be the same for any thread count, and never depend on the pixel's own
//! samples:
//!
//! 1. **Pilot**: every pixel of the window takes `min_spp` samples (at most `spp`), and
//!    the luminance moments of its beauty are kept ([`Pilot`]).
//! 2. From the pilot alone, each pixel *predicts* the count at which its error would
//!    reach X: `min_spp · (error / X)²` ([`Moments::error`]), rounded up to a power of two
//!    and clamped to `min_spp ..= spp` (a pixel without variance predicts `min_spp`).
//! 3. **The rest**: each pixel takes, in all, the largest count its **neighbours**
//!    predicted — the eight pixels around it within [`NEIGHBOUR_RADIUS`], not itself.
//!
//! The error is the standard error of the mean luminance divided by the square root of
//! the mean, as Cycles weighs it: with noise proportional to brightness this gives each
//! pixel samples in proportion to its standard deviation, the allocation that lowers the
//! image's summed variance most for a given total, and a bright lamp's edge is not left
//! at `min_spp` as a relative error would leave it.
//!
//! Why the neighbours, and only them: a count that depended on the pixel's own samples
//! would be smaller when they happened to be alike — a glossy pixel whose first samples
//! missed the rare reflection of a small lamp — and its mean biased dark (on
//! `scenes/many-lights.toml`: −0.5 % over the image and down to −7 % around the metal
//! ball with a per-pixel test at every power of two, −0.24 % and −4 % with the largest
//! prediction of the 3 × 3 window including the pixel). A count taken from the other
//! pixels' samples is independent of the pixel's own, so its mean stays an unbiased
//! estimate (`adaptive_sampling_is_unbiased`). And a small bright lamp covering part of a
//! pixel may be missed (or hit) by all of its first samples, leaving it no variance; the
//! neighbours, which see the lamp's edge, predict many samples and lend it their count.
//! The price: a feature smaller than a pixel that no neighbour sees (a lamp well under a
//! pixel wide, a one-pixel glint) keeps `min_spp`. Powers of two keep the Sobol points of
//! every count balanced.
//!
//! The target plane is a function of the pilot's moments only, so the second pass is
//! again one independent job per pixel: any thread count gives the same image, and a
//! checkpoint holding the pilot's moments resumes bit for bit. A crop (`--crop`) takes
//! pilot samples of the pixels just outside its window too (their moments only, not their
//! values), so tiles see the same neighbourhoods as the whole frame and join into it
//! exactly.

use crate::film::PixelWindow;
use crate::settings::{RenderDesc, DEFAULT_MIN_SPP};

/// How far a pixel looks for the neighbours whose predictions set its count: 1, the
/// eight pixels around it (Cycles' adaptive sampling looks as far).
pub const NEIGHBOUR_RADIUS: u32 = 1;

/// Below this mean luminance a pixel's error is weighed as at this mean (the square root
/// would otherwise ask near-black pixels for ever more samples).
const DARKEST_WEIGHED: f64 = 1e-4;

/// Running sums of a pixel's beauty luminance, for its standard error.
#[derive(Clone, Copy, Debug, Default)]
pub struct Moments {
    pub n: u32,
    pub sum: f64,
    pub sum2: f64,
}

impl Moments {
    pub fn add(&mut self, v: f32) {
        let v = v as f64;
        self.n += 1;
        self.sum += v;
        self.sum2 += v * v;
    }

    /// The standard error of the mean over the square root of the mean, √(s² / n) /
    /// √mean: 0 when the samples are all equal (black background, a lamp's inside:
    /// nothing to estimate).
    pub fn error(&self) -> f64 {
        let n = self.n as f64;
        let mean = self.sum / n;
        let var = ((self.sum2 - self.sum * mean) / (n - 1.0)).max(0.0);
        if var == 0.0 {
            return 0.0;
        }
        (var / n).sqrt() / mean.max(DARKEST_WEIGHED).sqrt()
    }
}

/// The pilot pass of an adaptive render: each pixel's luminance moments over its first
/// samples. A checkpoint holds it, so that a resumed render computes the same targets.
#[derive(Clone, Debug, PartialEq)]
pub struct Pilot {
    /// Whether every pixel of the window has its pilot samples (the render is in its
    /// second pass).
    pub complete: bool,
    /// Per pixel of the window, row by row: the sum and the sum of squares of the
    /// beauty's luminance over the pilot samples (zero where not yet taken).
    pub sums: Vec<[f64; 2]>,
}

impl Pilot {
    /// A pilot not yet started for `pixels` pixels.
    pub fn new(pixels: usize) -> Pilot {
        Pilot {
            complete: false,
            sums: vec![[0.0; 2]; pixels],
        }
    }
}

/// The numbers of one adaptive render: the pilot's count, the most samples a
/// pixel takes and the noise threshold.
#[derive(Clone, Copy, Debug)]
pub(super) struct Rule {
    /// Samples every pixel takes in the pilot pass: `min_spp`, or `spp` if fewer.
    pub pilot: u32,
    pub spp: u32,
    pub threshold: f32,
}

impl Rule {
    /// The rule of a render of `spp` samples per pixel with these settings.
    pub fn new(settings: &RenderDesc, spp: u32) -> Rule {
        Rule {
            pilot: settings.min_spp.unwrap_or(DEFAULT_MIN_SPP).min(spp),
            spp,
            threshold: settings.noise_threshold,
        }
    }

    /// The moments of a pixel after the pilot, from its stored sums.
    pub fn pilot_moments(&self, sums: [f64; 2]) -> Moments {
        Moments {
            n: self.pilot,
            sum: sums[0],
            sum2: sums[1],
        }
    }

    /// The count at which a pixel's error would reach the threshold, from its pilot
    /// moments (the error falls as 1/√n), rounded up to a power of two and clamped to
    /// `pilot ..= spp`.
    pub fn predicted_count(&self, m: &Moments) -> u32 {
        let ratio = m.error() / self.threshold as f64;
        let wanted = m.n as f64 * ratio * ratio;
        if wanted.is_nan() || wanted >= self.spp as f64 {
            return self.spp;
        }
        let count = (wanted.ceil() as u32).max(self.pilot);
        // Past 2³¹ there is no power of two in u32: take every sample.
        count
            .checked_next_power_of_two()
            .map_or(self.spp, |c| c.min(self.spp))
    }
}

/// The region whose pilot moments decide the targets of `window`: the window grown by
/// `radius` on every side, within the frame.
pub(super) fn neighbourhood(window: PixelWindow, frame: [u32; 2], radius: u32) -> PixelWindow {
    PixelWindow {
        x0: window.x0.saturating_sub(radius),
        y0: window.y0.saturating_sub(radius),
        x1: (window.x1.saturating_add(radius)).min(frame[0]),
        y1: (window.y1.saturating_add(radius)).min(frame[1]),
    }
}

/// Each pixel of `window`'s target: the largest of `predicted` (one count per pixel of
/// `region`, row by row) at its neighbours within `radius` — not its own — and at least
/// `floor` (the pilot's count).
pub(super) fn targets(
    predicted: &[u32],
    region: PixelWindow,
    window: PixelWindow,
    radius: u32,
    floor: u32,
) -> Vec<u32> {
    let (w, h) = (region.width() as usize, region.height() as usize);
    let r = radius as usize;
    let (ox, oy) = (
        (window.x0 - region.x0) as usize,
        (window.y0 - region.y0) as usize,
    );
    let mut out = Vec::with_capacity(window.width() as usize * window.height() as usize);
    for y in oy..oy + window.height() as usize {
        for x in ox..ox + window.width() as usize {
            let mut most = floor;
            for yy in y.saturating_sub(r)..(y + r + 1).min(h) {
                for xx in x.saturating_sub(r)..(x + r + 1).min(w) {
                    if (xx, yy) != (x, y) {
                        most = most.max(predicted[yy * w + xx]);
                    }
                }
            }
            out.push(most);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn moments(values: &[f64]) -> Moments {
        let mut m = Moments::default();
        for &v in values {
            m.add(v as f32);
        }
        m
    }

    #[test]
    fn the_error_is_the_standard_error_over_the_root_of_the_mean() {
        assert_eq!(
            moments(&[1.0; 4]).error(),
            0.0,
            "no variance: nothing to estimate"
        );
        // Mean 1, sample variance 4/3 over 4 samples: standard error √(1/3), √mean 1.
        let se = (4.0f64 / 3.0 / 4.0).sqrt();
        assert!((moments(&[0.0, 2.0, 0.0, 2.0]).error() - se).abs() < 1e-12);
        // Four times brighter, the same relative noise: the error doubles (a relative
        // error would not move, and would leave a bright pixel as noisy as a dark one).
        assert!((moments(&[0.0, 8.0, 0.0, 8.0]).error() - 2.0 * se).abs() < 1e-12);
        // A rare bright sample makes a large error.
        let mut rare = [0.0; 10];
        rare[9] = 4.0;
        assert!(moments(&rare).error() > 0.5);
        // Near black, the error is weighed as at DARKEST_WEIGHED, not divided by ~0.
        let dim = moments(&[0.0, 2e-6, 0.0, 2e-6]);
        assert!((dim.error() - se * 1e-6 / DARKEST_WEIGHED.sqrt()).abs() < 1e-12);
    }

    fn rule(min_spp: u32, spp: u32, threshold: f32) -> Rule {
        let settings = RenderDesc {
            min_spp: Some(min_spp),
            noise_threshold: threshold,
            ..RenderDesc::default()
        };
        Rule::new(&settings, spp)
    }

    #[test]
    fn a_pixel_predicts_the_count_its_error_needs_in_a_power_of_two() {
        let s = rule(16, 1024, 0.125);
        // Mean 1, error √0.275 at 16 samples: 0.275 / 0.125² × 16 = 281.6 samples → 512.
        let m = Moments {
            n: 16,
            sum: 16.0,
            sum2: 82.0,
        };
        assert!((m.error() - 0.275f64.sqrt()).abs() < 1e-12);
        assert_eq!(s.predicted_count(&m), 512);
        assert_eq!(rule(16, 1024, 0.25).predicted_count(&m), 128, "70.4 → 128");
        let flat = Moments {
            n: 16,
            sum: 16.0,
            sum2: 16.0,
        };
        assert_eq!(s.predicted_count(&flat), 16, "no variance: min_spp");
        assert_eq!(rule(16, 300, 0.125).predicted_count(&m), 300, "at most spp");
        assert_eq!(rule(16, 8, 0.125).predicted_count(&m), 8);
        // Mean 1, variance 3·10⁹·0.125²: 3·10⁹ samples wanted of at most 4·10⁹, past the
        // largest power of two in u32.
        let huge = rule(16, 4_000_000_000, 0.125);
        let wanted = Moments {
            n: 16,
            sum: 16.0,
            sum2: 16.0 + 15.0 * 3e9 * 0.125 * 0.125,
        };
        assert!(wanted.error().powi(2) / 0.125f64.powi(2) * 16.0 > 2f64.powi(31));
        assert_eq!(huge.predicted_count(&wanted), 4_000_000_000);
    }

    #[test]
    fn a_target_is_the_largest_prediction_of_the_other_pixels_around() {
        let frame = [5, 4];
        let all = PixelWindow::full(5, 4);
        let mut predicted = vec![16u32; 20];
        predicted[5 + 2] = 64; // (2, 1)
        let t = targets(&predicted, all, all, 1, 16);
        for y in 0..4usize {
            for x in 0..5usize {
                let near = x.abs_diff(2) <= 1 && y.abs_diff(1) <= 1 && (x, y) != (2, 1);
                assert_eq!(t[y * 5 + x], if near { 64 } else { 16 }, "({x}, {y})");
            }
        }
        // Radius 0: no neighbours, every pixel stays at the pilot's count.
        assert_eq!(targets(&predicted, all, all, 0, 16), vec![16; 20]);
        // A crop sees the pixels around it: (3, 2)..(5, 4) has (2, 1) as a neighbour.
        let crop = PixelWindow {
            x0: 3,
            y0: 2,
            x1: 5,
            y1: 4,
        };
        let region = neighbourhood(crop, frame, 1);
        assert_eq!((region.x0, region.y0, region.x1, region.y1), (2, 1, 5, 4));
        let inside: Vec<u32> = (1..4)
            .flat_map(|y| (2..5).map(move |x| (x, y)))
            .map(|(x, y)| predicted[y * 5 + x])
            .collect();
        assert_eq!(targets(&inside, region, crop, 1, 16), vec![64, 16, 16, 16]);
    }
}
