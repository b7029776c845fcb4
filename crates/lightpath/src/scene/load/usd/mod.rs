//! USD stages (`.usd`, `.usda`, `.usdc`, `.usdz`) → `SceneDesc`, through the pure-Rust
//! `openusd` crate, which composes the stage (sublayers, references, payloads, variants,
//! inherits, instancing). See docs/scene-format.md ("USD") for what each schema becomes.
//!
//! - `stage.rs`: opening the stage within the input limits, values and xform stacks.
//! - `geometry.rs`: meshes, GeomSubsets, gprims, instances and point instancers.
//! - `materials.rs`: UsdPreviewSurface networks on the OpenPBR material.
//! - `lights.rs`: UsdLux lights in the UsdLux specification's units.
//! - `render_settings.rs`: RenderSettings, products and vars (AOVs), and cameras.
//!
//! The stage is walked once from its root at one time code (`--frame`, else the stage's
//! start time code when it has one, else the default time). `upAxis = "Z"` is turned to
//! Lightpath's +Y up and `metersPerUnit` scales the stage to metres, by one root
//! transform every placement starts from. Errors name the layer that holds the prim's
//! strongest opinion and the prim's path; the crate's panics, if any remain, become
//! errors naming the file.

mod geometry;
mod lights;
mod materials;
mod render_settings;
mod stage;

use crate::scene::desc::{ObjectDesc, Origin, SceneDesc};
use crate::scene::SceneError;
use glam::{Affine3A, Mat3A, Vec3A};
use openusd::usd::{self, Prim, TimeCode};
use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::sync::Arc;

/// What the command line tells the USD loader: the time code and the render settings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UsdOptions {
    /// The time code to read time samples at (None: the stage's start, else default).
    pub frame: Option<f64>,
    /// The path of the `RenderSettings` prim to use (None: the stage's
    /// `renderSettingsPrimPath`, else the first one found).
    pub render_settings: Option<String>,
}

/// Reads a USD stage into a scene description, without defaults (the caller adds a
/// camera or a dome where it has none). `at` is where the file was named.
pub fn load_scene(path: &Path, at: &Origin, options: &UsdOptions) -> Result<SceneDesc, SceneError> {
    let file = path.display().to_string();
    let meta = std::fs::metadata(path)
        .map_err(|e| at.error(format!("cannot read USD file {file}: {e}")))?;
    if !meta.is_file() {
        return Err(at.error(format!("{file}: not a regular file")));
    }
    let load = std::panic::catch_unwind(|| -> Result<SceneDesc, SceneError> {
        let stage = stage::open(&file)
            .map_err(|e| Origin::file(&file).error(format!("cannot open the USD stage: {e}")))?;
        Loader::new(stage, &file, options)?.scene()
    });
    load.unwrap_or_else(|panic| {
        let why = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(at.error(format!(
            "{file}: the USD reader failed on malformed data ({why})"
        )))
    })
}

/// What a walk below a prim inherits.
#[derive(Clone, Default)]
struct Context {
    /// Names of the ancestors, root first (each is an LPE group of what lies below).
    ancestors: Vec<String>,
    /// Object LPE tags authored on the ancestors (inherited primvars).
    tags: Vec<String>,
    /// The walk builds a prototype (an instance's or a point instancer's): lights and
    /// cameras there are not read.
    prototype: bool,
}

struct Loader {
    stage: usd::Stage,
    file: String,
    time: TimeCode,
    /// Stage space to Lightpath's world (upAxis, metersPerUnit).
    root: Affine3A,
    meters_per_unit: f32,
    desc: SceneDesc,
    /// Material prim path → name in `desc.materials`.
    materials: HashMap<String, String>,
    /// Prototype path → its objects, placed relative to the prototype.
    prototypes: HashMap<String, Arc<Vec<ObjectDesc>>>,
    /// Warnings already given (one per material or schema).
    warned: HashSet<String>,
    /// The purposes rendered (`default` and `render` unless the render settings say).
    purposes: Vec<String>,
    /// The camera the render settings name, if any.
    settings_camera: Option<String>,
    /// Material name → the emission of its surface (UsdPreviewSurface emissiveColor).
    emissive: HashMap<String, [f32; 3]>,
    /// Each of `desc.cameras`' horizontal and vertical apertures and focal length.
    apertures: Vec<(f32, f32, f32)>,
    /// PortalLight prim path → its rectangle's world corners (lights.rs).
    portal_corners: HashMap<String, [[f32; 3]; 4]>,
    /// Each dome of `desc.lights` (its index) with the paths its `portals` names.
    dome_portals: Vec<(usize, Vec<String>)>,
}

impl Loader {
    fn new(stage: usd::Stage, file: &str, options: &UsdOptions) -> Result<Loader, SceneError> {
        // The root layer's, else (a TD's layer over a DCC export that does not repeat
        // them) the strongest layer of its stack that authors it.
        let meta = |key: &str| {
            stage.stage_metadata(key).ok().flatten().or_else(|| {
                stage.layer_stack().iter().find_map(|id| {
                    let layer = stage.layer(id)?;
                    let root = layer.pseudo_root()?;
                    root.field(key).ok().flatten()
                })
            })
        };
        let up = meta("upAxis").and_then(|v| stage::string_of(&v));
        let mpu = meta("metersPerUnit")
            .and_then(|v| stage::f32_of(&v))
            .filter(|m| m.is_finite() && *m > 0.0)
            .unwrap_or(0.01);
        // USD's fallback unit is the centimetre; a stage without metersPerUnit is read
        // in centimetres, as every USD consumer does.
        let rotate = match up.as_deref() {
            Some("Z") => Mat3A::from_rotation_x(-std::f32::consts::FRAC_PI_2),
            _ => Mat3A::IDENTITY,
        };
        let root = Affine3A {
            matrix3: rotate * Mat3A::from_diagonal(glam::Vec3::splat(mpu)),
            translation: Vec3A::ZERO,
        };
        let time = match options.frame {
            Some(t) => TimeCode::new(t),
            None if stage.has_authored_time_code_range() => TimeCode::new(stage.start_time_code()),
            None => TimeCode::new(stage.start_time_code()),
        };
        let desc = SceneDesc {
            source: file.to_string(),
            ..SceneDesc::default()
        };
        let mut loader = Loader {
            stage,
            file: file.to_string(),
            time,
            root,
            meters_per_unit: mpu,
            desc,
            materials: HashMap::new(),
            prototypes: HashMap::new(),
            warned: HashSet::new(),
            purposes: vec!["default".into(), "render".into()],
            settings_camera: None,
            emissive: HashMap::new(),
            apertures: Vec::new(),
            portal_corners: HashMap::new(),
            dome_portals: Vec::new(),
        };
        loader.render_settings(options)?;
        Ok(loader)
    }

    /// An error about a prim: the layer of its strongest opinion, its path, the message.
    fn error(&self, prim: &Prim, message: impl std::fmt::Display) -> SceneError {
        let layer = stage::layer_of(prim, &self.file);
        Origin::file(layer).error(format!("{}: {message}", prim.path()))
    }

    fn warn(&mut self, prim: &Prim, message: impl std::fmt::Display) {
        let layer = stage::layer_of(prim, &self.file);
        self.desc
            .warnings
            .push(format!("{layer}: {}: {message}", prim.path()));
    }

    /// A warning given once for `key` (a material, a schema).
    fn warn_once(&mut self, key: &str, prim: &Prim, message: impl std::fmt::Display) {
        if self.warned.insert(key.to_string()) {
            self.warn(prim, message);
        }
    }

    fn origin(&self, prim: &Prim) -> Origin {
        Origin::file(format!(
            "{} {}",
            stage::layer_of(prim, &self.file),
            prim.path()
        ))
    }

    fn scene(mut self) -> Result<SceneDesc, SceneError> {
        let roots = self
            .stage
            .root_prims()
            .map_err(|e| Origin::file(&self.file).error(format!("{e:#}")))?;
        for name in roots {
            let prim = self.stage.prim(format!("/{}", name.as_str()).as_str());
            let mut out = Vec::new();
            self.walk(&prim, self.root, &Context::default(), &mut out)?;
            self.desc.objects.extend(out);
        }
        for e in self.stage.composition_errors() {
            self.desc
                .warnings
                .push(format!("{}: composition: {e}", self.file));
        }
        self.pick_camera()?;
        self.resolve_portals();
        Ok(self.desc)
    }

    /// Reads `prim` and what lies below it, placed under `parent`; objects go to `out`.
    fn walk(
        &mut self,
        prim: &Prim,
        parent: Affine3A,
        ctx: &Context,
        out: &mut Vec<ObjectDesc>,
    ) -> Result<(), SceneError> {
        if !prim.is_active().unwrap_or(true)
            || prim.is_abstract().unwrap_or(false)
            // openusd 0.6 reports a prototype's children as undefined (its specifier is
            // the source's `over`): inside prototypes only `active` counts.
            || (!ctx.prototype && !prim.is_defined().unwrap_or(true))
        {
            return Ok(());
        }
        let ty = stage::type_of(prim);
        if let Some(v) =
            stage::value(prim, "visibility", self.time).and_then(|v| stage::string_of(&v))
        {
            if v == "invisible" {
                return Ok(());
            }
        }
        if let Some(p) = stage::value(prim, "purpose", self.time).and_then(|v| stage::string_of(&v))
        {
            if !self.purposes.contains(&p) {
                return Ok(());
            }
        }
        // Materials, shaders and render prims are read where they are used.
        if matches!(
            ty.as_str(),
            "Material"
                | "Shader"
                | "NodeGraph"
                | "RenderSettings"
                | "RenderProduct"
                | "RenderVar"
                | "RenderPass"
                | "GeomSubset"
        ) {
            return Ok(());
        }
        let (local, resets) =
            stage::local_transform(prim, self.time).map_err(|e| self.error(prim, e))?;
        let base = if resets {
            if ctx.prototype {
                Affine3A::IDENTITY
            } else {
                self.root
            }
        } else {
            parent
        };
        let world = base * local;
        let name = stage::name_of(prim.path());
        let mut below = ctx.clone();
        below.tags.extend(geometry::object_tags(prim, self.time));
        below.tags.dedup();
        if prim.is_instance().unwrap_or(false) {
            if let Some(proto) = prim.prototype().ok().flatten() {
                let objects = self.prototype(&proto.to_string(), &below, &name)?;
                for o in objects.iter() {
                    let mut o = o.clone();
                    o.transform = world * o.transform;
                    if ctx.ancestors.is_empty() {
                        o.asset = Some(name.clone());
                    }
                    out.push(o);
                }
                return Ok(());
            }
        }
        match ty.as_str() {
            "Mesh" | "Sphere" | "Cube" | "Cylinder" | "Cone" | "Plane" | "Capsule" => {
                self.gprim(prim, &ty, world, &below, out)?;
            }
            "PointInstancer" => {
                self.point_instancer(prim, world, &below, out)?;
                return Ok(());
            }
            "Camera" if !ctx.prototype => self.camera(prim, world),
            "RectLight" | "DiskLight" | "SphereLight" | "DistantLight" | "DomeLight"
            | "DomeLight_1" | "CylinderLight"
                if !ctx.prototype =>
            {
                self.light(prim, &ty, world)?;
            }
            "PortalLight" if !ctx.prototype => self.portal(prim, world),
            "RectLight" | "DiskLight" | "SphereLight" | "DistantLight" | "DomeLight"
            | "DomeLight_1" | "CylinderLight" | "PortalLight" | "Camera" => {
                self.warn(prim, "lights and cameras inside instances are not read");
            }
            "" | "Xform" | "Scope" | "SkelRoot" => {}
            other => {
                let key = format!("type {other}");
                self.warn_once(
                    &key,
                    prim,
                    format!("prims of type {other} are not rendered (this one and any others)"),
                );
            }
        }
        below.ancestors.push(name);
        let children = prim
            .children()
            .map_err(|e| self.error(prim, format!("{e:#}")))?;
        for child in children {
            self.walk(&child, world, &below, out)?;
        }
        Ok(())
    }

    /// The objects of a prototype (an instance's, or a point instancer's prototype prim),
    /// placed relative to it, read once.
    fn prototype(
        &mut self,
        path: &str,
        ctx: &Context,
        name: &str,
    ) -> Result<Arc<Vec<ObjectDesc>>, SceneError> {
        if let Some(p) = self.prototypes.get(path) {
            return Ok(p.clone());
        }
        let prim = self.stage.prim(path);
        let mut inner = ctx.clone();
        inner.prototype = true;
        inner.ancestors.push(name.to_string());
        let mut out = Vec::new();
        let children = prim
            .children()
            .map_err(|e| self.error(&prim, format!("{e:#}")))?;
        for child in children {
            self.walk(&child, Affine3A::IDENTITY, &inner, &mut out)?;
        }
        let out = Arc::new(out);
        self.prototypes.insert(path.to_string(), out.clone());
        Ok(out)
    }

    /// The world direction of a local vector, normalised.
    fn direction(world: &Affine3A, local: Vec3A) -> [f32; 3] {
        world.transform_vector3a(local).normalize_or(local).into()
    }
}

#[cfg(test)]
mod tests;
