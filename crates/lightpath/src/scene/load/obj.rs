//! OBJ files (via tobj): every model becomes one mesh part, with its normals and UVs when
//! the file gives one per vertex.

use crate::scene::desc::MeshData;
use std::path::Path;

/// The models of an OBJ file; the error message names the file (and the line, for a
/// number that is not finite). The file is read within `Limits::file_bytes`; materials
/// (`mtllib`) are not loaded: shading comes from the scene file.
pub fn load(path: &Path) -> Result<Vec<MeshData>, String> {
    let bytes = crate::limits::read_input(path)
        .map_err(|e| format!("cannot load OBJ file {}: {e}", path.display()))?;
    check_numbers(&bytes).map_err(|e| format!("OBJ file {}:{e}", path.display()))?;
    let (models, _) = tobj::load_obj_buf(&mut &bytes[..], &tobj::GPU_LOAD_OPTIONS, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
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
            }
        })
        .collect();
    if parts.iter().all(|p| p.indices.is_empty()) {
        return Err(format!("OBJ file {} has no triangles", path.display()));
    }
    Ok(parts)
}

/// Every number of a `v`, `vn` or `vt` line must be finite as an f32: `1e300` or `nan`
/// would reach the BVH builder. Returns `line:col: message` for the first that is not.
fn check_numbers(bytes: &[u8]) -> Result<(), String> {
    for (i, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let text = String::from_utf8_lossy(line);
        let mut words = text.split_whitespace();
        if !matches!(words.next(), Some("v" | "vn" | "vt")) {
            continue;
        }
        for word in words {
            if let Ok(v) = word.parse::<f32>() {
                if !v.is_finite() {
                    let col = text.find(word).map_or(1, |c| c + 1);
                    return Err(format!(
                        "{}:{col}: '{word}' is not a finite 32-bit number: expected a coordinate",
                        i + 1
                    ));
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_coordinates_are_found_with_their_line() {
        assert!(check_numbers(b"v 0 0 0\nv 1 2 3\nf 1 2 3\n").is_ok());
        let e = check_numbers(b"# x\nv 0 0 0\nv 1 1e300 3\n").unwrap_err();
        assert!(e.starts_with("3:5: '1e300'"), "{e}");
        let e = check_numbers(b"vn nan 0 1\n").unwrap_err();
        assert!(e.starts_with("1:4: 'nan'"), "{e}");
    }
}
