//! Light tracing's film: what light subpaths joined to the camera add to pixels other
//! than their own camera sample's (integrator/light_tracing.rs).
//!
//! A splat lands wherever its light vertex is seen, so the rows of a band, the bands of
//! a pass and the runs of a resumed render add to the same pixels in an order that
//! depends on threads and on where a render stopped. The sums are therefore fixed-point
//! integers added atomically: integer addition is associative, so a window's sums are
//! the same bit for bit whatever order its splats come in, and the film's float sums
//! take them once, at the end (`Splats::add_to`).
//!
//! For the AOVs whose variance the render writes (`--variance`), the squares of the
//! splats are summed too: a pixel's splats are a random count of random values, whose sum
//! has a variance estimated by the sum of their squares (a compound Poisson sum), which
//! `add_to` adds to the camera samples' variance of the mean.

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

/// Units per 1.0 of a sum of squares, and the largest square one splat adds: 2⁻²⁴
/// resolution, sums up to 2³⁹.
const SQUARE_SCALE: f64 = 16_777_216.0;
const SQUARE_LIMIT: f64 = 1.0e9;

/// The splats of a window: RGB of every AOV of every pixel.
pub struct Splats {
    window: PixelWindow,
    aovs: usize,
    sums: Vec<AtomicI64>,
    /// Per AOV, its place among the AOVs whose squares are summed (`u32::MAX`: none).
    squared_at: Vec<u32>,
    squared: usize,
    squares: Vec<AtomicI64>,
}

impl Splats {
    /// Empty sums for the `aovs` AOVs of the pixels of `window`, and sums of squares for
    /// the AOVs `squared` (the film's `squared`).
    pub fn new(window: PixelWindow, aovs: usize, squared: &[u32]) -> Splats {
        let pixels = window.width() as usize * window.height() as usize;
        let mut squared_at = vec![u32::MAX; aovs];
        for (j, &k) in squared.iter().enumerate() {
            if let Some(at) = squared_at.get_mut(k as usize) {
                *at = j as u32;
            }
        }
        let zeros = |n: usize| (0..n).map(|_| AtomicI64::new(0)).collect();
        Splats {
            window,
            aovs,
            sums: zeros(pixels * aovs * 3),
            squared_at,
            squared: squared.len(),
            squares: zeros(pixels * squared.len() * 3),
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
        let square_at = self.squared_at[aov];
        for (c, v) in value.to_array().into_iter().enumerate() {
            if v != 0.0 && v.is_finite() {
                let v = (v as f64).clamp(-LIMIT, LIMIT);
                self.sums[at + c].fetch_add((v * SCALE).round() as i64, Ordering::Relaxed);
                if square_at != u32::MAX {
                    let units = ((v * v).min(SQUARE_LIMIT) * SQUARE_SCALE).round() as i64;
                    let at = (pixel * self.squared + square_at as usize) * 3 + c;
                    self.squares[at].fetch_add(units, Ordering::Relaxed);
                }
            }
        }
    }

    /// The sums, then the sums of squares, as raw units (a checkpoint's copy).
    pub fn units(&self) -> Vec<i64> {
        self.sums
            .iter()
            .chain(&self.squares)
            .map(|s| s.load(Ordering::Relaxed))
            .collect()
    }

    /// Sets the sums from `units` (as `units` gave them); `false` if the count differs.
    pub fn set_units(&self, units: &[i64]) -> bool {
        if units.len() != self.sums.len() + self.squares.len() {
            return false;
        }
        for (s, &u) in self.sums.iter().chain(&self.squares).zip(units) {
            s.store(u, Ordering::Relaxed);
        }
        true
    }

    /// Adds the sums to `film`'s AOV sums (a film of the same window and AOVs), and to
    /// the sums of squares of its variance AOVs what makes their variance of the mean
    /// that of the camera samples plus the splats' (module doc): with n samples, camera
    /// mean m and splat mean s, the squares gain n((m + s)² − m²) (the mean moved) and
    /// the splats' squares × (n − 1)/n (`film::variance_of_mean` divides by n(n − 1)).
    pub fn add_to(&self, film: &mut Film) {
        debug_assert_eq!((film.window, film.aovs), (self.window, self.aovs));
        let pixels = self.window.width() as usize * self.window.height() as usize;
        let base = 3 * film.aovs;
        for (j, &k) in film.squared.clone().iter().enumerate().take(self.squared) {
            let k = k as usize;
            for c in 0..3 {
                for i in 0..pixels {
                    let n = film.samples_at(i).max(1) as f64;
                    let sum = self.sums[(i * self.aovs + k) * 3 + c].load(Ordering::Relaxed);
                    let square =
                        self.squares[(i * self.squared + j) * 3 + c].load(Ordering::Relaxed);
                    let m = film.planes[3 * k + c][i] as f64 / n;
                    let s = sum as f64 / SCALE / n;
                    let gain = n * ((m + s) * (m + s) - m * m)
                        + square as f64 / SQUARE_SCALE * (n - 1.0) / n;
                    film.planes[base + 3 * j + c][i] += gain as f32;
                }
            }
        }
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
            let s = Splats::new(window, 2, &[]);
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
        let s = Splats::new(window, 2, &[]);
        assert!(s.set_units(&a));
        s.add_to(&mut film);
        let pixel = 4; // (3, 2) in a window from (2, 1), 3 wide
        let expected: f64 = values.iter().map(|&v| v as f64).sum();
        assert!((film.planes[3][pixel] as f64 - expected).abs() < 1e-5 * expected);
        // Each splat is exact to half a unit (2⁻³³).
        let unit = 1.0 / SCALE;
        assert!((film.planes[4][pixel] as f64 - 200e-7).abs() <= 200.0 * 0.5 * unit);
        assert_eq!(film.planes[0].iter().sum::<f32>(), 0.0);
    }
}
