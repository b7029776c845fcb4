//! Sample streams indexed by dimension: the one owner of which number of a camera sample
//! drives which decision (DESIGN.md). A camera sample's numbers depend only on (seed,
//! pixel, sample index, dimension), so a low-discrepancy sampler (Owen-scrambled Sobol)
//! drops in by implementing [`Sampler`] and nothing else changes.
//!
//! Dimension layout of one camera sample (`dim::*`):
//!
//! | dimensions | decision |
//! |---|---|
//! | 0, 1 | pixel filter offset (2D) |
//! | 2, 3 | lens position (2D) |
//! | `bounce(d) + 0` | light choice at scattering vertex `d` (1D) |
//! | `bounce(d) + 1, 2` | point on that light (2D) |
//! | `bounce(d) + 3` | BSDF lobe choice (1D) |
//! | `bounce(d) + 4, 5` | BSDF direction (2D) |
//! | `bounce(d) + 6` | Russian roulette after the bounce (1D) |
//!
//! with `bounce(d) = 4 + 7 d`, `d` counting scattering vertices from 0 at the first hit.
//! A path may skip dimensions (no roulette before `rr_depth`, a path that ends early) but
//! never asks for one out of order.

use crate::sampling::Rng;
use glam::Vec2;

/// The dimension numbers of the layout above.
pub mod dim {
    pub const FILTER: u32 = 0;
    pub const LENS: u32 = 2;
    /// Per scattering vertex, offsets from [`bounce`].
    pub const LIGHT_CHOICE: u32 = 0;
    pub const LIGHT_POINT: u32 = 1;
    pub const LOBE_CHOICE: u32 = 3;
    pub const DIRECTION: u32 = 4;
    pub const ROULETTE: u32 = 6;
    /// Dimensions one scattering vertex uses.
    pub const PER_BOUNCE: u32 = 7;

    // The layout's dimensions of one bounce follow the lens and do not overlap the next
    // bounce's.
    const _: () = assert!(DIRECTION + 2 <= ROULETTE && ROULETTE + 1 == PER_BOUNCE);
    const _: () = assert!(LENS + 2 == 4);

    /// First dimension of scattering vertex `depth`.
    #[inline(always)]
    pub fn bounce(depth: u32) -> u32 {
        4 + PER_BOUNCE * depth
    }
}

/// The numbers of one camera sample, by dimension (the layout above).
pub trait Sampler {
    /// Uniform in [0, 1) for dimension `dim`.
    fn get_1d(&mut self, dim: u32) -> f32;
    /// Uniform in [0, 1)² for dimensions `dim` and `dim + 1`.
    fn get_2d(&mut self, dim: u32) -> Vec2;
}

/// The name of the sampler renders use, as the header's `lightpath/setting/sampler`
/// records it.
pub const NAME: &str = "independent";

/// Independent uniform numbers: one PCG32 stream per camera sample, read in dimension
/// order (which is why the layout forbids asking out of order). This is the sequence
/// renders have always used, so its pixels are those of earlier versions.
pub struct IndependentSampler {
    rng: Rng,
    /// The next dimension allowed, to check the order in debug builds.
    #[cfg(debug_assertions)]
    next_dim: u32,
}

impl IndependentSampler {
    pub fn new(seed: u64, pixel: u64, sample: u64) -> IndependentSampler {
        IndependentSampler {
            rng: Rng::for_sample(seed, pixel, sample),
            #[cfg(debug_assertions)]
            next_dim: 0,
        }
    }

    #[inline(always)]
    fn check_order(&mut self, _dim: u32, _count: u32) {
        #[cfg(debug_assertions)]
        {
            debug_assert!(
                _dim >= self.next_dim,
                "dimension {_dim} asked after {}",
                self.next_dim
            );
            self.next_dim = _dim + _count;
        }
    }
}

impl Sampler for IndependentSampler {
    #[inline(always)]
    fn get_1d(&mut self, dim: u32) -> f32 {
        self.check_order(dim, 1);
        self.rng.next_f32()
    }

    #[inline(always)]
    fn get_2d(&mut self, dim: u32) -> Vec2 {
        self.check_order(dim, 2);
        self.rng.next_2d()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reading the layout in order gives exactly the stream `Rng` gives: the pixels of
    /// renders made before the sampler existed.
    #[test]
    fn independent_sampler_reads_the_rng_stream_in_order() {
        let mut rng = Rng::for_sample(7, 123, 4);
        let mut s = IndependentSampler::new(7, 123, 4);
        assert_eq!(s.get_2d(dim::FILTER), rng.next_2d());
        assert_eq!(s.get_2d(dim::LENS), rng.next_2d());
        for d in 0..3 {
            let b = dim::bounce(d);
            assert_eq!(s.get_1d(b + dim::LIGHT_CHOICE), rng.next_f32());
            assert_eq!(s.get_2d(b + dim::LIGHT_POINT), rng.next_2d());
            assert_eq!(s.get_1d(b + dim::LOBE_CHOICE), rng.next_f32());
            assert_eq!(s.get_2d(b + dim::DIRECTION), rng.next_2d());
            if d > 0 {
                assert_eq!(s.get_1d(b + dim::ROULETTE), rng.next_f32());
            }
        }
    }

    #[cfg(debug_assertions)]
    #[test]
    #[should_panic(expected = "asked after")]
    fn asking_out_of_order_is_caught() {
        let mut s = IndependentSampler::new(1, 2, 3);
        s.get_2d(dim::LENS);
        s.get_2d(dim::FILTER);
    }
}
