//! Light tracing's film: what light subpaths joined to the camera add to pixels other
//! than their own camera sample's (integrator/light_tracing.rs).
//!
//! A splat lands wherever its light vertex is seen, so the rows of a band, the bands of
//! a pass and the runs of a resumed render add to the same pixels in an order that
//! depends on threads and on where a render stopped. The sums are therefore fixed-point
//! integers added atomically: integer addition is associative, so a window's sums are
//! the same bit for bit whatever order its splats come in, and the film's float sums
//! take them once, at the end (`Splats::add_to`).

use super::{Film, PixelWindow};
use glam::Vec3A;
use std::sync::atomic::{AtomicI64, Ordering};

/// Units per 1.0 of a sum: 2⁻³² resolution (a splat below half of it is lost; one
/// sample's value in a pixel lit at 10⁻³ is ~10⁶ units) with sums up to 2³¹ (a pixel's
/// sum over its samples: spp × its value).
const SCALE: f64 = 4_294_967_296.0;

/// The largest value one splat may add, so that no sum can wrap: 2³¹ units of headroom
/// hold 2³¹ / LIMIT such splats in one pixel; more clamp (they are fireflies).
const LIMIT: f64 = 1.0e6;

/// The splats of a window: RGB of every AOV of every pixel.
pub struct Splats {
    window: PixelWindow,
    aovs: usize,
    sums: Vec<AtomicI64>,
}

impl Splats {
    /// Empty sums for the `aovs` AOVs of the pixels of `window`.
    pub fn new(window: PixelWindow, aovs: usize) -> Splats {
        let n = window.width() as usize * window.height() as usize * aovs * 3;
        Splats {
            window,
            aovs,
            sums: (0..n).map(|_| AtomicI64::new(0)).collect(),
        }
    }

    /// The window the splats are kept for.
    pub fn window(&self) -> PixelWindow {
        self.window
    }

    /// Adds `value` to AOV `aov` of frame pixel (`x`, `y`), if the window holds it. A
    /// value that is not finite adds nothing.
    #[inline]
    pub fn add(&self, x: u32, y: u32, aov: usize, value: Vec3A) {
        let w = self.window;
        if !(w.x0..w.x1).contains(&x) || !(w.y0..w.y1).contains(&y) {
            return;
        }
        let pixel = (y - w.y0) as usize * w.width() as usize + (x - w.x0) as usize;
        let at = (pixel * self.aovs + aov) * 3;
        for (c, v) in value.to_array().into_iter().enumerate() {
            if v != 0.0 && v.is_finite() {
                let units = ((v as f64).clamp(-LIMIT, LIMIT) * SCALE).round() as i64;
                self.sums[at + c].fetch_add(units, Ordering::Relaxed);
            }
        }
    }

    /// The sums as raw units, pixel by pixel (a checkpoint's copy).
    pub fn units(&self) -> Vec<i64> {
        self.sums
            .iter()
            .map(|s| s.load(Ordering::Relaxed))
            .collect()
    }

    /// Sets the sums from `units` (as `units` gave them); `false` if the count differs.
    pub fn set_units(&self, units: &[i64]) -> bool {
        if units.len() != self.sums.len() {
            return false;
        }
        for (s, &u) in self.sums.iter().zip(units) {
            s.store(u, Ordering::Relaxed);
        }
        true
    }

    /// Adds the sums to `film`'s AOV sums (a film of the same window and AOVs).
    pub fn add_to(&self, film: &mut Film) {
        debug_assert_eq!((film.window, film.aovs), (self.window, self.aovs));
        let pixels = self.window.width() as usize * self.window.height() as usize;
        for k in 0..self.aovs.min(film.aovs) {
            for c in 0..3 {
                let plane = &mut film.planes[3 * k + c];
                for (i, sum) in plane.iter_mut().enumerate().take(pixels) {
                    let units = self.sums[(i * self.aovs + k) * 3 + c].load(Ordering::Relaxed);
                    if units != 0 {
                        *sum += (units as f64 / SCALE) as f32;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_do_not_depend_on_the_order_of_the_splats() {
        let window = PixelWindow {
            x0: 2,
            y0: 1,
            x1: 5,
            y1: 3,
        };
        let values: Vec<f32> = (0..200).map(|i| 1.0 / (1.0 + i as f32 * 0.37)).collect();
        let sum_in = |order: &[usize]| {
            let s = Splats::new(window, 2);
            for &i in order {
                s.add(3, 2, 1, Vec3A::new(values[i], 1e-7, 1e5));
                s.add(0, 0, 0, Vec3A::ONE); // outside the window: dropped
            }
            s.units()
        };
        let forward: Vec<usize> = (0..values.len()).collect();
        let backward: Vec<usize> = forward.iter().rev().copied().collect();
        let a = sum_in(&forward);
        assert_eq!(a, sum_in(&backward));
        let mut film = Film::for_window(window, [8, 8], 2, 1);
        let s = Splats::new(window, 2);
        assert!(s.set_units(&a));
        s.add_to(&mut film);
        let pixel = 3;
        let expected: f64 = values.iter().map(|&v| v as f64).sum();
        assert!((film.planes[3][pixel] as f64 - expected).abs() < 1e-5 * expected);
        assert!((film.planes[4][pixel] as f64 - 200e-7).abs() < 1e-9);
        assert_eq!(film.planes[0].iter().sum::<f32>(), 0.0);
    }
}
