//! Throughput of the renderer's parts on `cornell-classic`: closest-hit and shadow rays,
//! and whole samples with beauty alone and with ~40 AOVs; rays and BVH builds with a
//! bumpy sphere of ~82k and ~1.3M triangles in the box (made here: no mesh files in git).
//! `cargo bench -p lightpath`; `LIGHTPATH_ACCEL=embree cargo bench -p lightpath --features
//! embree` traces the same rays and samples with Intel Embree instead of the BVH.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3A;
use lightpath::aov::{self, AovSpec};
use lightpath::geometry::{Ray, Visibility};
use lightpath::sampling::{uniform_sphere, Rng};
use lightpath::scene::desc::{MeshData, SceneDesc, ShapeDesc};
use lightpath::{render, RenderOptions, Scene};

fn classic(aovs: Vec<AovSpec>, res: u32) -> Scene {
    let src = lightpath::load_source("cornell-classic").unwrap();
    let mut desc = src.parse().unwrap();
    desc.render.resolution = [res, res];
    with_backend(Scene::build(&desc, &aov::assemble(aovs)).unwrap())
}

/// The scene traced by what `LIGHTPATH_ACCEL` names (`bvh`, the default, or `embree`).
fn with_backend(mut scene: Scene) -> Scene {
    let name = std::env::var("LIGHTPATH_ACCEL").unwrap_or_else(|_| "bvh".into());
    let backend = lightpath::geometry::Backend::parse(&name).unwrap();
    scene.accel.use_backend(backend).unwrap();
    scene
}

/// An icosphere subdivided `levels` times (20·4^levels triangles), radius 0.4 with bumps,
/// at the middle of the box.
fn bumpy_sphere(levels: u32) -> MeshData {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3A> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|p| Vec3A::from(p).normalize())
    .to_vec();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut midpoints = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, positions: &mut Vec<Vec3A>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                positions.push((positions[a as usize] + positions[b as usize]).normalize());
                positions.len() as u32 - 1
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (
                    mid(a, b, &mut positions),
                    mid(b, c, &mut positions),
                    mid(c, a, &mut positions),
                );
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    MeshData {
        positions: positions
            .iter()
            .map(|p| {
                let bump = 1.0 + 0.08 * (9.0 * p.x).sin() * (7.0 * p.y).sin() * (8.0 * p.z).sin();
                (*p * 0.4 * bump).into()
            })
            .collect(),
        indices: faces,
        normals: None,
        uvs: None,
        tangents: None,
        colors: None,
    }
}

/// cornell-classic with the bumpy sphere of `levels` in it.
fn classic_with_mesh(levels: u32) -> SceneDesc {
    let src = lightpath::load_source("cornell-classic").unwrap();
    let mut desc = src.parse().unwrap();
    desc.render.resolution = [64, 64];
    let mut object = desc.objects[0].clone();
    object.name = Some("mesh".into());
    object.shape = ShapeDesc::Mesh {
        parts: vec![bumpy_sphere(levels)],
    };
    object.transform = glam::Affine3A::IDENTITY;
    desc.objects.push(object);
    desc
}

/// Random rays from inside the box.
fn box_rays() -> Vec<Ray> {
    let mut rng = Rng::for_sample(1, 2, 3);
    (0..4096)
        .map(|_| {
            let o = Vec3A::new(
                rng.next_f32() * 1.6 - 0.8,
                rng.next_f32() * 1.6 - 0.8,
                rng.next_f32() * 1.6 - 0.8,
            );
            Ray {
                origin: o,
                dir: uniform_sphere(rng.next_2d()),
                tmax: f32::INFINITY,
            }
        })
        .collect()
}

fn mesh_rays(c: &mut Criterion) {
    for (levels, name) in [(6, "82k"), (8, "1.3M")] {
        let desc = classic_with_mesh(levels);
        let mut g = c.benchmark_group(format!("box with a {name}-triangle mesh"));
        g.sample_size(10);
        g.bench_function("scene build", |b| {
            b.iter(|| black_box(Scene::build(&desc, &aov::assemble(vec![])).unwrap()))
        });
        let scene = with_backend(Scene::build(&desc, &aov::assemble(vec![])).unwrap());
        let rays = box_rays();
        g.throughput(Throughput::Elements(rays.len() as u64));
        g.bench_function("closest hit", |b| {
            b.iter(|| {
                rays.iter()
                    .filter(|r| {
                        scene
                            .accel
                            .intersect(r, 0.0, Visibility::INDIRECT)
                            .is_some()
                    })
                    .count()
            })
        });
        g.bench_function("shadow", |b| {
            b.iter(|| {
                rays.iter()
                    .filter(|r| {
                        scene
                            .accel
                            .occluded(&Ray { tmax: 1.0, ..**r }, 0.0, u32::MAX)
                    })
                    .count()
            })
        });
        g.finish();
    }
}

fn rays(c: &mut Criterion) {
    let scene = classic(vec![], 64);
    let mut rng = Rng::for_sample(1, 2, 3);
    let rays: Vec<Ray> = (0..4096)
        .map(|_| {
            let o = Vec3A::new(
                rng.next_f32() * 1.6 - 0.8,
                rng.next_f32() * 1.6 - 0.8,
                rng.next_f32() * 1.6 - 0.8,
            );
            Ray {
                origin: o,
                dir: uniform_sphere(rng.next_2d()),
                tmax: f32::INFINITY,
            }
        })
        .collect();
    let mut g = c.benchmark_group("rays");
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function("closest hit", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| {
                    scene
                        .accel
                        .intersect(r, 0.0, Visibility::INDIRECT)
                        .is_some()
                })
                .count()
        })
    });
    g.bench_function("shadow", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| {
                    scene
                        .accel
                        .occluded(&Ray { tmax: 1.0, ..**r }, 0.0, u32::MAX)
                })
                .count()
        })
    });
    g.finish();
}

fn samples(c: &mut Criterion) {
    let mut g = c.benchmark_group("render 64x64 at 4 spp");
    g.throughput(Throughput::Elements(64 * 64 * 4));
    g.sample_size(10);
    let beauty = classic(vec![], 64);
    let mut many: Vec<AovSpec> = aov::standard().into_iter().map(AovSpec::split).collect();
    many.extend(aov::bounces(3));
    let forty = classic(many, 64);
    let options = RenderOptions {
        spp: 4,
        first_sample: 0,
    };
    g.bench_function(format!("{} AOV", beauty.aovs.len()), |b| {
        b.iter(|| black_box(render(&beauty, &options)))
    });
    g.bench_function(format!("{} AOVs", forty.aovs.len()), |b| {
        b.iter(|| black_box(render(&forty, &options)))
    });
    g.finish();
}

criterion_group!(benches, rays, samples, mesh_rays);
criterion_main!(benches);
