//! The same render is bit-identical on 1 and 2 threads, and tracked pixels too.

use vpl_core::SceneSetup;
use vpl_pathtrace::{Mode, PathTracer, RenderSettings, render, track};
use vpl_scene_io::ImageFile;

fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap()
}

#[test]
fn render_is_bit_identical_on_one_and_two_threads() {
    let setup = SceneSetup::builtin("cornell").unwrap();
    let cam = setup.camera.with_resolution((48, 40)).unwrap();
    for mode in [Mode::Full, Mode::Indirect] {
        let pt = PathTracer::new(5, mode);
        let s = RenderSettings { spp: 8, seed: 11, frame: 2 };
        let a = pool(1).install(|| render(&setup.scene, &cam, &pt, s, &|_, _| {}).unwrap());
        let b = pool(2).install(|| render(&setup.scene, &cam, &pt, s, &|_, _| {}).unwrap());
        let bits = |i: &vpl_core::Image| i.data.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&a.image), bits(&b.image));
        assert_eq!(bits(&a.stderr), bits(&b.stderr));
        // A different seed gives a different image (the test can fail).
        let c = pool(2).install(|| render(&setup.scene, &cam, &pt, RenderSettings { seed: 12, ..s }, &|_, _| {}).unwrap());
        assert_ne!(bits(&a.image), bits(&c.image));
    }
}

#[test]
fn tracked_pixels_are_thread_independent_and_agree_with_mitsuba() {
    let setup = SceneSetup::builtin("cornell").unwrap();
    let pt = PathTracer::new(5, Mode::Indirect);
    let px = [(128u32, 128u32), (10, 250), (60, 90)];
    let a = pool(1).install(|| track(&setup.scene, &setup.camera, &pt, &px, 10_000, 4, 0));
    let b = pool(2).install(|| track(&setup.scene, &setup.camera, &pt, &px, 10_000, 4, 0));
    assert_eq!(a, b);
    let reference = vpl_core::Image::read_exr(vpl_tests::data_dir().join("cornell-box/reference_indirect.exr")).unwrap();
    let reference_se = vpl_core::Image::read_exr(vpl_tests::data_dir().join("cornell-box/reference_indirect_stderr.exr")).unwrap();
    for t in &a {
        assert_eq!(t.samples, 10_000);
        let (r, rs) = (reference.get(t.pixel.0, t.pixel.1), reference_se.get(t.pixel.0, t.pixel.1));
        for c in 0..3 {
            let z = (t.mean[c] - r[c]) / (t.stderr[c].powi(2) + rs[c].powi(2)).sqrt();
            assert!(z.abs() < 4.0, "pixel {:?} channel {c}: {} vs {} (z {z:.2})", t.pixel, t.mean[c], r[c]);
        }
    }
}

#[test]
fn clamping_removes_energy_and_an_infinite_clamp_changes_nothing() {
    let setup = SceneSetup::builtin("cornell").unwrap();
    let cam = setup.camera.with_resolution((32, 32)).unwrap();
    let s = RenderSettings { spp: 16, seed: 2, frame: 0 };
    let plain = PathTracer::new(5, Mode::Indirect);
    let mut inf = plain;
    inf.clamp = Some(vpl_core::GeometryClamp::new(f32::INFINITY));
    let mut tight = plain;
    tight.clamp = Some(vpl_core::GeometryClamp::new(0.5));
    let a = render(&setup.scene, &cam, &plain, s, &|_, _| {}).unwrap();
    let b = render(&setup.scene, &cam, &inf, s, &|_, _| {}).unwrap();
    let c = render(&setup.scene, &cam, &tight, s, &|_, _| {}).unwrap();
    assert_eq!(a.image, b.image);
    for (x, y) in a.image.data.iter().zip(&c.image.data) {
        assert!(y.x <= x.x + 1e-6 && y.y <= x.y + 1e-6 && y.z <= x.z + 1e-6);
    }
    assert!(c.image.mean()[0] < 0.97 * a.image.mean()[0], "{:?} vs {:?}", c.image.mean(), a.image.mean());
}
