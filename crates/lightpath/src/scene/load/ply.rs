//! PLY files (ASCII and both binary encodings, through `ply-rs-bw`): the `vertex`
//! element's positions, normals and texture coordinates, and the `face` element's
//! polygons (fan-triangulated) become one mesh object named after the file.
//!
//! Elements are read one at a time, so an error names the element and its number (and,
//! in an ASCII file, the line).

use super::text;
use crate::material::texture;
use crate::scene::desc::{
    MaterialDesc, MaterialKind, MeshData, NameRef, ObjectDesc, Origin, SceneDesc, ShapeDesc,
};
use crate::scene::SceneError;
use glam::Affine3A;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{ElementDef, Encoding, Property, PropertyAccess, PropertyType, ScalarType};
use std::io::BufRead;
use std::path::Path;

/// The material of a PLY's object (PLY has none).
pub const MATERIAL: &str = "(ply)";

/// A PLY file as a scene: one object (named after the file) with a grey diffuse material.
pub fn load_scene(path: &Path, at: &Origin) -> Result<SceneDesc, SceneError> {
    let file = path.display().to_string();
    let (mesh, warnings) = load(path, at)?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "ply".into());
    let origin = Origin::file(&file);
    let mut desc = SceneDesc {
        source: file.clone(),
        warnings,
        ..SceneDesc::default()
    };
    desc.materials.insert(
        MATERIAL.into(),
        MaterialDesc {
            kind: MaterialKind::Diffuse { albedo: [0.8; 3] },
            roughness: 0.0,
            user_color: None,
            base_color_map: None,
            normal_map: None,
            textures: Default::default(),
            origin: origin.clone(),
        },
    );
    desc.objects.push(ObjectDesc {
        name: Some(name.clone()),
        shape_name: "ply".into(),
        shape: ShapeDesc::Mesh { parts: vec![mesh] },
        transform: Affine3A::IDENTITY,
        material: Some(NameRef {
            name: MATERIAL.into(),
            origin: origin.clone(),
        }),
        lpegroups: Some(vec![name]),
        emission: None,
        holdout: false,
        visible_camera: true,
        visible_indirect: true,
        casts_shadows: true,
        asset: None,
        origin,
    });
    Ok(desc)
}

/// The mesh of a PLY file and the warnings about it; `at` is where it was named.
pub fn load(path: &Path, at: &Origin) -> Result<(MeshData, Vec<String>), SceneError> {
    let file = path.display().to_string();
    let bytes = text::read(path, at, "PLY")?;
    if !bytes.starts_with(b"ply") {
        return Err(Origin::file(&file).error(
            "not a PLY file: it does not start with 'ply' (the PLY magic number)".to_string(),
        ));
    }
    let parser = Parser::<Row>::new();
    let mut reader: &[u8] = &bytes;
    let header = parser.read_header(&mut reader).map_err(|e| {
        Origin::file(&file).error(format!("PLY header: {}", first_line(&e.to_string())))
    })?;
    // Lines the header took, for the line numbers of an ASCII payload.
    let mut line = bytes[..bytes.len() - reader.len()]
        .iter()
        .filter(|&&b| b == b'\n')
        .count();
    let mut mesh = Gathered::default();
    let mut warnings = Vec::new();
    for (name, def) in &header.elements {
        match name.as_str() {
            "vertex" => mesh.layout = VertexLayout::of(def, &file)?,
            "face" => check_face_element(def, &file)?,
            _ if def.count > 0 => {
                warnings.push(format!("{file}: PLY element '{name}' is not used"))
            }
            _ => {}
        }
        for k in 0..def.count {
            line += 1;
            let at = ElementAt {
                file: &file,
                element: name,
                index: k,
                count: def.count,
                line: (header.encoding == Encoding::Ascii).then_some(line),
            };
            let row = read_row(&parser, &mut reader, def, header.encoding)
                .map_err(|e| at.error(&first_line(&e.to_string())))?;
            if let Some(bad) = &row.bad {
                return Err(at.error(bad));
            }
            match name.as_str() {
                "vertex" => mesh.vertex(&row, &at)?,
                "face" => mesh.face(&row, &at)?,
                _ => {}
            }
        }
    }
    Ok((mesh.finish(&file)?, warnings))
}

/// Which of the optional vertex properties a PLY file has.
#[derive(Clone, Copy, Default)]
struct VertexLayout {
    normals: bool,
    uvs: bool,
    colors: bool,
    /// Integer colours are sRGB-encoded fractions of their range (as Blender's PLY
    /// importer reads them by default); float colours are linear.
    srgb: bool,
}

impl VertexLayout {
    fn of(def: &ElementDef, file: &str) -> Result<VertexLayout, SceneError> {
        let props = |names: &[&str]| names.iter().all(|n| def.properties.contains_key(*n));
        if !props(&["x", "y", "z"]) {
            return Err(
                Origin::file(file).error("PLY element 'vertex' needs properties x, y and z")
            );
        }
        let srgb = ["red", "green", "blue"].iter().all(|n| {
            def.properties.get(*n).is_some_and(|p| {
                !matches!(
                    p.data_type,
                    PropertyType::Scalar(ScalarType::Float | ScalarType::Double)
                )
            })
        });
        Ok(VertexLayout {
            normals: props(&["nx", "ny", "nz"]),
            uvs: UV_NAMES.iter().any(|[u, v]| props(&[u, v])),
            colors: props(&["red", "green", "blue"]),
            srgb,
        })
    }
}

fn check_face_element(def: &ElementDef, file: &str) -> Result<(), SceneError> {
    if ["vertex_indices", "vertex_index"]
        .iter()
        .any(|n| def.properties.contains_key(*n))
    {
        Ok(())
    } else {
        Err(Origin::file(file)
            .error("PLY element 'face' needs a list property vertex_indices (or vertex_index)"))
    }
}

/// The mesh as its elements are read.
#[derive(Default)]
struct Gathered {
    layout: VertexLayout,
    mesh: MeshData,
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    colors: Vec<[f32; 3]>,
}

impl Gathered {
    fn vertex(&mut self, row: &Row, at: &ElementAt) -> Result<(), SceneError> {
        let p = [row.v[X], row.v[Y], row.v[Z]].map(|c| c as f32);
        if !p.iter().all(|c| c.is_finite()) {
            return Err(at.error(&format!("vertex position {p:?} is not finite")));
        }
        self.mesh.positions.push(p);
        if self.layout.normals {
            let n = [row.v[NX], row.v[NY], row.v[NZ]].map(|c| c as f32);
            if !n.iter().all(|c| c.is_finite()) {
                return Err(at.error(&format!("vertex normal {n:?} is not finite")));
            }
            self.normals.push(n);
        }
        if self.layout.uvs {
            // v runs up in PLY as in OBJ; ours from the image's top.
            self.uvs.push([row.v[U] as f32, 1.0 - row.v[V] as f32]);
        }
        if self.layout.colors {
            let c = [row.v[R], row.v[R + 1], row.v[R + 2]].map(|c| c as f32);
            if !c.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(at.error(&format!(
                    "vertex colour {c:?}: expected finite, non-negative numbers"
                )));
            }
            self.colors.push(if self.layout.srgb {
                c.map(texture::srgb_to_linear)
            } else {
                c
            });
        }
        Ok(())
    }

    /// A polygon, fan-triangulated; its indices must name vertices read before it.
    fn face(&mut self, row: &Row, at: &ElementAt) -> Result<(), SceneError> {
        let n = self.mesh.positions.len();
        if let Some(&bad) = row.list.iter().find(|&&i| i as usize >= n) {
            return Err(at.error(&format!(
                "vertex index {bad} is out of range: the file has {n} vertices"
            )));
        }
        if row.list.len() < 3 {
            return Err(at.error(&format!(
                "a face needs at least 3 vertices, found {}",
                row.list.len()
            )));
        }
        for t in 1..row.list.len() - 1 {
            self.mesh
                .indices
                .push([row.list[0], row.list[t], row.list[t + 1]]);
        }
        Ok(())
    }

    fn finish(self, file: &str) -> Result<MeshData, SceneError> {
        let mut mesh = self.mesh;
        if mesh.indices.is_empty() {
            return Err(Origin::file(file).error("the PLY file has no faces (a point cloud?)"));
        }
        mesh.normals = self.layout.normals.then_some(self.normals);
        mesh.uvs = self.layout.uvs.then_some(self.uvs);
        mesh.colors = self.layout.colors.then_some(self.colors);
        Ok(mesh)
    }
}

fn first_line(s: &str) -> String {
    s.lines().next().unwrap_or("").to_string()
}

/// An element of the payload, for errors.
struct ElementAt<'a> {
    file: &'a str,
    element: &'a str,
    index: usize,
    count: usize,
    /// Its line, in an ASCII file.
    line: Option<usize>,
}

impl ElementAt<'_> {
    fn error(&self, message: &str) -> SceneError {
        let origin = Origin {
            file: self.file.into(),
            line: self.line.unwrap_or(0),
            col: self.line.map_or(0, |_| 1),
        };
        origin.error(format!(
            "PLY element '{}' {} of {}: {message}",
            self.element,
            self.index + 1,
            self.count
        ))
    }
}

fn read_row(
    parser: &Parser<Row>,
    reader: &mut &[u8],
    def: &ElementDef,
    encoding: Encoding,
) -> std::io::Result<Row> {
    match encoding {
        Encoding::Ascii => {
            let mut line = String::new();
            if reader.read_line(&mut line)? == 0 {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::UnexpectedEof,
                    "the file ends before this element",
                ));
            }
            parser.read_ascii_element(&line, def).map_err(|_| {
                let props: Vec<String> = def
                    .properties
                    .values()
                    .map(|p| format!("{} ({})", p.name, type_name(&p.data_type)))
                    .collect();
                std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("cannot read '{}' as {}", line.trim(), props.join(", ")),
                )
            })
        }
        Encoding::BinaryLittleEndian => parser.read_little_endian_element(reader, def),
        Encoding::BinaryBigEndian => parser.read_big_endian_element(reader, def),
    }
}

fn type_name(t: &PropertyType) -> String {
    let scalar = |s: &ScalarType| match s {
        ScalarType::Char => "char",
        ScalarType::UChar => "uchar",
        ScalarType::Short => "short",
        ScalarType::UShort => "ushort",
        ScalarType::Int => "int",
        ScalarType::UInt => "uint",
        ScalarType::Float => "float",
        ScalarType::Double => "double",
    };
    match t {
        PropertyType::Scalar(s) => scalar(s).to_string(),
        PropertyType::List(n, s) => format!("list {} {}", scalar(n), scalar(s)),
    }
}

const X: usize = 0;
const Y: usize = 1;
const Z: usize = 2;
const NX: usize = 3;
const NY: usize = 4;
const NZ: usize = 5;
const U: usize = 6;
const V: usize = 7;
const R: usize = 8;

/// The names texture coordinates go by in PLY files.
const UV_NAMES: [[&str; 2]; 4] = [
    ["u", "v"],
    ["s", "t"],
    ["texture_u", "texture_v"],
    ["texture_s", "texture_t"],
];

/// One element as the loader keeps it: the scalars it knows by slot, the face's index
/// list, and what was wrong with it.
struct Row {
    v: [f64; 11],
    list: Vec<u32>,
    bad: Option<String>,
}

fn slot(name: &str) -> Option<usize> {
    Some(match name {
        "x" => X,
        "y" => Y,
        "z" => Z,
        "nx" => NX,
        "ny" => NY,
        "nz" => NZ,
        "u" | "s" | "texture_u" | "texture_s" => U,
        "v" | "t" | "texture_v" | "texture_t" => V,
        "red" => R,
        "green" => R + 1,
        "blue" => R + 2,
        _ => return None,
    })
}

impl PropertyAccess for Row {
    fn new() -> Self {
        Row {
            v: [0.0; 11],
            list: Vec::new(),
            bad: None,
        }
    }

    fn set_property(&mut self, name: &str, p: Property) {
        if let Some(s) = slot(name) {
            self.v[s] = match p {
                // Colours in integers are fractions of the type's range.
                Property::UChar(x) if s >= R => x as f64 / 255.0,
                Property::UShort(x) if s >= R => x as f64 / 65535.0,
                Property::Char(x) => x as f64,
                Property::UChar(x) => x as f64,
                Property::Short(x) => x as f64,
                Property::UShort(x) => x as f64,
                Property::Int(x) => x as f64,
                Property::UInt(x) => x as f64,
                Property::Float(x) => x as f64,
                Property::Double(x) => x,
                _ => {
                    self.bad = Some(format!("property '{name}' is a list, expected a number"));
                    0.0
                }
            };
        } else if name == "vertex_indices" || name == "vertex_index" {
            let list: Result<Vec<u32>, i64> = match p {
                Property::ListChar(l) => l
                    .iter()
                    .map(|&i| u32::try_from(i).map_err(|_| i as i64))
                    .collect(),
                Property::ListUChar(l) => Ok(l.iter().map(|&i| i as u32).collect()),
                Property::ListShort(l) => l
                    .iter()
                    .map(|&i| u32::try_from(i).map_err(|_| i as i64))
                    .collect(),
                Property::ListUShort(l) => Ok(l.iter().map(|&i| i as u32).collect()),
                Property::ListInt(l) => l
                    .iter()
                    .map(|&i| u32::try_from(i).map_err(|_| i as i64))
                    .collect(),
                Property::ListUInt(l) => Ok(l),
                _ => {
                    self.bad = Some(format!("property '{name}' must be a list of integers"));
                    Ok(Vec::new())
                }
            };
            match list {
                Ok(l) => self.list = l,
                Err(i) => self.bad = Some(format!("vertex index {i} is negative")),
            }
        }
    }
}
