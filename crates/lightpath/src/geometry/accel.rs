//! The accelerator's interface: [`Accel`] holds the scene's primitives (laid out in
//! the BVH's leaf order), answers `intersect` and `occluded` through the BVH (`bvh`) or
//! through Embree (`embree`, feature `embree`), and computes the surface at a hit the
//! same way for both. `bvh` and `embree` each depend on this module only, not on each
//! other.

use super::bvh::{Trees, Width};
#[cfg(feature = "embree")]
use super::embree::EmbreeScene;
use super::{Hit, Instance, Prim, Ray};
use crate::error::AccelError;
use glam::Vec3A;

/// Ray kinds, as bits: an object can be hidden from each (trace sets).
pub struct Visibility;

impl Visibility {
    pub const CAMERA: u8 = 1;
    pub const INDIRECT: u8 = 2;
    pub const SHADOW: u8 = 4;
    pub const ALL: u8 = 7;
}

/// The scene's primitives and what traces rays through them: the BVH (`bvh`), or
/// Embree once `use_embree` was called (`embree`).
pub struct Accel {
    pub(super) tree: Trees,
    pub(super) prims: Vec<Prim>,
    /// Object id of each primitive, in the same order.
    pub(super) objects: Vec<u32>,
    /// Per-vertex shading normals of triangles that have them, three per entry.
    pub(super) normals: Vec<[Vec3A; 3]>,
    /// Unit geometric normal of each triangle (unused for spheres), in the same order.
    pub(super) face_normals: Vec<Vec3A>,
    /// Where each primitive, by its index as given to `build`, sits in `prims`.
    pub(super) slots: Vec<u32>,
    /// Shared meshes, each in its own space, and their placements (`Prim::Instance`).
    pub(super) meshes: Vec<Accel>,
    pub(super) instances: Vec<Instance>,
    /// Which ray kinds see each primitive, in the same order (for building Embree's scene).
    #[cfg(feature = "embree")]
    pub(super) visibility: Vec<u8>,
    /// See [`Accel::shadows_match_indirect`] (instances included).
    shadows_match_indirect: bool,
    /// See [`Accel::shadows_match_camera`] (instances included).
    shadows_match_camera: bool,
    /// When set (`use_embree`), `intersect` and `occluded` ask Embree instead of the tree.
    #[cfg(feature = "embree")]
    embree: Option<Box<EmbreeScene>>,
}

impl Accel {
    /// Builds the BVH. `prims[i]` belongs to object `objects[i]`.
    /// `visibility[i]` says which ray kinds see it.
    pub fn build(
        prims: Vec<Prim>,
        objects: Vec<u32>,
        normals: Vec<[Vec3A; 3]>,
        visibility: Vec<u8>,
    ) -> Accel {
        Accel::build_with(prims, objects, normals, visibility, Width::detect())
    }

    /// [`build`](Self::build) at a given lane width (eight falls back to four on CPUs
    /// without AVX2).
    pub fn build_with(
        prims: Vec<Prim>,
        objects: Vec<u32>,
        normals: Vec<[Vec3A; 3]>,
        visibility: Vec<u8>,
        width: Width,
    ) -> Accel {
        let laid = super::bvh::lay_out(&prims, &visibility, width);
        let mut slots = vec![0; laid.order.len()];
        for (slot, &i) in laid.order.iter().enumerate() {
            slots[i as usize] = slot as u32;
        }
        let shadows_match_indirect = visibility
            .iter()
            .all(|&v| (v & Visibility::INDIRECT != 0) == (v & Visibility::SHADOW != 0));
        let shadows_match_camera = visibility
            .iter()
            .all(|&v| (v & Visibility::CAMERA != 0) == (v & Visibility::SHADOW != 0));
        Accel {
            shadows_match_indirect,
            shadows_match_camera,
            tree: laid.tree,
            objects: laid.order.iter().map(|&i| objects[i as usize]).collect(),
            face_normals: laid.prims.iter().map(Prim::face_normal).collect(),
            prims: laid.prims,
            normals,
            slots,
            meshes: Vec::new(),
            instances: Vec::new(),
            #[cfg(feature = "embree")]
            visibility: laid.visibility,
            #[cfg(feature = "embree")]
            embree: None,
        }
    }

    pub fn prims(&self) -> &[Prim] {
        &self.prims
    }

    /// Whether every primitive that indirect rays see casts shadows and the other way
    /// round: then a shadow ray is blocked exactly where an indirect ray stops.
    pub fn shadows_match_indirect(&self) -> bool {
        self.shadows_match_indirect
    }

    /// Whether every primitive that camera rays see casts shadows and the other way
    /// round: then a shadow ray towards the camera is blocked exactly where a camera ray
    /// from there would stop (light tracing, connect.rs).
    pub fn shadows_match_camera(&self) -> bool {
        self.shadows_match_camera
    }

    /// Which ray kinds see each primitive of `prims()`.
    #[cfg(feature = "embree")]
    pub(super) fn visibility(&self) -> &[u8] {
        &self.visibility
    }

    /// From now on `intersect` and `occluded` ask Intel Embree (an Embree scene built
    /// over the same primitives, instances and visibility); hits are the BVH's up to
    /// float rounding, and the surface at a hit is computed as before. Errors when Embree
    /// cannot make a device or build the scene.
    #[cfg(feature = "embree")]
    pub fn use_embree(&mut self) -> Result<(), AccelError> {
        if !self.prims.is_empty() {
            let scene = EmbreeScene::build(self, &self.visibility, false)?;
            self.embree = Some(Box::new(scene));
        }
        Ok(())
    }

    /// Traces with `backend` from now on (`Bvh`: nothing to do; `Embree`: `use_embree`,
    /// or an error in a build without the `embree` feature).
    pub fn use_backend(&mut self, backend: super::Backend) -> Result<(), AccelError> {
        match backend {
            super::Backend::Bvh => Ok(()),
            #[cfg(feature = "embree")]
            super::Backend::Embree => self.use_embree(),
            #[cfg(not(feature = "embree"))]
            super::Backend::Embree => Err(AccelError::EmbreeUnavailable),
        }
    }

    /// Whether `use_embree` took effect.
    pub fn uses_embree(&self) -> bool {
        #[cfg(feature = "embree")]
        {
            self.embree.is_some()
        }
        #[cfg(not(feature = "embree"))]
        {
            false
        }
    }

    /// Gives the accelerator the meshes and placements its `Prim::Instance` primitives
    /// name (`index` into `instances`, each naming one of `meshes`). Meshes hold no
    /// instances themselves: the structure has two levels.
    pub fn with_instances(mut self, meshes: Vec<Accel>, instances: Vec<Instance>) -> Accel {
        debug_assert!(meshes.iter().all(|m| m.instances.is_empty()));
        self.shadows_match_indirect &= meshes.iter().all(|m| m.shadows_match_indirect);
        self.shadows_match_camera &= meshes.iter().all(|m| m.shadows_match_camera);
        self.meshes = meshes;
        self.instances = instances;
        self
    }

    /// The box around every primitive (inverted, min > max, when there are none).
    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        self.prims.iter().fold(
            (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| {
                let (a, b) = p.bounds();
                (lo.min(a), hi.max(b))
            },
        )
    }

    pub fn instances(&self) -> &[Instance] {
        &self.instances
    }

    pub fn meshes(&self) -> &[Accel] {
        &self.meshes
    }

    /// The index in `prims()` of the primitive given to `build` as number `original`.
    pub fn slot(&self, original: u32) -> u32 {
        self.slots[original as usize]
    }

    pub fn object_of(&self, prim: u32) -> u32 {
        self.objects[prim as usize]
    }

    /// The nearest hit along the ray among primitives visible to rays of kind `mask`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, mask: u8) -> Option<Hit> {
        self.intersect_except(ray, tmin, mask, u32::MAX)
    }

    /// As [`intersect`](Self::intersect), on anything but object `ignore` (`u32::MAX`:
    /// none): what lies on a surface just passed, other than that surface's object.
    /// Always inlined: as a call it was ~50 instructions a ray of its own (saving
    /// registers, the `Option<Hit>` returned through memory) on the indirect box.
    #[inline(always)]
    pub fn intersect_except(&self, ray: &Ray, tmin: f32, mask: u8, ignore: u32) -> Option<Hit> {
        if self.prims.is_empty() {
            return None;
        }
        #[cfg(feature = "embree")]
        if let Some(embree) = &self.embree {
            let (prim, t, inner) = embree.intersect(ray, tmin, mask, ignore)?;
            return Some(self.surface(ray, prim, t, inner));
        }
        let (prim, t, inner) = self.bvh_nearest(ray, tmin, mask, ignore);
        (prim != u32::MAX).then(|| self.surface(ray, prim, t, inner))
    }

    /// The lane width this accelerator's BVH was built with.
    pub fn width(&self) -> Width {
        self.tree.width()
    }

    /// Is anything that casts shadows between the origin and `tmax`, other than object
    /// `ignore` (the light the shadow ray aims at)?
    #[inline]
    pub fn occluded(&self, ray: &Ray, tmin: f32, ignore: u32) -> bool {
        if self.prims.is_empty() {
            return false;
        }
        #[cfg(feature = "embree")]
        if let Some(embree) = &self.embree {
            return embree.occluded(ray, tmin, ignore);
        }
        self.bvh_occluded(ray, tmin, ignore)
    }

    /// The ray in instance `index`'s space (same distances along it).
    #[inline]
    pub(super) fn local_ray(&self, index: u32, ray: &Ray, tmax: f32) -> (&Instance, Ray) {
        let inst = &self.instances[index as usize];
        let local = Ray {
            origin: inst.to_local.transform_point3a(ray.origin),
            dir: inst.to_local.transform_vector3a(ray.dir),
            tmax,
        };
        (inst, local)
    }

    pub(super) fn surface(&self, ray: &Ray, prim: u32, t: f32, inner: u32) -> Hit {
        if let Prim::Instance { index, .. } = self.prims[prim as usize] {
            return self.instance_surface(ray, prim, index, t, inner);
        }
        let p = ray.origin + ray.dir * t;
        let (ng, ns) = match self.prims[prim as usize] {
            Prim::Triangle {
                p0,
                e1,
                e2,
                normals,
            } => {
                let ng = self.face_normals[prim as usize];
                let ns = if normals == u32::MAX {
                    ng
                } else {
                    // Barycentrics of the hit point.
                    let d = p - p0;
                    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
                    let (d20, d21) = (d.dot(e1), d.dot(e2));
                    let denom = d00 * d11 - d01 * d01;
                    let v = (d11 * d20 - d01 * d21) / denom;
                    let w = (d00 * d21 - d01 * d20) / denom;
                    let [n0, n1, n2] = self.normals[normals as usize];
                    let n = (n0 * (1.0 - v - w) + n1 * v + n2 * w).normalize_or(ng);
                    if n.dot(ng) < 0.0 {
                        -n
                    } else {
                        n
                    }
                };
                (ng, ns)
            }
            curved @ (Prim::Sphere { .. } | Prim::Cylinder { .. }) => {
                let n = curved.curved_normal(p);
                (n, n)
            }
            Prim::Instance { .. } => unreachable!("instances are placed above"),
        };
        Hit {
            t,
            p,
            ng,
            ns,
            prim,
            inner: u32::MAX,
            object: self.objects[prim as usize],
        }
    }

    /// The hit on an instance: the mesh's own surface at the same distance, placed.
    #[inline(never)]
    fn instance_surface(&self, ray: &Ray, prim: u32, index: u32, t: f32, inner: u32) -> Hit {
        let (inst, local) = self.local_ray(index, ray, t);
        let mesh = &self.meshes[inst.mesh as usize];
        let h = mesh.surface(&local, inner, t, u32::MAX);
        let ng = (inst.normal_to_world * h.ng).normalize_or(Vec3A::Z);
        let ns = (inst.normal_to_world * h.ns).normalize_or(ng);
        Hit {
            t,
            p: ray.origin + ray.dir * t,
            ng,
            ns: if ns.dot(ng) < 0.0 { -ns } else { ns },
            prim,
            inner,
            object: self.objects[prim as usize],
        }
    }
}
