//! The acceleration structure: an 8-wide compressed BVH from `obvhs` over our primitives,
//! reordered so that leaf indices address the primitive array directly.

use super::{Hit, Prim, Ray};
use glam::{UVec2, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::Ray as BvhRay;
use obvhs::{Boundable, BvhBuildParams};

struct Bounded(Aabb);

impl Boundable for Bounded {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

pub struct Accel {
    bvh: CwBvh,
    prims: Vec<Prim>,
    /// Object id of each primitive, in the same order.
    objects: Vec<u32>,
    /// Per-vertex shading normals of triangles that have them, three per entry.
    normals: Vec<[Vec3A; 3]>,
    /// Which kinds of ray see each primitive (`Visibility` bits), in the same order.
    visibility: Vec<u8>,
    /// Unit geometric normal of each triangle (unused for spheres), in the same order.
    face_normals: Vec<Vec3A>,
    empty: bool,
}

/// Ray kinds, as bits: an object can be hidden from each (trace sets).
pub struct Visibility;

impl Visibility {
    pub const CAMERA: u8 = 1;
    pub const INDIRECT: u8 = 2;
    pub const SHADOW: u8 = 4;
    pub const ALL: u8 = 7;
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
        if prims.is_empty() {
            let dummy = [Bounded(Aabb::new(Vec3A::ZERO, Vec3A::ZERO))];
            let bvh = build_cwbvh(
                &dummy,
                BvhBuildParams::fast_build(),
                &mut Default::default(),
            );
            return Accel {
                bvh,
                prims,
                objects,
                normals,
                visibility,
                face_normals: Vec::new(),
                empty: true,
            };
        }
        let boxes: Vec<Bounded> = prims
            .iter()
            .map(|p| {
                let (lo, hi) = p.bounds();
                Bounded(Aabb::new(lo, hi))
            })
            .collect();
        let mut bvh = build_cwbvh(
            &boxes,
            // Spatial pre-splits and more optimisation make a better tree (4.5 % fewer
            // instructions on cornell-classic); past a few hundred thousand primitives the
            // build time is not worth it.
            if boxes.len() < 200_000 {
                BvhBuildParams::slow_build()
            } else {
                BvhBuildParams::medium_build()
            },
            &mut Default::default(),
        );
        // Lay the primitives out in leaf order so traversal indexes them directly.
        let order = std::mem::take(&mut bvh.primitive_indices);
        let prims: Vec<Prim> = order.iter().map(|&i| prims[i as usize]).collect();
        let objects: Vec<u32> = order.iter().map(|&i| objects[i as usize]).collect();
        let visibility: Vec<u8> = order.iter().map(|&i| visibility[i as usize]).collect();
        bvh.primitive_indices = (0..order.len() as u32).collect();
        let face_normals = prims
            .iter()
            .map(|p| match p {
                Prim::Triangle { e1, e2, .. } => e1.cross(*e2).normalize_or(Vec3A::Z),
                Prim::Sphere { .. } => Vec3A::Z,
            })
            .collect();
        Accel {
            bvh,
            prims,
            objects,
            normals,
            visibility,
            face_normals,
            empty: false,
        }
    }

    pub fn prims(&self) -> &[Prim] {
        &self.prims
    }

    pub fn object_of(&self, prim: u32) -> u32 {
        self.objects[prim as usize]
    }

    /// The nearest hit along the ray among primitives visible to rays of kind `mask`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, mask: u8) -> Option<Hit> {
        if self.empty {
            return None;
        }
        // obvhs's traversal macro, so the primitive test inlines into the loop.
        let mut traverse_ray = BvhRay::new(ray.origin, ray.dir, tmin, ray.tmax);
        let mut state = self.bvh.new_traversal(ray.dir);
        let mut node;
        let mut best = u32::MAX;
        let bvh = &self.bvh;
        obvhs::traverse!(
            bvh,
            node,
            state,
            node.intersect_ray(&traverse_ray, state.oct_inv4),
            {
                let i = state.primitive_id as usize;
                if self.visibility[i] & mask != 0 {
                    let t = self.prims[i].intersect(
                        traverse_ray.origin,
                        traverse_ray.direction,
                        traverse_ray.tmin,
                        traverse_ray.tmax,
                    );
                    if t < traverse_ray.tmax {
                        best = i as u32;
                        traverse_ray.tmax = t;
                    }
                }
            }
        );
        (best != u32::MAX).then(|| self.surface(ray, best, traverse_ray.tmax))
    }

    /// Is anything that casts shadows between the origin and `tmax`, other than object
    /// `ignore` (the light the shadow ray aims at)?
    #[inline]
    pub fn occluded(&self, ray: &Ray, tmin: f32, ignore: u32) -> bool {
        if self.empty {
            return false;
        }
        let bray = BvhRay::new(ray.origin, ray.dir, tmin, ray.tmax);
        let mut state = self.bvh.new_traversal(ray.dir);
        let mut node;
        let mut hit = false;
        let bvh = &self.bvh;
        obvhs::traverse!(
            bvh,
            node,
            state,
            node.intersect_ray(&bray, state.oct_inv4),
            {
                let i = state.primitive_id as usize;
                if self.visibility[i] & Visibility::SHADOW != 0
                    && self.objects[i] != ignore
                    && self.prims[i]
                        .intersect(bray.origin, bray.direction, bray.tmin, bray.tmax)
                        .is_finite()
                {
                    hit = true;
                    break;
                }
            }
        );
        hit
    }

    fn surface(&self, ray: &Ray, prim: u32, t: f32) -> Hit {
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
            Prim::Sphere { center, radius } => {
                let n = (p - center) / radius;
                (n, n)
            }
        };
        Hit {
            t,
            p,
            ng,
            ns,
            prim,
            object: self.objects[prim as usize],
        }
    }
}
