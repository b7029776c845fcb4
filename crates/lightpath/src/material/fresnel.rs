//! Fresnel terms and the reflection / refraction of directions about a normal.

use glam::Vec3A;

/// Unpolarised Fresnel reflectance of a dielectric; `eta` = inside / outside, `cos_i`
/// signed (negative: arriving from inside).
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let (cos_i, eta) = if cos_i < 0.0 {
        (-cos_i, 1.0 / eta)
    } else {
        (cos_i, eta)
    };
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Schlick's approximation, used for metals given by their normal-incidence colour.
pub fn schlick(f0: Vec3A, cos: f32) -> Vec3A {
    let m = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3A::ONE - f0) * m
}

/// Mirrors `wo` about the (micro)normal `m`.
pub fn reflect(wo: Vec3A, m: Vec3A) -> Vec3A {
    -wo + m * (2.0 * wo.dot(m))
}

/// Refracts `wi` about `n` (same side as `wi`) with relative index `eta`; None on total
/// internal reflection.
pub fn refract(wi: Vec3A, n: Vec3A, eta: f32) -> Option<Vec3A> {
    let cos_i = wi.dot(n);
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-wi / eta + n * (cos_i / eta - cos_t))
}

/// The cosine of the F82-tint model's reference angle (about 82°): μ̄ = 1/7.
pub const MU_BAR: f32 = 1.0 / 7.0;

/// Metal Fresnel as OpenPBR's "metal" section specifies it: Hoffman's (2023)
/// generalized Schlick with an F82 tint, F(μ) = F_s(μ) − a·μ(1 − μ)⁶ with
/// F_s the Schlick term of `f0` and a = F_s(μ̄)(1 − tint) / (μ̄(1 − μ̄)⁶), so that
/// F(μ̄) = tint · F_s(μ̄). `tint` 1 is Schlick's approximation. Clamped to [0, 1].
pub fn f82_tint(f0: Vec3A, tint: Vec3A, cos: f32) -> Vec3A {
    let mu = cos.clamp(0.0, 1.0);
    let a = f82_a(f0, tint);
    let m = 1.0 - mu;
    let m6 = {
        let m2 = m * m;
        m2 * m2 * m2
    };
    (schlick(f0, mu) - a * (mu * m6)).clamp(Vec3A::ZERO, Vec3A::ONE)
}

fn f82_a(f0: Vec3A, tint: Vec3A) -> Vec3A {
    let m = 1.0 - MU_BAR;
    schlick(f0, MU_BAR) * (Vec3A::ONE - tint) / (MU_BAR * m.powi(6))
}

/// The cosine-weighted hemispherical average 2∫F(μ)μ dμ of [`f82_tint`]:
/// F0 + (1 − F0)/21 − a/126 (from ∫(1 − μ)⁵μ dμ = 1/42 and ∫μ²(1 − μ)⁶ dμ = 1/252),
/// ignoring the clamp (which only binds for tints far outside [0, 1]).
pub fn f82_tint_avg(f0: Vec3A, tint: Vec3A) -> Vec3A {
    (f0 + (Vec3A::ONE - f0) / 21.0 - f82_a(f0, tint) / 126.0).clamp(Vec3A::ZERO, Vec3A::ONE)
}
