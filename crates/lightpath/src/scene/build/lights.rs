//! Lights: shapes, colours, environment maps and light linking (the selection
//! probabilities are `light/select.rs`'s).

use crate::geometry::shapes::{self, ShapePrims};
use crate::geometry::{Accel, Prim};
use crate::light::portal::Portal;
use crate::light::spherical_rect::Rect;
use crate::light::triangles::Shaping;
use crate::light::{
    Cylinder, Distant, Dome, EnvMap, Light, LightModel, LightShape, Mesh, Point, Sphere, Spot,
    Triangles,
};
use crate::sampling::Distribution1D;
use crate::scene::desc::{LightDesc, LightKind, Origin};
use crate::scene::{Object, SceneError};
use glam::Vec3A;
use std::ops::Range;
use std::path::Path;

/// A light's shape and colour, and for area lights the primitives it adds to the scene.
pub fn light_shape(l: &LightDesc) -> Result<(LightShape, Option<ShapePrims>, Vec3A), SceneError> {
    let v3 = Vec3A::from;
    let xf = &l.transform;
    let color = v3(l.color) * l.strength;
    check_light_numbers(l)?;
    let area = |prims: ShapePrims| -> Result<_, SceneError> {
        super::geometry::check_finite(&prims, &l.origin)?;
        let areas: Vec<f32> = prims.prims.iter().map(Prim::area).collect();
        let normals = prims.prims.iter().map(Prim::face_normal).collect();
        let parallelogram = parallelogram(&prims.prims);
        let shape = Triangles {
            parallelogram,
            rect: parallelogram.and_then(|[p0, e1, e2]| Rect::new(p0, e1, e2)),
            // Filled once the primitives are in the scene (`locate_prims`).
            prims: Vec::new(),
            normals,
            by_area: Distribution1D::new(&areas),
            area: areas.iter().sum(),
            two_sided: l.two_sided,
            shaping: l.shaping.map(|s| {
                let cutoff = s.cone_angle.clamp(0.0, 180.0).to_radians();
                Shaping {
                    cutoff,
                    start: cutoff * (1.0 - s.cone_softness.clamp(0.0, 1.0)),
                    focus: s.focus.max(0.0),
                    tint: Vec3A::from(s.focus_tint).max(Vec3A::ZERO),
                }
            }),
        };
        Ok((shape.into(), Some(prims), color))
    };
    Ok(match &l.kind {
        LightKind::Rectangle => area(shapes::rectangle(xf))?,
        LightKind::Quad { corners } => area(shapes::quad(corners.map(v3)))?,
        LightKind::Disk { segments } => area(shapes::disk(
            xf,
            super::geometry::disk_segments(*segments, &l.origin)?,
        ))?,
        LightKind::Sphere { center, radius } => {
            let center = xf.transform_point3a(v3(*center));
            let radius = *radius;
            if !(radius > 0.0 && radius.is_finite()) {
                return Err(l.origin.error(format!(
                    "sphere light radius must be positive, got {radius}"
                )));
            }
            let prims = shapes::sphere(center, radius);
            super::geometry::check_finite(&prims, &l.origin)?;
            (Sphere { center, radius }.into(), Some(prims), color)
        }
        LightKind::Cylinder { radius, length } => {
            let cylinder = Cylinder::placed(*radius, *length, xf, &l.origin)?;
            let prims = cylinder.surface();
            (cylinder.into(), Some(prims), color)
        }
        LightKind::Point { position } => (
            Point {
                position: v3(*position),
            }
            .into(),
            None,
            color,
        ),
        LightKind::Spot {
            position,
            direction,
            cone_angle,
            cone_softness,
        } => {
            let half = cone_angle.to_radians() * 0.5;
            let soft = cone_softness.to_radians();
            let shape = Spot {
                position: v3(*position),
                axis: v3(*direction).normalize_or(-Vec3A::Y),
                cos_inner: (half - soft).max(0.0).cos(),
                cos_outer: half.cos(),
            };
            (shape.into(), None, color)
        }
        LightKind::Distant { direction, angle } => (
            Distant::new(v3(*direction).normalize_or(-Vec3A::Y), *angle).into(),
            None,
            color,
        ),
        // Its object's triangles, filled once they are in the scene (`mesh_surfaces`).
        LightKind::Mesh { .. } => {
            let shape = Mesh(Triangles {
                prims: Vec::new(),
                normals: Vec::new(),
                parallelogram: None,
                rect: None,
                by_area: Distribution1D::default(),
                area: 0.0,
                two_sided: l.two_sided,
                shaping: None,
            });
            (shape.into(), None, color)
        }
        LightKind::Dome { map, portals } => {
            let portals = dome_portals(portals, &l.origin)?;
            let map = match map {
                None => None,
                Some((path, origin)) => {
                    let map = load_env(path, origin)?;
                    match dome_rotation(xf, &l.origin)? {
                        None => Some(map),
                        Some(r) => Some(map.rotated(r)),
                    }
                }
            };
            (Dome { map, portals }.into(), None, color)
        }
    })
}

/// Every number of a light finite (colour × strength too, and not negative), and its
/// surface's primitives once placed: NaN or infinite geometry panicked the BVH builder.
fn check_light_numbers(l: &LightDesc) -> Result<(), SceneError> {
    let color = Vec3A::from(l.color) * l.strength;
    super::materials::check_color(color.into(), "the light's colour × strength")
        .map_err(|e| l.origin.error(e))?;
    super::geometry::check_transform(&l.transform, &l.origin)?;
    let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
    let ok = match &l.kind {
        LightKind::Rectangle
        | LightKind::Disk { .. }
        | LightKind::Dome { .. }
        | LightKind::Mesh { .. }
        | LightKind::Cylinder { .. } => true,
        LightKind::Quad { corners } => corners.iter().all(|c| finite(c)),
        LightKind::Sphere { center, .. } => finite(center),
        LightKind::Point { position } => finite(position),
        LightKind::Spot {
            position,
            direction,
            cone_angle,
            cone_softness,
        } => finite(position) && finite(direction) && finite(&[*cone_angle, *cone_softness]),
        LightKind::Distant { direction, angle } => finite(direction) && angle.is_finite(),
    } && l
        .shaping
        .is_none_or(|s| finite(&[s.cone_angle, s.cone_softness, s.focus]) && finite(&s.focus_tint));
    if ok {
        Ok(())
    } else {
        Err(l.origin.error(
            "the light has a position, direction, corner, angle or shaping number that is NaN, \
             infinite or too large for 32-bit floats",
        ))
    }
}

/// The rotation of a dome's `rotate`/`matrix` (None: none). Scale is divided out and the
/// translation ignored (the dome is infinitely far); a shear is an error, since it would
/// not keep solid angles.
/// The most portals a dome takes: each light sample of it looks at every one.
pub const MAX_PORTALS: usize = 256;

/// A dome's portals from their corners; an error names the one that is not a flat
/// parallelogram, or says there are too many.
fn dome_portals(corners: &[[[f32; 3]; 4]], origin: &Origin) -> Result<Vec<Portal>, SceneError> {
    if corners.len() > MAX_PORTALS {
        return Err(origin.error(format!(
            "the dome has {} portals: at most {MAX_PORTALS} (each light sample looks at every one)",
            corners.len()
        )));
    }
    corners
        .iter()
        .enumerate()
        .map(|(k, c)| {
            Portal::new(c.map(Vec3A::from)).ok_or_else(|| {
                origin.error(format!(
                    "portal {} of the dome: its four corners must make a flat \
                     parallelogram of some area, in order round it",
                    k + 1
                ))
            })
        })
        .collect()
}

fn dome_rotation(xf: &glam::Affine3A, origin: &Origin) -> Result<Option<glam::Mat3A>, SceneError> {
    let m = xf.matrix3;
    if m == glam::Mat3A::IDENTITY {
        return Ok(None);
    }
    let cols = [m.x_axis, m.y_axis, m.z_axis];
    let lengths = cols.map(|c| c.length());
    if lengths.iter().any(|l| !(l.is_finite() && *l > 0.0)) {
        return Err(origin.error("a dome's transform must be invertible (a rotation)"));
    }
    let [x, y, z] = [0, 1, 2].map(|i| cols[i] / lengths[i]);
    if x.dot(y).abs() > 1e-4 || y.dot(z).abs() > 1e-4 || x.dot(z).abs() > 1e-4 {
        return Err(origin.error(
            "a dome's transform must be a rotation (with scale, which is ignored), not a shear",
        ));
    }
    Ok(Some(glam::Mat3A::from_cols(x, y, z)))
}

/// Points each area light at its triangles: `added` is where the scene's primitive list
/// gave them (`GeometryBuilder::add`), the accelerator then reordered that list.
pub fn locate_prims(lights: &mut [Light], added: &[Option<Range<u32>>], accel: &Accel) {
    for (l, range) in lights.iter_mut().zip(added) {
        if let (LightShape::Triangles(t), Some(range)) = (&mut l.shape, range) {
            t.prims = range.clone().map(|i| accel.slot(i)).collect();
        }
    }
}

/// Gives each mesh light the triangles of its object (`ranges[object]`: where
/// `GeometryBuilder::add` put them), their normals, and the distribution it picks them
/// by: power, which is area × emitted luminance, and the radiance is uniform over a light,
/// so area. Returns the lights-only BVH of all mesh-light triangles (object id: the
/// light), so that finding one along a ray is not linear in their number.
pub fn mesh_surfaces(
    lights: &mut [Light],
    descs: &[LightDesc],
    ranges: &[Range<u32>],
    accel: &Accel,
) -> Result<Accel, SceneError> {
    let mut prims = Vec::new();
    let mut owners = Vec::new();
    for (li, (light, desc)) in lights.iter_mut().zip(descs).enumerate() {
        let LightKind::Mesh { object } = desc.kind else {
            continue;
        };
        let LightShape::Mesh(Mesh(Triangles {
            prims: ids,
            normals,
            by_area,
            area,
            parallelogram: quad,
            rect,
            ..
        })) = &mut light.shape
        else {
            continue;
        };
        // In slot order: the BVH's primitive order, so the light's triangles are read
        // in the order they sit in memory.
        *ids = ranges[object].clone().map(|i| accel.slot(i)).collect();
        ids.sort_unstable();
        let mut areas = Vec::with_capacity(ids.len());
        for &slot in ids.iter() {
            let p = accel.prims()[slot as usize];
            let Prim::Triangle { p0, e1, e2, .. } = p else {
                return Err(desc.origin.error(
                    "a mesh light's object must be made of triangles (a sphere is a sphere light)",
                ));
            };
            areas.push(p.area());
            normals.push(p.face_normal());
            prims.push(Prim::Triangle {
                p0,
                e1,
                e2,
                normals: u32::MAX,
            });
            owners.push(li as u32);
        }
        *area = areas.iter().sum();
        if *area <= 0.0 || area.is_nan() {
            return Err(desc
                .origin
                .error("a mesh light's object has no area: it cannot emit"));
        }
        *by_area = Distribution1D::new(&areas);
        // A rectangle of two triangles (an OBJ's or glTF's emissive quad) is sampled in
        // solid angle, as a rect light.
        *quad = either_order(ids, accel.prims());
        *rect = quad.and_then(|[p0, e1, e2]| Rect::new(p0, e1, e2));
    }
    let n = prims.len();
    Ok(Accel::build(
        prims,
        owners,
        Vec::new(),
        vec![crate::geometry::Visibility::ALL; n],
    ))
}

/// [`parallelogram`] of the two triangles in `slots` of `prims`, in either order (a BVH's
/// slot order may swap them).
pub(super) fn either_order(slots: &[u32], prims: &[Prim]) -> Option<[Vec3A; 3]> {
    match slots {
        &[a, b] => {
            let (a, b) = (*prims.get(a as usize)?, *prims.get(b as usize)?);
            parallelogram(&[a, b]).or_else(|| parallelogram(&[b, a]))
        }
        _ => None,
    }
}

/// Two triangles `(c0, c1, c2)`, `(c0, c2, c3)` that form a parallelogram, as corner and
/// edges.
fn parallelogram(prims: &[Prim]) -> Option<[Vec3A; 3]> {
    let [Prim::Triangle {
        p0, e1: a1, e2: a2, ..
    }, Prim::Triangle {
        p0: q0,
        e1: b1,
        e2: b2,
        ..
    }] = prims
    else {
        return None;
    };
    let same_start = (*p0 - *q0).length() <= 1e-6 * (1.0 + p0.length());
    let diagonal_shared = (*a2 - *b1).length() <= 1e-6 * (1.0 + a2.length());
    // c1 + c3 = c0 + c2  ⇔  a1 + b2 = a2.
    let closes = (*a1 + *b2 - *a2).length() <= 1e-5 * (1.0 + a2.length());
    (same_start && diagonal_shared && closes).then_some([*p0, *a1, *b2])
}

fn load_env(path: &Path, origin: &Origin) -> Result<EnvMap, SceneError> {
    let cannot = |e: &dyn std::fmt::Display| {
        origin.error(format!(
            "cannot read environment map {}: {e}",
            path.display()
        ))
    };
    // Read as every input is (limits, identity), decoded by the one EXR reader.
    let bytes = crate::limits::read_input(path).map_err(|e| cannot(&e))?;
    let (w, h, texels) = crate::output::decode_exr_rgba(&bytes).map_err(|e| cannot(&e))?;
    let texels = texels
        .into_iter()
        .map(|[r, g, b, _]| Vec3A::new(r, g, b))
        .collect();
    Ok(EnvMap::new(w, h, texels))
}

/// Light and shadow linking, resolved per object once: each object's `unlit_by` and
/// `unshadowing`, and which lights have shadow linking.
pub fn link(descs: &[LightDesc], objects: &mut [Object], lights: &mut [Light]) {
    for (light_id, l) in descs.iter().enumerate() {
        let linked = |o: &Object, include: &Option<Vec<String>>, exclude: &[String]| {
            let any = |set: &[String]| o.groups.iter().any(|g| set.contains(g));
            include.as_deref().is_none_or(any) && !any(exclude)
        };
        let light_id = light_id as u32;
        for o in objects.iter_mut().filter(|o| o.light != Some(light_id)) {
            if !linked(o, &l.include, &l.exclude) {
                o.unlit_by.push(light_id);
            }
            if !linked(o, &l.shadow_include, &l.shadow_exclude) {
                o.unshadowing.push(light_id);
                if let Some(light) = lights.get_mut(light_id as usize) {
                    light.shadow_linked = true;
                }
            }
        }
    }
}

/// Lights reached by rays that escape the scene.
pub fn escape_lights(lights: &[Light]) -> Vec<u32> {
    lights
        .iter()
        .enumerate()
        .filter(|(_, l)| l.shape.escapes())
        .map(|(i, _)| i as u32)
        .collect()
}

/// Light group names, sorted; sets each light's part in split AOVs (its first group, or
/// the default part after all groups).
pub fn groups(lights: &mut [Light]) -> Vec<String> {
    let mut light_groups: Vec<String> = lights
        .iter()
        .flat_map(|l| l.groups.iter().cloned())
        .collect();
    light_groups.sort();
    light_groups.dedup();
    let default_part = light_groups.len() as u32;
    for l in lights.iter_mut() {
        l.part = l
            .groups
            .first()
            .and_then(|g| light_groups.iter().position(|x| x == g))
            .map_or(default_part, |p| p as u32);
    }
    light_groups
}
