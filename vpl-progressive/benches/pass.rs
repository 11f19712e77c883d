//! Criterion bench of one progressive pass and its hot loops: VPL gathering
//! on `cornell` (diffuse only) and caustic photons with projection maps on
//! `glass`. `vpl render --method progressive` prints passes/s at full size.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use vpl_progressive::projection::{ProjectionMap, SpecularSet};
use vpl_progressive::{Progressive, ProgressiveConfig, Techniques, specular_bounds};

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("progressive");
    g.sample_size(20);
    for scene in ["cornell", "glass"] {
        let setup = vpl_core::SceneSetup::builtin(scene).unwrap();
        let camera = setup.camera.with_resolution((96, 72)).unwrap();
        let r = Progressive::new(&setup.scene, camera.clone(), ProgressiveConfig::default()).unwrap();
        g.throughput(Throughput::Elements(1));
        g.bench_function(format!("{scene}_96x72_pass"), |b| {
            let mut p = 0;
            b.iter(|| {
                p += 1;
                r.render_pass(p)
            })
        });
        if scene == "glass" {
            let only = |t: Techniques| {
                Progressive::new(&setup.scene, camera.clone(), ProgressiveConfig { techniques: t, ..Default::default() }).unwrap()
            };
            let caustics = only(Techniques { caustics: true, ..Techniques::NONE });
            g.bench_function("glass_96x72_caustics_only", |b| b.iter(|| caustics.render_pass(1)));
            let vpl = only(Techniques { vpl: true, ..Techniques::NONE });
            g.bench_function("glass_96x72_vpl_only", |b| b.iter(|| vpl.render_pass(1)));
            let bounds = SpecularSet::new(specular_bounds(&setup.scene));
            let y = vpl_core::glam::Vec3::new(0.0, 2.98, 0.0);
            g.throughput(Throughput::Elements(bounds.triangles.len() as u64));
            g.bench_function("glass_projection_map_128x256", |b| {
                b.iter(|| ProjectionMap::build(y, Some(-vpl_core::glam::Vec3::Y), &bounds, (128, 256)))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
