//! Instances: one mesh stored once (its own `Accel`, in its own space) and placed many
//! times. The scene's accelerator holds each placement as a `Prim::Instance` with its
//! world bounds, so the scene's tree is the top level of a two-level BVH: a ray that
//! reaches a placement is carried into the mesh's space by the inverse transform (its
//! direction not renormalised, so distances along it stay the same) and traced there.

use glam::{Affine3A, Mat3A, Vec3A};

/// One placement of a shared mesh.
#[derive(Clone, Debug)]
pub struct Instance {
    /// Which of the accelerator's meshes.
    pub mesh: u32,
    pub to_world: Affine3A,
    pub(super) to_local: Affine3A,
    /// Takes a local geometric normal to the world one, keeping the winding's side (the
    /// inverse transpose, negated by a mirroring transform), before normalisation.
    pub(super) normal_to_world: Mat3A,
}

impl Instance {
    /// A placement of mesh `mesh` by `to_world`; None when the transform is not
    /// invertible (or not finite).
    pub fn new(mesh: u32, to_world: Affine3A) -> Option<Instance> {
        let det = to_world.matrix3.determinant();
        if !(det.is_finite() && det.abs() > 1e-30 && to_world.translation.is_finite()) {
            return None;
        }
        let to_local = to_world.inverse();
        Some(Instance {
            mesh,
            to_world,
            to_local,
            normal_to_world: to_local.matrix3.transpose() * det.signum(),
        })
    }

    /// The world box of the local box `lo..hi` (its eight corners placed).
    pub fn world_bounds(&self, lo: Vec3A, hi: Vec3A) -> (Vec3A, Vec3A) {
        let (mut a, mut b) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        for k in 0..8 {
            let corner = Vec3A::select(
                glam::BVec3A::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
                hi,
                lo,
            );
            let p = self.to_world.transform_point3a(corner);
            a = a.min(p);
            b = b.max(p);
        }
        (a, b)
    }
}
