//! Throughput of the renderer's parts on `cornell-classic`: closest-hit and shadow rays,
//! and whole samples with beauty alone and with ~40 AOVs. `cargo bench -p lightpath`.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3A;
use lightpath::aov::{self, AovSpec};
use lightpath::geometry::{Ray, Visibility};
use lightpath::sampling::{uniform_sphere, Rng};
use lightpath::{render, RenderOptions, Scene};

fn classic(aovs: Vec<AovSpec>, res: u32) -> Scene {
    let src = lightpath::load_source("cornell-classic").unwrap();
    let mut desc = src.parse().unwrap();
    desc.film.resolution = [res, res];
    Scene::build(&desc, &aov::assemble(aovs)).unwrap()
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

criterion_group!(benches, rays, samples);
criterion_main!(benches);
