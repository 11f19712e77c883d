//! Nearest neighbours on the device ([`vpl_gpu::Gpu::neighbours`]) against
//! the k-d trees of vpl-density: the k-th squared distance of every point
//! (not its own neighbour) and of other queries, and every point's nearest
//! other point, on points in a volume, on surfaces (a G-buffer's, with the
//! ties a lattice of pixels makes), and on sets smaller than k. The
//! distances agree to a few ulps (a fused multiply-add may round once
//! less), the nearest points exactly unless two lie that close.

mod common;

use common::context;
use vpl_core::Purpose;
use vpl_core::SceneSetup;
use vpl_core::glam::Vec3;
use vpl_core::rng::stream;
use vpl_density::KnnDensity;
use vpl_gpu::Gpu;

fn close(a: f32, b: f32) -> bool {
    a == b || (a - b).abs() <= 4.0 * f32::EPSILON * a.abs().max(b.abs())
}

fn check(gpu: &Gpu, name: &str, points: &[Vec3], queries: &[Vec3]) {
    let tree = KnnDensity::new(points).unwrap();
    let (mut exact, mut all) = (0usize, 0usize);
    for k in [1, 8, 64] {
        let dev = gpu.neighbours(points, None, k).unwrap();
        let host = tree.member_radii_sq(k);
        for (i, (d, h)) in dev.iter().zip(&host).enumerate() {
            assert!(close(d.kth_sq, *h), "{name}, k = {k}: point {i}'s k-th neighbour at {} on the device, {h} on the host", d.kth_sq);
            exact += (d.kth_sq == *h) as usize;
            all += 1;
        }
        if k == 1 {
            for (i, (d, h)) in dev.iter().zip(tree.member_nearest()).enumerate() {
                let (dj, dd) = d.nearest.expect("a nearest point");
                let (hj, hd) = h.expect("a nearest point");
                assert!(close(dd, hd), "{name}: point {i}'s nearest at {dd} on the device, {hd} on the host");
                assert!(
                    dj == hj || close(dd, points[i].distance_squared(points[hj])),
                    "{name}: point {i}'s nearest {dj}, {hj} on the host"
                );
            }
        }
        let dev = gpu.neighbours(points, Some(queries), k).unwrap();
        for (i, d) in dev.iter().enumerate() {
            let h = tree.radius_sq(queries[i], k).unwrap();
            assert!(close(d.kth_sq, h), "{name}, k = {k}: query {i}'s k-th neighbour at {} on the device, {h} on the host", d.kth_sq);
            exact += (d.kth_sq == h) as usize;
            all += 1;
        }
    }
    eprintln!("{name}: {} points, {} queries agree; {exact} of {all} distances bit for bit", points.len(), queries.len());
}

#[test]
fn the_devices_neighbours_are_the_k_d_trees() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let mut rng = stream(1, 0, Purpose::TEST, 0);
    let mut cube =
        |n: usize, scale: f32| -> Vec<Vec3> { (0..n).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * scale).collect() };
    let volume = cube(3000, 10.0);
    let queries = cube(500, 12.0);
    check(&gpu, "a volume", &volume, &queries);
    // Surfaces: the points a camera sees in office, a lattice of pixels
    // with ties, and queries off them.
    let setup = SceneSetup::builtin("office").unwrap();
    let camera = setup.camera.with_resolution((80, 60)).unwrap();
    let g = gpu.render_gbuffer(&setup.scene, &camera).unwrap();
    let surface: Vec<Vec3> = g.samples.iter().filter(|s| s.hit()).map(|s| s.p).collect();
    let off: Vec<Vec3> = surface.iter().step_by(7).map(|p| *p + Vec3::new(0.01, 0.02, -0.015)).collect();
    check(&gpu, "office's surfaces", &surface, &off);
    // Fewer points than neighbours: no k-th neighbour, as on the host.
    let few = &volume[..5];
    let d = gpu.neighbours(few, None, 8).unwrap();
    assert!(d.iter().all(|n| n.kth_sq == f32::INFINITY && n.nearest.is_some()), "{d:?}");
    let one = gpu.neighbours(&volume[..1], None, 1).unwrap();
    assert_eq!((one[0].kth_sq, one[0].nearest), (f32::INFINITY, None));
    assert!(gpu.neighbours(&volume, None, 0).is_err() && gpu.neighbours(&volume, None, 65).is_err());
    assert!(gpu.neighbours(&[Vec3::splat(f32::NAN)], None, 1).is_err());
}

/// A search whose loops run long (every point in one cell, 64 neighbours
/// kept in order: about 100,000 iterations a query) either answers right
/// or says the device cut it short (llvmpipe stops a kernel's loops after
/// 65,535 iterations); it never answers wrong.
#[test]
fn a_search_is_right_or_refused_never_wrong() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let mut rng = stream(2, 0, Purpose::TEST, 0);
    // 3000 points in a ball of 1 mm, and a lone point far away that stretches the grid.
    let mut points: Vec<Vec3> = (0..3000).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 1e-3).collect();
    points.push(Vec3::splat(10.0));
    let host = KnnDensity::new(&points).unwrap().member_radii_sq(64);
    match gpu.neighbours(&points, None, 64) {
        Ok(dev) => {
            for (i, (d, h)) in dev.iter().zip(&host).enumerate() {
                assert!(close(d.kth_sq, *h), "point {i}: {} on the device, {h} on the host", d.kth_sq);
            }
            eprintln!("the device answered every search");
        }
        Err(e) => {
            assert!(matches!(e, vpl_gpu::GpuError::CutShort(_)), "{e}");
            eprintln!("refused: {e}");
        }
    }
}
