//! Texture coordinates, tangents and vertex colours of triangles, read only where a
//! textured material needs them (a material on a mesh with vertex colours is one): the
//! hit itself carries none, so untextured scenes pay nothing.
//!
//! A triangle with per-vertex attributes has an entry in the scene's attribute tables
//! (`Prim::Triangle::normals` indexes them): its shading normals (kept by the
//! acceleration structure), its UVs, tangents and colours here, each table either empty
//! (no mesh of the scene has that attribute) or as long as the normals table.

use super::shapes::VertexAttrs;
use super::{Accel, Hit, Prim};
use glam::{Affine3A, Vec2, Vec3, Vec3A, Vec4};

/// Per-vertex UVs, tangents and colours, indexed like the shading normals.
#[derive(Clone, Debug, Default)]
pub struct SurfaceAttrs {
    uvs: Vec<[Vec2; 3]>,
    /// World-space tangent (xyz) and bitangent sign (w); w = 0: none given. (In a shared
    /// mesh's table: in the mesh's own space.)
    tangents: Vec<[Vec4; 3]>,
    /// Linear RGB vertex colours (they multiply the base colour); a triangle without
    /// them has white.
    colors: Vec<[Vec3; 3]>,
    /// Each shared mesh's own table, by mesh (`Instance::mesh`).
    pub meshes: Vec<SurfaceAttrs>,
}

/// The attributes at a hit: what a texture lookup needs, if the triangle has UVs, and the
/// interpolated vertex colour (white without one).
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub uv: Option<SurfaceUv>,
    pub color: Vec3A,
}

/// What a texture lookup needs at a hit.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceUv {
    pub uv: Vec2,
    /// ∂p/∂u and ∂p/∂v (world units per UV unit); zero on a triangle whose UVs are
    /// degenerate.
    pub dpdu: Vec3A,
    pub dpdv: Vec3A,
    /// The interpolated world tangent and bitangent sign (w = 0: none given).
    pub tangent: Vec4,
    /// UV units per world unit (the root of the UV-to-world area ratio), for the
    /// footprint of a ray cone.
    pub uv_per_world: f32,
}

impl SurfaceAttrs {
    /// Appends one attributed triangle's UVs, tangents and colours; `count` is the number
    /// of entries (normals) before it, so tables that were empty are filled up to it.
    pub fn push(&mut self, count: usize, attrs: VertexAttrs) {
        let VertexAttrs {
            uvs,
            tangents,
            colors,
        } = attrs;
        fn put<T: Copy>(table: &mut Vec<T>, count: usize, value: Option<T>, zero: T) {
            if value.is_none() && table.is_empty() {
                return;
            }
            table.resize(count, zero);
            table.push(value.unwrap_or(zero));
        }
        put(&mut self.uvs, count, uvs, [Vec2::ZERO; 3]);
        put(&mut self.tangents, count, tangents, [Vec4::ZERO; 3]);
        put(&mut self.colors, count, colors, [Vec3::ONE; 3]);
    }

    /// Bytes held, for the memory figures.
    pub fn bytes(&self) -> usize {
        self.uvs.len() * 24
            + self.tangents.len() * 48
            + self.colors.len() * 36
            + self.meshes.iter().map(SurfaceAttrs::bytes).sum::<usize>()
    }

    /// UVs and derivatives at `hit` if the triangle has UVs, and its colour (on an
    /// instance: the shared mesh's triangle, placed); `None` for a hit on a primitive
    /// without attributes.
    pub fn at(&self, accel: &Accel, hit: &Hit) -> Option<SurfacePoint> {
        match accel.prims()[hit.prim as usize] {
            Prim::Instance { index, .. } => {
                let inst = &accel.instances()[index as usize];
                let mesh = accel.meshes().get(inst.mesh as usize)?;
                let table = self.meshes.get(inst.mesh as usize)?;
                let tri = *mesh.prims().get(hit.inner as usize)?;
                table.at_triangle(tri, hit.p, Some(&inst.to_world))
            }
            tri => self.at_triangle(tri, hit.p, None),
        }
    }

    /// [`SurfaceAttrs::at`] on triangle `tri` of this table, placed by `to_world` (an
    /// instance's) or already in world space. Barycentrics are kept by an affine map, so
    /// the placed triangle's edges give the world derivatives directly.
    fn at_triangle(
        &self,
        tri: Prim,
        p: Vec3A,
        to_world: Option<&Affine3A>,
    ) -> Option<SurfacePoint> {
        let Prim::Triangle {
            p0,
            e1,
            e2,
            normals,
        } = tri
        else {
            return None;
        };
        let uvs = self.uvs.get(normals as usize);
        let colors = self.colors.get(normals as usize);
        if uvs.is_none() && colors.is_none() {
            return None;
        }
        let (p0, e1, e2) = match to_world {
            Some(m) => (
                m.transform_point3a(p0),
                m.transform_vector3a(e1),
                m.transform_vector3a(e2),
            ),
            None => (p0, e1, e2),
        };
        // Barycentrics of the hit point, as the acceleration structure finds normals.
        let d = p - p0;
        let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d20, d21) = (d.dot(e1), d.dot(e2));
        let denom = d00 * d11 - d01 * d01;
        let (b1, b2) = if denom != 0.0 {
            (
                (d11 * d20 - d01 * d21) / denom,
                (d00 * d21 - d01 * d20) / denom,
            )
        } else {
            (0.0, 0.0)
        };
        let b0 = 1.0 - b1 - b2;
        let color = match colors {
            Some([c0, c1, c2]) => Vec3A::from(*c0 * b0 + *c1 * b1 + *c2 * b2).max(Vec3A::ZERO),
            None => Vec3A::ONE,
        };
        let Some(&[t0, t1, t2]) = uvs else {
            return Some(SurfacePoint { uv: None, color });
        };
        let uv = t0 * b0 + t1 * b1 + t2 * b2;
        // pbrt-v4's ∂p/∂u, ∂p/∂v from the two edges and their UV differences.
        let (duv1, duv2) = (t1 - t0, t2 - t0);
        let det = duv1.x * duv2.y - duv1.y * duv2.x;
        let world_area = e1.cross(e2).length();
        let (dpdu, dpdv, uv_per_world) = if det.abs() > 1e-12 && world_area > 0.0 {
            (
                (e1 * duv2.y - e2 * duv1.y) / det,
                (e2 * duv1.x - e1 * duv2.x) / det,
                (det.abs() / world_area).sqrt(),
            )
        } else {
            (Vec3A::ZERO, Vec3A::ZERO, 0.0)
        };
        let tangent = match self.tangents.get(normals as usize) {
            Some([a, b, c]) if a.w != 0.0 => {
                let t = *a * b0 + *b * b1 + *c * b2;
                match to_world {
                    // A mirroring placement flips the frame's handedness.
                    Some(m) => {
                        let sign = a.w.signum() * m.matrix3.determinant().signum();
                        m.transform_vector3(t.truncate()).extend(sign)
                    }
                    None => t.truncate().extend(a.w.signum()),
                }
            }
            _ => Vec4::ZERO,
        };
        Some(SurfacePoint {
            uv: Some(SurfaceUv {
                uv,
                dpdu,
                dpdv,
                tangent,
                uv_per_world,
            }),
            color,
        })
    }
}

impl SurfaceUv {
    /// Unit tangent and bitangent around the shading normal `ns` for a tangent-space
    /// normal map: the given tangents, or else ∂p/∂u, with the bitangent towards −∂p/∂v
    /// (glTF's `v` grows down the image, its normal maps' green points up it). `None`
    /// where neither defines a direction.
    pub fn tangent_frame(&self, ns: Vec3A) -> Option<(Vec3A, Vec3A)> {
        let (t, sign) = if self.tangent.w != 0.0 {
            (Vec3A::from(self.tangent.truncate()), self.tangent.w)
        } else {
            let t = self.dpdu;
            let b = ns.cross(t);
            (t, if b.dot(-self.dpdv) < 0.0 { -1.0 } else { 1.0 })
        };
        let t = (t - ns * ns.dot(t)).try_normalize()?;
        Some((t, ns.cross(t) * sign))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Accel, Ray, Visibility};

    /// A 2×2 square in z = 0 with UVs spanning [0, 1]², v down the +y axis flipped.
    fn square() -> (Accel, SurfaceAttrs) {
        let p = [
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(2.0, 0.0, 0.0),
            Vec3A::new(0.0, 2.0, 0.0),
        ];
        let prim = Prim::Triangle {
            p0: p[0],
            e1: p[1] - p[0],
            e2: p[2] - p[0],
            normals: 0,
        };
        let accel = Accel::build(
            vec![prim],
            vec![0],
            vec![[Vec3A::Z; 3]],
            vec![Visibility::ALL],
        );
        let mut attrs = SurfaceAttrs::default();
        // (0,0) → uv (0,1), (2,0) → (1,1), (0,2) → (0,0): v grows towards −y.
        attrs.push(
            0,
            VertexAttrs {
                uvs: Some([
                    Vec2::new(0.0, 1.0),
                    Vec2::new(1.0, 1.0),
                    Vec2::new(0.0, 0.0),
                ]),
                ..VertexAttrs::default()
            },
        );
        (accel, attrs)
    }

    #[test]
    fn uvs_interpolate_and_derivatives_follow_the_layout() {
        let (accel, attrs) = square();
        let ray = Ray {
            origin: Vec3A::new(0.5, 0.5, 1.0),
            dir: -Vec3A::Z,
            tmax: f32::INFINITY,
        };
        let hit = accel
            .intersect(&ray, 0.0, Visibility::CAMERA)
            .expect("the ray hits the triangle");
        let point = attrs.at(&accel, &hit).expect("the triangle has attributes");
        assert_eq!(point.color, Vec3A::ONE, "no colours: white");
        let s = point.uv.expect("the triangle has UVs");
        assert!((s.uv - Vec2::new(0.25, 0.75)).length() < 1e-6, "{}", s.uv);
        assert!((s.dpdu - Vec3A::new(2.0, 0.0, 0.0)).length() < 1e-6);
        assert!((s.dpdv - Vec3A::new(0.0, -2.0, 0.0)).length() < 1e-6);
        assert!((s.uv_per_world - 0.5).abs() < 1e-6);
        // The tangent along +x, the bitangent up the image (+y).
        let (t, b) = s.tangent_frame(Vec3A::Z).unwrap();
        assert!((t - Vec3A::X).length() < 1e-6 && (b - Vec3A::Y).length() < 1e-6);
    }

    #[test]
    fn tables_stay_empty_without_attributes_and_fill_up_when_one_comes() {
        let mut attrs = SurfaceAttrs::default();
        attrs.push(0, VertexAttrs::default());
        attrs.push(1, VertexAttrs::default());
        assert_eq!(attrs.bytes(), 0);
        attrs.push(
            2,
            VertexAttrs {
                uvs: Some([Vec2::ONE; 3]),
                ..VertexAttrs::default()
            },
        );
        assert_eq!(attrs.uvs.len(), 3);
        assert!(attrs.tangents.is_empty() && attrs.colors.is_empty());
        assert_eq!(attrs.uvs[0], [Vec2::ZERO; 3]);
        attrs.push(
            3,
            VertexAttrs {
                colors: Some([Vec3::X; 3]),
                ..VertexAttrs::default()
            },
        );
        // Triangles before the first coloured one are white; UVs fill up with zeros.
        assert_eq!(attrs.colors.len(), 4);
        assert_eq!(attrs.colors[2], [Vec3::ONE; 3]);
        assert_eq!(attrs.uvs.len(), 4);
    }

    #[test]
    fn colours_interpolate_without_uvs_and_on_instances() {
        // Red, green and blue corners; no UVs.
        let mut attrs = SurfaceAttrs::default();
        attrs.push(
            0,
            VertexAttrs {
                colors: Some([Vec3::X, Vec3::Y, Vec3::Z]),
                ..VertexAttrs::default()
            },
        );
        let p = [
            Vec3A::ZERO,
            Vec3A::new(2.0, 0.0, 0.0),
            Vec3A::new(0.0, 2.0, 0.0),
        ];
        let prim = Prim::Triangle {
            p0: p[0],
            e1: p[1] - p[0],
            e2: p[2] - p[0],
            normals: 0,
        };
        let ray = |x: f32, y: f32| Ray {
            origin: Vec3A::new(x, y, 1.0),
            dir: -Vec3A::Z,
            tmax: f32::INFINITY,
        };
        // Barycentrics (0.5, 0.25, 0.25) at (0.5, 0.5).
        let want = Vec3A::new(0.5, 0.25, 0.25);
        let accel = Accel::build(
            vec![prim],
            vec![0],
            vec![[Vec3A::Z; 3]],
            vec![Visibility::ALL],
        );
        let hit = accel
            .intersect(&ray(0.5, 0.5), 0.0, Visibility::CAMERA)
            .unwrap();
        let s = attrs.at(&accel, &hit).expect("a coloured triangle");
        assert!(s.uv.is_none());
        assert!((s.color - want).length() < 1e-5, "{}", s.color);

        // The same triangle as a shared mesh, placed 10 units along x.
        let mesh = Accel::build(
            vec![prim],
            vec![0],
            vec![[Vec3A::Z; 3]],
            vec![Visibility::ALL],
        );
        let inst =
            crate::geometry::Instance::new(0, Affine3A::from_translation(glam::Vec3::X * 10.0))
                .unwrap();
        let (lo, hi) = inst.world_bounds(Vec3A::ZERO, Vec3A::new(2.0, 2.0, 0.0));
        let scene = Accel::build(
            vec![Prim::Instance { lo, hi, index: 0 }],
            vec![0],
            vec![],
            vec![Visibility::ALL],
        )
        .with_instances(vec![mesh], vec![inst]);
        let placed = SurfaceAttrs {
            meshes: vec![attrs],
            ..SurfaceAttrs::default()
        };
        let hit = scene
            .intersect(&ray(10.5, 0.5), 0.0, Visibility::CAMERA)
            .unwrap();
        let s = placed
            .at(&scene, &hit)
            .expect("the instance's triangle is coloured");
        assert!((s.color - want).length() < 1e-5, "{}", s.color);
    }
}
