//! Materials: a `UsdPreviewSurface` network (with `UsdUVTexture` and
//! `UsdPrimvarReader_float2` nodes) on the OpenPBR material, as the glTF loader maps
//! glTF's PBR (both are the same metallic-roughness model). Any other surface (MaterialX,
//! a renderer's own shaders) falls back to the prim's displayColor, with one warning
//! naming the material.
//!
//! | UsdPreviewSurface | OpenPBR |
//! |---|---|
//! | diffuseColor | base_color |
//! | metallic | base_metalness |
//! | roughness | specular_roughness |
//! | ior | specular_ior |
//! | clearcoat, clearcoatRoughness | coat_weight, coat_roughness (coat ior 1.5, no darkening) |
//! | useSpecularWorkflow = 1, specularColor | F0 = specularColor, white at grazing: specular_ior from its brightest channel, specular_color the rest, tinting F0 only (metalness 0; `ior` not used for it) |
//! | emissiveColor | the object's emission (a glowing surface, `O`) |
//! | opacity (a texture too), opacityThreshold | geometry_opacity, presence (docs/lpe.md#presence); with a threshold > 0 a cut-out: present where opacity ≥ threshold |
//! | normal (a UsdUVTexture, scale 2 bias −1) | the tangent-space normal map |
//!
//! A texture multiplies its input by its `scale` (its `bias` is honoured only as the
//! normal map's −1); `sourceColorSpace` `raw` reads colours linearly, `sRGB` and `auto`
//! (for 8-bit images) decode sRGB; `wrapS`/`wrapT` `repeat`, `clamp`, `mirror` (`black`
//! clamps, with a warning). USD's `st` has its origin at the image's bottom-left corner;
//! Lightpath's at the top-left, so `t` is flipped when the mesh is read.

use super::{stage, Loader};
use crate::material::openpbr::{self, InputMut, OpenPbr};
use crate::material::texture::{UvTransform, Wrap};
use crate::scene::desc::{
    ImageSource, InputTexture, MaterialDesc, MaterialKind, TextureDesc, TexturesDesc,
};
use crate::scene::SceneError;
use glam::Vec3A;
use openusd::schemas::shade::MaterialBindingAPI;
use openusd::usd::Prim;
use std::path::PathBuf;

/// Reflectance at normal incidence of index 1.5.
const F0_OF_1_5: f32 = 0.04;

/// The index of refraction whose reflectance at normal incidence is `f0` (below 1).
fn ior_of_f0(f0: f32) -> f32 {
    let r = f0.sqrt();
    (1.0 + r) / (1.0 - r)
}

/// A texture on OpenPBR number `input` in [0, 1]: its scale in the texture's channel is the
/// input's factor.
fn number_input(p: &mut OpenPbr, textures: &mut TexturesDesc, input: &'static str, tex: Texture) {
    if let Some(InputMut::Scalar(v)) = openpbr::input(input).map(|i| (i.get)(p)) {
        *v = tex.scale[tex.channel as usize].clamp(0.0, 1.0);
    }
    textures
        .inputs
        .push(input_texture(input, tex.desc, tex.channel, false));
}

/// A `UsdUVTexture` as an input reads it.
struct Texture {
    desc: TextureDesc,
    /// The channel an output reads (0 r … 3 a; `rgb` reads 0).
    channel: u8,
    srgb: bool,
    scale: [f32; 4],
    bias: [f32; 4],
}

/// The fallback colour of a prim without displayColor (Hydra's).
const FALLBACK_GREY: [f32; 3] = [0.5, 0.5, 0.5];

impl Loader {
    /// The material a gprim renders with: its bound material, else its displayColor.
    pub(super) fn surface_material(
        &mut self,
        prim: &Prim,
        display: Option<[f32; 3]>,
    ) -> Result<String, SceneError> {
        if let Some(path) = self.bound_material_path(prim) {
            let name = self.material(&path, prim)?;
            if self.desc.materials.contains_key(&name) {
                return Ok(name);
            }
        }
        Ok(self.display_material(display.unwrap_or(FALLBACK_GREY), prim))
    }

    /// A diffuse material of a displayColor (vertex colours multiply it).
    fn display_material(&mut self, color: [f32; 3], prim: &Prim) -> String {
        let name = format!("displayColor({}, {}, {})", color[0], color[1], color[2]);
        if !self.desc.materials.contains_key(&name) {
            let p = OpenPbr {
                base_color: Vec3A::from(color).max(Vec3A::ZERO),
                specular_weight: 0.0,
                ..OpenPbr::default()
            };
            self.desc.materials.insert(
                name.clone(),
                material_desc(p, 1.0, TexturesDesc::default(), self.origin(prim)),
            );
        }
        name
    }

    /// The material bound to a prim (purpose `full`, else all-purpose), walking its
    /// ancestors as UsdShade resolves bindings.
    pub(super) fn bound_material_path(&self, prim: &Prim) -> Option<String> {
        if let Ok(Some(api)) = MaterialBindingAPI::get(&self.stage, prim.path().clone()) {
            if let Ok(Some(m)) = api.compute_bound_material("full") {
                return Some(m.to_string());
            }
        }
        // Without the API on the prim itself: the nearest direct binding up the tree.
        let mut cur = Some(prim.path().clone());
        while let Some(p) = cur {
            if p.is_abs_root() {
                break;
            }
            let here = self.stage.prim(p.clone());
            for rel in ["material:binding:full", "material:binding"] {
                if let Ok(t) = here.relationship(rel).targets() {
                    if let Some(first) = t.into_iter().next() {
                        return Some(first.to_string());
                    }
                }
            }
            cur = p.parent();
        }
        None
    }

    /// The scene material of a USD material prim, made once (its name: its path). An
    /// unsupported network gives the displayColor material of `user`, with a warning.
    pub(super) fn material(&mut self, path: &str, user: &Prim) -> Result<String, SceneError> {
        if let Some(name) = self.materials.get(path) {
            return Ok(name.clone());
        }
        let material = self.stage.prim(path);
        let surface = self.surface_shader(&material);
        let name = match surface {
            Some(shader) if shader_id(&shader) == "UsdPreviewSurface" => {
                let desc = self.preview_surface(&material, &shader)?;
                self.desc.materials.insert(path.to_string(), desc);
                path.to_string()
            }
            other => {
                let what = match other {
                    Some(s) => format!("its surface shader {} is {}", s.path(), {
                        let id = shader_id(&s);
                        if id.is_empty() {
                            "of no known id".to_string()
                        } else {
                            format!("'{id}'")
                        }
                    }),
                    None => "it has no surface output connected to a shader".to_string(),
                };
                self.warn_once(
                    &format!("material {path}"),
                    &material,
                    format!(
                        "material {path}: {what}; only UsdPreviewSurface networks are read, so \
                         its objects render with their displayColor"
                    ),
                );
                let display = self.display_color_of(user);
                let name = self.display_material(display.unwrap_or(FALLBACK_GREY), user);
                // Each user keeps its own displayColor: not cached by material.
                return Ok(name);
            }
        };
        self.materials.insert(path.to_string(), name.clone());
        Ok(name)
    }

    fn display_color_of(&self, prim: &Prim) -> Option<[f32; 3]> {
        // A subset's displayColor is its mesh's.
        let target = if stage::type_of(prim) == "GeomSubset" {
            self.stage.prim(prim.path().parent()?)
        } else {
            prim.clone()
        };
        stage::value(&target, "primvars:displayColor", self.time)
            .and_then(stage::vec3_array)
            .and_then(|c| c.first().copied())
    }

    /// The shader the material's surface output connects to (the universal render
    /// context's output, else any context's).
    fn surface_shader(&self, material: &Prim) -> Option<Prim> {
        let mut names = vec!["outputs:surface".to_string()];
        if let Ok(props) = material.property_names() {
            names.extend(
                props
                    .iter()
                    .map(|p| p.as_str().to_string())
                    .filter(|p| p.starts_with("outputs:") && p.ends_with(":surface")),
            );
        }
        for n in names {
            if let Some(p) = self.source_of(material, &n) {
                return Some(p.0);
            }
        }
        None
    }

    /// Follows a connection (through node graphs' interface outputs and inputs) to the
    /// shader prim that produces it, and the output's name.
    fn source_of(&self, prim: &Prim, attr: &str) -> Option<(Prim, String)> {
        let mut prim = prim.clone();
        let mut attr = attr.to_string();
        for _ in 0..16 {
            let target = prim
                .attribute(attr.as_str())
                .connections()
                .ok()?
                .into_iter()
                .next()?;
            let owner = self.stage.prim(target.prim_path());
            let out = target.name().unwrap_or_default().to_string();
            let ty = stage::type_of(&owner);
            if ty == "Shader" {
                return Some((owner, out));
            }
            // A NodeGraph or Material output or input: follow its own connection.
            prim = owner;
            attr = out;
        }
        None
    }

    fn preview_surface(
        &mut self,
        material: &Prim,
        shader: &Prim,
    ) -> Result<MaterialDesc, SceneError> {
        let t = self.time;
        let num = |n: &str, d: f32| {
            stage::value(shader, &format!("inputs:{n}"), t)
                .and_then(|v| stage::f32_of(&v))
                .filter(|x| x.is_finite())
                .unwrap_or(d)
        };
        let color = |n: &str, d: [f32; 3]| {
            stage::value(shader, &format!("inputs:{n}"), t)
                .and_then(|v| stage::vec3_of(&v))
                .filter(|c| c.iter().all(|x| x.is_finite()))
                .unwrap_or(d)
                .map(|x| x.max(0.0))
        };
        let specular_workflow = num("useSpecularWorkflow", 0.0) != 0.0;
        let opacity = num("opacity", 1.0).clamp(0.0, 1.0);
        let roughness = num("roughness", 0.5).clamp(0.0, 1.0);
        let mut p = OpenPbr {
            base_color: Vec3A::from(color("diffuseColor", [0.18; 3])),
            base_metalness: if specular_workflow {
                0.0
            } else {
                num("metallic", 0.0).clamp(0.0, 1.0)
            },
            specular_roughness: roughness,
            specular_ior: num("ior", 1.5).max(1.0),
            coat_weight: num("clearcoat", 0.0).clamp(0.0, 1.0),
            coat_roughness: num("clearcoatRoughness", 0.01).clamp(0.0, 1.0),
            coat_ior: 1.5,
            coat_darkening: 0.0,
            // UsdPreviewSurface's opacity is coverage, not glass (Cycles' USD import
            // makes it the Principled alpha): presence.
            geometry_opacity: opacity,
            ..OpenPbr::default()
        };
        if specular_workflow {
            // specularColor is the reflectance at normal incidence, white at grazing: a
            // tint on F0 only, over the index whose F0 is its brightest channel.
            let f0 = Vec3A::from(color("specularColor", [0.0; 3]));
            let top = f0.max_element().min(0.999);
            p.specular_color_f0_only = true;
            if top > 0.0 {
                p.specular_ior = ior_of_f0(top);
                p.specular_color = f0 / top;
            } else {
                p.specular_weight = 0.0;
            }
        }
        let mut textures = TexturesDesc::default();
        // With a threshold, a cut-out: present where opacity ≥ it, absent elsewhere.
        let threshold = num("opacityThreshold", 0.0);
        if threshold > 0.0 {
            textures.opacity_cutoff = Some(threshold.min(1.0));
        }
        let mut inputs = Vec::new();
        for input in [
            "diffuseColor",
            "metallic",
            "roughness",
            "normal",
            "emissiveColor",
            "clearcoat",
            "clearcoatRoughness",
            "opacity",
            "specularColor",
            "occlusion",
            "displacement",
            "ior",
        ] {
            let Some((node, output)) = self.source_of(shader, &format!("inputs:{input}")) else {
                continue;
            };
            let id = shader_id(&node);
            if id != "UsdUVTexture" {
                self.warn_once(
                    &format!("input {} {input}", material.path()),
                    &node,
                    format!(
                        "material {}: its {input} is connected to a '{id}' node, which is not read \
                         (its authored value is used)",
                        material.path()
                    ),
                );
                continue;
            }
            let tex = self.uv_texture(&node, &output)?;
            inputs.push((input, tex));
        }
        let emissive =
            self.textured_inputs(material, inputs, specular_workflow, &mut p, &mut textures);
        let emissive = emissive.unwrap_or_else(|| color("emissiveColor", [0.0; 3]));
        if emissive != [0.0; 3] {
            self.emissive.insert(material.path().to_string(), emissive);
        }
        Ok(material_desc(p, roughness, textures, self.origin(material)))
    }

    /// Each texture on its OpenPBR input (its `scale` the input's factor); returns the
    /// emission factor when `emissiveColor` is textured.
    fn textured_inputs(
        &mut self,
        material: &Prim,
        inputs: Vec<(&str, Texture)>,
        specular_workflow: bool,
        p: &mut OpenPbr,
        textures: &mut TexturesDesc,
    ) -> Option<[f32; 3]> {
        let mut emissive = None;
        for (input, tex) in inputs {
            let s = tex.scale;
            match input {
                "diffuseColor" => {
                    p.base_color = Vec3A::new(s[0], s[1], s[2]).max(Vec3A::ZERO);
                    if tex.srgb {
                        textures.base_color = Some(tex.desc);
                    } else {
                        textures
                            .inputs
                            .push(input_texture("base_color", tex.desc, 0, false));
                    }
                }
                "metallic" if !specular_workflow => {
                    number_input(p, textures, "base_metalness", tex)
                }
                "roughness" => number_input(p, textures, "specular_roughness", tex),
                "clearcoat" => number_input(p, textures, "coat_weight", tex),
                "clearcoatRoughness" => number_input(p, textures, "coat_roughness", tex),
                "specularColor" if specular_workflow => {
                    // The texture's F0 as a tint on the F0 of index 1.5.
                    p.specular_ior = 1.5;
                    p.specular_weight = 1.0;
                    p.specular_color = Vec3A::new(s[0], s[1], s[2]).max(Vec3A::ZERO) / F0_OF_1_5;
                    textures
                        .inputs
                        .push(input_texture("specular_color", tex.desc, 0, tex.srgb));
                }
                "emissiveColor" => {
                    emissive = Some([s[0], s[1], s[2]]);
                    textures.emissive = Some(tex.desc);
                }
                "normal" => {
                    // The usual encoding: scale 2, bias −1 (a strength other than 1 scales xy).
                    let strength = if (s[0] - 2.0).abs() < 1e-3 && (tex.bias[0] + 1.0).abs() < 1e-3
                    {
                        1.0
                    } else {
                        self.warn_once(
                            &format!("normal {}", material.path()),
                            material,
                            format!(
                                "material {}: a normal map without scale 2 and bias −1 is read as one with them",
                                material.path()
                            ),
                        );
                        1.0
                    };
                    textures.normal = Some((tex.desc, strength));
                }
                "opacity" => number_input(p, textures, "geometry_opacity", tex),
                other => self.warn_once(
                    &format!("input {} {other}", material.path()),
                    material,
                    format!(
                        "material {}: a texture on {other} is not read",
                        material.path()
                    ),
                ),
            }
        }
        emissive
    }

    /// A `UsdUVTexture` node read through one of its outputs.
    fn uv_texture(&mut self, node: &Prim, output: &str) -> Result<Texture, SceneError> {
        let t = self.time;
        let file = stage::value(node, "inputs:file", t);
        let asset = match &file {
            Some(openusd::sdf::Value::AssetPath(a)) => a.clone(),
            _ => return Err(self.error(node, "a UsdUVTexture without inputs:file")),
        };
        let image = self.image(node, &asset)?;
        let wrap = |n: &str, me: &mut Loader| match stage::value(node, n, t)
            .and_then(|v| stage::string_of(&v))
            .as_deref()
        {
            Some("clamp") => Wrap::Clamp,
            Some("mirror") => Wrap::Mirror,
            Some("black") => {
                me.warn_once(
                    &format!("black {}", node.path()),
                    node,
                    "wrap 'black' is read as 'clamp'",
                );
                Wrap::Clamp
            }
            _ => Wrap::Repeat,
        };
        let wrap = [wrap("inputs:wrapS", self), wrap("inputs:wrapT", self)];
        let four = |n: &str, d: [f32; 4]| {
            stage::value(node, n, t)
                .and_then(|v| stage::vec4_of(&v))
                .filter(|c| c.iter().all(|x| x.is_finite()))
                .unwrap_or(d)
        };
        let scale = four("inputs:scale", [1.0; 4]);
        let bias = four("inputs:bias", [0.0; 4]);
        let space = stage::value(node, "inputs:sourceColorSpace", t)
            .and_then(|v| stage::string_of(&v))
            .unwrap_or_else(|| "auto".into());
        let channel = match output.trim_start_matches("outputs:") {
            "g" => 1,
            "b" => 2,
            "a" => 3,
            _ => 0,
        };
        // `auto`: 8-bit images are sRGB, float images (EXR) linear.
        let linear_file = asset.asset_path().to_ascii_lowercase().ends_with(".exr");
        let srgb = match space.as_str() {
            "raw" => false,
            "sRGB" => true,
            _ => !linear_file,
        };
        let transform = self.uv_transform(node);
        Ok(Texture {
            desc: TextureDesc {
                image,
                wrap,
                transform,
                origin: self.origin(node),
            },
            channel,
            srgb,
            scale,
            bias,
        })
    }

    /// A `UsdTransform2d` between the texture and its primvar reader, if any.
    fn uv_transform(&mut self, node: &Prim) -> UvTransform {
        let Some((t2d, _)) = self.source_of(node, "inputs:st") else {
            return UvTransform::default();
        };
        if shader_id(&t2d) != "UsdTransform2d" {
            return UvTransform::default();
        }
        let t = self.time;
        let two = |n: &str, d: [f32; 2]| {
            stage::value(&t2d, n, t)
                .and_then(|v| stage::vec2_of(&v))
                .unwrap_or(d)
        };
        let rotation = stage::value(&t2d, "inputs:rotation", t)
            .and_then(|v| stage::f32_of(&v))
            .unwrap_or(0.0);
        // USD's transform is of st (origin bottom-left, rotation counter-clockwise in
        // degrees); glTF's (which UvTransform follows) of uv with v down.
        let [tx, ty] = two("inputs:translation", [0.0; 2]);
        let [sx, sy] = two("inputs:scale", [1.0; 2]);
        if rotation != 0.0 {
            self.warn_once(
                &format!("t2d {}", t2d.path()),
                &t2d,
                "the rotation of a UsdTransform2d is not read",
            );
        }
        UvTransform::new([tx, 1.0 - sy - ty], 0.0, [sx, sy])
    }

    /// The image an asset path names: a file, or the bytes of a file inside a .usdz.
    fn image(
        &mut self,
        node: &Prim,
        asset: &openusd::sdf::AssetPath,
    ) -> Result<ImageSource, SceneError> {
        let resolved = asset.resolved_path().map(str::to_string).or_else(|| {
            use openusd::ar::Resolver;
            let r = openusd::ar::DefaultResolver::new();
            r.resolve(asset.asset_path())
                .map(|p| p.to_string_lossy().into_owned())
        });
        let Some(resolved) = resolved.filter(|r| !r.is_empty()) else {
            return Err(self.error(
                node,
                format!(
                    "inputs:file: the texture '{}' cannot be found",
                    asset.asset_path()
                ),
            ));
        };
        if openusd::ar::is_package_relative_path(&resolved) {
            use openusd::ar::Resolver;
            let r = super::stage::LimitedResolver(openusd::ar::DefaultResolver::new());
            let bytes = r
                .open_asset(&openusd::ar::ResolvedPath::new(&resolved))
                .and_then(|mut a| a.read_all())
                .map_err(|e| {
                    self.error(node, format!("inputs:file: cannot read '{resolved}': {e}"))
                })?;
            return Ok(ImageSource::Bytes {
                name: resolved,
                bytes: bytes.into(),
            });
        }
        let path = PathBuf::from(&resolved);
        if !path.is_file() {
            return Err(self.error(
                node,
                format!(
                    "inputs:file: the texture '{}' does not exist",
                    path.display()
                ),
            ));
        }
        Ok(ImageSource::File(path))
    }
}

fn shader_id(shader: &Prim) -> String {
    stage::value(shader, "info:id", openusd::usd::TimeCode::new(0.0))
        .and_then(|v| stage::string_of(&v))
        .unwrap_or_default()
}

fn material_desc(
    p: OpenPbr,
    roughness: f32,
    textures: TexturesDesc,
    origin: crate::scene::desc::Origin,
) -> MaterialDesc {
    MaterialDesc {
        kind: MaterialKind::OpenPbr(Box::new(p)),
        roughness,
        user_color: None,
        textures,
        base_color_map: None,
        normal_map: None,
        origin,
    }
}

fn input_texture(input: &str, texture: TextureDesc, channel: u8, srgb: bool) -> InputTexture {
    InputTexture {
        input: openpbr::input(input)
            .expect("UsdPreviewSurface maps to OpenPBR inputs")
            .name,
        texture,
        channel,
        srgb,
        exponent: 1.0,
    }
}
