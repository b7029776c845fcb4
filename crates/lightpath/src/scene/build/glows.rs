//! Glowing surfaces (objects with `emission`, not lights) sampled as lights. A glow stays
//! what docs/lpe.md says it is, emission seen as `O` with its object's labels, in the default
//! light-group part; but it joins light selection, so that a small glowing object is not
//! found by BSDF rays alone (a firefly each time one finds it), and both ways of reaching
//! it are weighed by MIS. The integrator routes a light sample of a glow with the glow's
//! `O` event, like a ray that hits it (`Light::glow`).
//!
//! A glow is sampled when its object is one sphere or made of triangles, its emission is
//! finite, not black and not textured (a light's radiance is the same all over), and
//! indirect rays see it (light sampling must not find what a BSDF ray could not). Others
//! (instances of a shared mesh, emissive textures, holdouts, infinite emission for the
//! `noinfinitecheck` prefix, objects hidden from indirect rays) glow as before: found by
//! rays only.

use crate::geometry::{Accel, Prim};
use crate::light::spherical_rect::Rect;
use crate::light::{Light, LightShape, Mesh, Sphere, Triangles};
use crate::sampling::Distribution1D;
use crate::scene::desc::ObjectDesc;
use crate::scene::{Material, Object};
use std::ops::Range;

/// Appends a light for each glowing object of `descs` that can be sampled (`ranges`:
/// where `GeometryBuilder::add` put each object's primitives) and records it in the
/// object's `glow_light`. Call after every declared light is in `lights`.
pub fn add(
    lights: &mut Vec<Light>,
    objects: &mut [Object],
    materials: &[Material],
    descs: &[ObjectDesc],
    ranges: &[Range<u32>],
    accel: &Accel,
) {
    for (id, (desc, range)) in descs.iter().zip(ranges).enumerate() {
        let obj = &objects[id];
        let e = obj.emission;
        // A light sample's radiance is the light's colour: the same all over.
        let textured = obj.material.is_some_and(|m| {
            materials[m as usize]
                .textured
                .as_ref()
                .is_some_and(|t| t.textures.emissive.is_some())
        });
        // A holdout's glow reaches only `holdouts` AOVs, through the path that hits it.
        if obj.light.is_some()
            || obj.holdout
            || textured
            || !desc.visible_indirect
            || !e.is_finite()
            || e.max_element() <= 0.0
        {
            continue;
        }
        let Some(shape) = shape(range, accel) else {
            continue;
        };
        objects[id].glow_light = Some(lights.len() as u32);
        lights.push(Light {
            object: Some(id as u32),
            glow: true,
            ..Light::new(shape, e)
        });
    }
}

/// The light shape of an object's primitives: one sphere, or triangles (two-sided, as a
/// glow emits on both sides, and shadowing one another like a mesh light's).
fn shape(range: &Range<u32>, accel: &Accel) -> Option<LightShape> {
    let prims = accel.prims();
    let mut slots: Vec<u32> = range.clone().map(|i| accel.slot(i)).collect();
    if let [slot] = slots[..] {
        if let Prim::Sphere { center, radius } = prims[slot as usize] {
            return Some(Sphere { center, radius }.into());
        }
    }
    slots.sort_unstable();
    let mut areas = Vec::with_capacity(slots.len());
    let mut normals = Vec::with_capacity(slots.len());
    for &s in &slots {
        let p = &prims[s as usize];
        if !matches!(p, Prim::Triangle { .. }) {
            return None;
        }
        areas.push(p.area());
        normals.push(p.face_normal());
    }
    let area: f32 = areas.iter().sum();
    // A glowing rectangle (two triangles) is sampled in solid angle, as a rect light.
    let parallelogram = super::lights::either_order(&slots, prims);
    (area > 0.0 && area.is_finite()).then(|| {
        Mesh(Triangles {
            prims: slots,
            normals,
            parallelogram,
            rect: parallelogram.and_then(|[p0, e1, e2]| Rect::new(p0, e1, e2)),
            by_area: Distribution1D::new(&areas),
            area,
            two_sided: true,
            shaping: None,
        })
        .into()
    })
}
