//! Criterion bench of the path tracer on `cornell` (max-depth 5): throughput in paths.
//! `cargo xtask bench-pt` gives the headline 256×256 figure; this tracks regressions.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use vpl_bench::rays::RaySets;
use vpl_core::{Ray, SceneSetup};
use vpl_pathtrace::{Mode, PathTracer, RenderSettings, render};

fn bench(c: &mut Criterion) {
    let setup = SceneSetup::load("cornell").unwrap();
    let cam = setup.camera.with_resolution((64, 64)).unwrap();
    let mut g = c.benchmark_group("pathtrace");
    for (name, mode) in [("full", Mode::Full), ("indirect", Mode::Indirect)] {
        let pt = PathTracer::new(5, mode);
        g.throughput(Throughput::Elements(64 * 64 * 4));
        g.bench_function(format!("cornell_64x64_4spp_{name}"), |b| {
            b.iter(|| render(&setup.scene, &cam, &pt, RenderSettings { spp: 4, seed: 0, frame: 0 }, &|_, _| {}).unwrap())
        });
    }
    g.finish();
    let mut g = c.benchmark_group("bvh");
    let rays: Vec<Ray> = (0..1024).map(|i| setup.camera.ray((i % 32) as f32 * 8.0, (i / 32) as f32 * 8.0, (0.5, 0.5))).collect();
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function("cornell_primary_closest", |b| b.iter(|| rays.iter().filter(|r| setup.scene.intersect(r).is_some()).count()));
    g.bench_function("cornell_primary_occluded", |b| b.iter(|| rays.iter().filter(|r| setup.scene.occluded(r)).count()));
    // The traversal kernels alone, one thread, on the three kinds of rays of `vpl bench-rays`.
    for name in ["cornell", "office"] {
        let s = SceneSetup::load(name).unwrap();
        let sets = RaySets::new(&s.scene, &s.camera, (64, 64), 1);
        let bvh = &s.scene.geometry.bvh;
        for (kind, rays, closest) in [("primary", &sets.primary, true), ("diffuse", &sets.diffuse, true), ("shadow", &sets.shadow, false)] {
            g.throughput(Throughput::Elements(rays.len() as u64));
            g.bench_function(format!("{name}_{kind}_traversal"), |b| {
                b.iter(|| {
                    if closest {
                        rays.iter().filter(|r| bvh.closest(r).is_some()).count()
                    } else {
                        rays.iter().filter(|r| bvh.occluded(r)).count()
                    }
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
