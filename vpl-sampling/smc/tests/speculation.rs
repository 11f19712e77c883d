//! Rounds of visibility tests cast together by a caster that speculates
//! ([`RayCaster::speculates`]: a GPU, where a batch is a round trip) take
//! the same decisions as rounds cast one by one: the mailbox rounds of the
//! indirect-visibility check and the probes' owner rounds of the flux
//! estimator both take the first test that passes in round order, and a
//! test's answer depends on its ray alone. Both casters here are the CPU
//! BVH, so the check is exact: the same VPL in every slot, bit for bit, and
//! the same statistics (the rays the rounds cast included), on a camera walk
//! whose moves leave VPLs to re-verify; and fewer batches when speculating.

use std::sync::Mutex;
use vpl_core::{CpuRays, Frame, GBuffer, Hit, Ray, RayCaster, Scene, SceneSetup, Services, VplSampler};
use vpl_smc::{SmcConfig, SmcSampler};

/// The CPU BVH, counting batches; `speculates` as told.
struct Counted {
    speculates: bool,
    batches: Mutex<usize>,
}

impl RayCaster for Counted {
    fn name(&self) -> &'static str {
        "counted"
    }
    fn intersect(&self, scene: &Scene, rays: &[Ray]) -> Vec<Option<Hit>> {
        *self.batches.lock().unwrap() += 1;
        CpuRays.intersect(scene, rays)
    }
    fn occluded(&self, scene: &Scene, rays: &[Ray]) -> Vec<bool> {
        *self.batches.lock().unwrap() += 1;
        CpuRays.occluded(scene, rays)
    }
    fn speculates(&self) -> bool {
        self.speculates
    }
}

#[test]
fn speculative_rounds_take_the_round_by_round_decisions() {
    let setup = SceneSetup::builtin("office").unwrap();
    let config = SmcConfig { vpls: 256, warmup: 8, ..SmcConfig::default() };
    let casters = [false, true].map(|speculates| std::sync::Arc::new(Counted { speculates, batches: Mutex::new(0) }));
    let mut samplers =
        casters.clone().map(|c| SmcSampler::with_services(config, &Services { rays: c, radiosity: None, samplers: None }).unwrap());
    let gbuffer = GBuffer::empty();
    let (mut re_verified, mut probe_rays) = (0, 0);
    for f in [0u32, 10, 20, 30, 40, 50] {
        let (scene, camera) = setup.frame(f).unwrap();
        let camera = camera.with_resolution((64, 36)).unwrap();
        let frame =
            Frame { scene: &scene, camera: &camera, time: f as f32 / 30.0, index: f as u64, seed: 5, gbuffer: &gbuffer, previous: None };
        let [a, b] = &mut samplers;
        let (va, vb) = (a.next_frame(&frame).clone(), b.next_frame(&frame).clone());
        let same = (0..va.len()).filter(|&s| va.get(s) == vb.get(s)).count();
        assert_eq!(same, va.len(), "frame {f}: {same} of {} slots agree", va.len());
        assert_eq!(a.stats(), b.stats(), "frame {f}");
        re_verified += a.stats().ray_valid;
        probe_rays += a.stats().probe_rays;
    }
    let [round_by_round, together] = casters.map(|c| *c.batches.lock().unwrap());
    eprintln!(
        "{re_verified} VPLs re-verified by rays, {probe_rays} probe rays; batches: {round_by_round} round by round, {together} speculating"
    );
    // The walk exercises both kinds of rounds, and speculating saves batches.
    assert!(re_verified > 0 && probe_rays > 0);
    assert!(together < round_by_round);
}
