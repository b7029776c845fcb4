//! Reading a composed stage: opening it through a resolver that keeps the input-size
//! limit and the render's identity (every layer, texture and package goes through
//! `limits::read_input`), values of any authored precision as `f32`s, and xform stacks.

use glam::{Affine3A, Mat4};
use openusd::ar::{self, Asset, Resolver};
use openusd::schemas::geom::{Imageable, Xformable};
use openusd::sdf::{self, Value};
use openusd::usd::{self, Prim, SchemaBase, SchemaKind, TimeCode};
use std::io;

/// The crate's resolver, except that files are read through `limits::read_input`:
/// within LIGHTPATH_MAX_FILE_BYTES, never a device, and noted as inputs of the render.
pub struct LimitedResolver(pub ar::DefaultResolver);

impl Resolver for LimitedResolver {
    fn create_identifier(&self, asset_path: &str, anchor: Option<&ar::ResolvedPath>) -> String {
        self.0.create_identifier(asset_path, anchor)
    }
    fn resolve(&self, asset_path: &str) -> Option<ar::ResolvedPath> {
        self.0.resolve(asset_path)
    }
    fn resolve_for_new_asset(&self, asset_path: &str) -> Option<ar::ResolvedPath> {
        self.0.resolve_for_new_asset(asset_path)
    }
    fn open_asset(&self, resolved: &ar::ResolvedPath) -> io::Result<Box<dyn Asset>> {
        let text = resolved.to_str().unwrap_or_default();
        if ar::is_package_relative_path(text) {
            // A file inside a .usdz: the package itself was read (and checked) when the
            // stage opened it; an entry is bounded by the limit too.
            let mut asset = self.0.open_asset(resolved)?;
            let size = asset.size()?;
            crate::limits::Limits::current()
                .check_file_bytes(size, "reading this package entry")
                .map_err(io::Error::other)?;
            let bytes = asset.read_all()?;
            return Ok(Box::new(io::Cursor::new(bytes)));
        }
        let bytes = crate::limits::read_input(std::path::Path::new(text))
            .map_err(|e| io::Error::other(e.to_string()))?;
        Ok(Box::new(io::Cursor::new(bytes)))
    }
    fn get_extension<'a>(&self, asset_path: &'a str) -> &'a str {
        self.0.get_extension(asset_path)
    }
    fn identity(&self) -> String {
        self.0.identity()
    }
}

/// Any prim as an `Xformable`, to compose its xform stack with the crate's code (lights,
/// cameras and gprims all are; a prim without `xformOpOrder` is the identity).
pub struct AnyXformable(pub Prim);

impl SchemaBase for AnyXformable {
    const KIND: SchemaKind = SchemaKind::ConcreteTyped;
    fn prim(&self) -> &Prim {
        &self.0
    }
}
impl Imageable for AnyXformable {}
impl Xformable for AnyXformable {}

/// USD's row-vector matrix as glam's column-vector one: the same sixteen numbers read
/// column by column.
pub fn mat4(m: &openusd::gf::Matrix4d) -> Mat4 {
    Mat4::from_cols_array(&m.0.map(|x| x as f32))
}

/// The prim's local-to-parent transform at `time`, and whether it resets the stack.
pub fn local_transform(prim: &Prim, time: TimeCode) -> Result<(Affine3A, bool), String> {
    let x = AnyXformable(prim.clone());
    let m = mat4(
        &x.local_to_parent_transform(time)
            .map_err(|e| format!("{e:#}"))?,
    );
    if !m.is_finite() {
        return Err("its transform is not finite".into());
    }
    let resets = x.resets_xform_stack().map_err(|e| format!("{e:#}"))?;
    Ok((Affine3A::from_mat4(m), resets))
}

/// The attribute's value at `time` (its default without samples); None when unauthored
/// or blocked.
pub fn value(prim: &Prim, name: &str, time: TimeCode) -> Option<Value> {
    match prim.attribute(name).get_at::<Value>(time) {
        Ok(Some(Value::ValueBlock)) => None,
        Ok(v) => v,
        Err(_) => None,
    }
}

/// The first of `names` that is authored (UsdLux's `inputs:` names and their older bare
/// spellings).
pub fn value_of(prim: &Prim, names: &[&str], time: TimeCode) -> Option<Value> {
    names.iter().find_map(|n| value(prim, n, time))
}

pub fn f32_of(v: &Value) -> Option<f32> {
    Some(match v {
        Value::Float(x) => *x,
        Value::Double(x) => *x as f32,
        Value::Half(x) => x.to_f32(),
        Value::Int(x) => *x as f32,
        Value::Uint(x) => *x as f32,
        Value::Int64(x) => *x as f32,
        Value::Uchar(x) => *x as f32,
        Value::Bool(b) => *b as u8 as f32,
        Value::FloatVec(a) if a.len() == 1 => a[0],
        Value::DoubleVec(a) if a.len() == 1 => a[0] as f32,
        _ => return None,
    })
}

pub fn bool_of(v: &Value) -> Option<bool> {
    match v {
        Value::Bool(b) => Some(*b),
        other => f32_of(other).map(|x| x != 0.0),
    }
}

pub fn vec2_of(v: &Value) -> Option<[f32; 2]> {
    Some(match v {
        Value::Vec2f(a) => [a.x, a.y],
        Value::Vec2d(a) => [a.x as f32, a.y as f32],
        Value::Vec2h(a) => [a.x.to_f32(), a.y.to_f32()],
        Value::Vec2i(a) => [a.x as f32, a.y as f32],
        _ => return None,
    })
}

pub fn vec3_of(v: &Value) -> Option<[f32; 3]> {
    Some(match v {
        Value::Vec3f(a) => [a.x, a.y, a.z],
        Value::Vec3d(a) => [a.x as f32, a.y as f32, a.z as f32],
        Value::Vec3h(a) => [a.x.to_f32(), a.y.to_f32(), a.z.to_f32()],
        Value::Vec3i(a) => [a.x as f32, a.y as f32, a.z as f32],
        // A one-element colour array (a constant displayColor).
        Value::Vec3fVec(a) if a.len() == 1 => [a[0].x, a[0].y, a[0].z],
        _ => return None,
    })
}

pub fn vec4_of(v: &Value) -> Option<[f32; 4]> {
    Some(match v {
        Value::Vec4f(a) => [a.x, a.y, a.z, a.w],
        Value::Vec4d(a) => [a.x as f32, a.y as f32, a.z as f32, a.w as f32],
        Value::Vec4h(a) => [a.x.to_f32(), a.y.to_f32(), a.z.to_f32(), a.w.to_f32()],
        _ => return None,
    })
}

pub fn vec2_array(v: Value) -> Option<Vec<[f32; 2]>> {
    Some(match v {
        Value::Vec2fVec(a) => a.into_iter().map(|p| [p.x, p.y]).collect(),
        Value::Vec2dVec(a) => a.into_iter().map(|p| [p.x as f32, p.y as f32]).collect(),
        Value::Vec2hVec(a) => a
            .into_iter()
            .map(|p| [p.x.to_f32(), p.y.to_f32()])
            .collect(),
        _ => return None,
    })
}

pub fn vec3_array(v: Value) -> Option<Vec<[f32; 3]>> {
    Some(match v {
        Value::Vec3fVec(a) => a.into_iter().map(|p| [p.x, p.y, p.z]).collect(),
        Value::Vec3dVec(a) => a
            .into_iter()
            .map(|p| [p.x as f32, p.y as f32, p.z as f32])
            .collect(),
        Value::Vec3hVec(a) => a
            .into_iter()
            .map(|p| [p.x.to_f32(), p.y.to_f32(), p.z.to_f32()])
            .collect(),
        Value::Vec3f(p) => vec![[p.x, p.y, p.z]],
        _ => return None,
    })
}

pub fn vec4_array(v: Value) -> Option<Vec<[f32; 4]>> {
    Some(match v {
        Value::Vec4fVec(a) => a.into_iter().map(|p| [p.x, p.y, p.z, p.w]).collect(),
        Value::QuathVec(a) => a
            .into_iter()
            .map(|q| [q.x.to_f32(), q.y.to_f32(), q.z.to_f32(), q.w.to_f32()])
            .collect(),
        Value::QuatfVec(a) => a.into_iter().map(|q| [q.x, q.y, q.z, q.w]).collect(),
        Value::QuatdVec(a) => a
            .into_iter()
            .map(|q| [q.x as f32, q.y as f32, q.z as f32, q.w as f32])
            .collect(),
        _ => return None,
    })
}

pub fn int_array(v: Value) -> Option<Vec<i64>> {
    Some(match v {
        Value::IntVec(a) => a.into_iter().map(i64::from).collect(),
        Value::UintVec(a) => a.into_iter().map(i64::from).collect(),
        Value::Int64Vec(a) => a,
        Value::UcharVec(a) => a.into_iter().map(i64::from).collect(),
        _ => return None,
    })
}

pub fn string_of(v: &Value) -> Option<String> {
    match v {
        Value::String(s) => Some(s.clone()),
        Value::Token(t) => Some(t.as_str().to_string()),
        Value::AssetPath(a) => Some(a.asset_path().to_string()),
        _ => None,
    }
}

/// Strings of a string, a token or an array of either.
pub fn strings_of(v: &Value) -> Vec<String> {
    match v {
        Value::StringVec(a) => a.clone(),
        Value::TokenVec(a) => a.iter().map(|t| t.as_str().to_string()).collect(),
        other => string_of(other).into_iter().collect(),
    }
}

/// The layer that holds the prim's strongest opinion, for messages.
pub fn layer_of(prim: &Prim, fallback: &str) -> String {
    prim.prim_stack()
        .ok()
        .and_then(|s| s.into_iter().next())
        .map(|(layer, _)| layer)
        .unwrap_or_else(|| fallback.to_string())
}

/// The type name, or "".
pub fn type_of(prim: &Prim) -> String {
    prim.type_name()
        .ok()
        .flatten()
        .map(|t| t.as_str().to_string())
        .unwrap_or_default()
}

/// The interpolation of a primvar (its metadata; `vertex` for `normals` without one,
/// `constant` for other primvars).
pub fn interpolation(prim: &Prim, name: &str, default: &str) -> String {
    prim.attribute(name)
        .get_metadata::<Value>("interpolation")
        .ok()
        .flatten()
        .and_then(|v| string_of(&v))
        .unwrap_or_else(|| default.to_string())
}

/// The prim's name (the last element of its path).
pub fn name_of(path: &sdf::Path) -> String {
    path.name().unwrap_or("").to_string()
}

/// Opens a stage with every payload loaded and the limited resolver.
pub fn open(path: &str) -> Result<usd::Stage, String> {
    usd::Stage::builder()
        .resolver(LimitedResolver(ar::DefaultResolver::new()))
        .open(path)
        .map_err(|e| format!("{e:#}"))
}
