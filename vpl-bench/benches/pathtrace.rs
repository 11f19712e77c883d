//! Criterion bench of the path tracer on `cornell` (max-depth 5): throughput in paths.
//! `cargo xtask bench-pt` gives the headline 256×256 figure; this tracks regressions.
//! Also the BVH's traversal kernels and one shadow map's rays.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use vpl_bench::rays::RaySets;
use vpl_core::{Ray, SceneSetup};
use vpl_pathtrace::{Mode, PathTracer, RenderSettings, render};

fn bench(c: &mut Criterion) {
    let setup = SceneSetup::builtin("cornell").unwrap();
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
        let s = vpl_scene_io::load(name).unwrap();
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
    // One 128² paraboloid shadow map (16,384 rays from one VPL, traced in bundles), one thread.
    let mut g = c.benchmark_group("shadow_map");
    for name in ["cornell", "office"] {
        let s = vpl_scene_io::load(name).unwrap();
        let set = vpl_sampling::InstantRadiosity::new(vpl_sampling::IrConfig { vpls: 64, ..Default::default() })
            .unwrap()
            .sample(&s.scene, 3)
            .clone();
        let one = |k: usize| {
            let mut v = vpl_core::VplSet::new(1);
            v.set(0, set.get(k).copied());
            v
        };
        let sets: Vec<_> = (0..set.len()).filter(|&k| set.get(k).is_some()).take(8).map(one).collect();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        g.throughput(Throughput::Elements(128 * 128 * sets.len() as u64));
        g.bench_function(format!("{name}_128x128_x{}", sets.len()), |b| {
            b.iter(|| {
                pool.install(|| {
                    sets.iter()
                        .map(|v| {
                            let mut m = vpl_visibility::ShadowMaps::new(128).unwrap();
                            vpl_core::VplVisibility::update(&mut m, &s.scene, v).rebuilt
                        })
                        .sum::<usize>()
                })
            })
        });
    }
    g.finish();
    // The interleaved gather (128 VPLs per pixel from 2048, shadow-map visibility) and the
    // cross-bilateral filter at 640×360 on `office`, all threads.
    let mut g = c.benchmark_group("shading");
    g.sample_size(20);
    let s = SceneSetup::builtin("office").unwrap();
    let camera = s.camera.with_resolution((640, 360)).unwrap();
    let gbuf = vpl_shading::render_gbuffer(&s.scene, &camera);
    let set = vpl_sampling::InstantRadiosity::new(vpl_sampling::IrConfig { vpls: 2048, ..Default::default() })
        .unwrap()
        .sample(&s.scene, 0)
        .clone();
    let mut maps = vpl_visibility::ShadowMaps::new(128).unwrap();
    vpl_core::VplVisibility::update(&mut maps, &s.scene, &set);
    let mut shader = vpl_shading::InterleavedShader::new(Some(vpl_core::GeometryClamp::for_view(2048, &s.scene, &camera)), 0);
    g.throughput(Throughput::Elements(640 * 360 * 128));
    g.bench_function("office_640x360_gather", |b| b.iter(|| shader.irradiance(&gbuf, &set, &maps)));
    let e = shader.irradiance(&gbuf, &set, &maps);
    let filter = vpl_shading::CrossBilateral::default();
    g.throughput(Throughput::Elements(640 * 360));
    g.bench_function("office_640x360_filter", |b| b.iter(|| filter.apply(&gbuf, &e)));
    g.finish();
}

// No plots: criterion's plotting backend panics on machines without fonts.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
