//! A mesh light: the triangles of an object emit (`type = "mesh"`, `object = "name"`),
//! sampled by area like any triangle light. Unlike a rectangle's, its triangles may
//! shadow one another, so shadow rays towards it do not pass through its object, and
//! the lights-only test finds them in the scene's mesh-light BVH (`Scene::mesh_lights`)
//! rather than one by one. Glowing objects sampled as lights are mesh lights too.
//!
//! ```toml
//! [[lights]]
//! type = "mesh"
//! object = "lamp"
//! radiance = [5, 5, 5]
//! ```

use super::select::Reach;
use super::{LightModel, LightSample, Triangles};
use crate::geometry::Prim;
use glam::{Vec2, Vec3A};

#[derive(Clone, Debug)]
pub struct Mesh(pub Triangles);

impl LightModel for Mesh {
    fn sample(
        &self,
        color: Vec3A,
        p: Vec3A,
        n: Vec3A,
        u: Vec2,
        prims: &[Prim],
    ) -> Option<LightSample> {
        self.0.sample(color, p, n, u, prims)
    }
    fn pdf(&self, p: Vec3A, n: Vec3A, dir: Vec3A, t: f32, ng: Vec3A) -> f32 {
        self.0.pdf(p, n, dir, t, ng)
    }
    fn emitted(&self, color: Vec3A, ng: Vec3A, dir: Vec3A) -> Vec3A {
        self.0.emitted(color, ng, dir)
    }
    fn power(&self, c: f32, scene_radius: f32) -> f32 {
        self.0.power(c, scene_radius)
    }
    fn reach(&self, c: f32, prims: &[Prim]) -> Reach {
        self.0.reach(c, prims)
    }
    fn shadows_itself(&self) -> bool {
        true
    }
}
