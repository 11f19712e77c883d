//! The frame on the device: a renderer on the GPU backend under
//! `ReadBack::Nothing` leaves the G-buffer and the image on the device, and
//! what crosses between host and device per frame is counted
//! ([`vpl_gpu::Traffic`]). The counts do not depend on the device's speed,
//! so lavapipe holds them for every GPU.
//!
//! - The resident frame's image, read back once on request, is the image the
//!   same renderer gives when it reads everything back, bit for bit (the same
//!   kernels on the same inputs).
//! - A steady-state frame of SMC at 1920×1080 with 2048 VPLs moves at most
//!   2 MB (2·10⁶ B, both directions together) in at most 16 submissions,
//!   the sampler's step included. Besides that step it moves at most 512 KiB
//!   and reads nothing back, in at most 8 submissions: the VPL rows (48 B a
//!   slot), the shadow maps' headers (64 B a slot) and jobs, and the
//!   kernels' parameters. Reading the G-buffer and image back instead moves
//!   5 + 1 buffers of 16 B a pixel (199 MB). The step's share: its camera
//!   rays made on the device (the camera and a key up, 4 B a ray back), its
//!   candidate rays too, from the camera hits the device holds (8 B up, 4 B
//!   back a ray), its shadow rays packed (28 B up, one bit back),
//!   its radiosity paths summed on the device (56 B a point up, 16 B back),
//!   and its rounds of visibility tests cast together; its kNN and flux
//!   estimates run on the host.

mod common;

use common::context;
use std::sync::{Arc, Mutex};
use vpl_core::{Frame, Mode, SceneSetup, Services, Stats, VplSampler, VplSet};
use vpl_gpu::{Gpu, GpuBackend, Traffic};
use vpl_render::{Backend, ReadBack, Renderer};
use vpl_smc::{SmcConfig, SmcSampler};

/// A sampler that records the device traffic of its own step.
struct Counted {
    inner: SmcSampler,
    gpu: Gpu,
    last: Arc<Mutex<Traffic>>,
}

impl VplSampler for Counted {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn next_frame(&mut self, frame: &Frame) -> &VplSet {
        let t0 = self.gpu.traffic();
        self.inner.next_frame(frame);
        *self.last.lock().unwrap() = self.gpu.traffic() - t0;
        self.inner.vpls()
    }
    fn stats(&self) -> Stats {
        VplSampler::stats(&self.inner)
    }
}

fn renderer(gpu: &Gpu, setup: &SceneSetup, vpls: usize, read_back: ReadBack) -> (Renderer, Arc<Mutex<Traffic>>) {
    let backend = GpuBackend::new(gpu.clone());
    let services: Services = backend.services();
    // A short warm-up: what a frame moves does not depend on how many
    // iterations came before it, and each one is a round of kernels on
    // lavapipe (the default 100 took this file from 362 s to 397 s).
    let inner = SmcSampler::with_services(SmcConfig { vpls, warmup: 4, ..SmcConfig::default() }, &services).unwrap();
    let last = Arc::new(Mutex::new(Traffic::default()));
    let sampler: Box<dyn VplSampler> = Box::new(Counted { inner, gpu: gpu.clone(), last: last.clone() });
    let r = Renderer::builder(&setup.scene)
        .vpls(vpls)
        .sampler(sampler)
        .mode(Mode::Indirect)
        .seed(7)
        .read_back(read_back)
        .backend(backend)
        .build()
        .unwrap();
    (r, last)
}

#[test]
fn the_resident_image_read_on_request_equals_the_read_back_one() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let setup = SceneSetup::builtin("office").unwrap();
    let camera = setup.camera.with_resolution((96, 72)).unwrap();
    let (mut all, _) = renderer(&gpu, &setup, 256, ReadBack::All);
    let (mut none, sampling) = renderer(&gpu, &setup, 256, ReadBack::Nothing);
    for f in 0..3 {
        let a = all.render(&setup.scene, &camera, f, 0.0).unwrap();
        assert!(a.image.on_host() && a.gbuffer.on_host());
        let before = gpu.traffic();
        let n = none.render(&setup.scene, &camera, f, 0.0).unwrap();
        let rest = (gpu.traffic() - before) - *sampling.lock().unwrap();
        assert!(!n.image.on_host() && !n.gbuffer.on_host(), "frame {f} left the device");
        assert_eq!(rest.bytes_down, 0, "frame {f}: the frame besides sampling read back {rest}");
        let image = none.read_image().expect("an image");
        assert_eq!((image.width, image.height), (96, 72));
        assert!(image.data == a.image.data, "frame {f}: the resident image differs from the read-back one");
        // The G-buffer it left is read back on request, and is the host one.
        let g = none.backend().host_gbuffer(n.gbuffer.clone(), &setup.scene, &camera).unwrap();
        assert!(g.samples == a.gbuffer.samples, "frame {f}: the G-buffer read on request differs");
    }
}

#[test]
fn a_steady_1080p_smc_frame_moves_little_besides_the_sampler() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let setup = SceneSetup::builtin("office").unwrap();
    let camera = setup.camera.with_resolution((1920, 1080)).unwrap();
    let (mut r, sampling) = renderer(&gpu, &setup, 2048, ReadBack::Nothing);
    let mut frames = Vec::new();
    // Frame 0 fills SMC's cells; frame 1 is a steady one (a second
    // steady 1080p frame in each of the two tests took 34 s on lavapipe).
    for f in 0..2 {
        let before = gpu.traffic();
        let out = r.render(&setup.scene, &camera, f, 0.0).unwrap();
        let t = gpu.traffic() - before;
        let s = *sampling.lock().unwrap();
        eprintln!("frame {f}: {t}; of which the sampler: {s}; {} VPLs moved; {:?}", out.moved, out.timings);
        frames.push((t, s, out.image.on_host()));
    }
    for (f, &(t, s, on_host)) in frames.iter().enumerate().skip(1) {
        assert!(!on_host, "frame {f} read its image back");
        let rest = t - s;
        assert_eq!(rest.bytes_down, 0, "frame {f}: the frame besides sampling read back {rest}");
        assert!(rest.bytes_up <= 512 << 10, "frame {f}: the frame besides sampling moved {rest}");
        assert!(rest.submissions <= 8, "frame {f}: the frame besides sampling took {rest}");
        assert!(t.bytes_up + t.bytes_down <= 2_000_000, "frame {f} moved {t}");
        assert!(t.submissions <= 16, "frame {f} took {t}");
    }
    let before = gpu.traffic();
    let image = r.read_image().expect("an image");
    let t = gpu.traffic() - before;
    assert_eq!((image.width, image.height, t.reads), (1920, 1080, 1));
    assert_eq!(t.bytes_down, 1920 * 1080 * 16);
}

/// The host's Σ|ΔL| / ΣL, as the viewer plots it.
fn change_on_host(a: &vpl_core::Image, b: &vpl_core::Image) -> f64 {
    let (mut diff, mut sum) = (0.0f64, 0.0f64);
    for (p, q) in a.data.iter().zip(&b.data) {
        diff += (*q - *p).abs().element_sum() as f64;
        sum += q.element_sum().max(0.0) as f64;
    }
    diff / sum
}

#[test]
fn frames_left_on_the_device_are_published_and_their_change_is_reduced_there() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let setup = SceneSetup::builtin("office").unwrap();
    let camera = setup.camera.with_resolution((200, 150)).unwrap();
    let backend = GpuBackend::new(gpu.clone());
    let frames = backend.frames();
    let mut r = Renderer::builder(&setup.scene)
        .vpls(128)
        .sampler("smc")
        .params(vpl_core::Params::parse(["warmup=4"]).unwrap())
        .mode(Mode::Indirect)
        .seed(3)
        .read_back(ReadBack::Nothing)
        .backend(backend)
        .build()
        .unwrap();
    assert!(frames.latest().is_none(), "nothing published before the first frame");
    let mut kept = Vec::new();
    for f in 0..3 {
        r.render(&setup.scene, &camera, f, 0.0).unwrap();
        let frame = frames.latest().expect("the frame was published");
        assert_eq!((frame.width, frame.height), (200, 150));
        // What was published is the renderer's image and G-buffer.
        let image = frame.read_image(gpu.ctx()).unwrap();
        assert!(image.data == r.read_image().unwrap().data, "frame {f}: the published image is the renderer's");
        let g = frame.read_gbuffer(gpu.ctx()).unwrap();
        assert_eq!((g.width, g.height), (200, 150));
        kept.push((frame, image));
    }
    // A frame held stays as it was while later frames render.
    assert!(kept[0].0.read_image(gpu.ctx()).unwrap().data == kept[0].1.data, "a held frame was overwritten");
    for w in kept.windows(2) {
        let ((a, ia), (b, ib)) = (&w[0], &w[1]);
        let before = gpu.traffic();
        let device = gpu.temporal_change(a, b).unwrap().expect("a lit frame");
        let t = gpu.traffic() - before;
        let host = change_on_host(ia, ib);
        // f32 partial sums of ≤ 2 pixels each (30,000 pixels over 65,536
        // threads) added in f64: a few ulps of f32 relative.
        assert!((device - host).abs() <= 1e-5 * host.max(1e-6), "change {device} on the device, {host} on the host");
        assert!(host > 0.0, "SMC frames differ from frame to frame");
        assert_eq!((t.reads, t.bytes_down, t.submissions), (1, 2048, 1), "{t}");
    }
    // Same frame against itself: no change.
    assert_eq!(gpu.temporal_change(&kept[1].0, &kept[1].0).unwrap(), Some(0.0));
    // Read back instead: nothing is published.
    r.set_read_back(ReadBack::All);
    r.render(&setup.scene, &camera, 3, 0.0).unwrap();
    assert!(frames.latest().is_none(), "a frame read back is not published");
}

/// SMC with the paper's flux, asked for by name on the GPU backend, runs
/// wholly on the device ([`vpl_gpu::GpuSmcSampler`]): a steady 1080p frame
/// with 2048 VPLs, its sampling included, reads back only the VPL rows and
/// the statistics (48 B a slot and 64 B) and writes little more than the
/// iteration's parameters, in one submission for the sampler's step.
#[test]
fn a_steady_1080p_frame_of_smc_on_the_device_moves_only_the_vpls() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let setup = SceneSetup::builtin("office").unwrap();
    let camera = setup.camera.with_resolution((1920, 1080)).unwrap();
    let backend = GpuBackend::new(gpu.clone());
    let mut r = Renderer::builder(&setup.scene)
        .vpls(2048)
        .sampler("smc-knn")
        .params(vpl_core::Params::parse(["warmup=4"]).unwrap())
        .mode(Mode::Indirect)
        .seed(7)
        .read_back(ReadBack::Nothing)
        .backend(backend)
        .build()
        .unwrap();
    // Frame 0 warms up, frame 1 is a steady one.
    for f in 0..2 {
        let before = gpu.traffic();
        let out = r.render(&setup.scene, &camera, f, 0.0).unwrap();
        let t = gpu.traffic() - before;
        eprintln!("frame {f}: {t}; {} VPLs moved; {:?}", out.moved, out.timings);
        assert_eq!(r.sampler().stats().get("stored"), Some(2048.0));
        if f == 0 {
            continue;
        }
        // The VPL rows and statistics are all that come back.
        assert_eq!(t.bytes_down, 3 * 2048 * 16 + 64, "frame {f} read back {t}");
        assert_eq!(t.reads, 1, "frame {f}: {t}");
        assert!(t.bytes_up <= 512 << 10, "frame {f} moved {t}");
        // One submission for the sampler's step, the rest the frame's.
        assert!(t.submissions <= 9, "frame {f} took {t}");
    }
}
