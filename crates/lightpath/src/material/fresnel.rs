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
