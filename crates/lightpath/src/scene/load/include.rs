//! Scene files included in a TOML scene (`[[include]]`, docs/scene-format.md): any
//! loader's `SceneDesc` merged into the scene, placed by the include's transform, with
//! its objects overridden by name.

use crate::scene::desc::{LightDesc, LightKind, NameRef, ObjectDesc, Origin, SceneDesc, ShapeDesc};
use crate::scene::SceneError;
use glam::{Affine3A, Vec3A};

/// What an include changes on the imported objects of one name.
#[derive(Clone, Debug, Default)]
pub struct Override {
    pub name: String,
    pub material: Option<NameRef>,
    pub lpegroups: Option<Vec<String>>,
    pub visible_camera: Option<bool>,
    pub visible_indirect: Option<bool>,
    pub casts_shadows: Option<bool>,
    pub holdout: Option<bool>,
    /// `false`: an emissive object glows (`O`) instead of being a mesh light; `true`: the
    /// reverse.
    pub light: Option<bool>,
    pub origin: Origin,
}

/// Merges `from` (a whole file's scene) into `into`: its objects and lights placed by
/// `placement`, its materials under names that do not clash, its camera if `into` has
/// none, then `overrides` applied to its objects by name.
pub fn merge(
    into: &mut SceneDesc,
    mut from: SceneDesc,
    placement: Affine3A,
    overrides: &[Override],
) -> Result<(), SceneError> {
    // Materials: an imported name already taken by another file is suffixed with the
    // importing file's name; the same file included twice shares its materials.
    let mut renames = std::collections::HashMap::new();
    let file_name = std::path::Path::new(&from.source)
        .file_name()
        .map_or_else(|| from.source.clone(), |f| f.to_string_lossy().into_owned());
    for (name, m) in std::mem::take(&mut from.materials) {
        let mut key = name.clone();
        let mut k = 1;
        while let Some(existing) = into.materials.get(&key) {
            if existing.origin.file == m.origin.file {
                break;
            }
            k += 1;
            key = match k {
                2 => format!("{name} ({file_name})"),
                _ => format!("{name} ({file_name} {k})"),
            };
        }
        into.materials.entry(key.clone()).or_insert(m);
        renames.insert(name, key);
    }
    let rename = |r: &mut Option<NameRef>| {
        if let Some(r) = r {
            if let Some(k) = renames.get(&r.name) {
                r.name = k.clone();
            }
        }
    };
    let base = into.objects.len();
    for mut o in from.objects {
        rename(&mut o.material);
        place_object(&mut o, &placement);
        into.objects.push(o);
    }
    // Media keep their names unless this file already has one (its own wins), and
    // interiors follow their objects.
    for (name, m) in std::mem::take(&mut from.media.media) {
        into.media.media.entry(name).or_insert(m);
    }
    for mut i in std::mem::take(&mut from.media.interiors) {
        i.object += base;
        into.media.interiors.push(i);
    }
    let first_light = into.lights.len();
    for mut l in from.lights {
        rename(&mut l.material);
        if let LightKind::Mesh { object } = &mut l.kind {
            *object += base;
        }
        place_light(&mut l, &placement);
        into.lights.push(l);
    }
    if into.camera.is_none() {
        into.camera = from.camera.map(|mut c| {
            let p = |v: [f32; 3]| placement.transform_point3a(v.into()).into();
            c.position = p(c.position);
            c.look_at = p(c.look_at);
            c.up = placement.transform_vector3a(c.up.into()).into();
            c
        });
    }
    into.warnings.extend(from.warnings);
    for ov in overrides {
        apply(into, base, first_light, ov, &from.source)?;
    }
    Ok(())
}

fn place_object(o: &mut ObjectDesc, xf: &Affine3A) {
    o.transform = *xf * o.transform;
    if let ShapeDesc::Quad { corners } = &mut o.shape {
        *corners = corners.map(|c| xf.transform_point3a(c.into()).into());
    }
}

fn place_light(l: &mut LightDesc, xf: &Affine3A) {
    let point = |p: &mut [f32; 3]| *p = xf.transform_point3a(Vec3A::from(*p)).into();
    let vector = |v: &mut [f32; 3]| *v = xf.transform_vector3a(Vec3A::from(*v)).into();
    match &mut l.kind {
        // Mesh lights are their object's triangles, already placed.
        LightKind::Mesh { .. } => return,
        LightKind::Quad { corners } => corners.iter_mut().for_each(point),
        LightKind::Point { position } => point(position),
        LightKind::Spot {
            position,
            direction,
            ..
        } => {
            point(position);
            vector(direction);
        }
        LightKind::Distant { direction, .. } => vector(direction),
        LightKind::Rectangle
        | LightKind::Disk { .. }
        | LightKind::Sphere { .. }
        | LightKind::Cylinder { .. } => {}
        LightKind::Dome { portals, .. } => portals.iter_mut().flatten().for_each(point),
    }
    l.transform = *xf * l.transform;
}

/// Applies one override to the objects of its name among those from `base` on.
fn apply(
    desc: &mut SceneDesc,
    base: usize,
    first_light: usize,
    ov: &Override,
    file: &str,
) -> Result<(), SceneError> {
    let matching: Vec<usize> = (base..desc.objects.len())
        .filter(|&i| desc.objects[i].name.as_deref() == Some(ov.name.as_str()))
        .collect();
    if matching.is_empty() {
        let mut names: Vec<&str> = desc.objects[base..]
            .iter()
            .filter_map(|o| o.name.as_deref())
            .collect();
        names.sort();
        names.dedup();
        return Err(ov.origin.error(format!(
            "{file} has no object named '{}'; its objects are {names:?}",
            ov.name
        )));
    }
    for &i in &matching {
        let o = &mut desc.objects[i];
        if let Some(m) = &ov.material {
            o.material = Some(m.clone());
        }
        if let Some(g) = &ov.lpegroups {
            o.lpegroups = Some(g.clone());
        }
        let set = |field: &mut bool, v: Option<bool>| {
            if let Some(v) = v {
                *field = v;
            }
        };
        set(&mut o.visible_camera, ov.visible_camera);
        set(&mut o.visible_indirect, ov.visible_indirect);
        set(&mut o.casts_shadows, ov.casts_shadows);
        set(&mut o.holdout, ov.holdout);
        let light = desc.lights[first_light..]
            .iter()
            .position(|l| matches!(l.kind, LightKind::Mesh { object } if object == i))
            .map(|k| k + first_light);
        match (ov.light, light) {
            (Some(false), Some(k)) => {
                // The same radiance, seen as an `O` event and never sampled.
                let l = desc.lights.remove(k);
                desc.objects[i].emission = Some(l.color.map(|c| c * l.strength));
            }
            (Some(true), None) => {
                let o = &mut desc.objects[i];
                let Some(radiance) = o.emission.take() else {
                    return Err(ov.origin.error(format!(
                        "object '{}' of {file} emits no light: 'light = true' needs an emissive object",
                        ov.name
                    )));
                };
                let at = ov.origin.clone();
                desc.lights
                    .push(super::defaults::mesh_light(i, &ov.name, radiance, at));
            }
            _ => {}
        }
    }
    Ok(())
}
