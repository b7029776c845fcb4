//! Compile time of a production AOV set, and the per-vertex `step` cost as rules grow.
//! Run with `cargo bench -p lpe`.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use lpe::{Compiler, Event, EventType, Scatter, STANDARD_NAMES};

/// The standard names plus one light-group rule per group (beauty split 16 ways).
fn production_rules(groups: usize) -> Vec<String> {
    let mut rules: Vec<String> = STANDARD_NAMES
        .iter()
        .map(|(n, _)| format!("lpe:{n}"))
        .collect();
    rules.extend((0..groups).map(|g| format!("C[DS]*[<L.'group{g}'><O'group{g}'>]")));
    rules
}

/// `n` rules of varied shape: bounce counts, per-object and per-light splits.
fn many_rules(n: usize) -> Vec<String> {
    (0..n)
        .map(|i| match i % 4 {
            0 => format!("C<.>{{{}}}[<L.>O]", 1 + i % 6),
            1 => format!("C<RD'obj{}'>[DS]*[<L.>O]", i % 13),
            2 => format!("C[DS]*<L.'light{}'>", i % 7),
            _ => "C<RS>[DS]+[<L.>O]".to_string(),
        })
        .collect()
}

/// The events of a small scene: a few objects with diffuse and specular lobes, lights.
fn scene_events() -> Vec<Event> {
    let mut v = vec![Event::camera()];
    for o in 0..13 {
        let obj = format!("obj{o}");
        v.push(Event::new(
            EventType::Reflect,
            Some(Scatter::diffuse(2)),
            [obj.clone()],
        ));
        v.push(Event::new(
            EventType::Reflect,
            Some(Scatter::specular(2)),
            [obj.clone()],
        ));
        v.push(Event::new(
            EventType::Transmit,
            Some(Scatter::specular(8)),
            [obj],
        ));
    }
    for l in 0..16 {
        v.push(Event::new(
            EventType::Light,
            None,
            [format!("light{}", l % 7), format!("group{l}")],
        ));
        v.push(Event::new(EventType::Emission, None, [format!("group{l}")]));
    }
    v
}

fn compile_bench(c: &mut Criterion) {
    let rules = production_rules(16);
    let events = scene_events();
    c.bench_function("compile standard set + 16 light groups", |b| {
        b.iter(|| {
            let mut comp = Compiler::new().default_alphabet(false);
            for r in &rules {
                comp.add(r).unwrap();
            }
            comp.vocabulary(events.iter().cloned());
            black_box(comp.compile().unwrap())
        })
    });
}

fn step_bench(c: &mut Criterion) {
    let events = scene_events();
    let mut group = c.benchmark_group("step");
    const STEPS: usize = 1 << 16;
    group.throughput(Throughput::Elements(STEPS as u64));
    for n in [1usize, 10, 100] {
        let mut comp = Compiler::new().default_alphabet(false);
        for r in many_rules(n) {
            comp.add(&r).unwrap();
        }
        comp.vocabulary(events.iter().cloned());
        let a = comp.compile().unwrap();
        // A fixed pseudo-random walk over the scene's events (camera first, then bounces).
        let classes: Vec<_> = events.iter().map(|e| a.classify(e).unwrap()).collect();
        let mut x = 0x9e37_79b9_u32;
        let walk: Vec<_> = (0..STEPS)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                classes[1 + (x as usize % (classes.len() - 1))]
            })
            .collect();
        let camera = classes[0];
        // The bare chain of dependent table loads.
        group.bench_function(
            format!("{n} rules ({} states), raw chain", a.state_count()),
            |b| {
                b.iter(|| {
                    let mut s = a.step(a.start(), camera);
                    for &class in &walk {
                        s = a.step(s, class);
                    }
                    black_box(s)
                })
            },
        );
        group.bench_function(format!("{n} rules ({} states)", a.state_count()), |b| {
            b.iter(|| {
                // A dead state ends the path and the next one starts at the camera, as in
                // the renderer: the chain of dependent loads is what is measured.
                let after_camera = a.step(a.start(), camera);
                let mut s = after_camera;
                for &class in &walk {
                    s = a.step(s, class);
                    if a.is_dead(s) {
                        s = after_camera;
                    }
                }
                black_box(s)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, compile_bench, step_bench);
criterion_main!(benches);
