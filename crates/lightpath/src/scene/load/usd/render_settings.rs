//! `RenderSettings` → film, camera, output and AOVs; `UsdGeomCamera` → cameras.
//!
//! The settings used are `--render-settings /Path`, else the stage's
//! `renderSettingsPrimPath`, else the first `RenderSettings` prim. Its first product
//! gives the resolution, the camera and the output file (`productName`; `-o` overrides
//! it); with several products each is a file of its own holding its vars
//! (`SceneDesc::products`; job.rs writes them). The vars become the AOVs, named by
//! `driver:parameters:aov:name` or else the var's prim name:
//!
//! - `sourceType = "lpe"`: an AOV of that expression (`lpe:` before an expression is
//!   dropped; `lpe:<standard name>` is the standard AOV).
//! - `raw`, `primvar` or `intrinsic` naming the beauty (`Ci`, `C`, `color`, `a`, `alpha`)
//!   is the beauty; naming a standard AOV (`normal`, `depth`, `albedo`, …) that AOV;
//!   others are warned about.
//!
//! A stage with render settings renders the beauty and exactly these AOVs; the standard
//! set only with `--aovs standard`.

use super::{stage, Loader, UsdOptions};
use crate::camera::FovAxis;
use crate::scene::desc::{AovDesc, CameraDesc, NamedCamera, Origin, ProductDesc};
use crate::scene::SceneError;
use glam::{Affine3A, Vec3A};
use openusd::schemas::render::{compute_render_spec, SourceType};
use openusd::usd::{Prim, PrimPredicate};

/// Longer side of the film when only the camera's apertures give its shape.
const FILM_SIZE: f32 = 512.0;

/// Raw var names that are the beauty's channels.
const BEAUTY_NAMES: &[&str] = &["Ci", "C", "color", "rgba", "rgb", "a", "alpha", "beauty"];

impl Loader {
    pub(super) fn render_settings(&mut self, options: &UsdOptions) -> Result<(), SceneError> {
        let at = Origin::file(&self.file);
        let path = match &options.render_settings {
            Some(p) => {
                let prim = self.stage.prim(p.as_str());
                if stage::type_of(&prim) != "RenderSettings" {
                    return Err(at.error(format!(
                        "--render-settings {p}: there is no RenderSettings prim at that path"
                    )));
                }
                Some(p.clone())
            }
            None => {
                let meta = self
                    .stage
                    .stage_metadata("renderSettingsPrimPath")
                    .ok()
                    .flatten()
                    .and_then(|v| stage::string_of(&v))
                    .filter(|p| !p.is_empty());
                match meta {
                    Some(p) => Some(p),
                    None => {
                        let mut found = None;
                        let stage = self.stage.clone();
                        let _ = stage.traverse(PrimPredicate::DEFAULT, |p| {
                            if found.is_none()
                                && stage::type_of(&stage.prim(p.clone())) == "RenderSettings"
                            {
                                found = Some(p.to_string());
                            }
                        });
                        found
                    }
                }
            }
        };
        let Some(path) = path else {
            return Ok(());
        };
        let settings = self.stage.prim(path.as_str());
        let spec = compute_render_spec(&self.stage, settings.path(), &[])
            .map_err(|e| self.error(&settings, format!("{e:#}")))?;
        let Some(spec) = spec else {
            return Ok(());
        };
        if !spec.included_purposes.is_empty() {
            self.purposes = spec.included_purposes.clone();
        }
        self.desc.standard_aovs = Some(false);
        if let Some(product) = spec.products.first() {
            let [w, h] = product.resolution;
            if w > 0 && h > 0 {
                self.desc.render.resolution = [w as u32, h as u32];
            }
            if (product.pixel_aspect_ratio - 1.0).abs() > 1e-4 && product.pixel_aspect_ratio > 0.0 {
                self.warn(
                    &settings,
                    format!(
                        "pixelAspectRatio {} is read as 1 (square pixels)",
                        product.pixel_aspect_ratio
                    ),
                );
            }
            self.settings_camera = product.camera_path.clone();
            if !product.name.is_empty() {
                self.desc.output = Some(product.name.clone().into());
            }
        }
        // Each var's AOV: Some(name), the beauty (None), or skipped (not in the map).
        let mut var_aov: Vec<Option<Option<String>>> = Vec::with_capacity(spec.render_vars.len());
        for var in &spec.render_vars {
            let prim = self.stage.prim(var.render_var_path.as_str());
            let name = var
                .namespaced_settings
                .iter()
                .find(|(k, _)| k == "driver:parameters:aov:name")
                .and_then(|(_, v)| stage::string_of(v))
                .filter(|n| !n.is_empty())
                .unwrap_or_else(|| stage::name_of(prim.path()));
            let source = var.source_name.trim().to_string();
            let definition = match var.source_type {
                SourceType::Lpe => Some(lpe_definition(&source)),
                _ if BEAUTY_NAMES.contains(&source.as_str()) => None,
                _ => match crate::aov::AovSpec::parse(&source) {
                    Ok(spec) => Some(spec.definition),
                    Err(_) => {
                        self.warn(
                            &prim,
                            format!(
                                "RenderVar '{name}': source '{source}' ({:?}) is not an AOV \
                                 Lightpath renders; it is skipped",
                                var.source_type
                            ),
                        );
                        var_aov.push(None);
                        continue;
                    }
                },
            };
            let Some(definition) = definition else {
                var_aov.push(Some(None));
                continue;
            };
            self.desc.aovs.insert(
                name.clone(),
                AovDesc {
                    definition,
                    origin: self.origin(&prim),
                },
            );
            var_aov.push(Some(Some(name)));
        }
        if spec.products.len() > 1 {
            self.products(&spec.products, &var_aov);
        }
        Ok(())
    }

    /// Several products: each its own file with its own vars. They share one film, so
    /// the first product's resolution and camera are every product's (a warning names
    /// a product that asks for others).
    fn products(
        &mut self,
        products: &[openusd::schemas::render::spec::Product],
        var_aov: &[Option<Option<String>>],
    ) {
        let first = &products[0];
        for p in products {
            let mut out = ProductDesc {
                output: p.name.clone().into(),
                aovs: Vec::new(),
                beauty: false,
            };
            for &k in &p.render_var_indices {
                match var_aov.get(k) {
                    Some(Some(Some(name))) if !out.aovs.contains(name) => {
                        out.aovs.push(name.clone())
                    }
                    Some(Some(None)) => out.beauty = true,
                    _ => {}
                }
            }
            let prim = self.stage.prim(p.render_product_path.as_str());
            if p.resolution != first.resolution || p.camera_path != first.camera_path {
                self.warn(
                    &prim,
                    format!(
                        "a product's resolution and camera are the first product's ({}): \
                         the products share one render",
                        first.render_product_path
                    ),
                );
            }
            if p.name.is_empty() {
                self.warn(&prim, "a RenderProduct without productName is not written");
                continue;
            }
            if out.aovs.is_empty() && !out.beauty {
                self.warn(
                    &prim,
                    format!(
                        "RenderProduct {}: none of its vars is rendered; it is not written",
                        p.name
                    ),
                );
                continue;
            }
            self.desc.products.push(out);
        }
        // Always one file holds the beauty (and the AOVs the command line adds).
        if !self.desc.products.iter().any(|p| p.beauty) {
            if let Some(p) = self.desc.products.first_mut() {
                p.beauty = true;
            }
        }
        if self.desc.products.len() < 2 {
            self.desc.products.clear();
        }
    }

    /// A `UsdGeomCamera`, named by its path (for `--camera`).
    pub(super) fn camera(&mut self, prim: &Prim, world: Affine3A) {
        let f = |n: &str, d: f32| {
            stage::value(prim, n, self.time)
                .and_then(|v| stage::f32_of(&v))
                .filter(|x| x.is_finite() && *x > 0.0)
                .unwrap_or(d)
        };
        let projection = stage::value(prim, "projection", self.time)
            .and_then(|v| stage::string_of(&v))
            .unwrap_or_default();
        if projection == "orthographic" {
            self.warn(
                prim,
                "orthographic cameras are not supported; it is skipped",
            );
            return;
        }
        let focal = f("focalLength", 50.0);
        let ha = f("horizontalAperture", 20.955);
        let va = f("verticalAperture", 15.2908);
        let position = world.transform_point3a(Vec3A::ZERO);
        let forward = world.transform_vector3a(-Vec3A::Z).normalize_or(-Vec3A::Z);
        let up = world.transform_vector3a(Vec3A::Y).normalize_or(Vec3A::Y);
        // Focal length and apertures are in tenths of a scene unit; the lens's
        // diameter is the focal length over the f-number.
        let tenth = 0.1 * self.meters_per_unit;
        let f_stop = stage::value(prim, "fStop", self.time)
            .and_then(|v| stage::f32_of(&v))
            .unwrap_or(0.0);
        let focus = stage::value(prim, "focusDistance", self.time)
            .and_then(|v| stage::f32_of(&v))
            .unwrap_or(0.0);
        let (aperture_radius, focus_distance) = if f_stop > 0.0 && focus > 0.0 {
            (
                focal * tenth / (2.0 * f_stop),
                Some(focus * self.meters_per_unit),
            )
        } else {
            (0.0, None)
        };
        let aspect = ha / va;
        let resolution = if aspect >= 1.0 {
            [
                FILM_SIZE as u32,
                (FILM_SIZE / aspect).round().max(1.0) as u32,
            ]
        } else {
            [
                (FILM_SIZE * aspect).round().max(1.0) as u32,
                FILM_SIZE as u32,
            ]
        };
        let camera = CameraDesc {
            position: position.into(),
            look_at: (position + forward).into(),
            up: up.into(),
            // Set for the film's shape in `pick_camera`.
            fov: 2.0 * (ha * 0.5 / focal).atan().to_degrees(),
            fov_axis: FovAxis::X,
            aperture_radius,
            focus_distance,
            origin: self.origin(prim),
        };
        let name = prim.path().to_string();
        self.desc.cameras.push(NamedCamera {
            name,
            camera,
            resolution: Some(resolution),
        });
        self.apertures.push((ha, va, focal));
    }

    /// The render settings' camera, else the first; its field of view fitted to the film
    /// as USD's default `expandAperture` conforms the aperture to the image.
    pub(super) fn pick_camera(&mut self) -> Result<(), SceneError> {
        if self.desc.cameras.is_empty() {
            if let Some(p) = &self.settings_camera {
                return Err(Origin::file(&self.file).error(format!(
                    "the render settings' camera {p} is not a camera of the stage"
                )));
            }
            return Ok(());
        }
        let k = match &self.settings_camera {
            Some(p) => self
                .desc
                .cameras
                .iter()
                .position(|c| &c.name == p)
                .ok_or_else(|| {
                    Origin::file(&self.file).error(format!(
                        "the render settings' camera {p} is not a camera of the stage"
                    ))
                })?,
            None => 0,
        };
        let has_settings = self.desc.standard_aovs.is_some();
        for (i, c) in self.desc.cameras.iter_mut().enumerate() {
            let (ha, va, focal) = self.apertures[i];
            let [w, h] = if has_settings {
                self.desc.render.resolution
            } else {
                c.resolution.unwrap_or([512, 512])
            };
            if has_settings {
                c.resolution = None;
            }
            let image = w as f32 / h.max(1) as f32;
            if image >= ha / va {
                c.camera.fov_axis = FovAxis::Y;
                c.camera.fov = 2.0 * (va * 0.5 / focal).atan().to_degrees();
            }
        }
        let chosen = self.desc.cameras[k].clone();
        self.desc.camera = Some(chosen.camera);
        if let Some(r) = chosen.resolution {
            self.desc.render.resolution = r;
        }
        if k != 0 {
            let c = self.desc.cameras.remove(k);
            self.desc.cameras.insert(0, c);
            let a = self.apertures.remove(k);
            self.apertures.insert(0, a);
        }
        Ok(())
    }
}

/// An LPE var's source as an AOV definition: `lpe:<standard name>` stays (the standard
/// AOV), `lpe:` before an expression is dropped.
fn lpe_definition(source: &str) -> String {
    let Some(rest) = source.strip_prefix("lpe:") else {
        return source.to_string();
    };
    let standard = lpe::standard_name(rest.trim()).is_some()
        || crate::aov::resolve_definition(source) != source;
    if standard {
        source.to_string()
    } else {
        rest.to_string()
    }
}
