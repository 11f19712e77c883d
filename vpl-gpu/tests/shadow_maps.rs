//! GPU shadow maps against `vpl_visibility::ShadowMaps`.
//!
//! Both cast one ray per texel from the same origin in the same frame; the
//! GPU traverses another tree and may round directions differently, so a
//! texel on a silhouette can see the surface on the other side of the edge.
//! Tolerances: texel depths within 1e-4 relative (plus 1e-6 of the scene's
//! extent) on at least 99.5 % of texels; the visibility of G-buffer points
//! the same for at least 99.8 % of (point, VPL) pairs; only moved slots
//! re-render.

mod common;

use common::context;
use vpl_core::{SceneSetup, Vpl, VplVisibility};
use vpl_gpu::{Gpu, GpuShadowMaps};
use vpl_visibility::ShadowMaps;

#[test]
fn gpu_shadow_maps_match_the_cpu_maps() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let setup = SceneSetup::builtin("office").unwrap();
    let scene = &setup.scene;
    let mut set = vpl_ir::InstantRadiosity::new(vpl_ir::IrConfig { vpls: 48, ..Default::default() }).unwrap().sample(scene, 3).clone();
    let res = 64;
    let mut cpu = ShadowMaps::new(res).unwrap();
    let mut gpu_maps = GpuShadowMaps::new(gpu.clone(), res).unwrap();
    assert_eq!(cpu.update(scene, &set).rebuilt, gpu_maps.update(scene, &set).rebuilt);
    let extent = (scene.geometry.bounds.1 - scene.geometry.bounds.0).max_element();
    let (mut close, mut total) = (0usize, 0usize);
    for slot in 0..set.len() {
        let (Some(c), Some(g)) = (cpu.view(slot), gpu_maps.depths(slot)) else {
            assert!(cpu.view(slot).is_none() && gpu_maps.depths(slot).is_none());
            continue;
        };
        for j in 0..res {
            for i in 0..res {
                let (dc, dg) = (c.depth_at(i as f32, j as f32), g[(j * res + i) as usize]);
                let dc = dc.min(3.0e38);
                total += 1;
                close += ((dc - dg).abs() <= 1e-4 * dc + 1e-6 * extent) as usize;
            }
        }
    }
    eprintln!("texels: {close} of {total} agree");
    assert!(total > 0 && close as f64 >= 0.995 * total as f64, "{close} of {total} texels agree");

    // Visibility of the points of a small G-buffer from every VPL.
    let camera = setup.camera.with_resolution((48, 27)).unwrap();
    let gbuf = vpl_shading::render_gbuffer(scene, &camera);
    let (mut same, mut pairs, mut lit) = (0usize, 0usize, 0usize);
    for slot in 0..set.len() {
        for g in gbuf.samples.iter().filter(|g| g.reflects()) {
            let (a, b) = (cpu.visible(slot, g.p, g.n), gpu_maps.visible(slot, g.p, g.n));
            pairs += 1;
            same += (a == b) as usize;
            lit += (b > 0.0) as usize;
        }
    }
    eprintln!("visibility: {same} of {pairs} pairs agree, {lit} visible");
    assert!(lit > pairs / 20 && lit < pairs * 19 / 20);
    assert!(same as f64 >= 0.998 * pairs as f64, "{same} of {pairs} pairs agree");

    // Move two VPLs, change one's flux, empty one: two maps re-render.
    set.begin_frame();
    let v = |s: usize| set.get(s).copied().unwrap();
    let (v0, v1, v2) = (v(0), v(1), v(2));
    set.set(0, Some(Vpl { y: v1.y, n: v1.n, ..v0 }));
    set.set(1, Some(Vpl { y: v0.y, n: v0.n, ..v1 }));
    set.set(2, Some(Vpl { flux: v2.flux * 2.0, ..v2 }));
    set.set(3, None);
    let u = gpu_maps.update(scene, &set);
    assert_eq!(u.rebuilt, 2);
    assert_eq!(cpu.update(scene, &set).rebuilt, 2);
    assert!(gpu_maps.depths(3).is_none());
    let x = gbuf.samples.iter().find(|g| g.reflects()).unwrap();
    for slot in 0..4 {
        assert_eq!(cpu.visible(slot, x.p, x.n), gpu_maps.visible(slot, x.p, x.n), "slot {slot}");
    }
}
