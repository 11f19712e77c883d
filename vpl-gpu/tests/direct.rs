//! A frame of every light path on the device: the G-buffer's emission (the
//! environment at misses included) and the direct light added there
//! ([`vpl_gpu::Gpu::finish_frame`]) against the same renderer's frame whose
//! emission and direct light the host adds to the read-back G-buffer. The
//! same light samples from the same streams, the same lights and shadow
//! rays: the images agree but for rounding and the rare shadow ray that
//! grazes an edge, on a scene with a light of every kind.

mod common;

use common::context;
use vpl_core::environment::Sky;
use vpl_core::glam::Vec3;
use vpl_core::{Image, Light, Mode, Scene, SceneSetup};
use vpl_gpu::{Gpu, GpuBackend};
use vpl_render::{ReadBack, Renderer};

fn frame(gpu: &Gpu, scene: &Scene, setup: &SceneSetup, read_back: ReadBack) -> (Image, bool) {
    let camera = setup.camera.with_resolution((96, 72)).unwrap();
    let mut r = Renderer::builder(scene)
        .vpls(64)
        .sampler("ir")
        .mode(Mode::Full)
        .seed(11)
        .read_back(read_back)
        .backend(GpuBackend::new(gpu.clone()))
        .build()
        .unwrap();
    let before = gpu.traffic();
    let out = r.render(scene, &camera, 0, 0.0).unwrap();
    let t = gpu.traffic() - before;
    let on_device = !out.image.on_host();
    if on_device {
        // IR samples on the host: a frame finished on the device reads nothing back.
        assert_eq!(t.bytes_down, 0, "{t}");
    }
    (if on_device { r.read_image().unwrap() } else { out.image }, on_device)
}

fn compare(name: &str, host: &Image, device: &Image) {
    let mean = |i: &Image| i.data.iter().map(|c| c.element_sum() as f64).sum::<f64>() / i.data.len() as f64;
    let (mh, md) = (mean(host), mean(device));
    let close =
        host.data.iter().zip(&device.data).filter(|(a, b)| (**a - **b).abs().max_element() <= 1e-3 * a.max_element().max(1e-3)).count();
    let share = close as f64 / host.data.len() as f64;
    eprintln!("{name}: mean {mh:.6} on the host, {md:.6} on the device; {:.2} % of pixels within 1e-3", 100.0 * share);
    assert!(mh > 0.0, "{name}: a lit frame");
    // A pixel whose shadow ray lands the other side of an edge differs by
    // its light sample's share: 1/16 of its direct light at most.
    assert!(share >= 0.995, "{name}: {:.2} % of pixels agree", 100.0 * share);
    assert!((mh - md).abs() <= 2e-3 * mh, "{name}: means {mh} and {md}");
}

#[test]
fn emission_and_direct_light_added_on_the_device_equal_the_hosts() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let cornell = SceneSetup::builtin("cornell").unwrap();
    let (lo, hi) = cornell.scene.geometry.bounds;
    let c = 0.5 * (lo + hi);
    let r = cornell.scene.radius();
    // Every kind of light: the box's area light, a point, a spot, the sun
    // and a sky (lighting what it reaches, and seen where camera rays miss).
    let extra = vec![
        Light::Point { position: c + Vec3::new(0.2, 0.3, 0.1) * r, intensity: Vec3::new(2.0, 1.5, 1.0) * r * r },
        Light::Spot {
            position: c + Vec3::new(-0.3, 0.35, 0.2) * r,
            direction: Vec3::new(0.2, -1.0, -0.1).normalize(),
            intensity: Vec3::new(1.0, 2.0, 3.0) * r * r,
            cos_falloff_start: 0.9,
            cos_total: 0.7,
        },
        Light::Directional { direction: Vec3::new(0.3, -1.0, -0.5).normalize(), irradiance: Vec3::splat(0.5) },
        Light::Environment { sky: Sky { zenith: Vec3::new(0.2, 0.3, 0.6), horizon: Vec3::new(0.5, 0.5, 0.5), nadir: Vec3::splat(0.05) } },
    ];
    let mut lights = cornell.scene.lights.clone();
    lights.extend(extra);
    let lit = cornell.scene.with_lights(lights).unwrap();
    let office = SceneSetup::builtin("office").unwrap();
    for (name, scene, setup) in [("cornell, every kind of light", &lit, &cornell), ("office", &office.scene, &office)] {
        let (host, on_host_device) = frame(&gpu, scene, setup, ReadBack::All);
        let (device, on_device) = frame(&gpu, scene, setup, ReadBack::Nothing);
        assert!(!on_host_device && on_device, "{name}: a full frame stays on the device under ReadBack::Nothing");
        compare(name, &host, &device);
    }
}
