//! OBJ files with their MTL materials (docs/scene-format.md, "OBJ and MTL").
//!
//! Every `o` or `g` statement starts an object: its name is the object's LPE group (the
//! names of a `g` line each, plus the enclosing `o` name, like a collection), and each
//! material used in it makes one part (one scene object of that name). MTL properties
//! become the renderer's materials as `mtl_material` documents; a material with `Ke`
//! makes each part that uses it a mesh light named after its object.
//!
//! Errors name the file, the line and column, and what was expected; the file is read
//! as bytes, so a binary file (a `.glb` or a PLY given as an OBJ) is recognised and said.

use super::defaults;
use super::text::{self, Line};
use crate::scene::desc::{
    MaterialDesc, MaterialKind, MeshData, NameRef, ObjectDesc, Origin, SceneDesc, ShapeDesc,
    TextureRef,
};
use crate::scene::SceneError;
use glam::Affine3A;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// The material of faces that name none (or one no MTL file defines).
pub const DEFAULT_MATERIAL: &str = "(default)";

/// An OBJ file as a scene: its objects with their materials, and a mesh light for each
/// part whose material has `Ke`. No camera (the caller decides on a default).
/// `at` is where the file was named, for an error opening it.
pub fn load_scene(path: &Path, at: &Origin) -> Result<SceneDesc, SceneError> {
    let file = path.display().to_string();
    let bytes = text::read(path, at, "OBJ")?;
    let obj = parse(&bytes, &file, path)?;
    let mut desc = SceneDesc {
        source: file.clone(),
        ..SceneDesc::default()
    };
    let mut warnings = obj.warnings;
    let mtls = load_mtllibs(path, &obj.mtllibs, &mut warnings)?;
    let mut used: BTreeMap<String, Origin> = BTreeMap::new();
    for part in obj.parts {
        let material = match &part.material {
            Some((name, at)) if mtls.contains_key(name) => {
                used.entry(name.clone()).or_insert_with(|| at.clone());
                name.clone()
            }
            Some((name, at)) => {
                warnings.push(format!(
                    "{at}: material '{name}' is defined in no MTL file; using a grey diffuse"
                ));
                DEFAULT_MATERIAL.to_string()
            }
            None => DEFAULT_MATERIAL.to_string(),
        };
        let emission = mtls.get(&material).and_then(|m| m.emission());
        let object = ObjectDesc {
            name: Some(part.name.clone()),
            shape_name: "obj".into(),
            shape: ShapeDesc::Mesh {
                parts: vec![part.mesh],
            },
            transform: Affine3A::IDENTITY,
            material: Some(NameRef {
                name: material.clone(),
                origin: part.origin.clone(),
            }),
            lpegroups: Some(part.groups.clone()),
            emission: None,
            holdout: false,
            visible_camera: true,
            visible_indirect: true,
            casts_shadows: true,
            asset: None,
            origin: part.origin.clone(),
        };
        if let Some((ke, at)) = emission {
            desc.lights
                .push(defaults::mesh_light(desc.objects.len(), &part.name, ke, at));
        }
        desc.objects.push(object);
    }
    for (name, m) in &mtls {
        if used.contains_key(name) {
            desc.materials
                .insert(name.clone(), m.desc(name, &mut warnings));
        }
    }
    if desc.objects.iter().any(|o| {
        o.material
            .as_ref()
            .is_some_and(|m| m.name == DEFAULT_MATERIAL)
    }) {
        desc.materials
            .insert(DEFAULT_MATERIAL.into(), default_material(&file));
    }
    desc.warnings = warnings;
    Ok(desc)
}

/// The meshes of an OBJ file, for a TOML object of `shape = "obj"` (its materials are
/// the TOML's); `at` is where the file was named, for an error opening it.
pub fn load_meshes(path: &Path, at: &Origin) -> Result<Vec<MeshData>, SceneError> {
    let bytes = text::read(path, at, "OBJ")?;
    let obj = parse(&bytes, &path.display().to_string(), path)?;
    Ok(obj.parts.into_iter().map(|p| p.mesh).collect())
}

fn default_material(file: &str) -> MaterialDesc {
    MaterialDesc {
        kind: MaterialKind::Diffuse { albedo: [0.8; 3] },
        roughness: 0.0,
        user_color: None,
        base_color_map: None,
        normal_map: None,
        textures: Default::default(),
        origin: Origin::file(file),
    }
}

/// One object's faces of one material, as a mesh with its own vertex list.
struct Part {
    name: String,
    groups: Vec<String>,
    /// The `usemtl` name and where it was written.
    material: Option<(String, Origin)>,
    /// Where the object (or its first face) was written.
    origin: Origin,
    mesh: MeshData,
    /// (position, uv, normal) indices of the file → index in `mesh`.
    remap: HashMap<(u32, u32, u32), u32>,
    /// Vertices with a normal and without one; a part with both drops its normals.
    with_normal: usize,
    without_normal: usize,
    with_uv: usize,
}

struct Obj {
    parts: Vec<Part>,
    mtllibs: Vec<(String, Origin)>,
    warnings: Vec<String>,
}

/// Where an object's `o` and `g` names were written.
#[derive(Clone, Default)]
struct Naming {
    o: Option<String>,
    g: Vec<String>,
    origin: Option<Origin>,
}

impl Naming {
    fn name(&self, stem: &str) -> String {
        if !self.g.is_empty() {
            self.g.join(" ")
        } else {
            self.o.clone().unwrap_or_else(|| stem.to_string())
        }
    }

    fn groups(&self, stem: &str) -> Vec<String> {
        let mut groups = self.g.clone();
        if let Some(o) = &self.o {
            if !groups.contains(o) {
                groups.push(o.clone());
            }
        }
        if groups.is_empty() {
            groups.push(stem.to_string());
        }
        groups
    }
}

const NONE: u32 = u32::MAX;

fn parse(bytes: &[u8], file: &str, path: &Path) -> Result<Obj, SceneError> {
    text::not_binary(bytes, file, "OBJ")?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "obj".into());
    let mut reader = Reader::new(stem);
    for line in text::lines(bytes, file) {
        reader.statement(&line)?;
    }
    reader.finish(file)
}

/// What reading an OBJ file has gathered so far, one statement at a time.
struct Reader {
    /// The file's name without extension: the object name when it gives none.
    stem: String,
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    obj: Obj,
    naming: Naming,
    /// Bumped by each `o`/`g`, so parts of one object share it.
    object_id: u32,
    material: Option<(String, Origin)>,
    part_of: HashMap<(u32, Option<String>), usize>,
    /// Statements read but not rendered, by kind: how many, and the first one.
    skipped: BTreeMap<&'static str, (usize, Origin)>,
    /// The first word that is no OBJ statement, for the error of a file with no faces.
    first_unknown: Option<(String, Origin)>,
    /// The current face's vertices (kept to reuse its allocation).
    face: Vec<u32>,
}

impl Reader {
    fn new(stem: String) -> Reader {
        Reader {
            stem,
            positions: Vec::new(),
            normals: Vec::new(),
            uvs: Vec::new(),
            obj: Obj {
                parts: Vec::new(),
                mtllibs: Vec::new(),
                warnings: Vec::new(),
            },
            naming: Naming::default(),
            object_id: 0,
            material: None,
            part_of: HashMap::new(),
            skipped: BTreeMap::new(),
            first_unknown: None,
            face: Vec::new(),
        }
    }

    fn statement(&mut self, line: &Line) -> Result<(), SceneError> {
        let mut words = line.words();
        let Some(keyword) = words.next() else {
            return Ok(());
        };
        match keyword.text {
            "v" => self.positions.push(line.vec3(words, keyword, "vertex")?),
            "vn" => self.normals.push(line.vec3(words, keyword, "normal")?),
            "vt" => {
                let u = line.number(words.next(), keyword, "texture coordinate u")?;
                let v = match words.next() {
                    Some(w) => line.number(Some(w), keyword, "texture coordinate v")?,
                    None => 0.0,
                };
                // Our UVs put (0, 0) at the image's top-left corner (glTF's
                // convention); OBJ's v runs up from the bottom.
                self.uvs.push([u, 1.0 - v]);
            }
            "f" => self.face(line, keyword, words)?,
            "o" | "g" => {
                let names: Vec<String> = words.map(|w| w.text.to_string()).collect();
                if keyword.text == "o" {
                    self.naming.o = (!names.is_empty()).then(|| names.join(" "));
                    self.naming.g.clear();
                } else {
                    self.naming.g = names;
                }
                self.naming.origin = Some(line.origin(keyword));
                self.object_id += 1;
            }
            "usemtl" => {
                let name = line.rest_after(keyword);
                self.material =
                    (!name.is_empty()).then(|| (name.to_string(), line.origin(keyword)));
            }
            "mtllib" => {
                let rest = line.rest_after(keyword);
                if !rest.is_empty() {
                    self.obj
                        .mtllibs
                        .push((rest.to_string(), line.origin(keyword)));
                }
            }
            "l" | "p" => self.skip("lines and points", line.origin(keyword)),
            "vp" | "cstype" | "deg" | "bmat" | "step" | "curv" | "curv2" | "surf" | "parm"
            | "trim" | "hole" | "scrv" | "sp" | "end" | "con" => {
                self.skip("free-form curves and surfaces", line.origin(keyword))
            }
            "s" | "mg" | "lod" | "bevel" | "c_interp" | "d_interp" | "shadow_obj" | "trace_obj"
            | "ctech" | "stech" | "usemap" | "maplib" => {}
            other => {
                if self.first_unknown.is_none() {
                    self.first_unknown = Some((other.to_string(), line.origin(keyword)));
                }
            }
        }
        Ok(())
    }

    fn skip(&mut self, what: &'static str, at: Origin) {
        self.skipped.entry(what).or_insert((0, at)).0 += 1;
    }

    /// The part that faces of the current object and material go to, made on first use.
    fn current_part(&mut self, at: impl FnOnce() -> Origin) -> usize {
        let key = (self.object_id, self.material.as_ref().map(|m| m.0.clone()));
        *self.part_of.entry(key).or_insert_with(|| {
            self.obj.parts.push(Part {
                name: self.naming.name(&self.stem),
                groups: self.naming.groups(&self.stem),
                material: self.material.clone(),
                origin: self.naming.origin.clone().unwrap_or_else(at),
                mesh: MeshData::default(),
                remap: HashMap::new(),
                with_normal: 0,
                without_normal: 0,
                with_uv: 0,
            });
            self.obj.parts.len() - 1
        })
    }

    /// An `f` statement: its corners join the current part's vertices (one per distinct
    /// position/uv/normal triple) and the polygon becomes a fan of triangles.
    fn face<'w>(
        &mut self,
        line: &Line,
        keyword: text::Word,
        words: impl Iterator<Item = text::Word<'w>>,
    ) -> Result<(), SceneError> {
        let part = self.current_part(|| line.origin(keyword));
        let part = &mut self.obj.parts[part];
        let face = &mut self.face;
        face.clear();
        let mut n = 0;
        for w in words {
            n += 1;
            let mut fields = w.text.split('/');
            let index = |s: Option<&str>, count: usize, what: &str| line.index(s, count, w, what);
            let v = index(fields.next(), self.positions.len(), "vertex")?;
            if v == NONE {
                return Err(line.origin(w).error(format!(
                    "expected a vertex index first in '{}' (like 3, 3/1 or 3//2)",
                    w.text
                )));
            }
            let vt = index(fields.next(), self.uvs.len(), "texture coordinate")?;
            let vn = index(fields.next(), self.normals.len(), "normal")?;
            let next = part.mesh.positions.len() as u32;
            let id = *part.remap.entry((v, vt, vn)).or_insert(next);
            if id == next {
                let m = &mut part.mesh;
                m.positions.push(self.positions[v as usize]);
                let nrm = self.normals.get(vn as usize).copied();
                part.with_normal += usize::from(nrm.is_some());
                part.without_normal += usize::from(nrm.is_none());
                m.normals
                    .get_or_insert_with(Vec::new)
                    .push(nrm.unwrap_or_default());
                let uv = self.uvs.get(vt as usize).copied();
                part.with_uv += usize::from(uv.is_some());
                m.uvs
                    .get_or_insert_with(Vec::new)
                    .push(uv.unwrap_or_default());
            }
            face.push(id);
        }
        if n < 3 {
            return Err(line
                .origin(keyword)
                .error(format!("a face needs at least 3 vertices, found {n}")));
        }
        // A fan, as tobj and Blender triangulate convex polygons.
        for k in 1..face.len() - 1 {
            part.mesh.indices.push([face[0], face[k], face[k + 1]]);
        }
        Ok(())
    }

    /// The parts with faces, each keeping normals and UVs only if all its vertices have
    /// them; an error if the file has no faces at all.
    fn finish(self, file: &str) -> Result<Obj, SceneError> {
        let mut obj = self.obj;
        for (what, (count, at)) in self.skipped {
            obj.warnings.push(format!(
                "{at}: {count} statements of {what} skipped (only faces render)"
            ));
        }
        obj.parts.retain(|p| !p.mesh.indices.is_empty());
        if obj.parts.is_empty() {
            let hint = match self.first_unknown {
                Some((word, at)) => format!(
                    "; {at} starts with '{word}', which is no OBJ statement: is this an OBJ file?"
                ),
                None => String::new(),
            };
            return Err(Origin::file(file).error(format!("the OBJ file has no faces{hint}")));
        }
        for p in &mut obj.parts {
            p.remap = HashMap::new();
            if p.with_normal == 0 || p.without_normal > 0 {
                p.mesh.normals = None;
            }
            if p.with_uv == 0 {
                p.mesh.uvs = None;
            }
        }
        Ok(obj)
    }
}

impl Line<'_> {
    /// A 1-based (or negative, relative) OBJ index among `count` items, 0-based; an
    /// empty or absent field is `NONE`.
    fn index(
        &self,
        field: Option<&str>,
        count: usize,
        word: text::Word,
        what: &str,
    ) -> Result<u32, SceneError> {
        let Some(s) = field.filter(|s| !s.is_empty()) else {
            return Ok(NONE);
        };
        let at = || self.origin(word);
        let i: i64 = s.parse().map_err(|_| {
            at().error(format!(
                "expected a {what} index in '{}', found '{s}'",
                word.text
            ))
        })?;
        let resolved = if i < 0 { count as i64 + i } else { i - 1 };
        if i == 0 || resolved < 0 || resolved >= count as i64 {
            let plural = match what {
                "vertex" => "vertices".to_string(),
                _ => format!("{what}s"),
            };
            return Err(at().error(format!(
                "{what} index {i} is out of range: the file defines {count} {plural} before this line"
            )));
        }
        Ok(resolved as u32)
    }
}

/// One `newmtl` of an MTL file, as written.
#[derive(Clone, Debug)]
struct Mtl {
    origin: Origin,
    kd: [f32; 3],
    ks: [f32; 3],
    ke: Option<([f32; 3], Origin)>,
    tf: Option<[f32; 3]>,
    ns: Option<f32>,
    ni: Option<f32>,
    /// Opacity: `d`, or 1 − `Tr`.
    d: f32,
    illum: Option<u32>,
    /// The PBR extension's roughness and metalness, if given.
    pr: Option<f32>,
    pm: Option<f32>,
    map_kd: Option<TextureRef>,
    map_bump: Option<TextureRef>,
}

impl Mtl {
    fn new(origin: Origin) -> Mtl {
        Mtl {
            origin,
            kd: [0.8; 3],
            ks: [0.0; 3],
            ke: None,
            tf: None,
            ns: None,
            ni: None,
            d: 1.0,
            illum: None,
            pr: None,
            pm: None,
            map_kd: None,
            map_bump: None,
        }
    }

    fn emission(&self) -> Option<([f32; 3], Origin)> {
        self.ke
            .clone()
            .filter(|(ke, _)| ke.iter().any(|&c| c > 0.0))
    }

    /// Our material for it (docs/scene-format.md has the table):
    /// - transparent (`d` < 1, `Tr` > 0 or `illum` 4, 6, 7, 9): glass of ior `Ni`
    ///   (default 1.5) tinted by `Tf`, smooth unless `Pr` says otherwise;
    /// - metallic (`Pm` ≥ 0.5, or a black `Kd` with a `Ks` and `illum` ≠ 0, 1): a conductor
    ///   of reflectance `Ks` (or `Kd` under `Pm`);
    /// - a non-black `Ks` (and `illum` ≠ 0, 1): `Kd` under a clear coat of ior `Ni`;
    /// - otherwise diffuse `Kd`.
    ///
    /// Roughness is `Pr`, or from the Phong exponent as Blender's importer maps it:
    /// 1 − √(clamp(Ns, 0, 1000) / 1000).
    fn desc(&self, name: &str, warnings: &mut Vec<String>) -> MaterialDesc {
        let clamp01 = |c: [f32; 3], what: &str, warnings: &mut Vec<String>| {
            if c.iter().any(|&x| x > 1.0) {
                warnings.push(format!(
                    "{}: material '{name}': {what} {c:?} is above 1, clamped",
                    self.origin
                ));
            }
            c.map(|x| x.clamp(0.0, 1.0))
        };
        let kd = clamp01(self.kd, "Kd", warnings);
        let ks = clamp01(self.ks, "Ks", warnings);
        let highlights = !matches!(self.illum, Some(0 | 1));
        let phong = self
            .ns
            .map_or(1.0, |ns| 1.0 - (ns.clamp(0.0, 1000.0) / 1000.0).sqrt());
        let roughness = self.pr.unwrap_or(phong).clamp(0.0, 1.0);
        let ior = self.ni.filter(|&n| n > 0.0 && n.is_finite());
        let transparent = self.d < 1.0 || matches!(self.illum, Some(4 | 6 | 7 | 9));
        let black = |c: [f32; 3]| c.iter().all(|&x| x <= 0.0);
        let (kind, roughness) = if transparent {
            let tint = self.tf.map(|t| clamp01(t, "Tf", warnings));
            let kind = MaterialKind::Dielectric { ior, tint };
            (kind, self.pr.unwrap_or(0.0))
        } else if self.pm.is_some_and(|m| m >= 0.5) {
            (MaterialKind::Conductor { f0: kd }, roughness)
        } else if highlights && black(kd) && !black(ks) {
            (MaterialKind::Conductor { f0: ks }, roughness)
        } else if highlights && !black(ks) {
            let kind = MaterialKind::Plastic {
                albedo: kd,
                ior: ior.filter(|&n| n > 1.0),
            };
            (kind, roughness)
        } else {
            (MaterialKind::Diffuse { albedo: kd }, roughness)
        };
        MaterialDesc {
            kind,
            roughness,
            user_color: None,
            base_color_map: self.map_kd.clone(),
            normal_map: self.map_bump.clone(),
            textures: Default::default(),
            origin: self.origin.clone(),
        }
    }
}

/// The materials of every `mtllib`, by name (a later definition of a name wins, as in
/// Blender). A missing MTL file is a warning: the faces become grey.
fn load_mtllibs(
    obj_path: &Path,
    libs: &[(String, Origin)],
    warnings: &mut Vec<String>,
) -> Result<BTreeMap<String, Mtl>, SceneError> {
    let dir = obj_path.parent().unwrap_or(Path::new(""));
    let mut out = BTreeMap::new();
    for (name, at) in libs {
        // A name with spaces is one file if it exists, else several.
        let whole = dir.join(name);
        let files: Vec<PathBuf> = if whole.is_file() || !name.contains(' ') {
            vec![whole]
        } else {
            name.split_whitespace().map(|n| dir.join(n)).collect()
        };
        for path in files {
            if !path.exists() {
                warnings.push(format!(
                    "{at}: MTL file {} does not exist; its materials render grey",
                    path.display()
                ));
                continue;
            }
            let bytes = text::read(&path, at, "MTL")?;
            parse_mtl(&bytes, &path, &mut out, warnings)?;
        }
    }
    Ok(out)
}

fn parse_mtl(
    bytes: &[u8],
    path: &Path,
    out: &mut BTreeMap<String, Mtl>,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let file = path.display().to_string();
    text::not_binary(bytes, &file, "MTL")?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut current: Option<(String, Mtl)> = None;
    let mut ignored: BTreeMap<String, Origin> = BTreeMap::new();
    for line in text::lines(bytes, &file) {
        let mut words = line.words();
        let Some(keyword) = words.next() else {
            continue;
        };
        if keyword.text == "newmtl" {
            if let Some((name, m)) = current.take() {
                out.insert(name, m);
            }
            let name = line.rest_after(keyword);
            if name.is_empty() {
                return Err(line.origin(keyword).error("newmtl needs a material name"));
            }
            current = Some((name.to_string(), Mtl::new(line.origin(keyword))));
            continue;
        }
        let Some((_, m)) = current.as_mut() else {
            return Err(line.origin(keyword).error(format!(
                "'{}' before any newmtl: expected newmtl NAME first",
                keyword.text
            )));
        };
        let colour = |words| line.colour(words, keyword);
        let number = |w| line.number(w, keyword, keyword.text);
        match keyword.text {
            "Kd" => m.kd = colour(words)?,
            "Ks" => m.ks = colour(words)?,
            "Ke" => m.ke = Some((colour(words)?, line.origin(keyword))),
            "Tf" => m.tf = Some(colour(words)?),
            "Ns" => m.ns = Some(number(words.next())?),
            "Ni" => m.ni = Some(number(words.next())?),
            "Pr" => m.pr = Some(number(words.next())?),
            "Pm" => m.pm = Some(number(words.next())?),
            "d" => {
                let mut w = words.next();
                if w.is_some_and(|w| w.text == "-halo") {
                    w = words.next();
                }
                m.d = number(w)?;
            }
            "Tr" => m.d = 1.0 - number(words.next())?,
            "illum" => {
                let w = words.next();
                let v = number(w)?;
                m.illum = Some(v.max(0.0) as u32);
            }
            "map_Kd" => m.map_kd = Some(line.texture(keyword, dir)?),
            "map_Bump" | "map_bump" | "bump" | "norm" => {
                m.map_bump = Some(line.texture(keyword, dir)?)
            }
            "Ka" | "Ni_" | "sharpness" => {}
            other => {
                ignored
                    .entry(other.to_string())
                    .or_insert_with(|| line.origin(keyword));
            }
        }
    }
    if let Some((name, m)) = current.take() {
        out.insert(name, m);
    }
    for (what, at) in ignored {
        warnings.push(format!(
            "{at}: MTL statement '{what}' is not supported, ignored"
        ));
    }
    Ok(())
}
