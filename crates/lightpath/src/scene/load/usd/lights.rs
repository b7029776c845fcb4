//! UsdLux lights, in the units of the UsdLux specification (docs/scene-format.md, "USD
//! lights"):
//!
//! - Every light's scalar emission is `intensity · 2^exposure` times `color` (and the
//!   colour of `colorTemperature` when `enableColorTemperature` is on).
//! - Rect, disk, sphere, cylinder and mesh lights emit that as radiance; `normalize`
//!   divides it by the light's world-space area, so the power stays when it is resized.
//! - A sphere light with `treatAsPoint` is a point light of the power of the sphere of its
//!   radius: intensity L·π·r² (normalized: L/4), in W/sr.
//! - A distant light with `normalize` gives irradiance `L` at a surface facing it; without
//!   it, L is the radiance of the sun disk of diameter `angle`, whose irradiance is
//!   L·π·sin²(angle/2) (an `angle` of 0 is read as normalized). A distant light whose
//!   intensity Blender's exporter wrote is read as Blender reads it back: irradiance
//!   4·L, Blender's sun strength (its exporter divides the strength by 4).
//! - A dome light emits radiance L (times its `latlong` EXR).
//! - `ShapingAPI`'s cone on a sphere light makes it a spot (full angle 2·`cone:angle`, soft
//!   edge as Blender reads `cone:softness`: its spot blend). On rect and disk lights the
//!   cone (`cone:angle`, `cone:softness`), `focus` and `focusTint` shape the emission about
//!   the normal by the schema's formulas (`light/triangles.rs`); on other kinds they are
//!   warned about and ignored.
//!
//! A light's group is the first authored of Karma's `karma:light:lpetag`, RenderMan's
//! `ri:light:lightGroup`, Cycles' `cycles:lightgroup` and Arnold's `primvars:arnold:aov`,
//! else its prim name.
//!
//! Colour temperature: Planck's law integrated against the CIE 1931 colour matching
//! functions in the multi-lobe analytic fit of Wyman, Sloan and Shirley, "Simple Analytic
//! Approximations to the CIE XYZ Color Matching Functions" (JCGT 2013), to linear Rec.709,
//! divided channel by channel by 6500 K's so that 6500 K is white, and scaled to
//! luminance 1.

use super::{stage, Loader};
use crate::scene::desc::{AreaShaping, LightDesc, LightKind, ObjectDesc};
use crate::scene::SceneError;
use glam::{Affine3A, Vec3, Vec3A};
use openusd::usd::Prim;
use std::f32::consts::PI;
use std::ops::Range;

/// Light-group attributes, in the order the first authored one wins.
pub const LIGHT_TAGS: &[&str] = &[
    "karma:light:lpetag",
    "ri:light:lightGroup",
    "cycles:lightgroup",
    "primvars:arnold:aov",
];

/// What Blender's USD importer multiplies a DistantLight's intensity by to get the sun's
/// strength (irradiance, W/m²), the inverse of its exporter's division.
const BLENDER_SUN: f32 = 4.0;

impl Loader {
    /// Whether the strongest opinion on the light's intensity is in a layer Blender's USD
    /// exporter wrote (its `doc` is `Blender v…`).
    fn intensity_from_blender(&self, prim: &Prim) -> bool {
        ["inputs:intensity", "intensity"].iter().any(|name| {
            let attr = prim.attribute(*name);
            let Some((layer, _)) = attr
                .property_stack()
                .ok()
                .and_then(|s| s.into_iter().next())
            else {
                return false;
            };
            self.stage
                .layer(&layer)
                .and_then(|l| l.pseudo_root().and_then(|r| r.documentation()))
                .is_some_and(|doc| doc.starts_with("Blender v"))
        })
    }

    fn light_number(&self, prim: &Prim, name: &str, default: f32) -> f32 {
        stage::value_of(prim, &[&format!("inputs:{name}"), name], self.time)
            .and_then(|v| stage::f32_of(&v))
            .filter(|x| x.is_finite())
            .unwrap_or(default)
    }

    fn light_bool(&self, prim: &Prim, name: &str) -> bool {
        stage::value_of(prim, &[&format!("inputs:{name}"), name], self.time)
            .and_then(|v| stage::bool_of(&v))
            .unwrap_or(false)
    }

    /// L = intensity · 2^exposure, and the colour (with the temperature's).
    fn emission(&self, prim: &Prim, default_intensity: f32) -> (f32, [f32; 3]) {
        let l = self.light_number(prim, "intensity", default_intensity)
            * 2f32.powf(self.light_number(prim, "exposure", 0.0));
        let mut color = stage::value_of(prim, &["inputs:color", "color"], self.time)
            .and_then(|v| stage::vec3_of(&v))
            .filter(|c| c.iter().all(|x| x.is_finite()))
            .unwrap_or([1.0; 3])
            .map(|x| x.max(0.0));
        if self.light_bool(prim, "enableColorTemperature") {
            let k = blackbody_rgb(self.light_number(prim, "colorTemperature", 6500.0));
            color = [color[0] * k[0], color[1] * k[1], color[2] * k[2]];
        }
        (l.max(0.0), color)
    }

    fn light_groups(&self, prim: &Prim) -> Vec<String> {
        for name in LIGHT_TAGS {
            if let Some(v) = stage::value(prim, name, self.time) {
                let tags: Vec<String> = stage::strings_of(&v)
                    .iter()
                    .flat_map(|s| s.split([',', ' ']))
                    .filter(|t| !t.is_empty())
                    .map(str::to_string)
                    .collect();
                if !tags.is_empty() {
                    return tags;
                }
            }
        }
        vec![stage::name_of(prim.path())]
    }

    /// Light and shadow linking: the `lightLink` and `shadowLink` collections' includes
    /// (when they do not include the root) and excludes, as the LPE groups of the prims
    /// they name.
    fn linking(&mut self, prim: &Prim) -> Linking {
        let targets = |rel: &str| -> Vec<String> {
            prim.relationship(rel)
                .targets()
                .unwrap_or_default()
                .iter()
                .map(stage::name_of)
                .collect()
        };
        let collection = |name: &str| {
            let include_root =
                stage::value(prim, &format!("collection:{name}:includeRoot"), self.time)
                    .and_then(|v| stage::bool_of(&v))
                    .unwrap_or(true);
            let includes = targets(&format!("collection:{name}:includes"));
            let excludes = targets(&format!("collection:{name}:excludes"));
            ((!include_root).then_some(includes), excludes)
        };
        let (include, exclude) = collection("lightLink");
        let (shadow_include, shadow_exclude) = collection("shadowLink");
        // The root not included and nothing listed: read as all, as before.
        let mut shadow_include = shadow_include.filter(|i| !i.is_empty());
        // ShadowAPI's `inputs:shadow:enable` off: no object shadows the light.
        let shadows = stage::value_of(prim, &["inputs:shadow:enable", "shadow:enable"], self.time)
            .and_then(|v| stage::bool_of(&v))
            .unwrap_or(true);
        if !shadows {
            shadow_include = Some(Vec::new());
        }
        Linking {
            include: include.filter(|i| !i.is_empty()),
            exclude,
            shadow_include,
            shadow_exclude,
        }
    }

    pub(super) fn light(
        &mut self,
        prim: &Prim,
        ty: &str,
        world: Affine3A,
    ) -> Result<(), SceneError> {
        let default_intensity = if ty == "DistantLight" { 50000.0 } else { 1.0 };
        let (mut l, color) = self.emission(prim, default_intensity);
        let mut normalize = self.light_bool(prim, "normalize");
        if ty == "DistantLight" && self.intensity_from_blender(prim) {
            // Blender's exporter writes a sun of strength S W/m² as intensity S/4 and its
            // importer reads it back as 4·intensity whatever `normalize` says: the number
            // means Blender's sun strength, not the specification's illuminance.
            l *= BLENDER_SUN;
            normalize = true;
        }
        let mut shaping = None;
        let cone = self.light_number(prim, "shaping:cone:angle", 90.0);
        if cone < 90.0 {
            shaping = Some((
                cone,
                self.light_number(prim, "shaping:cone:softness", 0.0)
                    .clamp(0.0, 1.0),
            ));
        }
        // The schema ignores a negative focus.
        let focus = self.light_number(prim, "shaping:focus", 0.0).max(0.0);
        let focus_tint = stage::value_of(
            prim,
            &["inputs:shaping:focusTint", "shaping:focusTint"],
            self.time,
        )
        .and_then(|v| stage::vec3_of(&v))
        .filter(|c| c.iter().all(|x| x.is_finite()))
        .unwrap_or([0.0; 3])
        .map(|x| x.max(0.0));
        // Rect and disk lights take the cone and the focus as their emission profile.
        let area_shaping =
            if matches!(ty, "RectLight" | "DiskLight") && (shaping.is_some() || focus > 0.0) {
                let (cone_angle, cone_softness) = shaping.take().unwrap_or((90.0, 0.0));
                Some(AreaShaping {
                    cone_angle,
                    cone_softness,
                    focus,
                    focus_tint,
                })
            } else {
                None
            };
        let (kind, transform, strength) =
            self.light_shape(prim, ty, world, (l, normalize), &mut shaping)?;
        if shaping.is_some() {
            self.warn_once(
                &format!("shaping {}", prim.path()),
                prim,
                format!(
                    "ShapingAPI's cone on a {ty} is not rendered (sphere lights become spots, \
                     rect and disk lights are shaped)"
                ),
            );
        }
        if focus > 0.0 && area_shaping.is_none() {
            self.warn_once(
                &format!("focus {}", prim.path()),
                prim,
                format!(
                    "ShapingAPI's focus on a {ty} is not rendered (only on rect and disk lights)"
                ),
            );
        }
        if !(strength.is_finite() && strength >= 0.0) {
            return Err(self.error(
                prim,
                format!("the light's emission is {strength}: its size or intensity is not usable"),
            ));
        }
        let Linking {
            include,
            exclude,
            shadow_include,
            shadow_exclude,
        } = self.linking(prim);
        let camera_visible = self.light_bool_default(prim, "karma:light:renderlightgeo", true)
            && !matches!(kind, LightKind::Distant { .. });
        self.desc.lights.push(LightDesc {
            kind,
            name: Some(stage::name_of(prim.path())),
            groups: self.light_groups(prim),
            color,
            strength,
            camera_visible,
            casts_shadows: false,
            shaping: area_shaping,
            two_sided: false,
            material: None,
            transform,
            include,
            exclude,
            shadow_include,
            shadow_exclude,
            origin: self.origin(prim),
        });
        Ok(())
    }

    /// A light's kind, placement and strength (radiance, intensity or irradiance) from
    /// its scalar emission `l`; a sphere light with a cone takes `shaping` and is a spot.
    fn light_shape(
        &mut self,
        prim: &Prim,
        ty: &str,
        world: Affine3A,
        (l, normalize): (f32, bool),
        shaping: &mut Option<(f32, f32)>,
    ) -> Result<(LightKind, Affine3A, f32), SceneError> {
        let flip = Affine3A::from_rotation_x(PI);
        let axes = world.matrix3;
        let origin: [f32; 3] = world.translation.into();
        let down = Loader::direction(&world, -Vec3A::Z);
        Ok(match ty {
            "RectLight" => {
                let w = self.light_number(prim, "width", 1.0);
                let h = self.light_number(prim, "height", 1.0);
                let area = axes.x_axis.cross(axes.y_axis).length() * w * h;
                (
                    LightKind::Rectangle,
                    world * flip * Affine3A::from_scale(Vec3::new(w * 0.5, h * 0.5, 1.0)),
                    if normalize { l / area } else { l },
                )
            }
            "DiskLight" => {
                let r = self.light_number(prim, "radius", 0.5);
                let area = axes.x_axis.cross(axes.y_axis).length() * PI * r * r;
                (
                    LightKind::Disk { segments: 64 },
                    world * flip * Affine3A::from_scale(Vec3::new(r, r, 1.0)),
                    if normalize { l / area } else { l },
                )
            }
            "SphereLight" => {
                let scale =
                    (axes.x_axis.length() + axes.y_axis.length() + axes.z_axis.length()) / 3.0;
                let r = self.light_number(prim, "radius", 0.5) * scale;
                let point = self.light_bool(prim, "treatAsPoint") || shaping.is_some() || r <= 0.0;
                let area = 4.0 * PI * r * r;
                let radiance = if normalize { l / area } else { l };
                if point {
                    // The power of the sphere, from a point.
                    let intensity = if normalize {
                        l / 4.0
                    } else {
                        radiance * PI * r * r
                    };
                    match shaping.take() {
                        Some((angle, softness)) => {
                            let (cone_angle, cone_softness) = super::super::gltf::spot_cone(
                                (angle * (1.0 - softness)).to_radians(),
                                angle.to_radians(),
                            );
                            (
                                LightKind::Spot {
                                    position: origin,
                                    direction: down,
                                    cone_angle,
                                    cone_softness,
                                },
                                Affine3A::IDENTITY,
                                intensity,
                            )
                        }
                        None => (
                            LightKind::Point { position: origin },
                            Affine3A::IDENTITY,
                            intensity,
                        ),
                    }
                } else {
                    (
                        LightKind::Sphere {
                            center: origin,
                            radius: r,
                        },
                        Affine3A::IDENTITY,
                        radiance,
                    )
                }
            }
            "CylinderLight" => {
                let len = self.light_number(prim, "length", 1.0);
                let r = self.light_number(prim, "radius", 0.5);
                let sx = axes.x_axis.length();
                let syz = (axes.y_axis.length() + axes.z_axis.length()) * 0.5;
                let area = 2.0 * PI * r * syz * len * sx;
                (
                    LightKind::Cylinder {
                        radius: r,
                        length: len,
                    },
                    world,
                    if normalize { l / area } else { l },
                )
            }
            "DistantLight" => {
                let angle = self.light_number(prim, "angle", 0.53).clamp(0.0, 180.0);
                let e = if normalize || angle <= 0.0 {
                    l
                } else {
                    l * PI * (angle.to_radians() * 0.5).sin().powi(2)
                };
                (
                    LightKind::Distant {
                        direction: down,
                        angle,
                    },
                    Affine3A::IDENTITY,
                    e,
                )
            }
            _ => {
                // Dome lights; their portals are filled in once every prim is read.
                self.note_portals(prim);
                let map = self.dome_map(prim)?;
                (
                    LightKind::Dome {
                        map,
                        portals: Vec::new(),
                    },
                    world,
                    l,
                )
            }
        })
    }

    /// A PortalLight: the rectangle `width` × `height` (default 1 × 1, the schema's unit
    /// square before the sizes were added) in its local XY plane, placed by `world`.
    pub(super) fn portal(&mut self, prim: &Prim, world: Affine3A) {
        let w = self.light_number(prim, "width", 1.0) * 0.5;
        let h = self.light_number(prim, "height", 1.0) * 0.5;
        let corners = [(-w, -h), (w, -h), (w, h), (-w, h)]
            .map(|(x, y)| world.transform_point3a(Vec3A::new(x, y, 0.0)).into());
        self.portal_corners
            .insert(prim.path().as_str().to_string(), corners);
    }

    /// Notes the paths the dome's `portals` relationship names, for `resolve_portals`
    /// (the dome is the next light of `desc.lights`).
    fn note_portals(&mut self, prim: &Prim) {
        let targets: Vec<String> = prim
            .relationship("portals")
            .targets()
            .unwrap_or_default()
            .iter()
            .map(|p| p.as_str().to_string())
            .collect();
        if !targets.is_empty() {
            self.dome_portals.push((self.desc.lights.len(), targets));
        }
    }

    /// Gives each dome the rectangles of the PortalLights its `portals` relationship
    /// names; a target that is no PortalLight read here is warned about and left out.
    pub(super) fn resolve_portals(&mut self) {
        for (li, targets) in std::mem::take(&mut self.dome_portals) {
            let mut found = Vec::new();
            for t in &targets {
                match self.portal_corners.get(t) {
                    Some(c) => found.push(*c),
                    None => self.desc.warnings.push(format!(
                        "{}: the dome's portal {t} is not a PortalLight that is read; it is left out",
                        self.file
                    )),
                }
            }
            if let Some(LightKind::Dome { portals, .. }) =
                self.desc.lights.get_mut(li).map(|l| &mut l.kind)
            {
                *portals = found;
            }
        }
    }

    fn light_bool_default(&self, prim: &Prim, name: &str, default: bool) -> bool {
        stage::value(prim, name, self.time)
            .and_then(|v| stage::bool_of(&v))
            .unwrap_or(default)
    }

    fn dome_map(
        &mut self,
        prim: &Prim,
    ) -> Result<Option<(std::path::PathBuf, crate::scene::desc::Origin)>, SceneError> {
        let Some(openusd::sdf::Value::AssetPath(a)) =
            stage::value_of(prim, &["inputs:texture:file", "texture:file"], self.time)
        else {
            return Ok(None);
        };
        if a.asset_path().is_empty() {
            return Ok(None);
        }
        let format = stage::value_of(
            prim,
            &["inputs:texture:format", "texture:format"],
            self.time,
        )
        .and_then(|v| stage::string_of(&v))
        .unwrap_or_else(|| "automatic".into());
        if !matches!(format.as_str(), "automatic" | "latlong") {
            self.warn(
                prim,
                format!(
                    "texture:format '{format}' is not read (only latlong): the dome is its colour"
                ),
            );
            return Ok(None);
        }
        let path = a
            .resolved_path()
            .filter(|p| !p.is_empty())
            .map(std::path::PathBuf::from)
            .ok_or_else(|| {
                self.error(
                    prim,
                    format!("inputs:texture:file: '{}' cannot be found", a.asset_path()),
                )
            })?;
        if !path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
        {
            self.warn(
                prim,
                format!(
                    "inputs:texture:file: {}: only EXR dome maps are read; the dome is its colour",
                    path.display()
                ),
            );
            return Ok(None);
        }
        Ok(Some((path, self.origin(prim))))
    }

    /// `MeshLightAPI` (or `LightAPI`) on a mesh: its parts `range` of `out` emit.
    pub(super) fn mesh_light(
        &mut self,
        prim: &Prim,
        range: Range<usize>,
        out: &mut [ObjectDesc],
    ) -> Result<(), SceneError> {
        let apis = prim.api_schemas().unwrap_or_default();
        if !apis
            .iter()
            .any(|a| a.as_str() == "MeshLightAPI" || a.as_str() == "LightAPI")
        {
            return Ok(());
        }
        let (l, color) = self.emission(prim, 1.0);
        let normalize = self.light_bool(prim, "normalize");
        let area: f32 = out[range.clone()]
            .iter()
            .map(|o| {
                let parts = o.shape.mesh_parts().unwrap_or_default();
                parts
                    .iter()
                    .flat_map(|p| {
                        p.indices.iter().map(|t| {
                            let [a, b, c] = t.map(|i| {
                                o.transform
                                    .transform_point3a(Vec3A::from(p.positions[i as usize]))
                            });
                            (b - a).cross(c - a).length() * 0.5
                        })
                    })
                    .sum::<f32>()
            })
            .sum();
        let radiance = if normalize && area > 0.0 { l / area } else { l };
        let groups = self.light_groups(prim);
        let link = self.linking(prim);
        let base = self.desc.objects.len();
        for k in range {
            out[k].emission = None;
            self.desc.lights.push(LightDesc {
                kind: LightKind::Mesh { object: base + k },
                name: out[k].name.clone(),
                groups: groups.clone(),
                color,
                strength: radiance,
                camera_visible: true,
                casts_shadows: true,
                shaping: None,
                two_sided: false,
                material: None,
                transform: Affine3A::IDENTITY,
                include: link.include.clone(),
                exclude: link.exclude.clone(),
                shadow_include: link.shadow_include.clone(),
                shadow_exclude: link.shadow_exclude.clone(),
                origin: self.origin(prim),
            });
        }
        Ok(())
    }
}

/// The CIE 1931 colour matching functions x̄, ȳ, z̄ at `nm`, by Wyman, Sloan and
/// Shirley's multi-lobe fit.
fn cie_xyz(nm: f32) -> [f32; 3] {
    let g = |x: f32, mu: f32, s1: f32, s2: f32| {
        let t = (x - mu) / if x < mu { s1 } else { s2 };
        (-0.5 * t * t).exp()
    };
    [
        1.056 * g(nm, 599.8, 37.9, 31.0) + 0.362 * g(nm, 442.0, 16.0, 26.7)
            - 0.065 * g(nm, 501.1, 20.4, 26.2),
        0.821 * g(nm, 568.8, 46.9, 40.5) + 0.286 * g(nm, 530.9, 16.3, 31.1),
        1.217 * g(nm, 437.0, 11.8, 36.0) + 0.681 * g(nm, 459.0, 26.0, 13.8),
    ]
}

/// Linear Rec.709 of a blackbody at `kelvin` (unnormalised).
fn planck_rgb(kelvin: f32) -> Vec3 {
    let t = kelvin.clamp(1000.0, 40000.0) as f64;
    let (c1, c2) = (3.741_771_85e-16_f64, 1.438_776_9e-2_f64);
    let mut xyz = [0.0f64; 3];
    let mut nm: f64 = 380.0;
    while nm <= 780.0 {
        let l = nm * 1e-9;
        let b = c1 / (l.powi(5) * ((c2 / (l * t)).exp() - 1.0));
        let m = cie_xyz(nm as f32);
        for i in 0..3 {
            xyz[i] += b * m[i] as f64;
        }
        nm += 5.0;
    }
    let [x, y, z] = xyz.map(|v| v as f32);
    Vec3::new(
        3.240_97 * x - 1.537_383 * y - 0.498_611 * z,
        -0.969_244 * x + 1.875_968 * y + 0.041_555 * z,
        0.055_63 * x - 0.203_977 * y + 1.056_972 * z,
    )
}

/// The colour of `colorTemperature`: white at 6500 K, of luminance 1.
pub fn blackbody_rgb(kelvin: f32) -> [f32; 3] {
    let c = planck_rgb(kelvin) / planck_rgb(6500.0);
    let c = c.max(Vec3::ZERO);
    let y = 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    if y > 0.0 && y.is_finite() {
        (c / y).into()
    } else {
        [1.0; 3]
    }
}

/// A light's linking collections, as LPE groups.
struct Linking {
    include: Option<Vec<String>>,
    exclude: Vec<String>,
    shadow_include: Option<Vec<String>>,
    shadow_exclude: Vec<String>,
}
