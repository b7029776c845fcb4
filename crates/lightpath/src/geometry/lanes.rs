//! The SIMD lanes the BVH tests boxes and triangles with: four (`Vec4`, SSE2 or glam's
//! portable code) or eight (`F8`, AVX, on x86-64 CPUs that have AVX2, chosen at run time).
//! The traversal is written once over [`Lanes`] and compiled for each; the arithmetic is
//! the same IEEE operations in the same order on every lane, so both widths find the same
//! distances.

use glam::{BVec4A, Vec4};
use std::ops::{Add, BitAnd, Div, Mul, Sub};

/// A lane mask of comparisons, combined before its bits are read.
pub(super) trait Mask: Copy + BitAnd<Output = Self> {
    /// Bit `l` set where lane `l` is true.
    fn bits(self) -> u32;
}

impl Mask for BVec4A {
    #[inline(always)]
    fn bits(self) -> u32 {
        self.bitmask()
    }
}

/// A vector of `WIDTH` floats, one box or triangle per lane.
pub(super) trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    const WIDTH: usize;
    const ZERO: Self;
    /// `[f32; WIDTH]` and `[u32; WIDTH]`.
    type Floats: Copy + AsRef<[f32]> + AsMut<[f32]>;
    type Refs: Copy + AsRef<[u32]> + AsMut<[u32]>;
    const ZERO_FLOATS: Self::Floats;
    const ZERO_REFS: Self::Refs;
    type Mask: Mask;

    fn splat(x: f32) -> Self;
    fn load(a: &Self::Floats) -> Self;
    fn store(self) -> Self::Floats;
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    fn abs(self) -> Self;
    /// `self` with its sign flipped in the lanes where `of`'s sign bit is set (exact).
    fn xor_sign(self, of: Self) -> Self;
    /// Lanes where `self <= o` (`<`, `>=`, `>`: the others), false for NaN.
    fn le(self, o: Self) -> Self::Mask;
    fn lt(self, o: Self) -> Self::Mask;
    fn ge(self, o: Self) -> Self::Mask;
    fn gt(self, o: Self) -> Self::Mask;
}

impl Lanes for Vec4 {
    const WIDTH: usize = 4;
    const ZERO: Self = Vec4::ZERO;
    type Floats = [f32; 4];
    type Refs = [u32; 4];
    const ZERO_FLOATS: [f32; 4] = [0.0; 4];
    const ZERO_REFS: [u32; 4] = [0; 4];
    type Mask = BVec4A;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Vec4::splat(x)
    }
    #[inline(always)]
    fn load(a: &[f32; 4]) -> Self {
        Vec4::from_array(*a)
    }
    #[inline(always)]
    fn store(self) -> [f32; 4] {
        self.to_array()
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Vec4::min(self, o)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Vec4::max(self, o)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Vec4::abs(self)
    }
    #[inline(always)]
    fn xor_sign(self, of: Self) -> Self {
        // Multiplying by ±1 is exact.
        self * Vec4::ONE.copysign(of)
    }
    #[inline(always)]
    fn le(self, o: Self) -> BVec4A {
        self.cmple(o)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> BVec4A {
        self.cmplt(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> BVec4A {
        self.cmpge(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> BVec4A {
        self.cmpgt(o)
    }
}

/// Eight lanes in one AVX register. Only ever used inside functions compiled with
/// `#[target_feature(enable = "avx2")]` and called after `is_x86_feature_detected!`:
/// the wrappers are `inline(always)` so the intrinsics inline into those functions.
#[cfg(target_arch = "x86_64")]
pub(super) use avx::F8;

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::{Lanes, Mask};
    use std::arch::x86_64::*;
    use std::ops::{Add, BitAnd, Div, Mul, Sub};

    #[derive(Clone, Copy)]
    pub(in crate::geometry) struct F8(__m256);

    /// Eight comparison results (all-ones lanes for true).
    #[derive(Clone, Copy)]
    pub(in crate::geometry) struct M8(__m256);

    impl BitAnd for M8 {
        type Output = M8;
        #[inline(always)]
        fn bitand(self, o: M8) -> M8 {
            unsafe { M8(_mm256_and_ps(self.0, o.0)) }
        }
    }

    impl Mask for M8 {
        #[inline(always)]
        fn bits(self) -> u32 {
            unsafe { _mm256_movemask_ps(self.0) as u32 }
        }
    }

    // SAFETY (every `unsafe` block below): AVX is present, because values of `F8` are
    // only made inside the BVH's AVX2 traversal, which runs only where
    // `is_x86_feature_detected!("avx2")` held (`bvh::Width::Eight`).
    macro_rules! binary {
        ($trait:ident, $method:ident, $intrinsic:ident) => {
            impl $trait for F8 {
                type Output = F8;
                #[inline(always)]
                fn $method(self, o: F8) -> F8 {
                    unsafe { F8($intrinsic(self.0, o.0)) }
                }
            }
        };
    }
    binary!(Add, add, _mm256_add_ps);
    binary!(Sub, sub, _mm256_sub_ps);
    binary!(Mul, mul, _mm256_mul_ps);
    binary!(Div, div, _mm256_div_ps);

    impl Lanes for F8 {
        const WIDTH: usize = 8;
        // SAFETY: `__m256` is eight `f32`s; every bit pattern is valid.
        const ZERO: Self = F8(unsafe { std::mem::transmute::<[f32; 8], __m256>([0.0; 8]) });
        type Floats = [f32; 8];
        type Refs = [u32; 8];
        const ZERO_FLOATS: [f32; 8] = [0.0; 8];
        const ZERO_REFS: [u32; 8] = [0; 8];
        type Mask = M8;

        #[inline(always)]
        fn splat(x: f32) -> Self {
            unsafe { F8(_mm256_set1_ps(x)) }
        }
        // Loads and stores are plain copies (no AVX instruction needed): nodes are built
        // outside the AVX2 functions.
        #[inline(always)]
        fn load(a: &[f32; 8]) -> Self {
            // SAFETY: `__m256` is eight `f32`s; every bit pattern is valid.
            F8(unsafe { std::mem::transmute::<[f32; 8], __m256>(*a) })
        }
        #[inline(always)]
        fn store(self) -> [f32; 8] {
            // SAFETY: as above.
            unsafe { std::mem::transmute::<__m256, [f32; 8]>(self.0) }
        }
        // min/max with the same operand order as SSE's `minps`/`maxps` (glam's Vec4),
        // so NaN and signed-zero cases pick the same lane value at both widths.
        #[inline(always)]
        fn min(self, o: Self) -> Self {
            unsafe { F8(_mm256_min_ps(self.0, o.0)) }
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            unsafe { F8(_mm256_max_ps(self.0, o.0)) }
        }
        #[inline(always)]
        fn abs(self) -> Self {
            unsafe { F8(_mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0)) }
        }
        #[inline(always)]
        fn xor_sign(self, of: Self) -> Self {
            unsafe {
                F8(_mm256_xor_ps(
                    self.0,
                    _mm256_and_ps(of.0, _mm256_set1_ps(-0.0)),
                ))
            }
        }
        #[inline(always)]
        fn le(self, o: Self) -> M8 {
            unsafe { M8(_mm256_cmp_ps::<_CMP_LE_OQ>(self.0, o.0)) }
        }
        #[inline(always)]
        fn lt(self, o: Self) -> M8 {
            unsafe { M8(_mm256_cmp_ps::<_CMP_LT_OQ>(self.0, o.0)) }
        }
        #[inline(always)]
        fn ge(self, o: Self) -> M8 {
            unsafe { M8(_mm256_cmp_ps::<_CMP_GE_OQ>(self.0, o.0)) }
        }
        #[inline(always)]
        fn gt(self, o: Self) -> M8 {
            unsafe { M8(_mm256_cmp_ps::<_CMP_GT_OQ>(self.0, o.0)) }
        }
    }
}
