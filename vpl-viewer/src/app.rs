//! The window: winit's event loop, a wgpu surface, egui's panel and the
//! view, the render thread's jobs and replies, the scripted session.

use crate::camera::FlyCamera;
use crate::inspect::{self, MapPicture};
use crate::record::{Pose, Recorder};
use crate::script::Step;
use crate::view::{Channel, Composite, Look, Overlay, Pick, SideFrame, against_reference, compose, pick_vpl};
use crate::worker::{self, BackendChoice, Job, Reference, ReferenceSpec, Reply, SideResult, SideSpec};
use crate::{BackendRequest, Summary, ViewerError, ViewerOptions};
use std::collections::VecDeque;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::time::{Duration, Instant};
use vpl_core::glam::Vec3;
use vpl_core::{Light, MaterialPolicy, Mode, Scene, SceneSetup};
use vpl_sampling::Registry;
use vpl_scene_io::ImageFile;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

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
    let (backend, renderer_line, default_scale) = choose_backend(BackendRequest::named(&options.pipeline.backend)?)?;
    // The window presents the renderer's frames from its device when it can.
    #[cfg(feature = "gpu")]
    let shared = match &backend {
        BackendChoice::Gpu(gpu) => Some(gpu.clone()),
        BackendChoice::Cpu => None,
    };
    #[cfg(not(feature = "gpu"))]
    let shared = None;
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
    app.st.scene_dir = scene_dir(&app.st.scene_spec);
    let looped = event_loop.run_app(&mut app).map_err(|e| ViewerError::NoDisplay(crate::display::reason(&e)));
    let App { st, gfx, .. } = app;
    drop(gfx);
    if let Some((_, cancel, _)) = &st.in_flight {
        cancel.store(true, Ordering::Relaxed);
    }
    let summary = st.summary();
    let fatal = st.fatal;
    drop(st.jobs);
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

fn choose_backend(req: BackendRequest) -> Result<(BackendChoice, String, f32), ViewerError> {
    const CPU_SCALE: f32 = 0.25;
    if req == BackendRequest::Cpu {
        return Ok((BackendChoice::Cpu, "renderer: CPU (--backend cpu), ¼ resolution".into(), CPU_SCALE));
    }
    #[cfg(feature = "gpu")]
    match vpl_gpu::Gpu::new() {
        Ok(gpu) => {
            let line = format!("renderer: GPU, {}", gpu.ctx().describe());
            Ok((BackendChoice::Gpu(gpu), line, 0.5))
        }
        Err(e) if req == BackendRequest::Gpu => Err(ViewerError::Backend(e.to_string())),
        Err(_) => Ok((BackendChoice::Cpu, "renderer: CPU at ¼ resolution (no GPU adapter)".into(), CPU_SCALE)),
    }
    #[cfg(not(feature = "gpu"))]
    match req {
        BackendRequest::Gpu => Err(ViewerError::Backend("this build has no GPU backend (feature `gpu` of vpl-viewer)".into())),
        _ => Ok((BackendChoice::Cpu, "renderer: CPU at ¼ resolution (built without the GPU backend)".into(), CPU_SCALE)),
    }
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

/// The window and what draws into it.
struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    device: wgpu::Device,
    queue: wgpu::Queue,
    config: wgpu::SurfaceConfiguration,
    egui: egui_winit::State,
    painter: egui_wgpu::Renderer,
    /// The view composed on the renderer's device, when the window shares it.
    #[cfg(feature = "gpu")]
    device_view: Option<crate::present::WindowView>,
}

impl Gfx {
    /// The window, on `shared` (the renderer's device) when a surface of
    /// the window can present from it, else on a device of its own.
    fn new(el: &ActiveEventLoop, size: (u32, u32), title: &str, shared: Option<&SharedGpu>) -> Result<Gfx, ViewerError> {
        let attrs = Window::default_attributes().with_title(title).with_inner_size(winit::dpi::PhysicalSize::new(size.0, size.1));
        let window = Arc::new(el.create_window(attrs).map_err(|e| ViewerError::NoDisplay(crate::display::reason(&e)))?);
        #[cfg(feature = "gpu")]
        if let Some(gpu) = shared {
            let ctx = gpu.ctx();
            if let Ok(surface) = ctx.instance.create_surface(window.clone())
                && ctx.adapter.is_surface_supported(&surface)
            {
                let mut g = Gfx::on(window, surface, &ctx.adapter, ctx.device.clone(), ctx.queue.clone())?;
                g.device_view = Some(crate::present::WindowView::new(gpu.clone()));
                return Ok(g);
            }
        }
        #[cfg(not(feature = "gpu"))]
        let _ = shared;
        let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY | wgpu::Backends::GL);
        let instance = wgpu::Instance::new(&wgpu::InstanceDescriptor { backends, ..Default::default() });
        let surface = instance.create_surface(window.clone()).map_err(|e| ViewerError::Surface(e.to_string()))?;
        let adapter = pollster::block_on(
            instance.request_adapter(&wgpu::RequestAdapterOptions { compatible_surface: Some(&surface), ..Default::default() }),
        )
        .map_err(|e| ViewerError::NoAdapter(e.to_string()))?;
        let (device, queue) =
            pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor { label: Some("vpl-viewer"), ..Default::default() }))
                .map_err(|e| ViewerError::NoAdapter(e.to_string()))?;
        Gfx::on(window, surface, &adapter, device, queue)
    }

    fn on(
        window: Arc<Window>,
        surface: wgpu::Surface<'static>,
        adapter: &wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Gfx, ViewerError> {
        let caps = surface.get_capabilities(adapter);
        let format = egui_wgpu::preferred_framebuffer_format(&caps.formats).map_err(|e| ViewerError::Surface(e.to_string()))?;
        let inner = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: inner.width.max(1),
            height: inner.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
        };
        surface.configure(&device, &config);
        let ctx = egui::Context::default();
        let max_side = device.limits().max_texture_dimension_2d as usize;
        let egui = egui_winit::State::new(ctx, egui::ViewportId::ROOT, &window, Some(window.scale_factor() as f32), None, Some(max_side));
        let painter = egui_wgpu::Renderer::new(&device, format, egui_wgpu::RendererOptions::default());
        Ok(Gfx {
            window,
            surface,
            device,
            queue,
            config,
            egui,
            painter,
            #[cfg(feature = "gpu")]
            device_view: None,
        })
    }

    fn resize(&mut self, w: u32, h: u32) {
        if w > 0 && h > 0 {
            self.config.width = w;
            self.config.height = h;
            self.surface.configure(&self.device, &self.config);
        }
    }

    /// Draws egui's primitives into `target`.
    fn paint(
        &mut self,
        target: &wgpu::TextureView,
        prims: &[egui::ClippedPrimitive],
        sd: &egui_wgpu::ScreenDescriptor,
    ) -> wgpu::CommandEncoder {
        let mut enc = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("vpl-viewer") });
        let extra = self.painter.update_buffers(&self.device, &self.queue, &mut enc, prims, sd);
        self.queue.submit(extra);
        {
            let mut pass = enc
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("egui"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: target,
                        resolve_target: None,
                        depth_slice: None,
                        ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                })
                .forget_lifetime();
            self.painter.render(&mut pass, prims, sd);
        }
        enc
    }

    /// The window's pixels as RGB (egui drawn into a texture like the surface's).
    fn capture(&mut self, prims: &[egui::ClippedPrimitive], sd: &egui_wgpu::ScreenDescriptor) -> Result<(u32, u32, Vec<u8>), String> {
        let (w, h) = (self.config.width, self.config.height);
        let extent = wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 };
        let texture = self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("vpl-viewer screenshot"),
            size: extent,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: self.config.format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let mut enc = self.paint(&view, prims, sd);
        let row = (w * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl-viewer screenshot"),
            size: row as u64 * h as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo { texture: &texture, mip_level: 0, origin: wgpu::Origin3d::ZERO, aspect: wgpu::TextureAspect::All },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(h) },
            },
            extent,
        );
        self.queue.submit([enc.finish()]);
        let slice = buffer.slice(..);
        let (tx, rx) = mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| e.to_string())?;
        rx.recv().map_err(|e| e.to_string())?.map_err(|e| e.to_string())?;
        let data = slice.get_mapped_range();
        let bgra = matches!(self.config.format, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb);
        let mut rgb = Vec::with_capacity((w * h * 3) as usize);
        for y in 0..h {
            let line = &data[(y * row) as usize..(y * row + w * 4) as usize];
            for p in line.chunks_exact(4) {
                if bgra { rgb.extend([p[2], p[1], p[0]]) } else { rgb.extend([p[0], p[1], p[2]]) }
            }
        }
        drop(data);
        buffer.unmap();
        Ok((w, h, rgb))
    }
}

/// One side's recent frames, for the plots.
#[derive(Default)]
struct History {
    /// (frame number, then the columns of [`History::COLUMNS`]).
    rows: VecDeque<[f64; 9]>,
}

impl History {
    /// What the columns after the frame number hold.
    const COLUMNS: [&'static str; 8] = ["total", "G-buffer", "sampling", "visibility", "shading", "direct", "VPLs moved", "Σ|ΔL|/ΣL"];

    fn push(&mut self, s: &SideResult) {
        // A rebuilt side (another sampler, budget or mode) starts its plot afresh.
        if s.index == 0 {
            self.rows.clear();
        }
        let t = s.out.timings;
        self.rows.push_back([
            s.index as f64,
            t.total_ms,
            t.gbuffer_ms,
            t.sampling_ms,
            t.visibility_ms,
            t.shading_ms,
            t.direct_ms,
            s.out.moved as f64,
            s.change.unwrap_or(f64::NAN),
        ]);
        while self.rows.len() > HISTORY {
            self.rows.pop_front();
        }
    }

    fn series(&self, column: usize) -> Vec<[f64; 2]> {
        self.rows.iter().filter(|r| r[column].is_finite()).map(|r| [r[0], r[column]]).collect()
    }
}

/// A side's image and G-buffer on the host: its frame's, or read back from
/// the device (on request: a click, a screenshot), `None` when the read
/// failed.
#[cfg(feature = "gpu")]
fn host_frame(s: &SideResult) -> Option<(vpl_core::Image, vpl_core::GBuffer)> {
    let (d, gpu) = (s.device.as_ref()?, s.gpu.as_ref()?);
    Some((d.read_image(gpu.ctx()).ok()?, d.read_gbuffer(gpu.ctx()).ok()?))
}

fn side(s: &SideResult) -> SideFrame<'_> {
    SideFrame { image: &s.out.image, gbuffer: &s.out.gbuffer, vpls: &s.out.vpls, camera: &s.camera }
}

/// What a shadow map was rendered for: side, slot, the VPL's position and normal.
type MapKey = (usize, usize, [f32; 6]);

/// Everything but the window.
struct State {
    scene_name: String,
    scene_spec: String,
    scene_dir: PathBuf,
    seed: u64,
    names: Vec<String>,
    setup: SceneSetup,
    cam: FlyCamera,
    speed: f32,
    renderer_line: String,
    window_size: (u32, u32),
    // What the frames are rendered with.
    sides: [String; 2],
    split: bool,
    vpls: usize,
    mode: Mode,
    scale: f32,
    channel: Channel,
    overlay: Overlay,
    exposure: f32,
    // Animation and a light moved by hand.
    frame_count: u32,
    anim_frame: u32,
    playing: bool,
    play_clock: f64,
    follow_camera: bool,
    manual_lights: Option<Vec<Light>>,
    lights_version: u64,
    scene_cache: Option<((u32, u64), Arc<Scene>)>,
    // The render thread.
    jobs: Sender<Job>,
    replies: Receiver<Reply>,
    generation: u64,
    in_flight: Option<(u64, Arc<AtomicBool>, Instant)>,
    stalled: bool,
    // The last frame and its picture.
    last: Vec<SideResult>,
    composite: Option<Composite>,
    recompose: bool,
    texture: Option<egui::TextureHandle>,
    /// What the view draws: `texture`'s id, or the device view's.
    view_texture: Option<egui::TextureId>,
    /// The window presents from the renderer's device: frames stay there.
    resident: bool,
    /// Frames composed on the device.
    device_frames: u64,
    view_rect: Option<egui::Rect>,
    pixels_per_point: f32,
    history: [History; 2],
    // The reference, a picked VPL, a recording.
    reference_on: bool,
    reference: Option<Reference>,
    picked: Option<(usize, usize)>,
    map: Option<(MapKey, MapPicture)>,
    map_texture: Option<egui::TextureHandle>,
    map_rect: Option<egui::Rect>,
    recording: Option<(Instant, Recorder)>,
    recordings: u32,
    error_line: Option<String>,
    status_line: Option<String>,
    frames_shown: u64,
    first_frame_at: Option<Instant>,
    last_frame_at: Option<Instant>,
    last_tick: Instant,
    // The scripted session.
    scripted: bool,
    script: VecDeque<Step>,
    waiting: u32,
    pending_shot: Option<PathBuf>,
    shots: u32,
    quit: bool,
    fatal: Option<ViewerError>,
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
            scene_name: setup.scene.name.clone(),
            scene_spec: o.scene.clone(),
            scene_dir: PathBuf::from("."),
            seed: o.pipeline.seed,
            names: registry.names().into_iter().map(str::to_string).collect(),
            cam: FlyCamera::from_camera(&setup.camera),
            speed: setup.scene.radius().max(1e-3) * 0.5,
            setup,
            renderer_line,
            window_size: o.window,
            sides: [o.pipeline.sampler, right],
            split,
            vpls: o.pipeline.budget.vpls,
            mode: o.pipeline.mode,
            scale,
            channel: Channel::Image,
            overlay: Overlay::Off,
            exposure: o.exposure,
            frame_count,
            anim_frame: 0,
            playing: false,
            play_clock: 0.0,
            follow_camera: true,
            manual_lights: None,
            lights_version: 0,
            scene_cache: None,
            jobs,
            replies,
            generation: 0,
            in_flight: None,
            stalled: false,
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
            reference_on: o.reference,
            reference: None,
            picked: None,
            map: None,
            map_texture: None,
            map_rect: None,
            recording: None,
            recordings: 0,
            error_line: None,
            status_line: None,
            frames_shown: 0,
            first_frame_at: None,
            last_frame_at: None,
            last_tick: Instant::now(),
            scripted,
            script: o.script.map(|s| s.steps.into()).unwrap_or_default(),
            waiting: 0,
            pending_shot: None,
            shots: 0,
            quit: false,
            fatal: None,
        }
    }

    fn summary(&self) -> Summary {
        let fps = match (self.first_frame_at, self.last_frame_at) {
            (Some(a), Some(b)) if self.frames_shown > 1 && b > a => (self.frames_shown - 1) as f64 / (b - a).as_secs_f64(),
            _ => 0.0,
        };
        Summary {
            frames: self.frames_shown,
            fps,
            renderer: self.renderer_line.clone(),
            resolution: self.resolution(),
            device_frames: self.device_frames,
        }
    }

    fn fail(&mut self, e: ViewerError) {
        if self.fatal.is_none() {
            self.fatal = Some(e);
        }
        self.quit = true;
    }

    /// The view's size in pixels: the central panel's last size, or the
    /// window's less the panel before the first layout.
    fn view_pixels(&self) -> (f32, f32) {
        match self.view_rect {
            Some(r) => (r.width() * self.pixels_per_point, r.height() * self.pixels_per_point),
            None => ((self.window_size.0 as f32 - PANEL_WIDTH * self.pixels_per_point).max(64.0), self.window_size.1 as f32),
        }
    }

    fn resolution(&self) -> (u32, u32) {
        let (w, h) = self.view_pixels();
        (((w * self.scale).round() as u32).max(16), ((h * self.scale).round() as u32).max(16))
    }

    fn specs(&self) -> Vec<SideSpec> {
        let n = if self.split { 2 } else { 1 };
        let resolution = self.resolution();
        self.sides[..n].iter().map(|s| SideSpec { sampler: s.clone(), vpls: self.vpls, mode: self.mode, resolution }).collect()
    }

    /// What the frames are rendered from changed. `hard`: what a side
    /// renders with changed, so the frame in flight is stopped at once;
    /// otherwise (the camera, the light) only once it has run a while.
    fn changed(&mut self, hard: bool) {
        self.generation += 1;
        self.stalled = false;
        if let Some((_, cancel, started)) = &self.in_flight
            && (hard || started.elapsed() > CANCEL_AFTER)
        {
            cancel.store(true, Ordering::Relaxed);
        }
    }

    fn scene(&mut self) -> Result<Arc<Scene>, ViewerError> {
        let key = (self.anim_frame, self.lights_version);
        if let Some((k, s)) = &self.scene_cache
            && *k == key
        {
            return Ok(s.clone());
        }
        let (mut scene, _) = self.setup.frame(self.anim_frame)?;
        if let Some(l) = &self.manual_lights {
            scene = scene.with_lights(l.clone())?;
        }
        let scene = Arc::new(scene);
        self.scene_cache = Some((key, scene.clone()));
        Ok(scene)
    }

    /// Sends the next job when none is in flight: frames render continuously.
    fn submit(&mut self) {
        if self.in_flight.is_some() || self.stalled || self.quit {
            return;
        }
        let scene = match self.scene() {
            Ok(s) => s,
            Err(e) => {
                self.error_line = Some(e.to_string());
                self.stalled = true;
                return;
            }
        };
        let camera = match self.cam.camera(&self.setup.camera, self.resolution()) {
            Ok(c) => c,
            Err(e) => {
                self.error_line = Some(format!("camera: {e}"));
                self.stalled = true;
                return;
            }
        };
        let time = self.setup.sequence.as_ref().map_or(0.0, |s| s.time(self.anim_frame));
        let cancel = Arc::new(AtomicBool::new(false));
        let reference = self.reference_on.then_some(ReferenceSpec {
            mode: self.mode,
            max_depth: vpl_core::Budget::default().max_depth,
            budget: REFERENCE_BUDGET,
        });
        let job = Job { scene, camera, time, sides: self.specs(), cancel: cancel.clone(), reference, resident: self.resident };
        if self.jobs.send(job).is_ok() {
            self.in_flight = Some((self.generation, cancel, Instant::now()));
        } else {
            self.fail(ViewerError::Render("the render thread stopped".into()));
        }
    }

    /// Takes the render thread's replies.
    fn poll(&mut self) {
        loop {
            let reply = match self.replies.try_recv() {
                Ok(r) => r,
                Err(mpsc::TryRecvError::Empty) => break,
                Err(mpsc::TryRecvError::Disconnected) => {
                    self.in_flight = None;
                    self.fail(ViewerError::Render("the render thread stopped".into()));
                    break;
                }
            };
            let Some((generation, _, _)) = self.in_flight.take() else { continue };
            match reply {
                Reply::Frame { sides, reference } => {
                    let now = Instant::now();
                    self.first_frame_at.get_or_insert(now);
                    self.last_frame_at = Some(now);
                    self.frames_shown += 1;
                    if generation == self.generation {
                        self.waiting = self.waiting.saturating_sub(1);
                    }
                    for (h, s) in self.history.iter_mut().zip(&sides) {
                        h.push(s);
                    }
                    self.last = sides;
                    self.error_line = None;
                    self.recompose = true;
                    match reference {
                        Some(Ok(r)) => self.reference = Some(r),
                        Some(Err(e)) => {
                            self.reference = None;
                            self.error_line = Some(e);
                        }
                        None => self.reference = None,
                    }
                    self.refresh_map();
                }
                Reply::Cancelled => {}
                Reply::Failed(e) => {
                    if self.scripted {
                        self.fail(ViewerError::Render(e.clone()));
                    }
                    self.error_line = Some(e);
                    if generation == self.generation {
                        self.stalled = true;
                    }
                }
            }
        }
    }

    /// The last frame's sides with their G-buffers on the host (read back
    /// where they stayed on the device).
    fn on_host(&self) -> Vec<(SideResult, vpl_core::GBuffer)> {
        self.last
            .iter()
            .map(|s| {
                #[cfg(feature = "gpu")]
                if let Some((image, gbuffer)) = host_frame(s) {
                    let out = vpl_render::FrameOutput { image, ..s.out.clone() };
                    return (SideResult { out, device: None, gpu: None, ..s.clone() }, gbuffer);
                }
                (s.clone(), s.out.gbuffer.clone())
            })
            .collect()
    }

    /// How the view is drawn now.
    fn look(&self) -> Look<'_> {
        Look {
            channel: self.channel,
            overlay: self.overlay,
            exposure: self.exposure,
            reference: self.reference.as_ref().map(|r| &r.image),
            picked: self.pick(),
        }
    }

    /// Composes the last frame on the device it was rendered on, when the
    /// window shares that device and every side stayed there.
    #[cfg(feature = "gpu")]
    fn compose_on_device(&mut self, gfx: &mut Gfx) {
        let Some(view) = gfx.device_view.as_mut().filter(|_| self.recompose) else { return };
        let look = self.look();
        match view.show(&gfx.device, &mut gfx.painter, &self.last, &look) {
            Ok(Some((id, c))) => {
                self.view_texture = Some(id);
                self.composite = Some(c);
                self.recompose = false;
                self.device_frames += 1;
            }
            Ok(None) => {}
            Err(e) => self.error_line = Some(format!("view on the device: {e}")),
        }
    }

    fn compose(&mut self, ctx: &egui::Context) {
        if !self.recompose {
            return;
        }
        self.recompose = false;
        let Some(left) = self.last.first() else { return };
        let right = self.last.get(1).filter(|r| r.out.image.width == left.out.image.width && r.out.image.height == left.out.image.height);
        let c = compose(side(left), right.map(side), &self.look());
        let image = egui::ColorImage::from_rgba_unmultiplied([c.width as usize, c.height as usize], &c.rgba);
        match &mut self.texture {
            Some(t) => t.set(image, egui::TextureOptions::NEAREST),
            None => self.texture = Some(ctx.load_texture("vpl-view", image, egui::TextureOptions::NEAREST)),
        }
        self.view_texture = self.texture.as_ref().map(|t| t.id());
        self.composite = Some(c);
    }

    /// Runs the script's steps up to the next wait (after the first frame).
    fn advance_script(&mut self) {
        if !self.scripted || self.frames_shown == 0 || self.pending_shot.is_some() || self.quit {
            return;
        }
        while self.waiting == 0 {
            let Some(step) = self.script.pop_front() else {
                self.quit = true;
                return;
            };
            match step {
                Step::Frames(n) => self.waiting = n,
                Step::Sampler(name) => {
                    if !self.check_sampler(&name) {
                        return;
                    }
                    self.sides[0] = name;
                    self.changed(true);
                }
                Step::Split(name) => {
                    if let Some(name) = name {
                        if !self.check_sampler(&name) {
                            return;
                        }
                        self.sides[1] = name;
                        self.split = true;
                    } else {
                        self.split = false;
                    }
                    self.changed(true);
                }
                Step::Overlay(o) => {
                    self.overlay = o;
                    self.recompose = true;
                }
                Step::Show(c) => {
                    self.channel = c;
                    self.recompose = true;
                }
                Step::Mode(m) => {
                    self.mode = m;
                    self.changed(true);
                }
                Step::Vpls(n) => {
                    self.vpls = n;
                    self.changed(true);
                }
                Step::Orbit(yaw, pitch) => {
                    self.cam.orbit(yaw.to_radians(), pitch.to_radians());
                    self.changed(true);
                }
                Step::Reference(on) => self.set_reference(on),
                Step::Pick(None) => {
                    self.picked = None;
                    self.refresh_map();
                }
                Step::Pick(Some((fx, fy))) => {
                    let Some(left) = self.last.first() else { continue };
                    let (w, h) = (left.out.image.width as f32, left.out.image.height as f32);
                    self.pick_at(fx * w, fy * h, f32::INFINITY);
                    if self.picked.is_none() {
                        self.fail(ViewerError::Render(format!("pick {fx} {fy}: the view shows no VPL")));
                        return;
                    }
                }
                Step::RecordStart => self.record_start(),
                Step::RecordStop(path) => {
                    if let Err(e) = self.record_stop(&path) {
                        self.fail(e);
                        return;
                    }
                }
                Step::Screenshot(path) => {
                    self.pending_shot = Some(path);
                    return;
                }
                Step::Quit => {
                    self.script.clear();
                    self.quit = true;
                    return;
                }
            }
        }
    }

    fn check_sampler(&mut self, name: &str) -> bool {
        if self.names.iter().any(|n| n == name) {
            return true;
        }
        self.fail(ViewerError::UnknownSampler { name: name.into(), known: self.names.join(", ") });
        false
    }

    /// The picked VPL, with the interleaving class that shades with it.
    fn pick(&self) -> Option<Pick> {
        let (side, slot) = self.picked?;
        let s = self.last.get(side)?;
        // The viewer's renderers shade interleaved (vpl_render's default).
        Some(Pick { side, slot, class: inspect::interleave_class(slot, s.out.vpls.len(), self.seed) })
    }

    /// Picks the visible VPL nearest to render pixel `(x, y)` (of the side
    /// the point lies in) within `radius` render pixels; none when no VPL is
    /// that near.
    fn pick_at(&mut self, x: f32, y: f32, radius: f32) {
        let split = self.composite.as_ref().and_then(|c| c.split_x);
        let k = match split {
            Some(sx) if x >= sx as f32 && self.last.len() > 1 => 1,
            _ => 0,
        };
        let hosted = self.on_host();
        self.picked = hosted.get(k).and_then(|(s, g)| pick_vpl(SideFrame { gbuffer: g, ..side(s) }, x, y, radius)).map(|slot| (k, slot));
        self.status_line = Some(match self.picked {
            Some((k, slot)) => format!("picked VPL {slot} of {}", self.last[k].spec.sampler),
            None => "no VPL near the click".into(),
        });
        self.refresh_map();
        self.recompose = true;
    }

    /// Renders the picked VPL's shadow map when the VPL is new or moved.
    fn refresh_map(&mut self) {
        let Some((k, slot)) = self.picked else {
            self.map = None;
            return;
        };
        let Some(v) = self.last.get(k).and_then(|s| s.out.vpls.get(slot)).copied() else {
            self.map = None;
            return;
        };
        let key = (k, slot, [v.y.x, v.y.y, v.y.z, v.n.x, v.n.y, v.n.z]);
        if self.map.as_ref().is_some_and(|(m, _)| *m == key) {
            return;
        }
        let scene = match self.scene() {
            Ok(s) => s,
            Err(e) => {
                self.error_line = Some(e.to_string());
                return;
            }
        };
        let vpls = &self.last[k].out.vpls;
        match inspect::shadow_map(&scene, vpls, slot, vpl_visibility::DEFAULT_RESOLUTION) {
            Ok(Some(m)) => {
                self.map = Some((key, m));
                self.map_texture = None;
            }
            Ok(None) => self.map = None,
            Err(e) => self.error_line = Some(format!("shadow map: {e}")),
        }
    }

    fn set_reference(&mut self, on: bool) {
        self.reference_on = on;
        if !on {
            self.reference = None;
            self.recompose = true;
        }
        self.changed(false);
    }

    /// The camera and the `[[lights]]` entries now.
    fn pose(&mut self) -> Pose {
        let lights = match &self.manual_lights {
            Some(l) => l.clone(),
            None => self.scene().map_or_else(|_| self.setup.scene.extra_lights(), |s| s.extra_lights()),
        };
        let lights = lights
            .iter()
            .map(|l| match l {
                Light::Point { position, .. } => (Some(*position), None),
                Light::Spot { position, direction, .. } => (Some(*position), Some(*direction)),
                Light::Directional { direction, .. } => (None, Some(*direction)),
                _ => (None, None),
            })
            .collect();
        Pose { origin: self.cam.origin, target: self.cam.target(), lights }
    }

    fn record_start(&mut self) {
        let fps = self.setup.sequence.as_ref().map_or(30.0, |s| s.fps);
        let mut r = Recorder::new(fps);
        r.push(0.0, self.pose());
        self.recording = Some((Instant::now(), r));
        self.status_line = Some("recording the camera and the lights".into());
    }

    /// Ends the recording and writes the scene file with it as its
    /// animation; model paths are made relative to the file's folder.
    fn record_stop(&mut self, path: &Path) -> Result<PathBuf, ViewerError> {
        let Some((start, mut r)) = self.recording.take() else {
            return Err(ViewerError::Invalid("record stop: nothing is being recorded".into()));
        };
        let t = start.elapsed().as_secs_f32();
        r.push(t, self.pose());
        let spec = r.finish(t).ok_or_else(|| ViewerError::Invalid("record stop: nothing was recorded".into()))?;
        let setup = self.setup.clone().with_world_sequence(spec)?;
        let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir).map_err(|e| ViewerError::Write { path: dir.to_path_buf(), reason: e.to_string() })?;
        let file = setup.description.relocated(&self.scene_dir, dir);
        let text = format!(
            "# Recorded by vpl view on {}: {} camera keys, {} light keys.\n{}",
            self.scene_name,
            file.sequence.as_ref().map_or(0, |s| s.camera.len()),
            file.sequence.as_ref().map_or(0, |s| s.lights.len()),
            vpl_scene_io::scene_toml(&file)
        );
        vpl_core::image::write_atomic(path, text.as_bytes())?;
        self.status_line = Some(format!("wrote {}", path.display()));
        Ok(path.to_path_buf())
    }

    /// Advances the animation and the keyboard flight by the time since the last tick.
    fn tick(&mut self, ctx: &egui::Context) {
        let now = Instant::now();
        let dt = (now - self.last_tick).as_secs_f32().min(0.1);
        self.last_tick = now;
        if self.recording.is_some() {
            let pose = self.pose();
            if let Some((start, r)) = &mut self.recording {
                r.push((now - *start).as_secs_f32(), pose);
            }
        }
        if self.playing
            && let Some(seq) = &self.setup.sequence
        {
            self.play_clock += dt as f64;
            let f = ((self.play_clock * seq.fps as f64) as u64 % self.frame_count as u64) as u32;
            if f != self.anim_frame {
                self.set_anim_frame(f);
            }
        }
        if ctx.wants_keyboard_input() {
            return;
        }
        let (mut f, mut r, mut u, fast) = ctx.input(|i| {
            let k = |key| if i.key_down(key) { 1.0f32 } else { 0.0 };
            (k(egui::Key::W) - k(egui::Key::S), k(egui::Key::D) - k(egui::Key::A), k(egui::Key::E) - k(egui::Key::Q), i.modifiers.shift)
        });
        if f != 0.0 || r != 0.0 || u != 0.0 {
            let step = self.speed * dt * if fast { 4.0 } else { 1.0 };
            f *= step;
            r *= step;
            u *= step;
            self.cam.fly(f, r, u);
            self.changed(false);
        }
    }

    fn set_anim_frame(&mut self, f: u32) {
        self.anim_frame = f.min(self.frame_count - 1);
        if self.follow_camera
            && let Ok(c) = self.setup.camera_at_frame(self.anim_frame)
        {
            self.cam = FlyCamera::from_camera(&c);
        }
        self.changed(false);
    }

    /// Keeps redrawing without input: keys held, an animation playing, a
    /// frame in flight is answered by a wake-up instead.
    fn wants_ticks(&self, ctx: &egui::Context) -> bool {
        self.playing
            || ctx.input(|i| {
                [egui::Key::W, egui::Key::A, egui::Key::S, egui::Key::D, egui::Key::Q, egui::Key::E].iter().any(|k| i.key_down(*k))
            })
    }

    /// Moves the first point or spot light in the view plane by a drag of
    /// `(dx, dy)` view pixels (turns a directional light).
    fn move_light(&mut self, dx: f32, dy: f32) {
        let view_w = self.view_pixels().0.max(1.0);
        let lights = self
            .manual_lights
            .get_or_insert_with(|| self.scene_cache.as_ref().map_or_else(|| self.setup.scene.extra_lights(), |(_, s)| s.extra_lights()));
        let right = self.cam.right();
        let up = right.cross(self.cam.forward).normalize_or(Vec3::Y);
        let fov = self.setup.camera.fov_deg.to_radians();
        let moved = lights.iter_mut().find_map(|l| match l {
            Light::Point { position, .. } | Light::Spot { position, .. } => {
                let dist = (*position - self.cam.origin).dot(self.cam.forward).abs().max(1e-3);
                let per_px = 2.0 * dist * (0.5 * fov).tan() / view_w;
                *position += (right * dx - up * dy) * per_px;
                Some(())
            }
            Light::Directional { direction, .. } => {
                let turn = vpl_core::glam::Quat::from_axis_angle(self.cam.up, -dx * 0.005)
                    * vpl_core::glam::Quat::from_axis_angle(right, -dy * 0.005);
                *direction = (turn * *direction).normalize_or(*direction);
                Some(())
            }
            _ => None,
        });
        if moved.is_some() {
            self.lights_version += 1;
            self.changed(false);
        } else {
            self.status_line = Some("the scene has no point, spot or directional light to move".into());
        }
    }

    fn ui(&mut self, ctx: &egui::Context) {
        egui::SidePanel::left("controls").resizable(false).exact_width(PANEL_WIDTH).show(ctx, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.panel(ui));
        });
        egui::CentralPanel::default().frame(egui::Frame::NONE.fill(egui::Color32::BLACK)).show(ctx, |ui| self.view(ui));
    }

    fn sampler_combo(ui: &mut egui::Ui, id: &str, names: &[String], value: &mut String) -> bool {
        let before = value.clone();
        egui::ComboBox::from_id_salt(id).selected_text(value.as_str()).show_ui(ui, |ui| {
            for n in names {
                ui.selectable_value(value, n.clone(), n.as_str());
            }
        });
        *value != before
    }

    fn panel(&mut self, ui: &mut egui::Ui) {
        ui.heading(format!("vpl view: {}", self.scene_name));
        ui.label(&self.renderer_line);
        let res = self.resolution();
        ui.label(format!("render {}×{} (scale {:.2} of the view)", res.0, res.1, self.scale));
        ui.separator();
        ui.horizontal(|ui| {
            ui.label("light");
            for (m, name) in [(Mode::Full, "full"), (Mode::Direct, "direct"), (Mode::Indirect, "indirect")] {
                if ui.selectable_label(self.mode == m, name).clicked() && self.mode != m {
                    self.mode = m;
                    self.changed(true);
                }
            }
        });
        ui.horizontal(|ui| {
            let mut v = self.vpls;
            ui.label("VPLs");
            ui.add(egui::DragValue::new(&mut v).range(1..=65536));
            if v != self.vpls {
                self.vpls = v;
                self.changed(true);
            }
            let mut s = self.scale;
            ui.label("scale");
            ui.add(egui::DragValue::new(&mut s).range(0.05..=1.0).speed(0.01));
            if s != self.scale {
                self.scale = s;
                self.changed(true);
            }
        });
        ui.horizontal(|ui| {
            ui.label(if self.split { "left" } else { "sampler" });
            if Self::sampler_combo(ui, "left", &self.names, &mut self.sides[0]) {
                self.changed(true);
            }
        });
        ui.horizontal(|ui| {
            if ui.checkbox(&mut self.split, "split, right").changed() {
                self.changed(true);
            }
            if self.split && Self::sampler_combo(ui, "right", &self.names, &mut self.sides[1]) {
                self.changed(true);
            }
        });
        ui.horizontal(|ui| {
            ui.label("overlay");
            for (o, name) in [(Overlay::Off, "off"), (Overlay::Vpls, "VPLs"), (Overlay::Interleave, "interleaving")] {
                if ui.selectable_label(self.overlay == o, name).clicked() {
                    self.overlay = o;
                    self.recompose = true;
                }
            }
        });
        ui.label(
            egui::RichText::new(match self.overlay {
                Overlay::Off => "click a VPL (VPL overlay) to see its shadow map".to_string(),
                Overlay::Vpls => "colour: flux against the median (blue ¹⁄₁₀₀×, red 100×); white ring: moved this frame".into(),
                Overlay::Interleave => "pixel class 4·(y mod 4) + (x mod 4) shades with VPL subset c; a picked VPL lights its class".into(),
            })
            .small(),
        );
        if let Some(p) = self.pick()
            && let Some(v) = self.last.get(p.side).and_then(|s| s.out.vpls.get(p.slot)).copied()
        {
            let sampler = self.last[p.side].spec.sampler.clone();
            ui.horizontal(|ui| {
                ui.label(
                    egui::RichText::new(format!(
                        "VPL {} of {}: bounce {}, flux {:.3e}{}",
                        p.slot,
                        sampler,
                        v.bounce,
                        vpl_core::image::luminance(v.flux),
                        p.class.map_or(String::new(), |c| format!(", pixel class {c}"))
                    ))
                    .small(),
                );
                if ui.small_button("unpick").clicked() {
                    self.picked = None;
                    self.refresh_map();
                    self.recompose = true;
                }
            });
        }
        ui.horizontal(|ui| {
            let mut on = self.reference_on;
            if ui.checkbox(&mut on, "reference (path tracer while still)").changed() {
                self.set_reference(on);
            }
        });
        if let Some(r) = &self.reference {
            let mut line = format!("reference: {} passes of 1 path per pixel", r.passes);
            for sd in &self.last {
                if let Some((ratio, rmse)) = against_reference(&sd.out.image, &r.image) {
                    line.push_str(&format!(
                        "\n{}: mean {:.3}× the reference, RMS difference {:.3} of its mean",
                        sd.spec.sampler, ratio, rmse
                    ));
                }
            }
            ui.label(egui::RichText::new(line).small());
        }
        ui.horizontal(|ui| {
            ui.label("show");
            let before = self.channel;
            egui::ComboBox::from_id_salt("channel").selected_text(self.channel.name()).show_ui(ui, |ui| {
                for c in Channel::ALL {
                    ui.selectable_value(&mut self.channel, c, c.name());
                }
            });
            ui.label("exposure");
            let e = self.exposure;
            ui.add(egui::DragValue::new(&mut self.exposure).range(0.01..=100.0).speed(0.05));
            if self.channel != before || self.exposure != e {
                self.recompose = true;
            }
        });
        if self.frame_count > 1 {
            ui.horizontal(|ui| {
                if ui.button(if self.playing { "pause" } else { "play" }).clicked() {
                    self.playing = !self.playing;
                    if let Some(seq) = &self.setup.sequence {
                        self.play_clock = self.anim_frame as f64 / seq.fps as f64;
                    }
                }
                let mut f = self.anim_frame;
                ui.add(egui::Slider::new(&mut f, 0..=self.frame_count - 1).text("frame"));
                if f != self.anim_frame {
                    self.playing = false;
                    self.set_anim_frame(f);
                }
            });
            ui.checkbox(&mut self.follow_camera, "camera follows the animation");
        }
        ui.separator();
        for s in &self.last {
            let t = s.out.timings;
            ui.label(
                egui::RichText::new(format!(
                    "{}: {:.1} ms (G-buffer {:.1}, sampling {:.1}, visibility {:.1}, shading {:.1}, direct {:.1})\n{} stored, {} moved{}",
                    s.spec.sampler,
                    t.total_ms,
                    t.gbuffer_ms,
                    t.sampling_ms,
                    t.visibility_ms,
                    t.shading_ms,
                    t.direct_ms,
                    s.out.stored,
                    s.out.moved,
                    s.change.map_or(String::new(), |c| format!(", Σ|ΔL|/ΣL {c:.4}"))
                ))
                .small(),
            );
        }
        let names: Vec<String> = self.last.iter().map(|s| s.spec.sampler.clone()).collect();
        let plot = |ui: &mut egui::Ui, id: &str, title: &str, columns: &[(usize, &str)], history: &[History; 2]| {
            ui.label(title);
            egui_plot::Plot::new(id)
                .height(80.0)
                .allow_drag(false)
                .allow_zoom(false)
                .allow_scroll(false)
                .include_y(0.0)
                .legend(egui_plot::Legend::default())
                .show(ui, |p| {
                    for (k, h) in history.iter().enumerate().take(names.len()) {
                        for (c, what) in columns {
                            let label =
                                if what.is_empty() || columns.len() == 1 { names[k].clone() } else { format!("{} {what}", names[k]) };
                            p.line(egui_plot::Line::new(label, h.series(*c)));
                        }
                    }
                });
        };
        let stages: Vec<(usize, &str)> = (1..=6).map(|c| (c, History::COLUMNS[c - 1])).collect();
        plot(ui, "ms", "milliseconds per stage", &stages, &self.history);
        plot(ui, "moved", "VPLs moved per frame", &[(7, "")], &self.history);
        plot(ui, "change", "frame-to-frame change Σ|ΔL|/ΣL", &[(8, "")], &self.history);
        ui.separator();
        ui.horizontal(|ui| {
            if ui.button("screenshot (PNG, EXR)").clicked() {
                self.shots += 1;
                self.pending_shot = Some(PathBuf::from(format!("vpl-view-{}-{}", self.scene_name, self.shots)));
            }
            if self.recording.is_none() {
                if ui.button("record path").clicked() {
                    self.record_start();
                }
            } else if ui.button("stop, write scene file").clicked() {
                self.recordings += 1;
                let path = PathBuf::from(format!("vpl-view-{}-path-{}.toml", self.scene_name, self.recordings));
                if let Err(e) = self.record_stop(&path) {
                    self.error_line = Some(e.to_string());
                }
            }
        });
        if let Some((start, r)) = &self.recording {
            ui.label(egui::RichText::new(format!("recording: {:.1} s, {} keys", start.elapsed().as_secs_f32(), r.len())).small());
        }
        ui.label(
            egui::RichText::new("left drag: orbit · right drag: look · WASD QE: fly · wheel: dolly · Ctrl+drag: move the light").small(),
        );
        if let Some(s) = &self.status_line {
            ui.label(egui::RichText::new(s).small());
        }
        if let Some(e) = &self.error_line {
            ui.colored_label(egui::Color32::from_rgb(255, 90, 90), e);
        }
    }

    fn view(&mut self, ui: &mut egui::Ui) {
        let rect = ui.available_rect_before_wrap();
        if self.view_rect.is_none_or(|r| (r.size() - rect.size()).length() > 0.5) {
            let first = self.view_rect.is_none();
            self.view_rect = Some(rect);
            if !first {
                self.changed(true);
            }
        }
        let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
        match self.view_texture {
            Some(t) => {
                ui.painter().image(t, rect, egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)), egui::Color32::WHITE);
            }
            None => {
                ui.painter().text(
                    rect.center(),
                    egui::Align2::CENTER_CENTER,
                    "rendering the first frame…",
                    egui::FontId::proportional(18.0),
                    egui::Color32::GRAY,
                );
            }
        }
        let d = response.drag_delta() * self.pixels_per_point;
        if d != egui::Vec2::ZERO {
            let ctrl = ui.input(|i| i.modifiers.command);
            if response.dragged_by(egui::PointerButton::Primary) && ctrl {
                self.move_light(d.x, d.y);
            } else if response.dragged_by(egui::PointerButton::Primary) {
                self.cam.orbit(-d.x * 0.005, -d.y * 0.005);
                self.changed(false);
            } else if response.dragged_by(egui::PointerButton::Secondary) {
                self.cam.look(-d.x * 0.003, -d.y * 0.003);
                self.changed(false);
            }
        }
        // A click (no drag) picks the VPL nearest to it.
        if response.clicked()
            && let Some(pos) = response.interact_pointer_pos()
            && let Some((cw, ch)) = self.composite.as_ref().map(|c| (c.width as f32, c.height as f32))
        {
            let x = (pos.x - rect.min.x) / rect.width().max(1.0) * cw;
            let y = (pos.y - rect.min.y) / rect.height().max(1.0) * ch;
            let radius = PICK_RADIUS * cw / (rect.width() * self.pixels_per_point).max(1.0);
            self.pick_at(x, y, radius);
        }
        // The picked VPL's shadow map, in the view's lower right corner.
        self.map_rect = None;
        if let Some((_, m)) = &self.map {
            let texture = self.map_texture.get_or_insert_with(|| {
                let image = egui::ColorImage::from_rgba_unmultiplied([m.res as usize, m.res as usize], &m.rgba);
                ui.ctx().load_texture("vpl-view shadow map", image, egui::TextureOptions::NEAREST)
            });
            let side = (rect.height() * 0.4).min(rect.width() * 0.4).min(256.0);
            let inset = egui::Rect::from_min_size(rect.max - egui::vec2(side + 8.0, side + 8.0), egui::vec2(side, side));
            let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            ui.painter().image(texture.id(), inset, uv, egui::Color32::WHITE);
            ui.painter().rect_stroke(inset, 0.0, egui::Stroke::new(2.0, egui::Color32::from_rgb(255, 0, 255)), egui::StrokeKind::Outside);
            ui.painter().text(
                inset.left_top() - egui::vec2(0.0, 2.0),
                egui::Align2::LEFT_BOTTOM,
                format!("shadow map of VPL {} ({}², paraboloid)", self.picked.map_or(0, |p| p.1), m.res),
                egui::FontId::proportional(12.0),
                egui::Color32::from_rgb(255, 0, 255),
            );
            self.map_rect = Some(inset);
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.cam.dolly(scroll * 0.002);
                self.changed(false);
            }
        }
    }

    /// Writes a screenshot: the window's pixels, the view's values, and
    /// where the view and the split lie in the window.
    fn write_shot(&self, path: &Path, window: (u32, u32, Vec<u8>)) -> Result<PathBuf, ViewerError> {
        let with = |ext: &str| {
            let mut s = OsString::from(path.as_os_str());
            s.push(ext);
            PathBuf::from(s)
        };
        let write_err = |p: &Path, e: &dyn std::fmt::Display| ViewerError::Write { path: p.to_path_buf(), reason: e.to_string() };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| write_err(dir, &e))?;
        }
        let (w, h, rgb) = window;
        let png = with(".png");
        vpl_scene_io::write_png_rgb8(&png, w, h, &rgb)?;
        let exr = with(".exr");
        match &self.composite {
            Some(c) if c.hdr.on_host() => c.hdr.write_exr(&exr)?,
            // Composed on the device: the values come from the frames read back.
            Some(_) => {
                let hosted = self.on_host();
                if let Some((left, lg)) = hosted.first() {
                    let right = hosted.get(1).map(|(s, g)| SideFrame { gbuffer: g, ..side(s) });
                    let c = compose(SideFrame { gbuffer: lg, ..side(left) }, right, &self.look());
                    c.hdr.write_exr(&exr)?;
                }
            }
            None => {}
        }
        let ppp = self.pixels_per_point;
        let view = self.view_rect.map_or([0.0; 4], |r| [r.min.x * ppp, r.min.y * ppp, r.max.x * ppp, r.max.y * ppp]);
        let split = self.composite.as_ref().and_then(|c| c.split_x.map(|s| view[0] + (s as f32 / c.width as f32) * (view[2] - view[0])));
        let sides: Vec<String> = self.last.iter().map(|s| format!("\"{}\"", s.spec.sampler)).collect();
        let res = self.composite.as_ref().map_or((0, 0), |c| (c.width, c.height));
        let json = format!(
            "{{\n  \"window\": [{w}, {h}],\n  \"view\": [{:.1}, {:.1}, {:.1}, {:.1}],\n  \"split_x\": {},\n  \"render\": [{}, {}],\n  \"sides\": [{}],\n  \"channel\": \"{}\",\n  \"overlay\": \"{}\",\n  \"frames\": {},\n  \"reference_passes\": {},\n  \"picked\": {},\n  \"shadow_map\": {}\n}}\n",
            view[0],
            view[1],
            view[2],
            view[3],
            split.map_or("null".to_string(), |s| format!("{s:.1}")),
            res.0,
            res.1,
            sides.join(", "),
            self.channel.name(),
            self.overlay.name(),
            self.frames_shown,
            self.reference.as_ref().map_or(0, |r| r.passes),
            self.picked.map_or("null".to_string(), |(k, slot)| format!("[{k}, {slot}]")),
            self.map_rect.map_or("null".to_string(), |r| format!(
                "[{:.1}, {:.1}, {:.1}, {:.1}]",
                r.min.x * ppp,
                r.min.y * ppp,
                r.max.x * ppp,
                r.max.y * ppp
            ))
        );
        let j = with(".json");
        vpl_core::image::write_atomic(&j, json.as_bytes())?;
        Ok(png)
    }
}

impl App {
    fn redraw(&mut self, el: &ActiveEventLoop) {
        let Some(gfx) = self.gfx.as_mut() else { return };
        let st = &mut self.st;
        st.poll();
        st.advance_script();
        if st.quit {
            el.exit();
            return;
        }
        let raw = gfx.egui.take_egui_input(&gfx.window);
        let ctx = gfx.egui.egui_ctx().clone();
        st.pixels_per_point = ctx.pixels_per_point();
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
        if st.view_texture.is_some()
            && !st.recompose
            && let Some(path) = st.pending_shot.take()
        {
            match gfx.capture(&prims, &sd).map_err(ViewerError::Surface).and_then(|px| st.write_shot(&path, px)) {
                Ok(p) => st.status_line = Some(format!("wrote {}", p.display())),
                Err(e) if st.scripted => {
                    st.fail(e);
                    el.exit();
                }
                Err(e) => st.error_line = Some(e.to_string()),
            }
            gfx.window.request_redraw();
        }
        for id in &out.textures_delta.free {
            gfx.painter.free_texture(id);
        }
        let delay = out.viewport_output.get(&egui::ViewportId::ROOT).map_or(Duration::MAX, |v| v.repaint_delay);
        if st.wants_ticks(&ctx) || st.pending_shot.is_some() || delay.is_zero() {
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
        match Gfx::new(el, self.st.window_size, &format!("vpl view: {}", self.st.scene_name), self.shared.as_ref()) {
            Ok(g) => {
                #[cfg(feature = "gpu")]
                {
                    self.st.resident = g.device_view.is_some();
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
                self.st.quit = true;
                el.exit();
            }
            WindowEvent::Resized(s) => {
                gfx.resize(s.width, s.height);
                self.st.window_size = (s.width, s.height);
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
