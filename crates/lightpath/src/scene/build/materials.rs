//! Materials: each description becomes a BSDF (a list of lobes) and a user colour.

use crate::material::{roughness_to_alpha, Bsdf};
use crate::scene::desc::{MaterialDesc, MaterialKind, NameRef, SceneDesc};
use crate::scene::{Material, SceneError};
use glam::Vec3A;
use std::collections::HashMap;

/// The scene's materials in name order, and each name's index.
pub fn build(desc: &SceneDesc) -> Result<(Vec<Material>, HashMap<String, u32>), SceneError> {
    let mut materials = Vec::new();
    let mut ids = HashMap::new();
    for (name, m) in &desc.materials {
        ids.insert(name.clone(), materials.len() as u32);
        let mut built = material(name, m)?;
        let roughness = desc.render.regularize;
        if roughness > m.roughness && !matches!(m.kind, MaterialKind::Diffuse { .. }) {
            let rough = MaterialDesc {
                roughness,
                ..m.clone()
            };
            let bsdf = material(name, &rough)?.bsdf;
            // Regularising changes how lobes scatter, never which events they emit.
            let same_events = bsdf.lobes().len() == built.bsdf.lobes().len()
                && bsdf
                    .lobes()
                    .iter()
                    .zip(built.bsdf.lobes())
                    .all(|(a, b)| (a.transmit, a.scatter) == (b.transmit, b.scatter));
            built.regularized = same_events.then_some(bsdf);
        }
        materials.push(built);
    }
    Ok((materials, ids))
}

/// A colour must be finite and not negative: a NaN albedo reached the `albedo` AOV and
/// every pixel that saw it.
pub fn check_color(c: [f32; 3], what: &str) -> Result<(), String> {
    if c.iter().all(|v| v.is_finite() && *v >= 0.0) {
        Ok(())
    } else {
        Err(format!(
            "{what} is {c:?}: expected finite, non-negative numbers"
        ))
    }
}

/// Resolves a material reference, pointing at it if the scene has no such material.
pub fn find(
    desc: &SceneDesc,
    ids: &HashMap<String, u32>,
    m: &Option<NameRef>,
) -> Result<Option<u32>, SceneError> {
    match m {
        None => Ok(None),
        Some(r) => ids.get(&r.name).copied().map(Some).ok_or_else(|| {
            let known: Vec<&String> = desc.materials.keys().collect();
            r.origin.error(format!(
                "unknown material '{}': the scene defines {known:?}",
                r.name
            ))
        }),
    }
}

fn material(name: &str, m: &MaterialDesc) -> Result<Material, SceneError> {
    let v3 = Vec3A::from;
    let mut colors = match &m.kind {
        MaterialKind::Diffuse { albedo } | MaterialKind::Plastic { albedo, .. } => {
            vec![("albedo", *albedo)]
        }
        MaterialKind::Translucent { reflect, transmit } => {
            vec![("reflect", *reflect), ("transmit", *transmit)]
        }
        MaterialKind::Conductor { f0 } => vec![("f0", *f0)],
        MaterialKind::Dielectric { tint, .. } => tint.map(|t| ("tint", t)).into_iter().collect(),
    };
    colors.extend(m.user_color.map(|c| ("user_color", c)));
    for (what, c) in colors {
        check_color(c, &format!("material '{name}': {what}")).map_err(|e| m.origin.error(e))?;
    }
    if !(m.roughness.is_finite() && m.roughness >= 0.0) {
        return Err(m.origin.error(format!(
            "material '{name}': roughness must be a number from 0 up, got {}",
            m.roughness
        )));
    }
    let alpha = roughness_to_alpha(m.roughness);
    let ior = |ior: Option<f32>| match ior.unwrap_or(1.5) {
        eta if eta > 0.0 && eta.is_finite() => Ok(eta),
        eta => Err(m.origin.error(format!(
            "material '{name}': ior must be positive, got {eta}"
        ))),
    };
    let bsdf = match &m.kind {
        MaterialKind::Diffuse { albedo } => Bsdf::diffuse(v3(*albedo)),
        MaterialKind::Translucent { reflect, transmit } => {
            Bsdf::translucent(v3(*reflect), v3(*transmit))
        }
        MaterialKind::Conductor { f0 } => Bsdf::conductor(v3(*f0), alpha),
        MaterialKind::Dielectric { ior: eta, tint } => {
            Bsdf::dielectric(ior(*eta)?, alpha, tint.map(v3).unwrap_or(Vec3A::ONE))
        }
        MaterialKind::Plastic { albedo, ior: eta } => Bsdf::plastic(v3(*albedo), ior(*eta)?, alpha),
    };
    Ok(Material {
        bsdf,
        regularized: None,
        user_color: m.user_color.map(v3),
    })
}
