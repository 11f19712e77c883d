//! `vpl render`: Render one frame of a scene.

use super::tev::TevSink;
use super::*;
use vpl_scene_io::ImageFile;

/// Render one frame of a scene.
#[derive(clap::Args)]
pub(super) struct Args {
    #[command(flatten)]
    s: SceneArgs,
    /// Rendering method.
    #[arg(long, value_enum, default_value_t = Method::Path)]
    method: Method,
    /// Which light paths to include.
    #[arg(long, value_enum, default_value_t = ModeArg::Full)]
    mode: ModeArg,
    /// Samples per pixel (path).
    #[arg(long, default_value_t = 64)]
    spp: u32,
    /// Which materials to draw: as-is (default for path and progressive) or diffuse (each material's
    /// albedo only, which is all the VPL pipeline can draw: the fair reference for a VPL render).
    /// --method vpl always draws diffuse and says so when the scene has layered materials.
    #[arg(long, value_enum)]
    materials: Option<MaterialsArg>,
    #[command(flatten)]
    v: VplArgs,
    #[command(flatten)]
    p: ProgressiveArgs,
    /// Output EXR; a PNG preview is written beside it.
    #[arg(long, default_value = "render.exr")]
    out: PathBuf,
    /// Also write the per-pixel standard error of the mean to this EXR.
    #[arg(long)]
    stderr: Option<PathBuf>,
    /// Exposure applied to the PNG preview.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// No progress bar or summary.
    #[arg(long)]
    quiet: bool,
    /// Show the image in the tev viewer at HOST:PORT (HOST alone: tev's port 14158) as it renders:
    /// the path tracer's tiles as they finish, each progressive pass (at most four a second, and the
    /// last), the VPL frame.
    #[arg(long, value_name = "HOST:PORT")]
    tev: Option<String>,
}

/// Runs `vpl render`.
impl Args {
    /// The VPL settings, for the sampler flags made at parse time.
    pub(super) fn vpl_args(&mut self) -> &mut VplArgs {
        &mut self.v
    }
}

pub(super) fn run(args: Args, registry: &Registry) -> Res<()> {
    let Args {
        s: SceneArgs { scene, frame, max_depth, clamp, vpls, size, seed, threads, memory_limit, allow_outside },
        method,
        mode,
        spp,
        materials,
        v,
        p,
        out,
        stderr,
        exposure,
        quiet,
        tev,
    } = args;
    let scene = SceneSource::new(scene, allow_outside, memory_limit);
    if method == Method::Vpl && materials == Some(MaterialsArg::AsIs) {
        return Err("--materials as-is: the VPL pipeline draws each material's albedo only (use --method path or progressive)".into());
    }
    let policy = materials.map_or(vpl_core::MaterialPolicy::AsIs, MaterialsArg::policy);
    if method == Method::Progressive && mode != ModeArg::Full {
        return Err("--mode: the progressive renderer renders full images (select path classes with --techniques)".into());
    }
    if method != Method::Progressive && spp == 0 {
        return Err("--spp must be at least 1".into());
    }
    check_depth(max_depth, vpls)?;
    if !(exposure.is_finite() && exposure > 0.0) {
        return Err("--exposure must be positive".into());
    }
    let out = ImageOut::new("--out", &out, true)?;
    let stderr = stderr.map(|s| ImageOut::new("--stderr", &s, false)).transpose()?;
    let mut names = vec![("--out", out.path.as_path())];
    names.extend(out.preview.as_deref().map(|p| ("the preview of --out", p)));
    names.extend(stderr.as_ref().map(|s| ("--stderr", s.path.as_path())));
    distinct(&names)?;
    let pool = pool(threads)?;
    let job = Job {
        scene: &scene,
        frame,
        size,
        seed,
        max_depth,
        clamp,
        vpls,
        out: &out,
        exposure,
        quiet,
        memory_limit,
        pool: &pool,
        tev: tev.as_deref(),
    };
    if method == Method::Progressive {
        return render_progressive(job, policy, &p, stderr.as_ref());
    }
    if method == Method::Vpl {
        if stderr.is_some() {
            return Err("--stderr is for --method path: one VPL render has no per-pixel error estimate".into());
        }
        return render_vpl(registry, job, mode, &v);
    }
    let (sc, camera) = load_frame(&scene, frame, size)?;
    let sc = with_policy(sc, policy, "the path tracer (--materials diffuse)");
    let estimate = vpl_render::MemoryEstimate::path_tracer(&sc, camera.resolution);
    check_memory(&estimate, memory_limit)?;
    let pt = tracer(max_depth, mode, clamp, vpls, &sc, &camera);
    let sink = tev.as_deref().map(|a| TevSink::open(a, format!("{} path {spp} spp", sc.name), camera.resolution)).transpose()?;
    let bar = ProgressBar::with_draw_target(Some(camera.resolution.0 as u64 * camera.resolution.1 as u64), ProgressDrawTarget::hidden());
    bar.set_style(
        ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:40}] {percent}% pixels, eta {eta}").unwrap().progress_chars("=> "),
    );
    let start = Instant::now();
    let shown = AtomicBool::new(false);
    let progress = |done: u64, _total: u64| {
        if !quiet && !shown.load(Ordering::Relaxed) && start.elapsed().as_secs_f32() > 1.0 {
            shown.store(true, Ordering::Relaxed);
            bar.set_draw_target(ProgressDrawTarget::stderr());
        }
        bar.set_position(done);
    };
    let on_tile = |t: vpl_pathtrace::Tile<'_>| {
        if let Some(s) = &sink {
            s.tile(t);
        }
    };
    let settings = RenderSettings { spp, seed, frame: frame as u64 };
    let never = AtomicBool::new(false);
    let r = pool
        .install(|| vpl_pathtrace::render_streamed(&sc, &camera, &pt, settings, &progress, &on_tile, &never))
        .map_err(|e| e.to_string())?;
    bar.finish_and_clear();
    if let (Some(s), Some(a)) = (sink, &tev) {
        s.finish(a, quiet);
    }
    let mut written = Written::default();
    written.image(&r.image, &out, exposure, "the path tracer")?;
    if let Some(s) = &stderr {
        written.image(&r.stderr, s, 1.0, "the path tracer's standard error")?;
    }
    written.keep()?;
    if !quiet {
        let m = r.image.mean();
        eprintln!(
            "vpl: {} {}x{} {spp} spp in {:.2} s ({:.2} M paths/s), mean RGB {:.5} {:.5} {:.5}, {} -> {}",
            sc.name,
            camera.resolution.0,
            camera.resolution.1,
            r.seconds,
            r.paths as f64 / r.seconds / 1e6,
            m[0],
            m[1],
            m[2],
            memory_line(&estimate),
            out.path.display()
        );
    }
    Ok(())
}

/// `vpl render --method vpl`.
/// What `--method vpl` and `--method progressive` share of a render: the
/// scene's flags, the output and how the run reports.
#[derive(Clone, Copy)]
struct Job<'a> {
    scene: &'a SceneSource,
    frame: u32,
    size: Option<Size>,
    seed: u64,
    max_depth: u32,
    clamp: Option<vpl_render::Clamp>,
    vpls: usize,
    out: &'a ImageOut,
    exposure: f32,
    quiet: bool,
    memory_limit: Option<MemoryArg>,
    pool: &'a rayon::ThreadPool,
    tev: Option<&'a str>,
}

fn render_vpl(registry: &Registry, job: Job<'_>, mode: ModeArg, v: &VplArgs) -> Res<()> {
    let Job { scene, frame, size, seed, max_depth, clamp, vpls, out, exposure, quiet, memory_limit, pool, tev } = job;
    let (sc, camera) = load_frame(scene, frame, size)?;
    let sc = with_policy(sc, vpl_core::MaterialPolicy::Diffuse, "the VPL pipeline (compare with --method path --materials diffuse)");
    let maps = (v.visibility == VisibilityArg::Shadowmap).then_some(v.shadowmap_res);
    let clamp = clamp.unwrap_or(vpl_render::Clamp::Auto).resolve(vpls, &sc, &camera);
    let spec = pipeline_spec(v, vpls, max_depth, mode, clamp.into(), seed)?;
    let estimate = with_sampler_memory(vpl_render::MemoryEstimate::vpl_frame(&sc, camera.resolution, vpls, maps), &spec, registry);
    check_memory(&estimate, memory_limit)?;
    let mut p = build_renderer(&spec, registry, &sc)?;
    p.backend().check_size(camera.resolution).map_err(vpl_bench::pipeline::backend_line)?;
    if let (Some(a), false) = (p.backend().device(), quiet) {
        eprintln!("vpl: GPU: {a}");
    }
    let sink = tev.map(|a| TevSink::open(a, format!("{} vpl {}", sc.name, p.sampler().name()), camera.resolution)).transpose()?;
    let r = pool.install(|| p.render(&sc, &camera, frame as u64, frame as f32 / 30.0)).map_err(vpl_bench::pipeline::backend_line)?;
    if let (Some(s), Some(a)) = (sink, tev) {
        s.image(&r.image);
        s.finish(a, quiet);
    }
    let mut written = Written::default();
    written.image(&r.image, out, exposure, "the VPL frame")?;
    written.keep()?;
    if !quiet {
        let t = r.timings;
        let m = r.image.mean();
        if r.indirect.is_some() {
            eprintln!("vpl: {}: {} of {} VPLs stored; {}", p.sampler().name(), r.stored, vpls, r.sampler_stats);
            eprintln!(
                "vpl: visibility {}: {} maps rebuilt, {:.1} MiB; clamp {}",
                p.visibility().name(),
                r.visibility.rebuilt,
                r.visibility.memory_bytes as f64 / (1 << 20) as f64,
                match (clamp, p.compensation()) {
                    (None, _) => "off".to_string(),
                    (Some(c), 0) => format!("G_max = {:.3} 1/m^2", c.g_max),
                    (Some(c), n) => format!("G_max = {:.3} 1/m^2, compensated ({n} gather rays, {:.1} ms)", c.g_max, t.compensation_ms),
                }
            );
        }
        eprintln!(
            "vpl: {} {}x{} in {:.1} ms (G-buffer {:.1}, sampling {:.1}, visibility {:.1}, {} shading {:.1}, direct {:.1}), mean RGB {:.5} {:.5} {:.5}, {} -> {}",
            sc.name,
            camera.resolution.0,
            camera.resolution.1,
            t.total_ms,
            t.gbuffer_ms,
            t.sampling_ms,
            t.visibility_ms,
            p.shader().map_or("no", |s| s.name()),
            t.shading_ms,
            t.direct_ms,
            m[0],
            m[1],
            m[2],
            memory_line(&estimate),
            out.path.display()
        );
    }
    Ok(())
}

/// `vpl render --method progressive`.
fn render_progressive(job: Job<'_>, policy: vpl_core::MaterialPolicy, p: &ProgressiveArgs, stderr: Option<&ImageOut>) -> Res<()> {
    let Job { scene, frame, size, seed, max_depth, clamp, vpls, out, exposure, quiet, memory_limit, pool, tev } = job;
    use vpl_progressive::{Culling, Progressive, ProgressiveConfig, Techniques};
    if p.passes == Some(0) {
        return Err("--passes must be at least 1".into());
    }
    if let Some(t) = p.seconds {
        if !(t.is_finite() && t > 0.0) {
            return Err("--seconds must be positive".into());
        }
    }
    if p.snapshot_every == Some(0) {
        return Err("--snapshot-every must be at least 1".into());
    }
    if p.snapshot_every.is_some() != p.snapshots.is_some() {
        return Err("--snapshot-every and --snapshots go together".into());
    }
    if let Some(d) = &p.snapshots {
        if d.exists() && !d.is_dir() {
            return Err(format!("--snapshots {} is not a directory", d.display()));
        }
    }
    if !(p.cull_accept > 0.0 && p.cull_accept <= 1.0) {
        return Err("--cull-accept must lie in (0, 1] (the acceptance probability of an unseen VPL)".into());
    }
    let techniques = Techniques::parse(&p.techniques).map_err(|e| format!("--techniques: {e}"))?;
    let culling = match p.culling {
        CullingArg::Unbiased => Culling::Unbiased { accept: p.cull_accept },
        CullingArg::Deterministic => Culling::Deterministic,
        CullingArg::Off => Culling::Off,
    };
    let (sc, mut camera) = load_frame(scene, frame, size)?;
    let sc = with_policy(sc, policy, "the progressive renderer (--materials diffuse)");
    let vpl_bytes = vpl_progressive::bytes_per_vpl(p.gather);
    let estimate = vpl_render::MemoryEstimate::progressive(&sc, camera.resolution, p.caustic_paths, p.vpl_paths, max_depth, vpl_bytes);
    check_memory(&estimate, memory_limit)?;
    if p.lens_radius.is_some() || p.focus_distance.is_some() {
        let r = p.lens_radius.unwrap_or(camera.lens_radius);
        let f = p.focus_distance.unwrap_or((camera.target - camera.origin).length());
        if !(r.is_finite() && r >= 0.0) {
            return Err("--lens-radius must be zero or positive".into());
        }
        if !(f.is_finite() && f > 0.0) {
            return Err("--focus-distance must be positive".into());
        }
        camera.lens_radius = r;
        camera.focus_distance = f;
    }
    let config = ProgressiveConfig {
        max_depth,
        vpl_paths: p.vpl_paths,
        caustic_paths: p.caustic_paths,
        gathering: p.gather,
        culling,
        clamp: clamp.unwrap_or(vpl_render::Clamp::Auto).resolve(vpls, &sc, &camera),
        projection_maps: !p.no_projection_maps,
        indirect_caustics: !p.primary_caustics_only,
        spectral: !p.no_spectral,
        bins: match p.bins {
            BinsArg::Closest => vpl_progressive::BinRule::Closest,
            BinsArg::All => vpl_progressive::BinRule::AllWithin,
        },
        techniques,
        seed,
        ..ProgressiveConfig::default()
    };
    let mut r = Progressive::new(&sc, camera, config).map_err(|e| e.to_string())?;
    let sink = tev.map(|a| TevSink::open(a, format!("{} progressive", sc.name), r.camera().resolution)).transpose()?;
    // At most four images a second: a whole image per pass would swamp tev on fast passes.
    let mut sent = None::<Instant>;
    let passes = p.passes.unwrap_or(if p.seconds.is_some() { u64::MAX } else { 64 });
    let snapshots = p.snapshots.as_deref().map(|d| OutDir::create("--snapshots", d)).transpose()?;
    let bar = if quiet {
        ProgressBar::hidden()
    } else if passes == u64::MAX {
        ProgressBar::new_spinner()
    } else {
        ProgressBar::new(passes)
    };
    let template = if passes == u64::MAX {
        "{spinner} {elapsed_precise} pass {pos} ({per_sec}) {msg}"
    } else {
        "{elapsed_precise} [{bar:40}] pass {pos}/{len} ({per_sec}) {msg}, eta {eta}"
    };
    bar.set_style(ProgressStyle::with_template(template).unwrap().progress_chars("=> "));
    let start = Instant::now();
    let mut last = vpl_progressive::PassStats::default();
    while r.passes() < passes {
        last = pool.install(|| r.pass());
        bar.set_message(format!("{} VPLs, {} photons", last.stored, last.photons));
        bar.inc(1);
        if let Some(s) = &sink
            && sent.is_none_or(|t| t.elapsed().as_secs_f32() >= 0.25)
        {
            s.image(&r.image());
            sent = Some(Instant::now());
        }
        if let (Some(k), Some(d)) = (p.snapshot_every, &snapshots) {
            if r.passes() % k == 0 {
                let img = r.image();
                check_finite(&img, &format!("progressive pass {}", r.passes()))?;
                img.write_exr(d.path().join(format!("pass_{:06}.exr", r.passes()))).map_err(|e| e.to_string())?;
            }
        }
        if p.seconds.is_some_and(|t| start.elapsed().as_secs_f64() >= t) {
            break;
        }
    }
    bar.finish_and_clear();
    let secs = start.elapsed().as_secs_f64();
    let img = r.image();
    if let (Some(s), Some(a)) = (sink, tev) {
        s.image(&img);
        s.finish(a, quiet);
    }
    let mut written = Written::default();
    written.image(&img, out, exposure, "the progressive renderer")?;
    if let Some(s) = stderr {
        written.image(&r.stderr(), s, 1.0, "the progressive renderer's standard error")?;
    }
    written.keep()?;
    if let Some(d) = snapshots {
        d.keep()?;
    }
    if !quiet {
        let m = img.mean();
        let (w, h) = r.camera().resolution;
        eprintln!(
            "vpl: {} {w}x{h} progressive, {} passes in {secs:.2} s ({:.2} passes/s; last pass {} of {} VPLs stored, {} photons of which {} caustic, map coverage {:.1} %, {:.0} ms), mean RGB {:.5} {:.5} {:.5}, {} -> {}",
            sc.name,
            r.passes(),
            r.passes() as f64 / secs,
            last.stored,
            last.vpls,
            last.photons,
            last.caustic_photons,
            100.0 * last.map_coverage,
            last.total_ms,
            m[0],
            m[1],
            m[2],
            memory_line(&estimate),
            out.path.display()
        );
    }
    Ok(())
}

/// `sc` drawn by `policy`, with a warning naming what `who` draws differently.
fn with_policy(sc: vpl_core::Scene, policy: vpl_core::MaterialPolicy, who: &str) -> vpl_core::Scene {
    match sc.material_policy_note(policy, who) {
        Some(note) => {
            eprintln!("vpl: warning: {note}");
            sc.with_material_policy(policy)
        }
        None => sc,
    }
}
