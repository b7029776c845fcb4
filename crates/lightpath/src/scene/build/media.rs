//! Media: the `[media.NAME]` tables objects' `interior` and the atmosphere name become
//! the scene's volumes; objects learn what they bound; and the interiors the camera
//! starts in are found by walking a ray out of the scene.

use crate::geometry::{Accel, Ray, Visibility};
use crate::material::openpbr::OpenPbr;
use crate::media::grid::{DensityGrid, GridDensity};
use crate::media::{HenyeyGreenstein, Heterogeneous, Homogeneous, Medium, MediumStack, Volume};
use crate::scene::desc::{DensityDesc, MaterialKind, MediumDesc, NameRef, SceneDesc, ShapeDesc};
use crate::scene::load::vdb;
use crate::scene::{MediumUse, Object, SceneError};
use glam::{Affine3A, Vec3A};
use std::collections::HashMap;
use std::sync::Arc;

/// Voxels along a majorant cell's edge: an OpenVDB leaf, so a cell over empty space is
/// skipped in one DDA step and one over a leaf bounds little more than that leaf.
const MAJORANT_CELL: u32 = 8;

/// Density grids by file, grid name and scale: objects sharing a heterogeneous medium
/// share its voxels.
type Grids = HashMap<(std::path::PathBuf, String, u32), Arc<GridDensity>>;

/// The density grid of `d`, read once.
fn density(d: &DensityDesc, grids: &mut Grids) -> Result<Arc<GridDensity>, SceneError> {
    let key = (d.path.clone(), d.grid.clone(), d.scale.to_bits());
    if let Some(g) = grids.get(&key) {
        return Ok(g.clone());
    }
    let file = d.path.display();
    let vdb = vdb::load(&d.path, &d.grid, &d.origin)?;
    let g = DensityGrid::from_vdb(&vdb, d.scale)
        .and_then(|g| GridDensity::new(g, MAJORANT_CELL))
        .map_err(|e| {
            d.origin
                .error(format!("OpenVDB file {file}: grid '{}': {e}", d.grid))
        })?;
    let g = Arc::new(g);
    grids.insert(key, g.clone());
    Ok(g)
}

/// The volume of `[media.NAME]`, from its checked numbers; a density grid is placed by
/// `transform` (the bounding object's, after the grid's own).
fn volume(
    name: &str,
    m: &MediumDesc,
    transform: Affine3A,
    grids: &mut Grids,
) -> Result<Volume, SceneError> {
    let (sigma_a, sigma_s) = (m.sigma_a.into(), m.sigma_s.into());
    let medium = match &m.density {
        None => Medium::Homogeneous(Homogeneous::new(sigma_a, sigma_s)),
        Some(d) => Medium::Heterogeneous(Heterogeneous::new(
            density(d, grids)?,
            transform,
            sigma_a,
            sigma_s,
        )),
    };
    Ok(Volume {
        name: name.to_string(),
        medium,
        phase: HenyeyGreenstein::new(m.g),
        emission: m.emission.map_or(Vec3A::ZERO, Vec3A::from),
    })
}

/// The scene's volumes (those something uses), each object's interior, and the
/// atmosphere's volume. An unknown medium is an error at the name.
pub fn build(
    desc: &SceneDesc,
    objects: &mut [Object],
) -> Result<(Vec<Volume>, Option<u32>), SceneError> {
    let mut volumes: Vec<Volume> = Vec::new();
    // A homogeneous medium is one volume however many objects bound it; a grid is
    // placed by each object's transform, so it is one volume per object.
    let mut ids: HashMap<(&str, Option<usize>), u32> = HashMap::new();
    let mut grids = Grids::new();
    let mut find = |r: &NameRef, object: Option<usize>| -> Result<u32, SceneError> {
        let Some((name, m)) = desc.media.media.get_key_value(&r.name) else {
            let known: Vec<&String> = desc.media.media.keys().collect();
            return Err(r.origin.error(format!(
                "unknown medium '{}': the scene's [media] tables are {known:?}",
                r.name
            )));
        };
        let key = (name.as_str(), object.filter(|_| m.density.is_some()));
        if let Some(&id) = ids.get(&key) {
            return Ok(id);
        }
        let transform = key
            .1
            .and_then(|o| desc.objects.get(o))
            .map_or(Affine3A::IDENTITY, |o| o.transform);
        let id = volumes.len() as u32;
        volumes.push(volume(name, m, transform, &mut grids)?);
        ids.insert(key, id);
        Ok(id)
    };
    for i in &desc.media.interiors {
        let volume = find(&i.medium, Some(i.object))?;
        // In a file with lines (a TOML scene) an open mesh is an error; an imported
        // file's (glTF) is taken as it is.
        if i.medium.origin.line > 0 {
            if let Some(e) = desc.objects.get(i.object).and_then(|o| open_edge(&o.shape)) {
                return Err(i.medium.origin.error(format!(
                    "interior '{}' on an open mesh: the edge {:?}–{:?} borders {} \
                     triangle(s), not 2 (a medium needs a closed surface)",
                    i.medium.name, e.0, e.1, e.2
                )));
            }
        }
        let Some(o) = objects.get_mut(i.object) else {
            return Err(i.medium.origin.error(format!(
                "interior of object {} of {}: there is no such object",
                i.object,
                objects.len()
            )));
        };
        o.interior = Some(MediumUse {
            volume,
            scatter_class: Default::default(),
            glow_class: Default::default(),
        });
        o.priority = i.priority;
    }
    let atmosphere = desc
        .media
        .atmosphere
        .as_ref()
        .map(|r| find(r, None))
        .transpose()?;
    // OpenPBR glass with a transmission depth bounds its own medium, unless the object
    // names another.
    let mut openpbr: HashMap<&str, u32> = HashMap::new();
    for (o, od) in objects.iter_mut().zip(&desc.objects) {
        let Some(r) = od.material.as_ref().filter(|_| o.interior.is_none()) else {
            continue;
        };
        let Some(MaterialKind::OpenPbr(p)) = desc.materials.get(&r.name).map(|m| &m.kind) else {
            continue;
        };
        let Some(v) = openpbr_interior(&r.name, p) else {
            continue;
        };
        let volume = *openpbr.entry(r.name.as_str()).or_insert_with(|| {
            volumes.push(v);
            volumes.len() as u32 - 1
        });
        o.interior = Some(MediumUse {
            volume,
            scatter_class: Default::default(),
            glow_class: Default::default(),
        });
    }
    Ok((volumes, atmosphere))
}

/// The interior of an OpenPBR material with transmission and a `transmission_depth`
/// (OpenPBR Surface 1.1, "Translucent base"): extinction μt = −ln(transmission_color) /
/// depth, scattering μs = transmission_scatter / depth, absorption μa = μt − μs raised
/// to be non-negative (as the specification's reference viewer does), phase
/// anisotropy `transmission_scatter_anisotropy`.
pub fn openpbr_interior(material: &str, p: &OpenPbr) -> Option<Volume> {
    let d = p.transmission_depth;
    if p.transmission_weight <= 0.0 || !(d > 0.0 && d.is_finite()) || p.geometry_thin_walled {
        return None;
    }
    let t = p.transmission_color.clamp(Vec3A::splat(1e-30), Vec3A::ONE);
    let mu_t = Vec3A::new(-t.x.ln(), -t.y.ln(), -t.z.ln()) / d;
    let mu_s = p.transmission_scatter.max(Vec3A::ZERO) / d;
    let mut mu_a = mu_t - mu_s;
    if mu_a.min_element() < 0.0 {
        mu_a -= Vec3A::splat(mu_a.min_element());
    }
    if (mu_a + mu_s) == Vec3A::ZERO {
        return None;
    }
    Some(Volume {
        name: format!("{material} (transmission)"),
        medium: Medium::Homogeneous(Homogeneous::new(mu_a, mu_s)),
        phase: HenyeyGreenstein::new(p.transmission_scatter_anisotropy),
        emission: Vec3A::ZERO,
    })
}

/// An edge of a mesh shape that does not border exactly two triangles (vertices
/// welded by position, degenerate edges skipped), with its count; `None` for a closed
/// mesh or a shape that is not a mesh (cubes and spheres are closed).
fn open_edge(shape: &ShapeDesc) -> Option<([f32; 3], [f32; 3], usize)> {
    let parts = shape.mesh_parts()?;
    let key = |p: [f32; 3]| p.map(f32::to_bits);
    // Edge (by its ends' bits, ordered) → triangles bordering it, and its ends.
    type Ends = ([u32; 3], [u32; 3]);
    let mut edges: HashMap<Ends, (usize, [f32; 3], [f32; 3])> = HashMap::new();
    for part in parts {
        for tri in &part.indices {
            let p = tri.map(|i| part.positions.get(i as usize).copied().unwrap_or_default());
            for (a, b) in [(p[0], p[1]), (p[1], p[2]), (p[2], p[0])] {
                let (ka, kb) = (key(a), key(b));
                if ka == kb {
                    continue;
                }
                let k = if ka < kb { (ka, kb) } else { (kb, ka) };
                edges.entry(k).or_insert((0, a, b)).0 += 1;
            }
        }
    }
    edges
        .into_values()
        .filter(|e| e.0 != 2)
        .min_by(|a, b| a.1.partial_cmp(&b.1).unwrap_or(std::cmp::Ordering::Equal))
        .map(|(n, a, b)| (a, b, n))
}

/// The interiors that contain `p`: along a fixed ray out of the scene, an interior
/// whose boundary is first crossed outwards (its normal along the ray) contains it.
/// Assumes closed, outward-facing boundaries, as interiors need anyway.
pub fn media_at(p: Vec3A, accel: &Accel, objects: &[Object], epsilon: f32) -> MediumStack {
    let mut stack = MediumStack::default();
    if !objects.iter().any(|o| o.interior.is_some()) {
        return stack;
    }
    // An irrational-looking direction, so the ray rarely grazes an edge of a box.
    let dir = Vec3A::new(0.3713, 0.8281, 0.4197).normalize();
    let mut seen: Vec<u32> = Vec::new();
    let mut ray = Ray {
        origin: p,
        dir,
        tmax: f32::INFINITY,
    };
    for _ in 0..4096 {
        let Some(hit) = accel.intersect(&ray, 0.0, Visibility::ALL) else {
            break;
        };
        let o = &objects[hit.object as usize];
        if o.interior.is_some() && !seen.contains(&hit.object) {
            seen.push(hit.object);
            if dir.dot(hit.ng) > 0.0 {
                stack.enter(hit.object, o.priority);
            }
        }
        let side = if dir.dot(hit.ng) >= 0.0 { 1.0 } else { -1.0 };
        ray.origin = hit.p + hit.ng * (epsilon * side);
    }
    stack
}
