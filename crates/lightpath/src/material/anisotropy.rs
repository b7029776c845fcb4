//! The direction anisotropic lobes stretch along (glTF's `KHR_materials_anisotropy`): the
//! mesh's tangent turned in the tangent plane by `anisotropyRotation`, and by the
//! direction a texture's red and green encode ([0, 1] → [−1, 1]; (1, 0.5) is the tangent).
//! Without it, anisotropy follows the shading frame's first axis.

use super::texture::Texture;
use glam::Vec2;

#[derive(Clone, Debug)]
pub struct AnisotropyDirection {
    /// Counter-clockwise from the tangent towards the bitangent, in radians.
    pub rotation: f32,
    /// The direction in red and green (linear), turned by `rotation`.
    pub texture: Option<Texture>,
}

impl AnisotropyDirection {
    /// (cos, sin) of the angle from the tangent towards the bitangent at `uv`.
    pub fn at(&self, uv: Option<Vec2>) -> (f32, f32) {
        let mut angle = if self.rotation.is_finite() {
            self.rotation
        } else {
            0.0
        };
        if let (Some(tex), Some(uv)) = (&self.texture, uv) {
            let v = tex.eval(uv, 0.0);
            let (x, y) = (2.0 * v.x - 1.0, 2.0 * v.y - 1.0);
            if x * x + y * y > 1e-12 && x.is_finite() && y.is_finite() {
                angle += y.atan2(x);
            }
        }
        let (s, c) = angle.sin_cos();
        (c, s)
    }
}
