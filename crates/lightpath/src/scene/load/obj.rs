//! OBJ files (via tobj): every model becomes one mesh part, with its normals and UVs when
//! the file gives one per vertex.

use crate::scene::desc::MeshData;
use std::path::Path;

/// The models of an OBJ file; the error message names the file.
pub fn load(path: &Path) -> Result<Vec<MeshData>, String> {
    let (models, _) = tobj::load_obj(path, &tobj::GPU_LOAD_OPTIONS)
        .map_err(|e| format!("cannot load OBJ file {}: {e}", path.display()))?;
    let triples =
        |v: &[f32]| -> Vec<[f32; 3]> { v.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect() };
    let parts: Vec<MeshData> = models
        .into_iter()
        .map(|m| {
            let m = m.mesh;
            let n = m.positions.len();
            MeshData {
                positions: triples(&m.positions),
                indices: m
                    .indices
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect(),
                normals: (m.normals.len() == n).then(|| triples(&m.normals)),
                uvs: (m.texcoords.len() / 2 == n / 3 && !m.texcoords.is_empty())
                    .then(|| m.texcoords.chunks_exact(2).map(|t| [t[0], t[1]]).collect()),
                tangents: None,
            }
        })
        .collect();
    if parts.iter().all(|p| p.indices.is_empty()) {
        return Err(format!("OBJ file {} has no triangles", path.display()));
    }
    Ok(parts)
}
