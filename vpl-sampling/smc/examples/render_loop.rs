//! SMC in your own render loop: the sampler hands you each frame's VPLs; the
//! shading (here 48×36 pixels, every VPL, a shadow ray each, the geometry
//! term clamped) is yours. The camera walks; the VPLs follow slowly.
//!
//! Run: `cargo run -p vpl-smc --example render_loop`

use vpl_core::glam::Vec3;
use vpl_core::{Camera, Frame, GBuffer, GeometryClamp, Scene, SceneSetup, VplSampler, VplSet};
use vpl_smc::{SmcConfig, SmcSampler};

/// Indirect radiance toward the camera at each pixel from the VPLs:
/// ρ/π · flux · G · V summed over the set (vpl-core's flux convention).
fn shade(scene: &Scene, camera: &Camera, vpls: &VplSet, clamp: GeometryClamp) -> Vec<Vec3> {
    let (w, h) = camera.resolution;
    (0..w * h)
        .map(|i| {
            let ray = camera.ray((i % w) as f32 + 0.5, (i / w) as f32 + 0.5, (0.5, 0.5));
            let Some(hit) = scene.intersect(&ray) else { return Vec3::ZERO };
            let x = hit.point.facing(-ray.d);
            let albedo = scene.material(&x).albedo;
            let mut sum = Vec3::ZERO;
            for (_, vpl) in vpls.iter() {
                let g = vpl.geometry(x.p, x.n);
                if g > 0.0 && scene.visible(x.p + x.ng * scene.epsilon(), vpl.y) {
                    sum += vpl.flux * clamp.clamp(g);
                }
            }
            albedo / std::f32::consts::PI * sum
        })
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let setup = SceneSetup::builtin("office")?;
    let vpls = 256;
    let mut smc = SmcSampler::new(SmcConfig { vpls, warmup: 20, m_max: 8, ..SmcConfig::default() })?;
    // The toolkit's default clamp, from the view of the first frame.
    let clamp = GeometryClamp::for_view(vpls, &setup.scene, &setup.camera);
    // The sampler casts its own camera rays: it needs no G-buffer.
    let gbuffer = GBuffer::empty();
    for index in 0..4u32 {
        let (scene, camera) = setup.frame(index * 15)?;
        let camera = camera.with_resolution((48, 36))?;
        let frame = Frame {
            scene: &scene,
            camera: &camera,
            time: index as f32 * 0.5,
            index: index as u64,
            seed: 7,
            gbuffer: &gbuffer,
            previous: None,
        };
        let set = smc.next_frame(&frame).clone();
        let image = shade(&scene, &camera, &set, clamp);
        let mean = image.iter().copied().sum::<Vec3>() / image.len() as f32;
        println!(
            "frame {index}: {} VPLs, {} moved, mean indirect radiance {:.4}",
            set.stored(),
            set.moved_count(),
            mean.element_sum() / 3.0
        );
        // The sampler's typed statistics of the frame (acceptance, timings, …).
        println!("  {}", VplSampler::stats(&smc));
    }
    Ok(())
}
