//! Textured materials at a hit: the UVs, the footprint that picks mip levels, the
//! BSDF with textured values and the normal-mapped shading normal. Untextured
//! materials never come here, so scenes without textures pay one branch per vertex.
//!
//! The footprint is a ray cone (Akenine-Möller et al., "Texture Level of Detail
//! Strategies for Real-Time Ray Tracing", 2019): it starts at the camera with a
//! pixel's spread angle, widens by `spread · t` along each segment, and keeps its spread
//! through delta (mirror, glass) bounces; any other bounce widens the spread to at
//! least [`SCATTERED_SPREAD`], since what it scatters blurs the texture anyway. At a
//! hit the width becomes UV units through the triangle's UV-to-world ratio, stretched
//! by 1/√|cos θ| (the mean of the footprint ellipse's axes).

use super::Tracer;
use crate::geometry::Hit;
use crate::material::textured::Textured;
use crate::material::Bsdf;
use crate::scene::Object;
use glam::{Vec2, Vec3A};

/// The least spread (radians) of a ray cone after a non-delta bounce.
pub(super) const SCATTERED_SPREAD: f32 = 0.05;

/// Footprint in UV units of a mesh without UVs: the whole texture, so it reads the
/// texture's average.
const NO_UV_WIDTH: f32 = 1.0;

impl Tracer<'_> {
    /// A textured material's BSDF and shading normal at `hit`, reached along `dir` by a
    /// ray cone `cone_width` wide there.
    pub(super) fn textured(
        &self,
        t: &Textured,
        hit: &Hit,
        dir: Vec3A,
        cone_width: f32,
    ) -> (Bsdf, Vec3A) {
        let scene = self.scene;
        let point = scene.surface.at(&scene.accel, hit);
        let color = point.map_or(Vec3A::ONE, |p| p.color);
        let Some(s) = point.and_then(|p| p.uv) else {
            return (t.bsdf(Vec2::ZERO, NO_UV_WIDTH, color), hit.ns);
        };
        let width = uv_width(cone_width, s.uv_per_world, dir, hit.ng);
        let mut ns = t.shading_normal(hit.ns, &s, width);
        // A mapped normal turned away from the geometric side would shade nothing.
        if ns.dot(hit.ng) <= 0.0 {
            ns = hit.ns;
        }
        (t.bsdf(s.uv, width, color), ns)
    }

    /// The factor an emissive texture puts on a glowing object's emission at `hit`.
    pub(super) fn glow_texture(
        &self,
        obj: &Object,
        hit: &Hit,
        dir: Vec3A,
        cone_width: f32,
    ) -> Vec3A {
        let scene = self.scene;
        let Some(t) = obj
            .material
            .and_then(|m| scene.materials[m as usize].textured.as_deref())
        else {
            return Vec3A::ONE;
        };
        match scene.surface.at(&scene.accel, hit).and_then(|p| p.uv) {
            Some(s) => t.emission(s.uv, uv_width(cone_width, s.uv_per_world, dir, hit.ng)),
            None => t.emission(Vec2::ZERO, NO_UV_WIDTH),
        }
    }
}

/// A ray cone's width at a hit, in UV units.
fn uv_width(cone_width: f32, uv_per_world: f32, dir: Vec3A, ng: Vec3A) -> f32 {
    let cos = dir.dot(ng).abs().max(1e-3);
    cone_width * uv_per_world / cos.sqrt()
}

impl Tracer<'_> {
    /// Whether `ray` goes on through `hit` without an event: the surface's material is
    /// only partly there (`material/presence.rs`) and this ray is one that misses it.
    /// Inlined, so that scenes without presence pay one test per hit, not a call.
    #[inline]
    pub(super) fn see_through(&self, hit: &Hit, ray: &crate::geometry::Ray) -> bool {
        self.scene.has_presence && self.see_through_presence(hit, ray)
    }

    fn see_through_presence(&self, hit: &Hit, ray: &crate::geometry::Ray) -> bool {
        let scene = self.scene;
        let Some(presence) = scene.objects[hit.object as usize]
            .material
            .and_then(|m| scene.materials[m as usize].presence.as_deref())
        else {
            return false;
        };
        let uv = if presence.texture.is_some() {
            scene
                .surface
                .at(&scene.accel, hit)
                .and_then(|p| p.uv)
                .map(|s| s.uv)
        } else {
            None
        };
        crate::material::presence::passes_through(presence.at(uv), ray, hit)
    }

    /// Whether the shadow ray `ray` (up to `ray.tmax`) towards `light` (index `li`) is blocked, the
    /// light's own object passed: past surfaces that are not there for it (presence) and
    /// objects that cast no shadow from it (shadow linking), if any.
    #[inline(always)]
    pub(super) fn occluded(
        &self,
        out: &mut super::Sink,
        ray: &crate::geometry::Ray,
        light: &crate::light::Light,
        li: u32,
    ) -> bool {
        let scene = self.scene;
        let ignore = light.shadow_exempt();
        if !scene.has_presence && !light.shadow_linked {
            return scene.accel.occluded(ray, 0.0, ignore);
        }
        self.occluded_past_presence(out, ray, ignore, li)
    }

    fn occluded_past_presence(
        &self,
        out: &mut super::Sink,
        ray: &crate::geometry::Ray,
        ignore: u32,
        li: u32,
    ) -> bool {
        let scene = self.scene;
        let mut ray = *ray;
        let mut tmin = 0.0;
        for _ in 0..super::volume::MAX_CROSSINGS {
            let Some(hit) = scene
                .accel
                .intersect(&ray, tmin, crate::geometry::Visibility::SHADOW)
            else {
                return false;
            };
            if hit.object != ignore
                && !self.unshadowing(hit.object, li)
                && !self.see_through(&hit, &ray)
            {
                return true;
            }
            out.rays += 1;
            ray.origin = hit.p;
            ray.tmax -= hit.t;
            tmin = scene.epsilon;
            if ray.tmax <= tmin {
                return false;
            }
        }
        true
    }

    /// `sh` with its first axis along the direction `material`'s anisotropy follows at
    /// `hit`: the mesh's tangent turned as it says (unchanged without one, or without UVs).
    /// Inlined, so that isotropic materials pay one test per vertex, not a call that
    /// copies the frame in and out.
    #[inline(always)]
    pub(super) fn oriented(
        &self,
        sh: crate::material::Shading,
        material: &crate::scene::Material,
        hit: &Hit,
    ) -> crate::material::Shading {
        match material.anisotropy.as_deref() {
            Some(d) => self.oriented_along(sh, d, hit),
            None => sh,
        }
    }

    fn oriented_along(
        &self,
        sh: crate::material::Shading,
        d: &crate::material::anisotropy::AnisotropyDirection,
        hit: &Hit,
    ) -> crate::material::Shading {
        let scene = self.scene;
        let Some(s) = scene.surface.at(&scene.accel, hit).and_then(|p| p.uv) else {
            return sh;
        };
        let Some((t, b)) = s.tangent_frame(sh.frame.n) else {
            return sh;
        };
        let (c, sn) = d.at(Some(s.uv));
        sh.along(t * c + b * sn)
    }

    /// The first surface along the scattered `ray` that is there for it, from `hit`, the
    /// first one found: past those it passes (presence) as the path itself does, so the
    /// lights-only test sees what the real ray reaches.
    pub(super) fn present_hit(&self, ray: &crate::geometry::Ray, hit: Option<&Hit>) -> Option<Hit> {
        let scene = self.scene;
        let mut hit = *hit?;
        if !scene.has_presence {
            return Some(hit);
        }
        let mut ray = *ray;
        for _ in 0..super::volume::MAX_CROSSINGS {
            if !self.see_through(&hit, &ray) {
                return Some(hit);
            }
            ray.origin = hit.p;
            hit = scene.accel.intersect(
                &ray,
                scene.epsilon,
                crate::geometry::Visibility::INDIRECT,
            )?;
        }
        None
    }
}
