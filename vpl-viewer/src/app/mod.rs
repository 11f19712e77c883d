//! The window: winit's event loop and the viewer's state. Each concern
//! of the state has its file: `gfx` (the surface and egui's painter),
//! `frames` (jobs to the render thread, its replies, the composed view),
//! `panel` (the control panel and the view), `animation` (the sequence and
//! a light moved by hand), `picking` (a picked VPL and the reference),
//! `recording` (a recorded path), `session` (the scripted session and its
//! screenshots) and `history` (the plots' frames).

use crate::camera::FlyCamera;
use crate::inspect::{self, MapPicture};
use crate::record::{Pose, Recorder};
use crate::script::Step;
use crate::view::{Channel, Composite, Look, Overlay, Pick, SideFrame, against_reference, compose, pick_vpl};
use crate::worker::{self, BackendChoice, Job, Reference, ReferenceSpec, Reply, SideResult, SideSpec};
use crate::{Summary, ViewerError, ViewerOptions};
use std::collections::VecDeque;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::time::{Duration, Instant};
use vpl_core::glam::Vec3;
use vpl_core::{Light, MaterialPolicy, Mode, Scene, SceneSetup};
use vpl_render::Backends;
use vpl_sampling::Registry;
use vpl_scene_io::ImageFile;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

mod animation;
mod frames;
mod gfx;
mod history;
mod panel;
mod picking;
mod recording;
mod session;

use animation::Animation;
use frames::{Link, Picture};
use gfx::Gfx;
#[cfg(feature = "gpu")]
use history::host_frame;
use history::{History, side};
use picking::Inspection;
use recording::Recordings;
use session::Session;

/// Width of the control panel in points.
const PANEL_WIDTH: f32 = 330.0;
/// Frames of history the plots show.
const HISTORY: usize = 240;
/// A camera move cancels the frame in flight once it has run this long
/// (shorter frames finish: flying on a slow backend still shows frames).
const CANCEL_AFTER: Duration = Duration::from_millis(150);
/// Time the render thread spends on reference passes after each frame.
const REFERENCE_BUDGET: Duration = Duration::from_millis(150);
/// A click picks the VPL nearest to it within this many view pixels.
const PICK_RADIUS: f32 = 12.0;

/// Wakes the event loop: the render thread has a reply.
#[derive(Clone, Copy, Debug)]
struct Wake;

pub(crate) fn run(options: ViewerOptions, registry: &Registry) -> Result<Summary, ViewerError> {
    let mut setup = vpl_scene_io::load_with(&options.scene, &options.load)?;
    // The VPL pipeline draws each material's diffuse albedo.
    setup.scene = setup.scene.with_material_policy(MaterialPolicy::Diffuse);
    // The window system, before anything loads a window-system or GPU
    // library (either may print its own lines to stderr).
    #[cfg(target_os = "linux")]
    let system = crate::display::from_env().map_err(ViewerError::NoDisplay)?;
    let mut builder = EventLoop::<Wake>::with_user_event();
    // A library call may come from any thread (a test, a notebook's worker);
    // X11 and Wayland allow it (macOS does not: call from the main thread there).
    #[cfg(target_os = "linux")]
    {
        use winit::platform::{wayland::EventLoopBuilderExtWayland, x11::EventLoopBuilderExtX11};
        EventLoopBuilderExtX11::with_any_thread(&mut builder, true);
        EventLoopBuilderExtWayland::with_any_thread(&mut builder, true);
        match system {
            crate::display::WindowSystem::Wayland => builder.with_wayland(),
            crate::display::WindowSystem::X11 => builder.with_x11(),
        };
    }
    let event_loop = builder.build().map_err(|e| ViewerError::NoDisplay(crate::display::reason(&e)))?;
    // The renderer's device after the window system's connection. With the
    // device first, about one `vpl view` in four failed to connect to the X
    // server while other sessions started on the same Xvfb (a driver's own
    // display connection racing winit's, we think); this order gave none
    // in 14 runs of the six scripted sessions.
    let (backend, renderer_line, default_scale) = choose_backend(&options.pipeline.backend)?;
    // The window presents the renderer's frames from its device when it can.
    #[cfg(feature = "gpu")]
    let shared = match &backend {
        BackendChoice::Gpu(gpu) => Some(gpu.clone()),
        BackendChoice::Entry(_) => None,
    };
    #[cfg(not(feature = "gpu"))]
    let shared = None;
    let proxy = event_loop.create_proxy();
    let (jobs, job_rx) = mpsc::channel::<Job>();
    let (reply_tx, replies) = mpsc::channel::<Reply>();
    let worker_registry = registry.clone();
    let pipeline = options.pipeline.clone();
    let worker = std::thread::Builder::new()
        .name("vpl-view render".into())
        .spawn(move || {
            worker::run(job_rx, reply_tx, worker_registry, backend, pipeline, move || {
                let _ = proxy.send_event(Wake);
            })
        })
        .map_err(|e| ViewerError::Render(format!("cannot start the render thread: {e}")))?;
    let scale = options.scale.unwrap_or(default_scale);
    let mut app = App { gfx: None, shared, st: State::new(options, registry, setup, renderer_line, scale, jobs, replies) };
    app.st.world.scene_dir = scene_dir(&app.st.world.scene_spec);
    let looped = event_loop.run_app(&mut app).map_err(|e| ViewerError::NoDisplay(crate::display::reason(&e)));
    let App { st, gfx, .. } = app;
    drop(gfx);
    if let Some((_, cancel, _)) = &st.link.in_flight {
        cancel.store(true, Ordering::Relaxed);
    }
    let summary = st.summary();
    let fatal = st.report.fatal;
    drop(st.link.jobs);
    let _ = worker.join();
    looped?;
    match fatal {
        Some(e) => Err(e),
        None => Ok(summary),
    }
}

/// The folder a scene's model paths are relative to: a scene file's own,
/// the working folder for a bare model file or a built-in.
fn scene_dir(spec: &str) -> PathBuf {
    let p = Path::new(spec);
    match p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()) {
        Some(e) if e == "toml" => p.parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf),
        _ => PathBuf::from("."),
    }
}

/// The backends the viewer offers: the CPU, and vpl-gpu's where built.
pub(crate) fn backends() -> Backends {
    let mut b = Backends::builtin();
    #[cfg(feature = "gpu")]
    vpl_gpu::register(&mut b);
    #[cfg(not(feature = "gpu"))]
    b.absent("gpu", "built without vpl-viewer's feature `gpu`");
    b
}

/// The backend `name` of [`backends`] (or [`vpl_render::AUTO`]: the first
/// that opens, a device first), a line saying what renders, and the
/// default render scale: ½ on a device, ¼ on the CPU. vpl-gpu's backend
/// runs on a device of its own here, which the window shares to present
/// the frames left there.
fn choose_backend(name: &str) -> Result<(BackendChoice, String, f32), ViewerError> {
    let backends = backends();
    let auto = name == vpl_render::AUTO;
    let tries = if auto { backends.auto_order() } else { vec![backends.entry(name).map_err(|e| ViewerError::Backend(e.to_string()))?] };
    let mut failed = Vec::new();
    for entry in tries {
        #[cfg(feature = "gpu")]
        if entry.name == vpl_gpu::NAME {
            match vpl_gpu::Gpu::new() {
                Ok(gpu) => {
                    let line = format!("renderer: GPU, {}", gpu.ctx().describe());
                    return Ok((BackendChoice::Gpu(gpu), line, 0.5));
                }
                Err(e) if !auto => return Err(ViewerError::Backend(e.to_string())),
                Err(e) => {
                    failed.push(format!("{}: {e}", entry.name));
                    continue;
                }
            }
        }
        match (entry.factory)() {
            Ok(b) => {
                let how = if auto && !failed.is_empty() { format!(" ({})", failed.join("; ")) } else { String::new() };
                let (line, scale) = match b.device() {
                    Some(d) => (format!("renderer: {}, {d}{how}", b.name()), 0.5),
                    None if b.name() == "cpu" => (format!("renderer: CPU at ¼ resolution{how}"), 0.25),
                    None => (format!("renderer: {} at ¼ resolution{how}", b.name()), 0.25),
                };
                return Ok((BackendChoice::Entry(*entry), line, scale));
            }
            Err(e) if !auto => return Err(ViewerError::Backend(e.to_string())),
            Err(e) => failed.push(format!("{}: {e}", entry.name)),
        }
    }
    Err(ViewerError::Backend(format!("no backend opened ({})", failed.join("; "))))
}

struct App {
    gfx: Option<Gfx>,
    /// The renderer's device, which the window presents from when its
    /// surface can.
    shared: Option<SharedGpu>,
    st: State,
}

#[cfg(feature = "gpu")]
type SharedGpu = vpl_gpu::Gpu;
#[cfg(not(feature = "gpu"))]
type SharedGpu = std::convert::Infallible;

/// What a shadow map was rendered for: side, slot, the VPL's position and normal.
type MapKey = (usize, usize, [f32; 6]);

/// The scene, the camera flying through it, and the window.
struct World {
    scene_name: String,
    scene_spec: String,
    scene_dir: PathBuf,
    seed: u64,
    names: Vec<String>,
    setup: SceneSetup,
    cam: FlyCamera,
    speed: f32,
    window_size: (u32, u32),
}

/// What the frames are rendered with (the sides' samplers, the budget, the
/// light paths, the render scale), and how they are shown.
struct Shown {
    sides: [String; 2],
    split: bool,
    vpls: usize,
    mode: Mode,
    scale: f32,
    channel: Channel,
    overlay: Overlay,
    exposure: f32,
}

/// What the panel reports, and what the session did.
struct Report {
    renderer_line: String,
    error_line: Option<String>,
    status_line: Option<String>,
    frames_shown: u64,
    first_frame_at: Option<Instant>,
    last_frame_at: Option<Instant>,
    last_tick: Instant,
    fatal: Option<ViewerError>,
}

/// Everything but the window.
struct State {
    /// The scene, the camera flying through it, and the window.
    world: World,
    /// What the frames are rendered with, and how they are shown.
    shown: Shown,
    /// What the panel reports, and what the session did.
    report: Report,
    /// The animation: the sequence's frames, playing them, and lights moved by hand.
    anim: Animation,
    /// The render thread: the jobs sent to it, its replies, and the frame in flight.
    link: Link,
    /// The last frame and what shows it: the composed view, its textures, and the plots' history.
    picture: Picture,
    /// A picked VPL with its shadow map, and the path tracer's reference.
    inspect: Inspection,
    /// A path being recorded, and how many were written.
    rec: Recordings,
    /// The scripted session: its steps, the frames it waits for, its screenshots, and whether it ends.
    session: Session,
}

impl State {
    fn new(
        o: ViewerOptions,
        registry: &Registry,
        setup: SceneSetup,
        renderer_line: String,
        scale: f32,
        jobs: Sender<Job>,
        replies: Receiver<Reply>,
    ) -> State {
        let frame_count = setup.sequence.as_ref().map_or(1, |s| s.frame_count().max(1));
        let split = o.split.is_some();
        let right = o.split.clone().unwrap_or_else(|| if o.pipeline.sampler == "smc" { "ir".into() } else { "smc".into() });
        let scripted = o.script.is_some();
        State {
            world: World {
                scene_name: setup.scene.name.clone(),
                scene_spec: o.scene.clone(),
                scene_dir: PathBuf::from("."),
                seed: o.pipeline.seed,
                names: registry.names().into_iter().map(str::to_string).collect(),
                cam: FlyCamera::from_camera(&setup.camera),
                speed: setup.scene.radius().max(1e-3) * 0.5,
                setup,
                window_size: o.window,
            },
            shown: Shown {
                sides: [o.pipeline.sampler, right],
                split,
                vpls: o.pipeline.budget.vpls,
                mode: o.pipeline.mode,
                scale,
                channel: Channel::Image,
                overlay: Overlay::Off,
                exposure: o.exposure,
            },
            report: Report {
                renderer_line,
                error_line: None,
                status_line: None,
                frames_shown: 0,
                first_frame_at: None,
                last_frame_at: None,
                last_tick: Instant::now(),
                fatal: None,
            },
            anim: Animation {
                frame_count,
                anim_frame: 0,
                playing: false,
                play_clock: 0.0,
                follow_camera: true,
                manual_lights: None,
                lights_version: 0,
                scene_cache: None,
            },
            link: Link { jobs, replies, generation: 0, in_flight: None, stalled: false },
            picture: Picture {
                last: Vec::new(),
                composite: None,
                recompose: false,
                texture: None,
                view_texture: None,
                resident: false,
                device_frames: 0,
                view_rect: None,
                pixels_per_point: 1.0,
                history: [History::default(), History::default()],
            },
            inspect: Inspection { reference_on: o.reference, reference: None, picked: None, map: None, map_texture: None, map_rect: None },
            rec: Recordings { recording: None, recordings: 0 },
            session: Session {
                scripted,
                script: o.script.map(|s| s.steps.into()).unwrap_or_default(),
                waiting: 0,
                pending_shot: None,
                shots: 0,
                quit: false,
            },
        }
    }

    fn summary(&self) -> Summary {
        let fps = match (self.report.first_frame_at, self.report.last_frame_at) {
            (Some(a), Some(b)) if self.report.frames_shown > 1 && b > a => (self.report.frames_shown - 1) as f64 / (b - a).as_secs_f64(),
            _ => 0.0,
        };
        Summary {
            frames: self.report.frames_shown,
            fps,
            renderer: self.report.renderer_line.clone(),
            resolution: self.resolution(),
            device_frames: self.picture.device_frames,
        }
    }

    fn fail(&mut self, e: ViewerError) {
        if self.report.fatal.is_none() {
            self.report.fatal = Some(e);
        }
        self.session.quit = true;
    }

    /// The view's size in pixels: the central panel's last size, or the
    /// window's less the panel before the first layout.
    fn view_pixels(&self) -> (f32, f32) {
        match self.picture.view_rect {
            Some(r) => (r.width() * self.picture.pixels_per_point, r.height() * self.picture.pixels_per_point),
            None => {
                ((self.world.window_size.0 as f32 - PANEL_WIDTH * self.picture.pixels_per_point).max(64.0), self.world.window_size.1 as f32)
            }
        }
    }

    fn resolution(&self) -> (u32, u32) {
        let (w, h) = self.view_pixels();
        (((w * self.shown.scale).round() as u32).max(16), ((h * self.shown.scale).round() as u32).max(16))
    }

    fn specs(&self) -> Vec<SideSpec> {
        let n = if self.shown.split { 2 } else { 1 };
        let resolution = self.resolution();
        self.shown.sides[..n]
            .iter()
            .map(|s| SideSpec { sampler: s.clone(), vpls: self.shown.vpls, mode: self.shown.mode, resolution })
            .collect()
    }

    /// What the frames are rendered from changed. `hard`: what a side
    /// renders with changed, so the frame in flight is stopped at once;
    /// otherwise (the camera, the light) only once it has run a while.
    fn changed(&mut self, hard: bool) {
        self.link.generation += 1;
        self.link.stalled = false;
        if let Some((_, cancel, started)) = &self.link.in_flight
            && (hard || started.elapsed() > CANCEL_AFTER)
        {
            cancel.store(true, Ordering::Relaxed);
        }
    }
}

impl App {
    fn redraw(&mut self, el: &ActiveEventLoop) {
        let Some(gfx) = self.gfx.as_mut() else { return };
        let st = &mut self.st;
        st.poll();
        st.advance_script();
        if st.session.quit {
            el.exit();
            return;
        }
        let raw = gfx.egui.take_egui_input(&gfx.window);
        let ctx = gfx.egui.egui_ctx().clone();
        st.picture.pixels_per_point = ctx.pixels_per_point();
        st.tick(&ctx);
        #[cfg(feature = "gpu")]
        st.compose_on_device(gfx);
        let out = ctx.run(raw, |ctx| {
            st.compose(ctx);
            st.ui(ctx);
        });
        #[cfg(feature = "gpu")]
        st.compose_on_device(gfx);
        st.compose(&ctx);
        st.submit();
        gfx.egui.handle_platform_output(&gfx.window, out.platform_output);
        let prims = ctx.tessellate(out.shapes, out.pixels_per_point);
        for (id, delta) in &out.textures_delta.set {
            gfx.painter.update_texture(&gfx.device, &gfx.queue, *id, delta);
        }
        let sd =
            egui_wgpu::ScreenDescriptor { size_in_pixels: [gfx.config.width, gfx.config.height], pixels_per_point: out.pixels_per_point };
        match gfx.surface.get_current_texture() {
            Ok(frame) => {
                let view = frame.texture.create_view(&wgpu::TextureViewDescriptor::default());
                let enc = gfx.paint(&view, &prims, &sd);
                gfx.queue.submit([enc.finish()]);
                gfx.window.pre_present_notify();
                frame.present();
            }
            Err(wgpu::SurfaceError::Outdated | wgpu::SurfaceError::Lost) => {
                let s = gfx.window.inner_size();
                gfx.resize(s.width, s.height);
                gfx.window.request_redraw();
            }
            Err(wgpu::SurfaceError::Timeout) => gfx.window.request_redraw(),
            Err(e) => {
                st.fail(ViewerError::Surface(e.to_string()));
                el.exit();
            }
        }
        // A screenshot once the view shows a frame of what the script set up.
        if st.picture.view_texture.is_some()
            && !st.picture.recompose
            && let Some(path) = st.session.pending_shot.take()
        {
            match gfx.capture(&prims, &sd).map_err(ViewerError::Surface).and_then(|px| st.write_shot(&path, px)) {
                Ok(p) => st.report.status_line = Some(format!("wrote {}", p.display())),
                Err(e) if st.session.scripted => {
                    st.fail(e);
                    el.exit();
                }
                Err(e) => st.report.error_line = Some(e.to_string()),
            }
            gfx.window.request_redraw();
        }
        for id in &out.textures_delta.free {
            gfx.painter.free_texture(id);
        }
        let delay = out.viewport_output.get(&egui::ViewportId::ROOT).map_or(Duration::MAX, |v| v.repaint_delay);
        if st.wants_ticks(&ctx) || st.session.pending_shot.is_some() || delay.is_zero() {
            el.set_control_flow(ControlFlow::WaitUntil(Instant::now() + Duration::from_millis(16)));
            gfx.window.request_redraw();
        } else if delay < Duration::from_secs(1) {
            el.set_control_flow(ControlFlow::WaitUntil(Instant::now() + delay));
        } else {
            el.set_control_flow(ControlFlow::Wait);
        }
    }
}

impl ApplicationHandler<Wake> for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.gfx.is_some() {
            return;
        }
        match Gfx::new(el, self.st.world.window_size, &format!("vpl view: {}", self.st.world.scene_name), self.shared.as_ref()) {
            Ok(g) => {
                #[cfg(feature = "gpu")]
                {
                    self.st.picture.resident = g.device_view.is_some();
                }
                g.window.request_redraw();
                self.gfx = Some(g);
            }
            Err(e) => {
                self.st.fail(e);
                el.exit();
            }
        }
    }

    fn user_event(&mut self, _el: &ActiveEventLoop, _wake: Wake) {
        if let Some(g) = &self.gfx {
            g.window.request_redraw();
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(gfx) = self.gfx.as_mut() else { return };
        let response = gfx.egui.on_window_event(&gfx.window, &event);
        match event {
            WindowEvent::CloseRequested => {
                self.st.session.quit = true;
                el.exit();
            }
            WindowEvent::Resized(s) => {
                gfx.resize(s.width, s.height);
                self.st.world.window_size = (s.width, s.height);
                gfx.window.request_redraw();
            }
            WindowEvent::RedrawRequested => self.redraw(el),
            _ => {
                if response.repaint {
                    gfx.window.request_redraw();
                }
            }
        }
    }
}
