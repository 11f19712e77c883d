//! SMC with its rays (camera points, candidate rays, mailbox and
//! indirect-visibility rays) cast on the GPU ([`GpuRays`]) against SMC on
//! the CPU BVH. The camera points' rays, and the candidate rays that leave
//! their hits, are made on the device.
//!
//! [`GpuRays`] completes each GPU hit with the CPU's test of the triangle the
//! GPU found, so a ray that finds the same triangle gives the CPU's hit bit
//! for bit; only ties (a ray through a shared edge) may differ. Tolerances:
//! at most 1 in 10⁴ of the sampler's rays differ, and the sampler takes the
//! same decisions: the same VPL, bit for bit, in every slot of every frame
//! of a camera walk (100 warm-up iterations, then four frames), with the
//! GPU's rounds of visibility tests cast together (it speculates) and the
//! CPU's one by one.

mod common;

use common::context;
use std::sync::{Arc, Mutex};
use vpl_core::{BounceRays, CameraRays, CpuRays, Frame, Hit, Ray, RayCaster, Scene, SceneSetup, Services, VplSampler};
use vpl_gpu::{Gpu, GpuRays};
use vpl_smc::{SmcConfig, SmcSampler};

/// Casts every batch on both and counts (closest, differing, occlusion, differing).
struct Both(GpuRays, Mutex<[usize; 4]>);

impl RayCaster for Both {
    fn name(&self) -> &'static str {
        "both"
    }
    fn intersect(&self, scene: &Scene, rays: &[Ray]) -> Vec<Option<Hit>> {
        let (g, c) = (self.0.intersect(scene, rays), CpuRays.intersect(scene, rays));
        let mut n = self.1.lock().unwrap();
        n[0] += rays.len();
        n[1] += c.iter().zip(&g).filter(|(a, b)| a != b).count();
        g
    }
    fn intersect_camera(&self, scene: &Scene, batch: &CameraRays) -> Vec<Option<Hit>> {
        let (g, c) = (self.0.intersect_camera(scene, batch), CpuRays.intersect(scene, &batch.rays));
        let mut n = self.1.lock().unwrap();
        n[0] += batch.rays.len();
        n[1] += c.iter().zip(&g).filter(|(a, b)| a != b).count();
        g
    }
    fn intersect_bounce(&self, scene: &Scene, batch: &BounceRays) -> Vec<Option<Hit>> {
        let (g, c) = (self.0.intersect_bounce(scene, batch), CpuRays.intersect(scene, &batch.rays));
        let mut n = self.1.lock().unwrap();
        n[0] += batch.rays.len();
        n[1] += c.iter().zip(&g).filter(|(a, b)| a != b).count();
        g
    }
    fn occluded(&self, scene: &Scene, rays: &[Ray]) -> Vec<bool> {
        let (g, c) = (self.0.occluded(scene, rays), CpuRays.occluded(scene, rays));
        let mut n = self.1.lock().unwrap();
        n[2] += rays.len();
        n[3] += c.iter().zip(&g).filter(|(a, b)| a != b).count();
        g
    }
    /// As the GPU: rounds of tests cast together, against the CPU's rounds.
    fn speculates(&self) -> bool {
        self.0.speculates()
    }
}

#[test]
fn smc_with_gpu_rays_takes_the_cpu_decisions() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let setup = SceneSetup::builtin("office").unwrap();
    let config = SmcConfig { vpls: 256, ..SmcConfig::default() };
    let mut cpu = SmcSampler::new(config).unwrap();
    let both = Arc::new(Both(GpuRays::new(gpu), Mutex::new([0; 4])));
    let services = Services { rays: both.clone(), radiosity: None, samplers: None };
    let mut on_gpu = SmcSampler::with_services(config, &services).unwrap();
    for f in [0u32, 15, 30, 45] {
        let (scene, camera) = setup.frame(f).unwrap();
        let camera = camera.with_resolution((64, 36)).unwrap();
        let gbuf = vpl_shading::render_gbuffer(&scene, &camera);
        let frame =
            Frame { scene: &scene, camera: &camera, time: f as f32 / 30.0, index: f as u64, seed: 3, gbuffer: &gbuf, previous: None };
        let a = cpu.next_frame(&frame).clone();
        let b = on_gpu.next_frame(&frame).clone();
        let same = (0..a.len()).filter(|&s| a.get(s) == b.get(s)).count();
        eprintln!("frame {f}: {same} of {} slots hold the same VPL; {} moved", a.len(), a.moved_count());
        assert_eq!(same, a.len(), "frame {f}");
        assert!(a.stored() > 0);
    }
    let [closest, c_diff, occl, o_diff] = *both.1.lock().unwrap();
    eprintln!("rays: {closest} closest-hit ({c_diff} differ), {occl} occlusion ({o_diff} differ)");
    assert!(closest > 100_000 && occl > 1_000);
    assert!(c_diff * 10_000 <= closest && o_diff * 10_000 <= occl);
}
