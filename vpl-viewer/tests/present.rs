//! The view composed on the device ([`vpl_viewer::present::DeviceView`])
//! against the host's [`vpl_viewer::view::compose`] of the same frames read
//! back: every channel, both overlays, split and whole, a picked VPL. The
//! display bytes agree to one step of 255 (the sRGB curve's `pow` rounds
//! differently in WGSL) and 99 % of them exactly. Without an adapter the
//! test says it skipped, unless VPL_REQUIRE_GPU=1 (CI).
#![cfg(feature = "gpu")]

use vpl_core::{Image, Mode, SceneSetup};
use vpl_gpu::{Gpu, GpuBackend, GpuContext};
use vpl_render::{ReadBack, Renderer};
use vpl_viewer::camera::FlyCamera;
use vpl_viewer::present::{DeviceSide, DeviceView};
use vpl_viewer::view::{Channel, Look, Overlay, Pick, SideFrame, compose};

fn gpu() -> Option<Gpu> {
    match GpuContext::new() {
        Ok(c) => Some(Gpu::from_context(c)),
        Err(e) if std::env::var("VPL_REQUIRE_GPU").is_ok_and(|v| v == "1") => panic!("VPL_REQUIRE_GPU=1 but {e}"),
        Err(e) => {
            eprintln!("skipped: {e}");
            None
        }
    }
}

#[test]
fn the_device_composite_is_the_host_composite() {
    let Some(gpu) = gpu() else { return };
    let setup = SceneSetup::builtin("office").unwrap();
    let camera = setup.camera.with_resolution((161, 97)).unwrap();
    let mut sides = Vec::new();
    for sampler in ["smc", "ir"] {
        let backend = GpuBackend::new(gpu.clone());
        let frames = backend.frames();
        let mut r = Renderer::builder(&setup.scene)
            .vpls(96)
            .sampler(sampler)
            .mode(Mode::Indirect)
            .seed(5)
            .read_back(ReadBack::Nothing)
            .backend(backend)
            .build()
            .unwrap();
        // Frames until some VPLs moved in the last (their rings are drawn);
        // IR's set stays, so two frames.
        // The first frames from a camera turned away, so that SMC replaces
        // VPLs the compared view no longer sees.
        let mut fly = FlyCamera::from_camera(&camera);
        fly.orbit(1.2, 0.0);
        let away = fly.camera(&camera, (161, 97)).unwrap();
        let mut out = r.render(&setup.scene, &away, 0, 0.0).unwrap();
        for f in 1..12 {
            out = r.render(&setup.scene, &camera, f, 0.0).unwrap();
            if out.vpls.moved_count() > 0 || sampler == "ir" {
                break;
            }
        }
        assert!(!out.image.on_host(), "{sampler}: the frame stayed on the device");
        let frame = frames.latest().expect("published");
        let image = frame.read_image(gpu.ctx()).unwrap();
        let gbuffer = frame.read_gbuffer(gpu.ctx()).unwrap();
        sides.push((frame, image, gbuffer, out.vpls));
    }
    assert!(sides[0].2.samples == sides[1].2.samples, "one camera, one scene: one G-buffer");
    assert!(sides.iter().any(|s| s.3.iter().any(|(slot, _)| s.3.moved(slot))), "some VPL moved (rings drawn)");
    // A reference that differs from the frames both ways.
    let reference = {
        let mut r = Image::new(161, 97);
        for (i, (p, q)) in r.data.iter_mut().zip(&sides[0].1.data).enumerate() {
            *p = *q * (0.6 + 0.8 * ((i * 37 % 101) as f32 / 100.0));
        }
        r
    };
    // A VPL the camera sees, picked on the right side.
    let picked_slot = sides[1]
        .3
        .iter()
        .find(|(_, v)| camera.project(v.y).is_some_and(|(x, y)| x > 90.0 && x < 150.0 && y > 10.0 && y < 85.0))
        .map(|(slot, _)| slot);
    assert!(picked_slot.is_some(), "a VPL of the right side in view to pick");
    let mut view = DeviceView::new(&gpu);
    let (mut compared, mut exact, mut worst) = (0usize, 0usize, 0i32);
    for split in [false, true] {
        for channel in Channel::ALL {
            for overlay in Overlay::ALL {
                for picked in [None, picked_slot.map(|slot| Pick { side: split as usize, slot, class: Some(slot % 16) })] {
                    let look = Look { channel, overlay, exposure: 1.7, reference: Some(&reference), picked };
                    let host = |k: usize| SideFrame { image: &sides[k].1, gbuffer: &sides[k].2, vpls: &sides[k].3, camera: &camera };
                    let want = compose(host(0), split.then(|| host(1)), &look);
                    let dev = |k: usize| DeviceSide { frame: &sides[k].0, vpls: &sides[k].3, camera: &camera };
                    view.compose(&gpu, dev(0), split.then(|| dev(1)), &look).unwrap();
                    let got = view.read(&gpu).unwrap();
                    assert_eq!(got.len(), want.rgba.len());
                    let what = format!("split {split}, {}, overlay {}, picked {:?}", channel.name(), overlay.name(), picked);
                    for (i, (a, b)) in got.iter().zip(&want.rgba).enumerate() {
                        let d = (*a as i32 - *b as i32).abs();
                        assert!(d <= 1, "{what}: byte {i} (pixel {}, {}) is {a} on the device, {b} on the host", i / 4 % 161, i / 4 / 161);
                        worst = worst.max(d);
                        exact += (d == 0) as usize;
                        compared += 1;
                    }
                }
            }
        }
    }
    let share = exact as f64 / compared as f64;
    eprintln!("{compared} bytes compared, {:.4} % exact, worst {worst}", share * 100.0);
    assert!(share >= 0.99, "only {:.3} % of the bytes agree exactly", share * 100.0);
}

#[test]
fn composing_reads_nothing_back_and_takes_one_submission() {
    let Some(gpu) = gpu() else { return };
    let setup = SceneSetup::builtin("cornell").unwrap();
    let camera = setup.camera.with_resolution((64, 48)).unwrap();
    let backend = GpuBackend::new(gpu.clone());
    let frames = backend.frames();
    let mut r =
        Renderer::builder(&setup.scene).vpls(32).mode(Mode::Indirect).read_back(ReadBack::Nothing).backend(backend).build().unwrap();
    let out = r.render(&setup.scene, &camera, 0, 0.0).unwrap();
    let frame = frames.latest().unwrap();
    let mut view = DeviceView::new(&gpu);
    let side = DeviceSide { frame: &frame, vpls: &out.vpls, camera: &camera };
    let look = Look { overlay: Overlay::Vpls, ..Look::image() };
    let before = gpu.traffic();
    view.compose(&gpu, side, None, &look).unwrap();
    let t = gpu.traffic() - before;
    assert_eq!((t.reads, t.bytes_down, t.submissions), (0, 0, 1), "{t}");
    // The parameters (80 B) and 16 B a VPL at most go up.
    assert!(t.bytes_up <= 80 + 16 * 32 + 64, "{t}");
    let texture = view.texture().expect("a texture");
    assert_eq!((texture.width(), texture.height()), (64, 48));
}

/// The render thread keeps a split view's frames on the device only when
/// both sides can stay there: beside RR, which reads the previous image on
/// the host, SMC's frame comes back too (image and G-buffer), so the window
/// composes both on the host.
#[test]
fn a_split_with_a_side_on_the_host_comes_back_whole() {
    use std::sync::atomic::AtomicBool;
    use std::sync::{Arc, mpsc};
    use vpl_viewer::worker::{self, BackendChoice, Job, Reply, SideSpec};
    let Some(gpu) = gpu() else { return };
    let setup = SceneSetup::builtin("cornell").unwrap();
    let camera = setup.camera.with_resolution((48, 36)).unwrap();
    let (jobs, job_rx) = mpsc::channel();
    let (reply_tx, replies) = mpsc::channel();
    let registry = vpl_sampling::Registry::builtin();
    let thread = std::thread::spawn(move || {
        worker::run(job_rx, reply_tx, registry, BackendChoice::Gpu(gpu), vpl_render::PipelineSpec { seed: 1, ..Default::default() }, || {})
    });
    let scene = Arc::new(setup.scene.clone());
    for (pair, on_device) in [(["smc", "ir"], true), (["smc", "rr"], false)] {
        let sides = pair.map(|s| SideSpec { sampler: s.into(), vpls: 32, mode: Mode::Full, resolution: (48, 36) }).to_vec();
        let cancel = Arc::new(AtomicBool::new(false));
        jobs.send(Job { scene: scene.clone(), camera: camera.clone(), time: 0.0, sides, cancel, reference: None, resident: true }).unwrap();
        match replies.recv().unwrap() {
            Reply::Frame { sides, .. } => {
                for s in &sides {
                    let what = format!("{} beside {}", s.spec.sampler, pair.join(" and "));
                    assert_eq!(s.device.is_some(), on_device, "{what}");
                    assert_eq!(s.out.image.on_host(), !on_device, "{what}");
                    assert_eq!(s.out.gbuffer.on_host(), !on_device, "{what}");
                    if !on_device {
                        assert_eq!(s.out.image.data.len(), 48 * 36, "{what}");
                    }
                }
            }
            Reply::Failed(e) => panic!("{e}"),
            Reply::Cancelled => panic!("cancelled"),
        }
    }
    drop(jobs);
    thread.join().unwrap();
}
