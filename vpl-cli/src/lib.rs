//! The `vpl` command line as a library: [`run`] takes a sampler
//! [`Registry`] and the arguments, so a user's own
//! binary of a few lines gets every subcommand (`render`, `sequence`,
//! `table1`, `bench-vpl`, …) with its own samplers registered:
//!
//! ```no_run
//! let mut registry = vpl_sampling::Registry::builtin();
//! // registry.register(my_sampler_entry()).unwrap();
//! vpl_cli::main(&registry);
//! ```
//!
//! One module per subcommand (`render`, `sequence`, `table1`, …), each with
//! its arguments and its `run`; what they share (scene and VPL flags, the
//! pipeline they describe, thread pools, output checks) is here. Errors are
//! one line on stderr and exit code 2.

mod args;
mod bench_gpu;
mod bench_pt;
mod bench_rays;
mod bench_vpl;
mod energy;
mod export_scene;
mod figures;
mod georgiev;
mod manylights;
mod merge;
mod output;
mod progressive_figures;
mod render;
mod sequence;
mod table1;
mod table2;
mod tev;
pub mod tev_ipc;
mod track;
mod validate_cornell;
mod view;

pub use args::{FramesArg, MemoryArg, PixelArg, Size};
use output::{ImageOut, OutDir, Written, check_finite, distinct};
use vpl_render::Clamp;

use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;
use vpl_core::image::write_atomic;
use vpl_core::{Mode, SceneSetup};
use vpl_pathtrace::{PathTracer, RenderSettings};
use vpl_sampling::Registry;

#[derive(Parser)]
#[command(name = "vpl", version, about = "Virtual-point-light global illumination toolkit")]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// The folder of the scene files of the real-scene rows (`scenes/` of the repository); default:
    /// VPL_SCENES, else the nearest scenes/ folder at or above the working folder or the executable.
    #[arg(long = "scenes-dir", global = true, value_name = "DIR")]
    scenes_dir: Option<PathBuf>,
}

/// Where the VPL stages run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum BackendArg {
    /// The CPU (rayon).
    Cpu,
    /// wgpu kernels: G-buffer, shadow maps or shadow rays, shading, filter (sampling stays on the CPU).
    Gpu,
}

impl BackendArg {
    fn backend(self) -> vpl_bench::pipeline::BackendKind {
        match self {
            BackendArg::Cpu => vpl_bench::pipeline::BackendKind::Cpu,
            BackendArg::Gpu => vpl_bench::pipeline::BackendKind::Gpu,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum ProfileArg {
    /// Minutes on a laptop.
    Quick,
    /// The paper's settings.
    Full,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Method {
    /// Path tracing (the reference).
    Path,
    /// Virtual point lights.
    Vpl,
    /// The progressive point-light renderer.
    Progressive,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum ModeArg {
    Full,
    Direct,
    Indirect,
}

/// Which materials a render draws (see [`vpl_core::MaterialPolicy`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum MaterialsArg {
    /// The scene's materials, layers included (path tracer, progressive renderer).
    AsIs,
    /// Each material's albedo only, as the VPL pipeline draws it: the fair reference for a VPL render.
    Diffuse,
}

impl MaterialsArg {
    fn policy(self) -> vpl_core::MaterialPolicy {
        match self {
            MaterialsArg::AsIs => vpl_core::MaterialPolicy::AsIs,
            MaterialsArg::Diffuse => vpl_core::MaterialPolicy::Diffuse,
        }
    }
}

/// What to render: scene, frame, path tracer settings, threads.
#[derive(clap::Args)]
struct SceneArgs {
    /// A built-in name (cornell, maze, office, courtyard, atrium, corner, glass, building, colonnade), a .toml scene file, an .obj file, a glTF 2.0 file (.gltf, .glb) or a Mitsuba 3 XML scene (.xml).
    #[arg(long)]
    scene: String,
    /// Frame of the scene's sequence.
    #[arg(long, default_value_t = 0)]
    frame: u32,
    /// Longest path in segments (Mitsuba 3's convention: 5 = direct + 3 indirect bounces).
    #[arg(long, default_value_t = 5)]
    max_depth: u32,
    /// Geometry-term clamp: a value in 1/m², `auto` (G_max = I / A_view, A_view the area the camera's
    /// points cover, with I from --vpls), `scene-area` (G_max = I / the scene's surface area; `area`
    /// is read as that too) or `off`.
    /// Default: off for --method path, auto for --method vpl and progressive. The path tracer clamps
    /// the segment leaving the primary hit (§5.4 of the SMC paper), VPL shading the VPL-to-pixel
    /// segment, the progressive renderer the eye-vertex-to-VPL segment (its bound of G, §8 of
    /// Dammertz et al.).
    #[arg(long, allow_hyphen_values = true)]
    clamp: Option<Clamp>,
    /// VPL budget I (--method vpl; also sets the `auto` clamp).
    #[arg(long, default_value_t = 2048)]
    vpls: usize,
    /// Image size WxH (default: the scene camera's).
    #[arg(long)]
    size: Option<Size>,
    /// Seed of all random streams.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores; at most 1024).
    #[arg(long)]
    threads: Option<usize>,
    /// Refuse a render whose estimated memory exceeds this (e.g. 8G, 512M, or bytes; default: half
    /// of this machine's physical memory).
    #[arg(long)]
    memory_limit: Option<MemoryArg>,
    /// Let the scene's files name files under this folder too (repeatable). Without it a scene file
    /// reads only files in its own folder and below.
    #[arg(long, value_name = "PATH")]
    allow_outside: Vec<PathBuf>,
}

/// A scene as the command line names it, with where its files may read and
/// the memory limit its loading keeps to.
pub(crate) struct SceneSource {
    spec: String,
    options: vpl_scene_io::LoadOptions,
}

impl SceneSource {
    fn new(spec: String, allow_outside: Vec<PathBuf>, memory: Option<MemoryArg>) -> SceneSource {
        let options = vpl_scene_io::LoadOptions { allow_outside, memory_limit: Some(memory_limit(memory).0) };
        SceneSource { spec, options }
    }

    /// The scene, loaded within its sandbox and memory limit.
    fn load(&self) -> Res<SceneSetup> {
        vpl_scene_io::load_with(&self.spec, &self.options).map_err(|e| e.to_string())
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum VisibilityArg {
    /// Exact BVH shadow rays.
    Raytrace,
    /// Paraboloid shadow maps.
    Shadowmap,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum ShadingArg {
    /// 4×4 interleaved VPL subsets and a cross-bilateral filter.
    Interleaved,
    /// Every VPL at every pixel.
    Exhaustive,
    /// Stochastic lightcuts: --cut VPLs a pixel, sampled through a light tree (unbiased).
    Lightcuts,
    /// Every VPL at every pixel, each VPL's range cut by Russian roulette at --culling-bound
    /// (unbiased: with --clamp off it converges to the unclamped image).
    Culled,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum BinsArg {
    /// The closest bin only (the paper's rule; darker where bins crowd).
    Closest,
    /// Every bin whose radius reaches the photon.
    All,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum CullingArg {
    /// Unseen VPLs kept with probability --cull-accept, their power divided by it (unbiased).
    Unbiased,
    /// Unseen VPLs dropped.
    Deterministic,
    /// No culling.
    Off,
}

/// Settings of `--method progressive` (Dammertz et al. 2010).
#[derive(clap::Args)]
struct ProgressiveArgs {
    /// Passes to render (default 64 when --seconds is not given).
    #[arg(long)]
    passes: Option<u64>,
    /// Time budget in seconds: stop after the pass that reaches it.
    #[arg(long, allow_hyphen_values = true)]
    seconds: Option<f64>,
    /// VPL light paths per pass.
    #[arg(long, default_value_t = 16)]
    vpl_paths: usize,
    /// Caustic photon paths per pass.
    #[arg(long, default_value_t = 100_000)]
    caustic_paths: usize,
    /// How the VPLs are gathered at the eye vertices: exhaustive (every VPL), or lightcuts:N
    /// (N VPLs sampled through a light tree over the pass's VPLs, unbiased: for many VPL
    /// paths, e.g. --vpl-paths 65536).
    #[arg(long, default_value = "exhaustive")]
    gather: vpl_progressive::Gathering,
    /// Stochastic VPL culling against 256 Halton-chosen eye vertices.
    #[arg(long, value_enum, default_value_t = CullingArg::Unbiased)]
    culling: CullingArg,
    /// Probability of keeping a VPL no representative sees (unbiased culling).
    #[arg(long, default_value_t = 0.125, allow_hyphen_values = true)]
    cull_accept: f32,
    /// Aim caustic photons over the whole emission distribution instead of projection maps.
    #[arg(long)]
    no_projection_maps: bool,
    /// Emit caustic photons from primary VPLs only (no indirect caustics EDS+D+L).
    #[arg(long)]
    primary_caustics_only: bool,
    /// Which caustic bins a photon falls into.
    #[arg(long, value_enum, default_value_t = BinsArg::Closest)]
    bins: BinsArg,
    /// RGB only: no wavelengths at dispersive surfaces.
    #[arg(long)]
    no_spectral: bool,
    /// Path classes to add: all, or a comma-separated list of direct, vpl, caustics, specular.
    #[arg(long, default_value = "all")]
    techniques: String,
    /// Thin-lens radius (scene units; 0 = pinhole).
    #[arg(long, allow_hyphen_values = true)]
    lens_radius: Option<f32>,
    /// Distance of the plane in focus (default: the distance to the camera target).
    #[arg(long, allow_hyphen_values = true)]
    focus_distance: Option<f32>,
    /// Write an EXR snapshot every K passes into --snapshots.
    #[arg(long)]
    snapshot_every: Option<u64>,
    /// Folder for the snapshots (pass_000016.exr, …).
    #[arg(long)]
    snapshots: Option<PathBuf>,
}

/// Settings of `--method vpl`. The sampler flags are the keys of the
/// registry's samplers (`--m-max 8` is `--set m-max=8`), made when the
/// command line is built, so a program's own sampler gets flags too; a flag
/// or key the chosen sampler does not read is an error.
#[derive(clap::Args)]
struct VplArgs {
    /// VPL sampler: a registry name (ir, rr, mir, mir-resample, tcas, smc, smc-knn, or one registered by the program).
    #[arg(long, default_value = "ir")]
    sampler: String,
    /// A sampler parameter KEY=VALUE (repeat for more): any key the sampler reads.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Values of the sampler flags (`--m-max 8`), made from the registry's
    /// keys when the command line is built ([`sampler_flags`]), in the
    /// order given.
    #[arg(skip)]
    flags: Vec<(String, String)>,
    /// VPL-to-pixel visibility.
    #[arg(long, value_enum, default_value_t = VisibilityArg::Shadowmap)]
    visibility: VisibilityArg,
    /// Shadow-map side in texels.
    #[arg(long, default_value_t = vpl_visibility::DEFAULT_RESOLUTION)]
    shadowmap_res: u32,
    /// Indirect shading.
    #[arg(long, value_enum, default_value_t = ShadingArg::Interleaved)]
    shading: ShadingArg,
    /// Leave interleaved shading unfiltered.
    #[arg(long)]
    no_filter: bool,
    /// VPLs a pixel of `--shading lightcuts`.
    #[arg(long, value_name = "N", default_value_t = vpl_render::ShadingSpec::DEFAULT_CUT)]
    cut: u32,
    /// The roulette's threshold of `--shading culled`, relative to the mean VPL's irradiance at the
    /// diagonal of what the camera sees (larger: fewer VPL terms, more noise).
    #[arg(long, value_name = "X", default_value_t = vpl_render::ShadingSpec::DEFAULT_BOUND, allow_hyphen_values = true)]
    culling_bound: f32,
    /// Bias compensation of the clamp (Kollig and Keller 2004): N gather rays per pixel add back
    /// the light the clamp removed, so the image converges to the unclamped one (0: off).
    #[arg(long, value_name = "N", default_value_t = 0)]
    compensate: u32,
    /// Light samples per pixel for direct light.
    #[arg(long, default_value_t = 16)]
    direct_samples: u32,
    /// Where the G-buffer, visibility and shading run: a registered backend (cpu; gpu where built)
    /// or auto, the first device that opens, else the CPU [default: cpu; for `vpl view`: auto].
    #[arg(long, value_name = "NAME")]
    backend: Option<String>,
}

#[derive(Subcommand)]
enum Command {
    /// Reproduce Georgiev & Slusallek's claims on `corner`: RR's mean acceptance and its
    /// efficiency gain over IR at equal stored VPLs (and RR's acceptance on cornell, office).
    Georgiev(georgiev::Args),
    /// Render one frame of a scene.
    Render(render::Args),
    /// Render frames of a scene's sequence with VPLs, the sampler keeping its state from frame to
    /// frame: one EXR (and PNG preview) per frame, tracked.csv (tracked pixels) and frames.csv (timings).
    Sequence(sequence::Args),
    /// Many path-traced samples at a few pixels: ground truth with standard errors, as CSV.
    Track(track::Args),
    /// Print a built-in scene (or any scene) as a TOML scene file.
    ExportScene(export_scene::Args),
    /// Path-tracing throughput on `cornell` 256×256, max-depth 5, all cores.
    BenchPt(bench_pt::Args),
    /// BVH build time and memory, and M rays/s for primary and diffuse closest hits and shadow
    /// occlusion, on cornell, Dabrovic's Sponza and five Sponzas side by side.
    BenchRays(bench_rays::Args),
    /// Milliseconds per VPL stage at 640×360 with 2048 IR VPLs on `cornell` and `office`, and the
    /// SMC sampler's steps (Table 2 of Hedman et al.) on `office` (I VPLs) and `maze` (I/4).
    BenchVpl(bench_vpl::Args),
    /// Milliseconds per GPU kernel and per indirect frame (SMC sampling on the CPU), and the adapter:
    /// G-buffer, shadow maps of moved VPLs, interleaved gathering, filter, uploads and read-backs.
    BenchGpu(bench_gpu::Args),
    /// Table 1 of the SMC paper (|E| and |E′| of eight tracked pixels over seven sequences, with
    /// confidence intervals over seeds and pixels): run the units of a shard into --out; without
    /// --shard, also merge them into table1.md, .csv, .json and the Fig. 7 plots.
    Table1(table1::Args),
    /// Table 2 of the SMC paper: milliseconds per stage of an SMC frame on courtyard, office, atrium
    /// (2048 VPLs) and maze (512); table2.md, .csv, .json.
    Table2(table2::Args),
    /// Figs. 8, 9 and 10 of the SMC paper: one frame by path tracing, clamped path tracing and three
    /// ways of shading the same VPLs; shadow-map resolutions against ray tracing; error against the
    /// VPL budget. fig8.md, fig10.md with images, CSV, JSON and a plot.
    Figures(figures::Args),
    /// A sampler's unclamped indirect image mean against the path tracer's, at frame 0 and over
    /// checkpoints of each scene's sequence (the sampler stepped along it), with the share of its
    /// light the default clamp removes; energy.md and energy.json.
    Energy(energy::Args),
    /// The many-light study: VPL sources (SMC 2K, IR 64K, IR 1M) gathered interleaved,
    /// exhaustively and by stochastic lightcuts; RMSE against the path tracer over wall time per
    /// scene, and |E|, |E′| on a Table 1 sequence; manylights.md, .json and plots.
    Manylights(manylights::Args),
    /// Merge the unit files of a sharded Table 1 run (all shards done) into its tables and plots.
    Merge(merge::Args),
    /// Figs. 6-8 of the progressive renderer (Dammertz et al. 2010): error against passes on a
    /// scene, and an equal-time comparison with path tracing on diffuse scenes.
    ProgressiveFigures(progressive_figures::Args),
    /// Compare the path tracer with the Mitsuba 3 references of `cornell`; write a Markdown report.
    ValidateCornell(validate_cornell::Args),
    /// Open a window that renders VPL frames continuously (crate vpl-viewer): fly through the
    /// scene, switch samplers live, split two samplers, splat the VPLs, plot the flicker.
    View(view::Args),
}

/// Runs the `vpl` command line on `args` (the program name first, as
/// [`std::env::args_os`] gives it) with the samplers of `registry`; returns
/// the exit code: 0, or 2 after one line on stderr for a bad argument, file
/// or failure.
pub fn run<I, T>(registry: &Registry, args: I) -> i32
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    use clap::{CommandFactory, FromArgMatches};
    let mut command = Cli::command();
    for name in SAMPLER_COMMANDS {
        command = command.mut_subcommand(name, |c| sampler_flags(c, registry));
    }
    let parsed = command.try_get_matches_from(args).and_then(|m| {
        let mut cli = Cli::from_arg_matches(&m)?;
        if let Some((_, sub)) = m.subcommand() {
            let flags = sampler_flag_values(sub, registry);
            match &mut cli.command {
                Command::Render(a) => a.vpl_args().flags = flags,
                Command::Sequence(a) => a.vpl_args().flags = flags,
                Command::View(a) => a.vpl_args().flags = flags,
                _ => {}
            }
        }
        Ok(cli)
    });
    let cli = match parsed {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand)
            {
                let _ = e.print();
                return if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand { 2 } else { 0 };
            }
            let text = e.to_string();
            let line = text.lines().next().unwrap_or("bad arguments").trim_start_matches("error: ");
            eprintln!("vpl: error: {line}");
            return 2;
        }
    };
    if let Some(dir) = cli.scenes_dir.as_ref().filter(|d| !d.is_dir()) {
        eprintln!("vpl: error: --scenes-dir {}: not a folder", dir.display());
        return 2;
    }
    vpl_bench::scenes::set_dir(cli.scenes_dir.clone());
    match dispatch(cli, registry) {
        Ok(()) => 0,
        Err(e) => {
            // One line, whatever a library's message holds.
            let line: String = e.to_string().chars().map(|c| if c.is_control() { ' ' } else { c }).collect();
            eprintln!("vpl: error: {}", line.trim());
            2
        }
    }
}

/// [`run`] on the process's arguments; exits with its code. SIGINT and
/// SIGTERM wait for the write in progress, remove the staged and temporary
/// files and the outputs of the unfinished command, then exit with 130.
pub fn main(registry: &Registry) -> ! {
    // Without a handler (another one is installed) the default action still ends the process;
    // only the clean-up is lost, so the error is not fatal.
    let _ = ctrlc::set_handler(|| {
        // On the writer's terms: wait for the file being written (or the
        // staged outputs being renamed) to be complete, and start no other
        // write; then remove what the command had not finished and exit.
        let _writes = vpl_core::image::stop_writes();
        output::interrupted();
        eprintln!("vpl: interrupted; unfinished outputs removed");
        std::process::exit(130);
    });
    std::process::exit(run(registry, std::env::args_os()))
}

type Res<T> = Result<T, String>;

/// The most worker threads `--threads` may ask for. Results do not depend on
/// the thread count, so more threads than cores only cost memory.
const MAX_THREADS: usize = 1024;

/// A scene as a study names it, and its setup.
type Named = (String, vpl_core::SceneSetup);

/// The scenes of a study (`vpl energy`, `vpl manylights`) by name: a Table 1
/// sequence by id (skipped, and said why, where its model is not here), a
/// built-in, or a scene file (which may name files under `allow_outside`).
/// The loaded (name, setup) pairs, and the skipped ones' reasons.
fn study_scenes(scenes: &[String], allow_outside: Vec<PathBuf>) -> Res<(Vec<Named>, Vec<String>)> {
    let options = vpl_scene_io::LoadOptions { allow_outside, ..Default::default() };
    let (mut setups, mut skipped) = (Vec::new(), Vec::new());
    for s in scenes {
        match vpl_bench::table1::rows::row(s) {
            Some(row) => match row.missing() {
                Some(why) => skipped.push(format!("{s}: {why}")),
                None => setups.push((s.clone(), row.setup().map_err(|e| e.to_string())?)),
            },
            None => setups.push((s.clone(), vpl_scene_io::load_with(s, &options).map_err(|e| e.to_string())?)),
        }
    }
    Ok((setups, skipped))
}

fn pool(threads: Option<usize>) -> Res<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 {
            return Err("--threads must be at least 1".into());
        }
        if n > MAX_THREADS {
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
            return Err(format!("--threads {n} is more than {MAX_THREADS} (this machine has {cores} cores)"));
        }
        b = b.num_threads(n);
    }
    b.build().map_err(|e| format!("cannot start threads: {e}"))
}

/// The memory budget: `--memory-limit`, or half the physical memory (8 GiB
/// where it cannot be read).
fn memory_limit(arg: Option<MemoryArg>) -> (u64, String) {
    match arg {
        Some(MemoryArg(b)) => (b, "--memory-limit".into()),
        None => match vpl_render::memory::physical_memory() {
            Some(m) => (m / 2, format!("the default --memory-limit (half of this machine's {})", vpl_render::memory::human(m))),
            None => (8 << 30, "the default --memory-limit (8 GiB; this machine's memory is unknown)".into()),
        },
    }
}

/// Refuses `estimate` beyond the budget, with one line naming the flags that drive its largest part.
fn check_memory(estimate: &vpl_render::MemoryEstimate, arg: Option<MemoryArg>) -> Res<()> {
    let (limit, what) = memory_limit(arg);
    estimate.check(limit).map_err(|e| {
        let flags: Vec<String> = e.largest.driver.iter().map(|d| format!("--{d}")).collect();
        format!(
            "this render needs about {}, more than the {} of {what}: {} is the largest part ({}); lower it or raise --memory-limit",
            vpl_render::memory::human(e.estimate),
            vpl_render::memory::human(e.limit),
            e.largest.what,
            flags.join(", ")
        )
    })
}

/// `memory: estimated X, peak Y` for summary lines.
fn memory_line(estimate: &vpl_render::MemoryEstimate) -> String {
    let peak = vpl_render::memory::peak_resident().map_or("unknown".to_string(), vpl_render::memory::human);
    format!("memory: estimated {}, peak {peak}", vpl_render::memory::human(estimate.total()))
}

/// Fails early, before any work, if `path` cannot be written.
fn check_writable(path: &Path) -> Res<()> {
    let dir = vpl_scene_io::input::folder_of(path);
    if !dir.is_dir() {
        return Err(format!("cannot write {}: directory {} does not exist", path.display(), dir.display()));
    }
    let md = std::fs::metadata(&dir).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    if md.permissions().readonly() {
        return Err(format!("cannot write {}: directory {} is read-only", path.display(), dir.display()));
    }
    // A folder, device, FIFO or link in the output's place is refused here,
    // before any work, by the rule the final write applies.
    vpl_core::image::check_replaceable(path).map_err(|e| e.to_string())
}

/// Loads a scene, checks the frame against its sequence, and applies `--size`.
fn load_frame(scene: &SceneSource, frame: u32, size: Option<Size>) -> Res<(vpl_core::Scene, vpl_core::Camera)> {
    let setup = scene.load()?;
    for w in &setup.warnings {
        eprintln!("vpl: warning: {w}");
    }
    if let Some(seq) = &setup.sequence {
        if frame >= seq.frame_count() {
            return Err(format!("--frame {frame} is past the end of the sequence ({} frames)", seq.frame_count()));
        }
    } else if frame > 0 {
        return Err(format!("--frame {frame}: the scene has no sequence"));
    }
    let (sc, mut camera) = setup.frame(frame).map_err(|e| e.to_string())?;
    if let Some(Size(w, h)) = size {
        camera = camera.with_resolution((w, h)).map_err(|e| e.to_string())?;
    }
    if let Some(w) = vpl_core::view::check_view(&sc, &camera) {
        eprintln!("vpl: warning: {w}");
    }
    Ok((sc, camera))
}

fn mode_of(mode: ModeArg) -> Mode {
    match mode {
        ModeArg::Full => Mode::Full,
        ModeArg::Direct => Mode::Direct,
        ModeArg::Indirect => Mode::Indirect,
    }
}

/// Checks `--max-depth` and `--vpls`.
fn check_depth(max_depth: u32, vpls: usize) -> Res<()> {
    if max_depth == 0 {
        return Err("--max-depth must be at least 1".into());
    }
    if vpls == 0 {
        return Err("--vpls must be at least 1".into());
    }
    Ok(())
}

/// The path tracer that `--max-depth`, `--mode` and `--clamp` describe (off by default).
fn tracer(
    max_depth: u32,
    mode: ModeArg,
    clamp: Option<Clamp>,
    vpls: usize,
    scene: &vpl_core::Scene,
    camera: &vpl_core::Camera,
) -> PathTracer {
    let mut pt = PathTracer::new(max_depth, mode_of(mode));
    pt.clamp = clamp.unwrap_or(Clamp::Off).resolve(vpls, scene, camera);
    pt
}

/// Writes `text` atomically to `out`, or to standard output when there is none.
fn emit(out: Option<&Path>, text: &str) -> Res<()> {
    match out {
        Some(p) => write_atomic(p, text.as_bytes()).map_err(|e| e.to_string()),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

fn dispatch(cli: Cli, registry: &Registry) -> Res<()> {
    match cli.command {
        Command::Georgiev(a) => georgiev::run(a, registry),
        Command::Render(a) => render::run(a, registry),
        Command::Sequence(a) => sequence::run(a, registry),
        Command::Track(a) => track::run(a, registry),
        Command::ExportScene(a) => export_scene::run(a, registry),
        Command::BenchPt(a) => bench_pt::run(a, registry),
        Command::BenchRays(a) => bench_rays::run(a, registry),
        Command::BenchVpl(a) => bench_vpl::run(a, registry),
        Command::BenchGpu(a) => bench_gpu::run(a, registry),
        Command::Table1(a) => table1::run(a, registry),
        Command::Table2(a) => table2::run(a, registry),
        Command::Energy(a) => energy::run(a, registry),
        Command::Manylights(a) => manylights::run(a, registry),
        Command::Figures(a) => figures::run(a, registry),
        Command::Merge(a) => merge::run(a, registry),
        Command::ProgressiveFigures(a) => progressive_figures::run(a, registry),
        Command::ValidateCornell(a) => validate_cornell::run(a, registry),
        Command::View(a) => view::run(a, registry),
    }
}

/// The pipeline that `--method vpl` and its flags describe.
fn pipeline_spec(
    v: &VplArgs,
    vpls: usize,
    max_depth: u32,
    mode: ModeArg,
    clamp: vpl_render::Clamp,
    seed: u64,
) -> Res<vpl_bench::pipeline::PipelineSpec> {
    use vpl_bench::pipeline::{PipelineSpec, ShadingSpec, VisibilitySpec};
    if v.direct_samples == 0 {
        return Err("--direct-samples must be at least 1".into());
    }
    if v.visibility == VisibilityArg::Shadowmap {
        vpl_visibility::ShadowMaps::new(v.shadowmap_res).map_err(|e| format!("--shadowmap-res: {e}"))?;
    }
    Ok(PipelineSpec {
        sampler: v.sampler.clone(),
        params: sampler_params(v)?,
        budget: vpl_core::Budget::new(vpls, max_depth),
        visibility: match v.visibility {
            VisibilityArg::Raytrace => VisibilitySpec::RayTraced,
            VisibilityArg::Shadowmap => VisibilitySpec::ShadowMaps(v.shadowmap_res),
        },
        shading: match v.shading {
            ShadingArg::Exhaustive => ShadingSpec::Exhaustive,
            ShadingArg::Lightcuts if v.cut == 0 => return Err("--cut must be at least 1".into()),
            ShadingArg::Lightcuts => ShadingSpec::Lightcuts { cut: v.cut },
            ShadingArg::Culled if !(v.culling_bound.is_finite() && v.culling_bound > 0.0) => {
                return Err(format!("--culling-bound must be a positive number, got {}", v.culling_bound));
            }
            ShadingArg::Culled => ShadingSpec::Culled { bound: v.culling_bound },
            ShadingArg::Interleaved => ShadingSpec::Interleaved { filter: !v.no_filter },
        },
        clamp,
        compensation: match (v.compensate, clamp) {
            (0, _) => 0,
            (_, vpl_render::Clamp::Off) => {
                return Err("--compensate adds back what the clamp removes: it needs a clamp (--clamp is off)".into());
            }
            (n, _) => n,
        },
        mode: mode_of(mode),
        direct_samples: v.direct_samples,
        seed,
        backend: v.backend.clone().unwrap_or_else(|| "cpu".into()),
    })
}

/// `estimate` with the sampler's own working memory, as its registry entry
/// states it ([`vpl_sampling::SamplerEntry::with_memory`]).
fn with_sampler_memory(
    estimate: vpl_render::MemoryEstimate,
    spec: &vpl_bench::pipeline::PipelineSpec,
    registry: &Registry,
) -> vpl_render::MemoryEstimate {
    let Ok(entry) = registry.entry(&spec.sampler) else { return estimate };
    entry.memory(&spec.budget, &spec.params).into_iter().fold(estimate, |e, part| e.with_part(part.what, part.bytes, part.keys))
}

/// The sampler parameters the command line gives: each sampler flag that
/// was given, under its own name as key, then every `--set KEY=VALUE`.
fn sampler_params(v: &VplArgs) -> Res<vpl_core::Params> {
    let mut p = vpl_core::Params::new();
    let mut put = |key: &str, value: &str| -> Res<()> {
        p.insert(key, value).map_err(|e| format!("--{e}"))?;
        Ok(())
    };
    for (k, value) in &v.flags {
        put(k, value)?;
    }
    for item in &v.set {
        let (k, value) = item.split_once('=').ok_or_else(|| format!("--set {item}: expected KEY=VALUE"))?;
        put(k, value)?;
    }
    Ok(p)
}

/// The subcommands whose `--sampler` takes sampler flags.
const SAMPLER_COMMANDS: [&str; 3] = ["render", "sequence", "view"];

/// One flag for each key the samplers of `registry` read (`--m-max N`),
/// added to the subcommand `c`: the help gathers what each sampler says of
/// it and its default there; a key whose default is `false` everywhere is a
/// switch. A key that one of the subcommand's own flags already names is
/// left to `--set`.
fn sampler_flags(mut c: clap::Command, registry: &Registry) -> clap::Command {
    use clap::{Arg, ArgAction};
    let mut keys: Vec<(&'static str, Vec<(String, vpl_core::ParamKey)>)> = Vec::new();
    for entry in registry.entries() {
        for k in &entry.keys {
            match keys.iter_mut().find(|(key, _)| *key == k.key) {
                Some((_, by)) => by.push((entry.name.clone(), *k)),
                None => keys.push((k.key, vec![(entry.name.clone(), *k)])),
            }
        }
    }
    for (key, by) in keys {
        let taken = key == "help" || c.get_arguments().any(|a| a.get_id() == key || a.get_long() == Some(key));
        if taken {
            continue;
        }
        // Samplers that say the same of the key are named together.
        let mut said: Vec<(Vec<&str>, &str, &str)> = Vec::new();
        for (name, k) in &by {
            match said.iter_mut().find(|(_, about, default)| *about == k.about && *default == k.default) {
                Some((names, _, _)) => names.push(name),
                None => said.push((vec![name], k.about, k.default)),
            }
        }
        let help: Vec<String> =
            said.iter().map(|(names, about, default)| format!("{}: {about} (default {default})", names.join(", "))).collect();
        let switch = by.iter().all(|(_, k)| k.default == "false");
        let first = by[0].1.default;
        let value_name = if first.parse::<u64>().is_ok() {
            "N"
        } else if first.parse::<f64>().is_ok() {
            "X"
        } else {
            "VALUE"
        };
        let arg = Arg::new(key).long(key).help(help.join("; ")).help_heading("Sampler flags (the registry's keys)");
        c = c.arg(if switch {
            arg.action(ArgAction::SetTrue)
        } else {
            arg.value_name(value_name).allow_hyphen_values(true).action(ArgAction::Set)
        });
    }
    c
}

/// The sampler flags given on a subcommand, as (key, value), in the order
/// of the registry's keys.
fn sampler_flag_values(m: &clap::ArgMatches, registry: &Registry) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for entry in registry.entries() {
        for k in &entry.keys {
            if out.iter().any(|(key, _)| key == k.key) || !m.try_contains_id(k.key).unwrap_or(false) {
                continue;
            }
            if m.value_source(k.key) != Some(clap::parser::ValueSource::CommandLine) {
                continue;
            }
            if let Ok(Some(v)) = m.try_get_one::<String>(k.key) {
                out.push((k.key.to_string(), v.clone()));
            } else if let Ok(Some(true)) = m.try_get_one::<bool>(k.key) {
                out.push((k.key.to_string(), "true".to_string()));
            }
        }
    }
    out
}

/// A sampler's error in the CLI's words: every key is a flag (`--rr-epsilon`
/// or `--set rr-epsilon=…`), so the keys are named as flags.
fn sampling_line(sampler: &str, e: &vpl_sampling::SamplingError) -> String {
    use vpl_core::ParamError as P;
    use vpl_sampling::SamplingError as S;
    let flags = |keys: &[String]| keys.iter().map(|k| format!("--{k}")).collect::<Vec<_>>().join(", ");
    match e {
        S::Param { source: P::Invalid { key, value, expected }, .. } => {
            format!("--sampler {sampler}: --{key} {value}: expected {expected}")
        }
        S::Param { source: P::OutOfRange { key, value, allowed }, .. } => {
            format!("--sampler {sampler}: --{key} {value}: must be {allowed}")
        }
        S::Unread { keys, reads, .. } => {
            let reads = if reads.is_empty() { "none".to_string() } else { flags(reads) };
            format!("--sampler {sampler} does not read {} (its flags: {reads})", flags(keys))
        }
        e => format!("--sampler {sampler}: {e}"),
    }
}

/// A renderer for `spec` on frames of `scene`, or one line that names what is wrong.
fn build_renderer(spec: &vpl_bench::pipeline::PipelineSpec, registry: &Registry, scene: &vpl_core::Scene) -> Res<vpl_render::Renderer> {
    spec.build(registry, &vpl_bench::pipeline::backends(), scene).map_err(|e| match e {
        vpl_render::RenderError::Sampling(e) => sampling_line(&spec.sampler, &e),
        e => vpl_bench::pipeline::backend_line(e),
    })
}
