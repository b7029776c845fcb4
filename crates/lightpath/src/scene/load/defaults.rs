//! What a scene file without a camera or a light gets (an OBJ, a PLY, a glTF without
//! them): a camera framing the scene and a white dome, each with a warning; and the
//! warning for a scene that has no light at all. Shared by every loader.

use crate::camera::FovAxis;
use crate::scene::desc::{CameraDesc, LightDesc, LightKind, Origin, SceneDesc, ShapeDesc};
use glam::{Affine3A, Vec3A};

/// The default camera's field of view along the image's smaller axis, in degrees.
pub const FRAMING_FOV: f32 = 40.0;

/// The world-space bounds of the scene's objects and area lights, if it has any.
pub fn bounds(desc: &SceneDesc) -> Option<(Vec3A, Vec3A)> {
    let mut lo = Vec3A::splat(f32::INFINITY);
    let mut hi = Vec3A::splat(f32::NEG_INFINITY);
    let mut add = |p: Vec3A| {
        if p.is_finite() {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    };
    let square = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    let shape = |s: &ShapeDesc, xf: &Affine3A, add: &mut dyn FnMut(Vec3A)| match s {
        ShapeDesc::Rectangle | ShapeDesc::Disk { .. } => square
            .iter()
            .for_each(|&c| add(xf.transform_point3a(c.into()))),
        ShapeDesc::Cube => {
            for i in 0..8 {
                let c = [i & 1, (i >> 1) & 1, (i >> 2) & 1].map(|b| b as f32 * 2.0 - 1.0);
                add(xf.transform_point3a(c.into()));
            }
        }
        ShapeDesc::Quad { corners } => corners.iter().for_each(|&c| add(c.into())),
        ShapeDesc::Sphere { center, radius } => {
            let c = xf.transform_point3a((*center).into());
            add(c - Vec3A::splat(*radius));
            add(c + Vec3A::splat(*radius));
        }
        ShapeDesc::Mesh { .. } | ShapeDesc::SharedMesh { .. } => s
            .mesh_parts()
            .unwrap_or_default()
            .iter()
            .flat_map(|p| &p.positions)
            .for_each(|&p| add(xf.transform_point3a(p.into()))),
    };
    for o in &desc.objects {
        shape(&o.shape, &o.transform, &mut add);
    }
    for l in &desc.lights {
        let xf = &l.transform;
        let s = match &l.kind {
            LightKind::Rectangle => ShapeDesc::Rectangle,
            LightKind::Disk { segments } => ShapeDesc::Disk {
                segments: *segments,
            },
            LightKind::Quad { corners } => ShapeDesc::Quad { corners: *corners },
            LightKind::Sphere { center, radius } => ShapeDesc::Sphere {
                center: *center,
                radius: *radius,
            },
            _ => continue,
        };
        shape(&s, xf, &mut add);
    }
    lo.x.is_finite().then_some((lo, hi))
}

/// A camera looking along −Z (+Y up) at the centre of the scene's bounds, from far enough
/// that their bounding sphere fits the field of view ([`FRAMING_FOV`] along the smaller
/// axis).
pub fn framing_camera(desc: &SceneDesc) -> CameraDesc {
    let origin = Origin::file(&desc.source);
    let Some((lo, hi)) = bounds(desc) else {
        return CameraDesc {
            origin,
            ..CameraDesc::default()
        };
    };
    let center = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-3);
    let distance = radius / (0.5 * FRAMING_FOV.to_radians()).sin();
    CameraDesc {
        position: (center + Vec3A::Z * distance).into(),
        look_at: center.into(),
        up: [0.0, 1.0, 0.0],
        fov: FRAMING_FOV,
        fov_axis: FovAxis::Smaller,
        aperture_radius: 0.0,
        focus_distance: None,
        origin,
    }
}

/// A white dome of radiance 1 (light group `dome`).
pub fn dome(source: &str) -> LightDesc {
    LightDesc {
        kind: LightKind::Dome {
            map: None,
            portals: Vec::new(),
        },
        name: Some("dome".into()),
        groups: vec!["dome".into()],
        color: [1.0; 3],
        strength: 1.0,
        camera_visible: true,
        casts_shadows: true,
        shaping: None,
        two_sided: false,
        material: None,
        transform: Affine3A::IDENTITY,
        include: None,
        exclude: Vec::new(),
        shadow_include: None,
        shadow_exclude: Vec::new(),
        origin: Origin::file(source),
    }
}

/// Whether anything in the scene emits light: a light, or a glowing surface.
pub fn has_light(desc: &SceneDesc) -> bool {
    !desc.lights.is_empty() || desc.objects.iter().any(|o| o.emission.is_some())
}

/// For a scene file that cannot say where to look or what lights it (OBJ, PLY, a glTF
/// without camera or lights): adds the framing camera if it has no camera and a white
/// dome if nothing emits light, each with a warning in `desc.warnings`.
pub fn complete(desc: &mut SceneDesc) {
    if desc.camera.is_none() {
        let c = framing_camera(desc);
        desc.warnings.push(format!(
            "{}: no camera; using one at {:?} looking at {:?} (fov {}°) that frames the scene",
            desc.source, c.position, c.look_at, c.fov
        ));
        desc.camera = Some(c);
    }
    if !has_light(desc) {
        desc.warnings.push(format!(
            "{}: no light; added a white dome of radiance 1 (light group 'dome')",
            desc.source
        ));
        desc.lights.push(dome(&desc.source));
    }
}

/// The warning for a scene in which nothing emits light (it renders black).
pub fn no_light_warning(desc: &SceneDesc) -> Option<String> {
    (!has_light(desc)).then(|| {
        format!(
            "{}: the scene has no light and no glowing surface: it renders black",
            desc.source
        )
    })
}

/// A mesh light over the triangles of `objects[object]`, as loaders make one for an
/// emissive material: two-sided, as Blender and Cycles render emission, and its light
/// group is the object's name (RenderMan's mesh lights, docs/lpe.md#paths-and-events).
pub fn mesh_light(object: usize, name: &str, radiance: [f32; 3], origin: Origin) -> LightDesc {
    LightDesc {
        kind: LightKind::Mesh { object },
        name: Some(name.to_string()),
        groups: vec![name.to_string()],
        color: radiance,
        strength: 1.0,
        camera_visible: true,
        casts_shadows: true,
        shaping: None,
        two_sided: true,
        material: None,
        transform: Affine3A::IDENTITY,
        include: None,
        exclude: Vec::new(),
        shadow_include: None,
        shadow_exclude: Vec::new(),
        origin,
    }
}
