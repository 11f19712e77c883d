//! `vpl`: render scenes, export built-ins, validate and benchmark the path tracer.
//!
//! Errors are one line on stderr and exit code 2.

use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;
use vpl_bench::cli::{ClampArg, FramesArg, PixelArg, Size};
use vpl_core::image::{preview_path, write_atomic};
use vpl_core::{Mode, SceneSetup};
use vpl_pathtrace::{render, track, PathTracer, RenderSettings};

#[derive(Parser)]
#[command(name = "vpl", version, about = "Virtual-point-light global illumination toolkit")]
struct Cli {
    #[command(subcommand)]
    command: Command,
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
    fn backend(self) -> vpl_bench::pipeline::Backend {
        match self {
            BackendArg::Cpu => vpl_bench::pipeline::Backend::Cpu,
            BackendArg::Gpu => vpl_bench::pipeline::Backend::Gpu,
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

/// What to render: scene, frame, path tracer settings, threads.
#[derive(clap::Args)]
struct SceneArgs {
    /// A built-in name (cornell, maze, office, courtyard, atrium, corner, glass), a .toml scene file or an .obj file.
    #[arg(long)]
    scene: String,
    /// Frame of the scene's sequence.
    #[arg(long, default_value_t = 0)]
    frame: u32,
    /// Longest path in segments (Mitsuba 3's convention: 5 = direct + 3 indirect bounces).
    #[arg(long, default_value_t = 5)]
    max_depth: u32,
    /// Geometry-term clamp: a value in 1/m², `auto` (G_max = I / scene area, with I from --vpls) or `off`.
    /// Default: off for --method path, auto for --method vpl and progressive. The path tracer clamps
    /// the segment leaving the primary hit (§5.4 of the SMC paper), VPL shading the VPL-to-pixel
    /// segment, the progressive renderer the eye-vertex-to-VPL segment (its bound of G, §8 of
    /// Dammertz et al.).
    #[arg(long, allow_hyphen_values = true)]
    clamp: Option<ClampArg>,
    /// VPL budget I (--method vpl; also sets the `auto` clamp).
    #[arg(long, default_value_t = 2048)]
    vpls: usize,
    /// Image size WxH (default: the scene camera's).
    #[arg(long)]
    size: Option<Size>,
    /// Seed of all random streams.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
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
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum PathSamplingArg {
    Random,
    Halton,
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

/// Settings of `--method vpl`.
#[derive(clap::Args)]
struct VplArgs {
    /// VPL sampler: ir, rr, mir, mir-resample, tcas or smc.
    #[arg(long, default_value = "ir")]
    sampler: String,
    /// How light paths draw their numbers (ir).
    #[arg(long, value_enum, default_value_t = PathSamplingArg::Random)]
    path_sampling: PathSamplingArg,
    /// New light paths every frame (ir; without it a static scene keeps its VPLs).
    #[arg(long)]
    fresh_paths: bool,
    /// SMC: VPLs allowed to move per frame (M_max).
    #[arg(long, default_value_t = 16)]
    m_max: usize,
    /// SMC: candidate-ray hits per candidate (default 16: 16·I hits to I candidates);
    /// mir-resample: camera paths per VPL (default 256).
    #[arg(long)]
    resample_ratio: Option<usize>,
    /// SMC, mir-resample: path-traced paths per VPL radiosity estimate.
    #[arg(long, default_value_t = 16)]
    radiosity_paths: u32,
    /// SMC, mir-resample: k of the VPL densities (default max(1, floor(sqrt(I/32))), eq. 8).
    #[arg(long)]
    knn_k: Option<usize>,
    /// SMC: iterations before the first frame.
    #[arg(long, default_value_t = 100)]
    warmup: u32,
    /// RR: epsilon of eq. (3), the least acceptance probability.
    #[arg(long, default_value_t = 0.05)]
    rr_epsilon: f32,
    /// RR: estimate the image's indirect luminance from a pilot set on the first
    /// frame (otherwise the first frame is plain IR, as in the paper).
    #[arg(long)]
    rr_pilot: bool,
    /// RR, MIR, TCAS: camera samples the VPLs' importance is estimated against
    /// (default 100 for rr and mir, 256 for tcas).
    #[arg(long)]
    camera_samples: Option<usize>,
    /// TCAS: Metropolis-Hastings iterations per chain and frame (default 16);
    /// MIR: steps between two recorded VPLs of a chain (default 4).
    #[arg(long)]
    mh_iterations: Option<u32>,
    /// MIR: Markov chains run side by side.
    #[arg(long, default_value_t = 64)]
    mir_chains: usize,
    /// MIR: probability of a large (independent) step.
    #[arg(long, default_value_t = 0.3)]
    mir_large_step: f32,
    /// MIR: defensive share of the target for paths no camera sample sees.
    #[arg(long, default_value_t = 0.05)]
    mir_defensive: f32,
    /// TCAS: texels per side of each light's reflective shadow map.
    #[arg(long, default_value_t = 64)]
    rsm_res: u32,
    /// TCAS: further iterations on the first frame.
    #[arg(long, default_value_t = 48)]
    tcas_warmup: u32,
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
    /// Light samples per pixel for direct light.
    #[arg(long, default_value_t = 16)]
    direct_samples: u32,
    /// Where the G-buffer, visibility and shading run.
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    backend: BackendArg,
}

#[derive(Subcommand)]
enum Command {
    /// Reproduce Georgiev & Slusallek's claims on `corner`: RR's mean acceptance and its
    /// efficiency gain over IR at equal stored VPLs (and RR's acceptance on cornell, office).
    Georgiev {
        /// Image size.
        #[arg(long, default_value = "160x120")]
        size: Size,
        /// Stored VPLs of both methods.
        #[arg(long, default_value_t = 1024)]
        vpls: usize,
        /// Frames measured (after 4 warm-up frames).
        #[arg(long, default_value_t = 8)]
        frames: u32,
        /// Samples per pixel of the path-traced reference.
        #[arg(long, default_value_t = 256)]
        spp: u32,
        /// Seed.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// RR's epsilon of eq. (3).
        #[arg(long, default_value_t = 0.05)]
        rr_epsilon: f32,
        /// RR's camera samples per frame.
        #[arg(long, default_value_t = 100)]
        camera_samples: usize,
        /// Further values of epsilon to run RR with on corner (comma-separated; a value equal to
        /// --rr-epsilon is skipped, so `--sweep 0.05` runs none).
        #[arg(long, default_value = "0.02,0.2", value_delimiter = ',')]
        sweep: Vec<f32>,
        /// Output folder (georgiev.md, georgiev.csv).
        #[arg(long)]
        out: PathBuf,
    },
    /// Render one frame of a scene.
    Render {
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
    },
    /// Render frames of a scene's sequence with VPLs, the sampler keeping its state from frame to
    /// frame: one EXR (and PNG preview) per frame, tracked.csv (tracked pixels) and frames.csv (timings).
    Sequence {
        #[command(flatten)]
        s: SceneArgs,
        /// Frames A..B (B not included), A.. (to the end) or one frame N. Default: the whole sequence.
        #[arg(long)]
        frames: Option<FramesArg>,
        /// Which light paths to include.
        #[arg(long, value_enum, default_value_t = ModeArg::Full)]
        mode: ModeArg,
        #[command(flatten)]
        v: VplArgs,
        /// A tracked pixel X,Y (repeat for more; default: 8 pixels spread over the image).
        #[arg(long = "pixel")]
        pixels: Vec<PixelArg>,
        /// Output folder (created if missing).
        #[arg(long)]
        out: PathBuf,
        /// Exposure applied to the PNG previews.
        #[arg(long, default_value_t = 1.0)]
        exposure: f32,
        /// No progress bar or summary.
        #[arg(long)]
        quiet: bool,
    },
    /// Many path-traced samples at a few pixels: ground truth with standard errors, as CSV.
    Track {
        #[command(flatten)]
        s: SceneArgs,
        /// Which light paths to include.
        #[arg(long, value_enum, default_value_t = ModeArg::Indirect)]
        mode: ModeArg,
        /// A pixel X,Y (repeat for more).
        #[arg(long = "pixel", required = true)]
        pixels: Vec<PixelArg>,
        /// Samples per pixel.
        #[arg(long, default_value_t = 65536)]
        spp: u32,
        /// Write the CSV here instead of standard output.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Print a built-in scene (or any scene) as a TOML scene file.
    ExportScene {
        /// Built-in name or scene file.
        name: String,
        /// Write to this file instead of standard output.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Path-tracing throughput on `cornell` 256×256, max-depth 5, all cores.
    BenchPt {
        /// Samples per pixel of each timed render.
        #[arg(long, default_value_t = 64)]
        spp: u32,
        /// Timed renders (the best and the median are reported).
        #[arg(long, default_value_t = 5)]
        repeat: u32,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Milliseconds per VPL stage at 640×360 with 2048 IR VPLs on `cornell` and `office`, and the
    /// SMC sampler's steps (Table 2 of Hedman et al.) on `office` (I VPLs) and `maze` (I/4).
    BenchVpl {
        /// Timed repetitions of each stage (the median is reported).
        #[arg(long, default_value_t = 5)]
        repeat: u32,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Image size.
        #[arg(long, default_value = "640x360")]
        size: Size,
        /// VPL budget.
        #[arg(long, default_value_t = 2048)]
        vpls: usize,
    },
    /// Milliseconds per GPU kernel and per indirect frame (SMC sampling on the CPU), and the adapter:
    /// G-buffer, shadow maps of moved VPLs, interleaved gathering, filter, uploads and read-backs.
    BenchGpu {
        /// Scenes (comma-separated).
        #[arg(long = "scene", value_delimiter = ',', default_value = "office,atrium")]
        scenes: Vec<String>,
        /// Image size.
        #[arg(long, default_value = "1920x1080")]
        size: Size,
        /// VPL budget.
        #[arg(long, default_value_t = 2048)]
        vpls: usize,
        /// Timed frames per scene (after one warm-up frame); medians are reported.
        #[arg(long, default_value_t = 5)]
        frames: u32,
        /// Worker threads of the CPU sampler (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Also write gpu_bench.md and gpu_bench.json into this folder.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Table 1 of the SMC paper (|E| and |E′| of eight tracked pixels over five sequences): run the
    /// units of a shard into --out; without --shard, also merge them into table1.md, .csv, .json and
    /// the Fig. 7 plots.
    Table1 {
        /// Settings: quick (8 frames a sequence, 65 536 truth samples) or full (whole sequences,
        /// 692 100 truth samples: the paper's).
        #[arg(long, value_enum, default_value_t = ProfileArg::Quick)]
        profile: ProfileArg,
        /// Sequences (comma-separated; default all: office, courtyard, maze, atrium, courtyard-sun).
        #[arg(long = "scene", value_delimiter = ',')]
        scenes: Vec<String>,
        /// Methods (comma-separated registry names; default ir, rr, mir-resample, tcas, smc).
        #[arg(long, value_delimiter = ',')]
        methods: Vec<String>,
        /// Frames A..B (or A.. to the end) of every sequence instead of the profile's.
        #[arg(long)]
        frames: Option<FramesArg>,
        /// Image size (default 320x240).
        #[arg(long)]
        size: Option<Size>,
        /// Path-traced samples per tracked pixel and frame of ground truth.
        #[arg(long)]
        truth_spp: Option<u32>,
        /// Seed.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Run only shard I of N (units k with k mod N = I); merge later with `vpl merge`.
        #[arg(long)]
        shard: Option<vpl_bench::table1::Shard>,
        /// Where the VPL stages run (the ground truth is always path traced on the CPU).
        #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
        backend: BackendArg,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Output folder (unit files under units/, the tables beside).
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Table 2 of the SMC paper: milliseconds per stage of an SMC frame on courtyard, office, atrium
    /// (2048 VPLs) and maze (512); table2.md, .csv, .json.
    Table2 {
        /// Image size.
        #[arg(long, default_value = "640x360")]
        size: Size,
        /// Frames timed per scene (after one warm-up frame).
        #[arg(long, default_value_t = 10)]
        frames: u32,
        /// Where the G-buffer, shadow maps and shading run (sampling stays on the CPU).
        #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
        backend: BackendArg,
        /// Scenes (comma-separated; default the paper's four: courtyard, office, atrium, maze).
        #[arg(long = "scene", value_delimiter = ',')]
        scenes: Vec<String>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
    },
    /// Figs. 8, 9 and 10 of the SMC paper: one frame by path tracing, clamped path tracing and three
    /// ways of shading the same VPLs; shadow-map resolutions against ray tracing; error against the
    /// VPL budget. fig8.md, fig10.md with images, CSV, JSON and a plot.
    Figures {
        /// Scenes of Figs. 8 and 9 (comma-separated; frame 0 of each).
        #[arg(long, value_delimiter = ',', default_value = "office")]
        scenes: Vec<String>,
        /// Scenes of Fig. 10.
        #[arg(long, value_delimiter = ',', default_value = "atrium")]
        fig10_scenes: Vec<String>,
        /// Image size of Figs. 8 and 9.
        #[arg(long, default_value = "320x240")]
        size: Size,
        /// Image size of Fig. 10.
        #[arg(long, default_value = "160x120")]
        fig10_size: Size,
        /// Samples per pixel of the path-traced references of Figs. 8 and 9.
        #[arg(long, default_value_t = 256)]
        spp: u32,
        /// Samples per pixel of the path-traced references of Fig. 10.
        #[arg(long, default_value_t = 1024)]
        fig10_spp: u32,
        /// Shadow-map sides of Fig. 9.
        #[arg(long, value_delimiter = ',', default_value = "128,256")]
        shadow_maps: Vec<u32>,
        /// VPL budgets of Fig. 10.
        #[arg(long, value_delimiter = ',', default_value = "2000,8000,40000")]
        budgets: Vec<usize>,
        /// SMC warm-up iterations in Fig. 10.
        #[arg(long, default_value_t = 20)]
        fig10_warmup: u32,
        /// Which figures: 8 (with 9), 10 or both.
        #[arg(long, value_delimiter = ',', default_value = "8,10")]
        only: Vec<u32>,
        /// Seed.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
    },
    /// Merge the unit files of a sharded Table 1 run (all shards done) into its tables and plots.
    Merge {
        /// The run's output folder.
        dir: PathBuf,
    },
    /// Figs. 6-8 of the progressive renderer (Dammertz et al. 2010): error against passes on a
    /// scene, and an equal-time comparison with path tracing on diffuse scenes.
    ProgressiveFigures {
        /// Scene of Fig. 7.
        #[arg(long, default_value = "glass")]
        fig7_scene: String,
        /// Image size of Fig. 7.
        #[arg(long, default_value = "160x120")]
        fig7_size: Size,
        /// Passes of the Fig. 7 curve.
        #[arg(long, default_value_t = 512)]
        passes: u64,
        /// Passes between points of the curve.
        #[arg(long, default_value_t = 16)]
        step: u64,
        /// Passes of the converged image.
        #[arg(long, default_value_t = 2048)]
        converged: u64,
        /// Caustic photon paths per pass in Fig. 7.
        #[arg(long, default_value_t = 100_000)]
        caustic_paths: usize,
        /// Scenes of Fig. 8 (comma-separated).
        #[arg(long, value_delimiter = ',', default_value = "cornell,office")]
        fig8_scenes: Vec<String>,
        /// Image size of Fig. 8 (cornell keeps the Mitsuba reference's 256x256).
        #[arg(long, default_value = "160x120")]
        fig8_size: Size,
        /// Seconds per method in Fig. 8.
        #[arg(long, default_value_t = 10.0, allow_hyphen_values = true)]
        seconds: f64,
        /// Samples per pixel of the path-traced references.
        #[arg(long, default_value_t = 1024)]
        reference_spp: u32,
        /// Folder of the Mitsuba cornell references.
        #[arg(long, default_value = "tests/data/cornell-box")]
        mitsuba: PathBuf,
        /// Which figures: 7, 8 or both.
        #[arg(long, value_delimiter = ',', default_value = "7,8")]
        only: Vec<u32>,
        /// VPL budget I of the progressive renderer's geometry clamp G ≤ I / A.
        #[arg(long, default_value_t = 2048)]
        vpls: usize,
        /// Seed.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Output folder (progressive.md, fig7.*, fig8_*).
        #[arg(long)]
        out: PathBuf,
    },
    /// Compare the path tracer with the Mitsuba 3 references of `cornell`; write a Markdown report.
    ValidateCornell {
        /// Samples per pixel.
        #[arg(long, default_value_t = 1024)]
        spp: u32,
        /// Folder holding the reference EXRs.
        #[arg(long, default_value = "tests/data/cornell-box")]
        data: PathBuf,
        /// Folder for the report and difference images.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
}

fn main() {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand) {
                let _ = e.print();
                std::process::exit(if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand { 2 } else { 0 });
            }
            let text = e.to_string();
            let line = text.lines().next().unwrap_or("bad arguments").trim_start_matches("error: ");
            eprintln!("vpl: error: {line}");
            std::process::exit(2);
        }
    };
    if let Err(e) = run(cli) {
        eprintln!("vpl: error: {e}");
        std::process::exit(2);
    }
}

type Res<T> = Result<T, String>;

fn pool(threads: Option<usize>) -> Res<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 {
            return Err("--threads must be at least 1".into());
        }
        b = b.num_threads(n);
    }
    b.build().map_err(|e| format!("cannot start threads: {e}"))
}

/// Fails early, before any work, if `path` cannot be written.
fn check_writable(path: &Path) -> Res<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(format!("cannot write {}: directory {} does not exist", path.display(), dir.display()));
    }
    let md = std::fs::metadata(dir).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    if md.permissions().readonly() {
        return Err(format!("cannot write {}: directory {} is read-only", path.display(), dir.display()));
    }
    if path.is_dir() {
        return Err(format!("cannot write {}: it is a directory", path.display()));
    }
    Ok(())
}

/// Loads a scene, checks the frame against its sequence, and applies `--size`.
fn load_frame(scene: &str, frame: u32, size: Option<Size>) -> Res<(vpl_core::Scene, vpl_core::Camera)> {
    let setup = SceneSetup::load(scene).map_err(|e| e.to_string())?;
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
fn tracer(max_depth: u32, mode: ModeArg, clamp: Option<ClampArg>, vpls: usize, scene: &vpl_core::Scene) -> PathTracer {
    let mut pt = PathTracer::new(max_depth, mode_of(mode));
    pt.clamp = clamp.unwrap_or(ClampArg::Off).resolve(vpls, scene.surface_area());
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

fn run(cli: Cli) -> Res<()> {
    match cli.command {
        Command::Render { s: SceneArgs { scene, frame, max_depth, clamp, vpls, size, seed, threads }, method, mode, spp, v, p, out, stderr, exposure, quiet } => {
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
            check_writable(&out)?;
            if let Some(s) = &stderr {
                check_writable(s)?;
            }
            let pool = pool(threads)?;
            if method == Method::Progressive {
                return render_progressive(&scene, frame, size, seed, max_depth, clamp, vpls, &p, &out, stderr.as_deref(), exposure, quiet, &pool);
            }
            if method == Method::Vpl {
                if stderr.is_some() {
                    return Err("--stderr is for --method path: one VPL render has no per-pixel error estimate".into());
                }
                return render_vpl(&scene, frame, size, seed, max_depth, mode, clamp, vpls, &v, &out, exposure, quiet, &pool);
            }
            let (sc, camera) = load_frame(&scene, frame, size)?;
            let pt = tracer(max_depth, mode, clamp, vpls, &sc);
            let bar = ProgressBar::with_draw_target(Some(camera.resolution.0 as u64 * camera.resolution.1 as u64), ProgressDrawTarget::hidden());
            bar.set_style(ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:40}] {percent}% pixels, eta {eta}").unwrap().progress_chars("=> "));
            let start = Instant::now();
            let shown = AtomicBool::new(false);
            let progress = |done: u64, _total: u64| {
                if !quiet && !shown.load(Ordering::Relaxed) && start.elapsed().as_secs_f32() > 1.0 {
                    shown.store(true, Ordering::Relaxed);
                    bar.set_draw_target(ProgressDrawTarget::stderr());
                }
                bar.set_position(done);
            };
            let r = pool
                .install(|| render(&sc, &camera, &pt, RenderSettings { spp, seed, frame: frame as u64 }, &progress))
                .map_err(|e| e.to_string())?;
            bar.finish_and_clear();
            r.image.write_exr(&out).map_err(|e| e.to_string())?;
            r.image.write_png(preview_path(&out), exposure).map_err(|e| e.to_string())?;
            if let Some(s) = &stderr {
                r.stderr.write_exr(s).map_err(|e| e.to_string())?;
            }
            if !quiet {
                let m = r.image.mean();
                eprintln!(
                    "vpl: {} {}x{} {spp} spp in {:.2} s ({:.2} M paths/s), mean RGB {:.5} {:.5} {:.5} -> {}",
                    sc.name, camera.resolution.0, camera.resolution.1, r.seconds, r.paths as f64 / r.seconds / 1e6, m[0], m[1], m[2], out.display()
                );
            }
            Ok(())
        }
        Command::Track { s: SceneArgs { scene, frame, max_depth, clamp, vpls, size, seed, threads }, mode, pixels, spp, out } => {
            if spp == 0 {
                return Err("--spp must be at least 1".into());
            }
            check_depth(max_depth, vpls)?;
            if let Some(p) = &out {
                check_writable(p)?;
            }
            let pool = pool(threads)?;
            let (sc, camera) = load_frame(&scene, frame, size)?;
            let pt = tracer(max_depth, mode, clamp, vpls, &sc);
            let (w, h) = camera.resolution;
            if let Some(p) = pixels.iter().find(|p| p.0 >= w || p.1 >= h) {
                return Err(format!("--pixel {},{} is outside the {w}x{h} image", p.0, p.1));
            }
            let px: Vec<(u32, u32)> = pixels.iter().map(|p| (p.0, p.1)).collect();
            let ts = pool.install(|| track(&sc, &camera, &pt, &px, spp, seed, frame as u64));
            let mut csv = String::from("x,y,r,g,b,stderr_r,stderr_g,stderr_b,samples\n");
            for t in ts {
                csv.push_str(&format!(
                    "{},{},{},{},{},{},{},{},{}\n",
                    t.pixel.0, t.pixel.1, t.mean.x, t.mean.y, t.mean.z, t.stderr.x, t.stderr.y, t.stderr.z, t.samples
                ));
            }
            emit(out.as_deref(), &csv)
        }
        Command::Sequence { s: SceneArgs { scene, frame, max_depth, clamp, vpls, size, seed, threads }, frames, mode, v, pixels, out, exposure, quiet } => {
            if frame != 0 {
                return Err("--frame is for render; a sequence takes --frames A..B".into());
            }
            check_depth(max_depth, vpls)?;
            if !(exposure.is_finite() && exposure > 0.0) {
                return Err("--exposure must be positive".into());
            }
            if out.exists() && !out.is_dir() {
                return Err(format!("--out {} is not a directory", out.display()));
            }
            let pool = pool(threads)?;
            let setup = SceneSetup::load(&scene).map_err(|e| e.to_string())?;
            for w in &setup.warnings {
                eprintln!("vpl: warning: {w}");
            }
            let count = setup.sequence.as_ref().map_or(1, |q| q.frame_count());
            let range = frames.unwrap_or(FramesArg { start: 0, end: None }).range(count);
            vpl_bench::sequence::check_frames(&setup, &range).map_err(|e| format!("--{e}"))?;
            let clamp = clamp.unwrap_or(ClampArg::Auto).resolve(vpls, setup.scene.surface_area());
            let mut p = vpl_bench::pipeline::Pipeline::new(pipeline_spec(&v, vpls, max_depth, mode, clamp, seed)?).map_err(|e| format!("--sampler {}: {e}", v.sampler))?;
            if let (Some(a), false) = (p.adapter(), quiet) {
                eprintln!("vpl: GPU: {a}");
            }
            let res = match size {
                Some(Size(w, h)) => (w, h),
                None => setup.camera.resolution,
            };
            p.gbuffer.fits(res)?;
            let tracked: Vec<(u32, u32)> = if pixels.is_empty() { vpl_bench::sequence::default_tracked_pixels(res.0, res.1) } else { pixels.iter().map(|p| (p.0, p.1)).collect() };
            std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
            let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::new(range.len() as u64) };
            bar.set_style(ProgressStyle::with_template("{elapsed_precise} [{bar:40}] frame {pos}/{len} {msg}, eta {eta}").unwrap().progress_chars("=> "));
            let start = Instant::now();
            let done = pool
                .install(|| {
                    vpl_bench::sequence::run_sequence(&setup, range.clone(), size.map(|s| (s.0, s.1)), &mut p, &tracked, Some((&out, exposure)), &mut |f, _| {
                        bar.set_message(format!("{:.0} ms, {} VPLs moved", f.timings.total_ms, f.moved));
                        bar.inc(1);
                    })
                })
                .map_err(|e| e.to_string())?;
            bar.finish_and_clear();
            if !quiet {
                let mean_ms = done.iter().map(|f| f.timings.total_ms).sum::<f64>() / done.len() as f64;
                let moved = done.iter().skip(1).map(|f| f.moved).max().unwrap_or(0);
                eprintln!(
                    "vpl: {} frames {}..{} with {} in {:.1} s ({mean_ms:.0} ms a frame; at most {moved} VPLs moved between frames) -> {}",
                    setup.scene.name,
                    range.start,
                    range.end,
                    v.sampler,
                    start.elapsed().as_secs_f64(),
                    out.display()
                );
            }
            Ok(())
        }
        Command::Table1 { profile, scenes, methods, frames, size, truth_spp, seed, shard, backend, threads, out, quiet } => {
            use vpl_bench::table1::{self, Table1Spec};
            let mut spec = match profile {
                ProfileArg::Quick => Table1Spec::quick(),
                ProfileArg::Full => Table1Spec::full().map_err(|e| e.to_string())?,
            };
            let custom = !scenes.is_empty() || !methods.is_empty() || frames.is_some() || size.is_some() || truth_spp.is_some() || seed != 0;
            if !scenes.is_empty() {
                let ids = table1::row_ids();
                if let Some(bad) = scenes.iter().find(|s| !ids.contains(&s.as_str())) {
                    return Err(format!("--scene: unknown sequence '{bad}' (sequences: {})", ids.join(", ")));
                }
                spec.rows.retain(|r| scenes.contains(&r.id));
            }
            if !methods.is_empty() {
                spec.methods = methods;
            }
            if let Some(f) = frames {
                for r in &mut spec.rows {
                    let n = table1::rows::row(&r.id).map(|row| row.frame_count()).transpose().map_err(|e| e.to_string())?.unwrap_or(1);
                    let range = f.range(n);
                    r.start = range.start;
                    r.end = range.end;
                }
            }
            if let Some(Size(w, h)) = size {
                spec.size = (w, h);
            }
            if let Some(n) = truth_spp {
                spec.truth_spp = n;
            }
            spec.seed = seed;
            spec.backend = backend.backend();
            if custom {
                spec.profile = format!("{}+custom", spec.profile);
            }
            spec.validate().map_err(|e| e.to_string())?;
            if out.exists() && !out.is_dir() {
                return Err(format!("--out {} is not a directory", out.display()));
            }
            std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
            let pool = pool(threads)?;
            let shard_arg = shard.unwrap_or(table1::Shard::ALL);
            let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr()) };
            bar.set_style(ProgressStyle::with_template("table1 {elapsed_precise} [{bar:40}] {pos}/{len} frames {msg}, eta {eta}").unwrap().progress_chars("=> "));
            let summary = pool
                .install(|| {
                    table1::run(&spec, &out, shard_arg, &mut |p| {
                        bar.set_length(p.total);
                        bar.set_position(p.done);
                        if !p.message.is_empty() {
                            bar.set_message(p.message.clone());
                        }
                    })
                })
                .map_err(|e| e.to_string())?;
            bar.finish_and_clear();
            if !quiet {
                eprintln!(
                    "vpl: table1 shard {}/{}: {} units run, {} already done, of {} in the run; {:.0} s",
                    shard_arg.index, shard_arg.count, summary.ran, summary.kept, summary.total_units, summary.seconds
                );
            }
            if shard.is_none() {
                pool.install(|| table1::merge(&out)).map_err(|e| e.to_string())?;
                if !quiet {
                    eprintln!("vpl: table1 -> {}", out.join("table1.md").display());
                }
            }
            Ok(())
        }
        Command::Table2 { size: Size(w, h), frames, backend, scenes, threads, out } => {
            if frames == 0 {
                return Err("--frames must be at least 1".into());
            }
            let pool = pool(threads)?;
            std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
            if let Some(bad) = scenes.iter().find(|s| !vpl_bench::table2::PAPER.iter().any(|p| p.1 == s.as_str())) {
                return Err(format!("--scene: '{bad}' is not a Table 2 scene (courtyard, office, atrium, maze)"));
            }
            let mut rows = Vec::new();
            let mut device = format!("this machine's CPU ({} threads)", pool.current_num_threads());
            for (paper, scene, _, vpls, _) in vpl_bench::table2::PAPER {
                if !scenes.is_empty() && !scenes.iter().any(|s| s == scene) {
                    continue;
                }
                eprintln!("vpl: table2: {scene} ({vpls} VPLs, {w}x{h}, {frames} frames)");
                let start = vpl_bench::table1::rows::row(scene).map_or(0, |r| r.quick_frames.start);
                let (row, adapter) = pool.install(|| vpl_bench::table2::time_scene(scene, paper, (w, h), vpls, start, frames, backend.backend()))?;
                if let Some(a) = adapter {
                    device = format!("{a} for the G-buffer, shadow maps and shading; sampling on the CPU ({} threads)", pool.current_num_threads());
                }
                rows.push(row);
            }
            vpl_bench::table2::write(&out, &rows, (w, h), frames, &device).map_err(|e| e.to_string())?;
            eprintln!("vpl: table2 -> {}", out.join("table2.md").display());
            Ok(())
        }
        Command::Figures { scenes, fig10_scenes, size: Size(w, h), fig10_size: Size(w10, h10), spp, fig10_spp, shadow_maps, budgets, fig10_warmup, only, seed, threads, out } => {
            use vpl_bench::figures;
            if spp == 0 || fig10_spp == 0 || budgets.contains(&0) || shadow_maps.is_empty() {
                return Err("--spp and --budgets must be positive and --shadow-maps not empty".into());
            }
            if let Some(bad) = only.iter().find(|f| **f != 8 && **f != 10) {
                return Err(format!("--only: no figure {bad} (8 or 10)"));
            }
            for sc in scenes.iter().chain(&fig10_scenes) {
                SceneSetup::load(sc).map_err(|e| e.to_string())?;
            }
            let pool = pool(threads)?;
            std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
            let settings = figures::FigureSettings { size: (w, h), reference_spp: spp, shadow_map_sides: shadow_maps, budgets, fig10_size: (w10, h10), fig10_spp, fig10_warmup, seed };
            if only.contains(&8) {
                let mut figs = Vec::new();
                for sc in &scenes {
                    eprintln!("vpl: figures: Figs. 8 and 9 on {sc}");
                    let (a, b) = pool.install(|| figures::fig8_9(&out, sc, 0, &settings)).map_err(|e| e.to_string())?;
                    figs.push((sc.clone(), a, b));
                }
                figures::write_fig8(&out, &figs, &settings).map_err(|e| e.to_string())?;
            }
            if only.contains(&10) {
                let mut figs = Vec::new();
                for sc in &fig10_scenes {
                    eprintln!("vpl: figures: Fig. 10 on {sc}");
                    figs.push((sc.clone(), pool.install(|| figures::fig10(&out, sc, &settings)).map_err(|e| e.to_string())?));
                }
                figures::write_fig10(&out, &figs, &settings).map_err(|e| e.to_string())?;
            }
            eprintln!("vpl: figures -> {}", out.display());
            Ok(())
        }
        Command::ProgressiveFigures {
            fig7_scene,
            fig7_size: Size(w7, h7),
            passes,
            step,
            converged,
            caustic_paths,
            fig8_scenes,
            fig8_size: Size(w8, h8),
            seconds,
            reference_spp,
            mitsuba,
            only,
            vpls,
            seed,
            threads,
            out,
        } => {
            use vpl_bench::progressive as pf;
            if vpls == 0 {
                return Err("--vpls must be at least 1".into());
            }
            if passes == 0 || step == 0 || converged == 0 || reference_spp == 0 {
                return Err("--passes, --step, --converged and --reference-spp must be at least 1".into());
            }
            if !(seconds.is_finite() && seconds > 0.0) {
                return Err("--seconds must be positive".into());
            }
            if let Some(bad) = only.iter().find(|f| **f != 7 && **f != 8) {
                return Err(format!("--only: no figure {bad} (7 or 8)"));
            }
            for sc in std::iter::once(&fig7_scene).chain(&fig8_scenes) {
                SceneSetup::load(sc).map_err(|e| e.to_string())?;
            }
            let pool = pool(threads)?;
            std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
            let say = |m: &str| eprintln!("vpl: progressive figures: {m}");
            let fig7 = if only.contains(&7) {
                let s = pf::Fig7Settings { scene: fig7_scene, size: (w7, h7), passes, step, converged, reference_spp, caustic_paths, clamp_budget: Some(vpls), seed };
                Some(pool.install(|| pf::fig7(&out, &s, &say)).map_err(|e| e.to_string())?)
            } else {
                None
            };
            let mut rows = Vec::new();
            if only.contains(&8) {
                let s = pf::Fig8Settings { scenes: fig8_scenes.clone(), size: (w8, h8), seconds, reference_spp, mitsuba: Some(mitsuba), clamp_budget: vpls, seed };
                for sc in &fig8_scenes {
                    rows.push(pool.install(|| pf::fig8_scene(&out, sc, &s, &say)).map_err(|e| e.to_string())?);
                }
                let json = serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?;
                write_atomic(&out.join("fig8.json"), json.as_bytes()).map_err(|e| e.to_string())?;
            }
            let md = format!("# Progressive point-light rendering (Dammertz et al. 2010)\n\n{}", pf::report(fig7.as_ref(), &rows, seconds, ""));
            write_atomic(&out.join("progressive.md"), md.as_bytes()).map_err(|e| e.to_string())?;
            eprintln!("vpl: progressive figures -> {}", out.join("progressive.md").display());
            Ok(())
        }
        Command::Merge { dir } => {
            if !dir.join("spec.json").exists() {
                return Err(format!("{} holds no Table 1 run (no spec.json)", dir.display()));
            }
            vpl_bench::table1::merge(&dir).map_err(|e| e.to_string())?;
            eprintln!("vpl: merged -> {}", dir.join("table1.md").display());
            Ok(())
        }
        Command::ExportScene { name, out } => {
            let setup = SceneSetup::load(&name).map_err(|e| e.to_string())?;
            emit(out.as_deref(), &setup.to_toml())
        }
        Command::BenchPt { spp, repeat, threads } => {
            if spp == 0 || repeat == 0 {
                return Err("--spp and --repeat must be at least 1".into());
            }
            let pool = pool(threads)?;
            let setup = SceneSetup::load("cornell").map_err(|e| e.to_string())?;
            let pt = PathTracer::new(5, Mode::Full);
            let mut rates = Vec::new();
            // One warm-up render, then the timed ones.
            for i in 0..=repeat {
                let r = pool
                    .install(|| render(&setup.scene, &setup.camera, &pt, RenderSettings { spp, seed: i as u64, frame: 0 }, &|_, _| {}))
                    .map_err(|e| e.to_string())?;
                if i > 0 {
                    rates.push(r.paths as f64 / r.seconds);
                }
            }
            rates.sort_by(f64::total_cmp);
            println!(
                "bench-pt: cornell 256x256, max-depth 5, {spp} spp, {} threads: best {:.3} M paths/s, median {:.3} M paths/s over {repeat} renders",
                pool.current_num_threads(),
                rates[rates.len() - 1] / 1e6,
                rates[rates.len() / 2] / 1e6
            );
            Ok(())
        }
        Command::BenchGpu { scenes, size: Size(w, h), vpls, frames, threads, out } => bench_gpu(&scenes, (w, h), vpls, frames, threads, out.as_deref()),
        Command::BenchVpl { repeat, threads, size, vpls } => {
            if repeat == 0 || vpls == 0 {
                return Err("--repeat and --vpls must be at least 1".into());
            }
            let pool = pool(threads)?;
            println!("bench-vpl: {}x{}, {vpls} IR VPLs, 128x128 shadow maps, {} threads, median of {repeat} (ms)", size.0, size.1, pool.current_num_threads());
            println!("| scene | G-buffer | direct (16 spp) | IR sampling | shadow maps, all | shadow maps, 16 changed | interleaved gather | filter | indirect frame, 16 changed |");
            println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
            for name in ["cornell", "office"] {
                let b = pool.install(|| vpl_bench::stages::bench_stages(name, (size.0, size.1), vpls, repeat)).map_err(|e| e.to_string())?;
                println!(
                    "| {name} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | **{:.1}** |",
                    b.gbuffer, b.direct, b.sampling, b.shadow_maps_all, b.shadow_maps_16, b.gather, b.filter, b.indirect_frame
                );
            }
            println!();
            println!("SMC sampling (Table 2 of Hedman et al.), camera walking the sequence from frame 300, median of {} frames (ms):", repeat.max(15));
            println!("| scene | VPLs | cand. sampling | cand. resampling | indirect visibility | radiosity | kNN | **total** | VPLs moved |");
            println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
            for (name, budget) in [("office", vpls), ("maze", (vpls / 4).max(1))] {
                let b = pool.install(|| vpl_bench::stages::bench_smc(name, (size.0, size.1), budget, 300, repeat.max(15))).map_err(|e| e.to_string())?;
                println!(
                    "| {name} | {budget} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | **{:.1}** | {:.0} |",
                    b.candidates, b.resampling, b.visibility, b.radiosity, b.knn, b.total, b.moved
                );
            }
            println!();
            println!("Every sampler on office, I = {vpls}, camera walking the sequence from frame 300: next_frame of the first frame, then the median of {} frames (ms):", repeat.max(8));
            println!("| sampler | first frame | **per frame** | VPLs moved per frame | VPLs stored |");
            println!("| --- | --- | --- | --- | --- |");
            let rows = pool.install(|| vpl_bench::stages::bench_samplers("office", (size.0, size.1), vpls, 300, repeat.max(8))).map_err(|e| e.to_string())?;
            for b in rows {
                println!("| {} | {:.1} | **{:.1}** | {:.0} | {:.0} |", b.name, b.first_ms, b.frame_ms, b.moved, b.stored);
            }
            Ok(())
        }
        Command::ValidateCornell { spp, data, out, seed } => {
            if spp == 0 {
                return Err("--spp must be at least 1".into());
            }
            std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
            let bar = ProgressBar::new(3 * 256 * 256);
            bar.set_style(ProgressStyle::with_template("{msg:>9} {elapsed_precise} [{bar:40}] {percent}%, eta {eta}").unwrap().progress_chars("=> "));
            let vs = vpl_bench::validation::validate_cornell(&data, spp, seed, &|m, d, t| {
                let k = vpl_bench::validation::MODES.iter().position(|x| x.0 == m).unwrap_or(0) as u64;
                bar.set_message(m.to_string());
                bar.set_position(k * t + d);
            })
            .map_err(|e| e.to_string())?;
            bar.finish_and_clear();
            for v in &vs {
                vpl_bench::validation::write_difference(v, &out).map_err(|e| e.to_string())?;
                v.ours.0.write_png(out.join(format!("cornell_{}_ours.png", v.mode)), 1.0).map_err(|e| e.to_string())?;
                v.theirs.0.write_png(out.join(format!("cornell_{}_mitsuba.png", v.mode)), 1.0).map_err(|e| e.to_string())?;
            }
            let md = vpl_bench::validation::report_markdown(&vs, spp);
            write_atomic(&out.join("cornell_validation.md"), md.as_bytes()).map_err(|e| e.to_string())?;
            print!("{md}");
            Ok(())
        }
        Command::Georgiev { size, vpls, frames, spp, seed, rr_epsilon, camera_samples, sweep, out } => {
            if vpls == 0 || frames == 0 || spp == 0 {
                return Err("--vpls, --frames and --spp must be at least 1".into());
            }
            let rr = vpl_sampling::RrConfig { vpls, epsilon: rr_epsilon, camera_samples, ..vpl_sampling::RrConfig::default() };
            rr.validate().map_err(|e| e.to_string())?;
            std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
            let settings = vpl_bench::georgiev::GeorgievSettings { size: (size.0, size.1), vpls, warmup_frames: 4, frames, reference_spp: spp, seed, rr };
            let bar = ProgressBar::new_spinner();
            bar.set_style(ProgressStyle::with_template("{elapsed_precise} {spinner} {msg}").unwrap());
            if let Some(bad) = sweep.iter().find(|e| !(**e > 0.0 && **e <= 1.0)) {
                return Err(format!("--sweep: epsilon {bad} is outside (0, 1]"));
            }
            let r = vpl_bench::georgiev::georgiev(&settings, &sweep, &|m| {
                let short: String = m.chars().take(100).collect();
                bar.set_message(short);
                bar.tick();
            })?;
            bar.finish_and_clear();
            // One exposure for all three pictures: the reference's mean luminance at 0.18.
            let mean = r.reference.data.iter().map(|c| vpl_core::image::luminance(*c) as f64).sum::<f64>() / r.reference.data.len().max(1) as f64;
            let exposure = if mean > 0.0 { (0.18 / mean) as f32 } else { 1.0 };
            for (name, img) in [("reference", &r.reference), ("ir", &r.ir), ("rr", &r.rr)] {
                img.write_exr(out.join(format!("corner_{name}.exr"))).map_err(|e| e.to_string())?;
                img.write_png(out.join(format!("corner_{name}.png")), exposure).map_err(|e| e.to_string())?;
            }
            write_atomic(&out.join("georgiev.md"), r.markdown.as_bytes()).map_err(|e| e.to_string())?;
            write_atomic(&out.join("georgiev.csv"), r.csv.as_bytes()).map_err(|e| e.to_string())?;
            print!("{}", r.markdown);
            Ok(())
        }
    }
}

/// The pipeline that `--method vpl` and its flags describe.
fn pipeline_spec(v: &VplArgs, vpls: usize, max_depth: u32, mode: ModeArg, clamp: Option<vpl_core::GeometryClamp>, seed: u64) -> Res<vpl_bench::pipeline::PipelineSpec> {
    use vpl_bench::pipeline::{PipelineSpec, ShadingSpec, VisibilitySpec};
    if v.direct_samples == 0 {
        return Err("--direct-samples must be at least 1".into());
    }
    if v.visibility == VisibilityArg::Shadowmap {
        vpl_visibility::ShadowMaps::new(v.shadowmap_res).map_err(|e| format!("--shadowmap-res: {e}"))?;
    }
    let defaults = vpl_sampling::SmcConfig::default();
    if v.resample_ratio == Some(0) || v.radiosity_paths == 0 || v.knn_k == Some(0) {
        return Err("--resample-ratio, --radiosity-paths and --knn-k must be at least 1".into());
    }
    if v.camera_samples == Some(0) || v.mh_iterations == Some(0) || v.mir_chains == 0 {
        return Err("--camera-samples, --mh-iterations and --mir-chains must be at least 1".into());
    }
    if !(v.rr_epsilon > 0.0 && v.rr_epsilon <= 1.0) {
        return Err(format!("--rr-epsilon {} is outside (0, 1]", v.rr_epsilon));
    }
    if !(0.0..=1.0).contains(&v.mir_large_step) || !(v.mir_defensive >= 0.0 && v.mir_defensive.is_finite()) {
        return Err("--mir-large-step must be in [0, 1] and --mir-defensive at least 0".into());
    }
    if !(1..=4096).contains(&v.rsm_res) {
        return Err(format!("--rsm-res {} is outside 1..=4096", v.rsm_res));
    }
    let (rr, mir, mir_resample, tcas) =
        (vpl_sampling::RrConfig::default(), vpl_sampling::MirConfig::default(), vpl_sampling::MirResampleConfig::default(), vpl_sampling::TcasConfig::default());
    let config = vpl_sampling::SamplerConfig {
        vpls,
        max_depth,
        sampling: match v.path_sampling {
            PathSamplingArg::Random => vpl_sampling::PathSampling::Random,
            PathSamplingArg::Halton => vpl_sampling::PathSampling::Halton,
        },
        fresh_paths: v.fresh_paths,
        smc: vpl_sampling::SmcConfig {
            m_max: v.m_max,
            resample_ratio: v.resample_ratio.unwrap_or(defaults.resample_ratio),
            radiosity_paths: v.radiosity_paths,
            knn_k: v.knn_k,
            warmup: v.warmup,
            ..defaults
        },
        rr: vpl_sampling::RrConfig { epsilon: v.rr_epsilon, camera_samples: v.camera_samples.unwrap_or(rr.camera_samples), pilot: v.rr_pilot, ..rr },
        mir: vpl_sampling::MirConfig {
            camera_samples: v.camera_samples.unwrap_or(mir.camera_samples),
            chains: v.mir_chains,
            mutations: v.mh_iterations.unwrap_or(mir.mutations),
            large_step: v.mir_large_step,
            defensive: v.mir_defensive,
            ..mir
        },
        mir_resample: vpl_sampling::MirResampleConfig {
            ratio: v.resample_ratio.unwrap_or(mir_resample.ratio),
            radiosity_paths: v.radiosity_paths,
            knn_k: v.knn_k,
            ..mir_resample
        },
        tcas: vpl_sampling::TcasConfig {
            rsm_res: v.rsm_res,
            iterations: v.mh_iterations.unwrap_or(tcas.iterations),
            warmup: v.tcas_warmup,
            camera_samples: v.camera_samples.unwrap_or(tcas.camera_samples),
            ..tcas
        },
    };
    Ok(PipelineSpec {
        sampler: v.sampler.clone(),
        config,
        visibility: match v.visibility {
            VisibilityArg::Raytrace => VisibilitySpec::RayTraced,
            VisibilityArg::Shadowmap => VisibilitySpec::ShadowMaps(v.shadowmap_res),
        },
        shading: match v.shading {
            ShadingArg::Exhaustive => ShadingSpec::Exhaustive,
            ShadingArg::Interleaved => ShadingSpec::Interleaved { filter: !v.no_filter },
        },
        clamp,
        mode: mode_of(mode),
        direct_samples: v.direct_samples,
        seed,
        backend: v.backend.backend(),
    })
}

/// `vpl render --method vpl`.
#[allow(clippy::too_many_arguments)]
fn render_vpl(
    scene: &str,
    frame: u32,
    size: Option<Size>,
    seed: u64,
    max_depth: u32,
    mode: ModeArg,
    clamp: Option<ClampArg>,
    vpls: usize,
    v: &VplArgs,
    out: &Path,
    exposure: f32,
    quiet: bool,
    pool: &rayon::ThreadPool,
) -> Res<()> {
    let (sc, camera) = load_frame(scene, frame, size)?;
    let clamp = clamp.unwrap_or(ClampArg::Auto).resolve(vpls, sc.surface_area());
    let mut p = vpl_bench::pipeline::Pipeline::new(pipeline_spec(v, vpls, max_depth, mode, clamp, seed)?).map_err(|e| format!("--sampler {}: {e}", v.sampler))?;
    p.gbuffer.fits(camera.resolution)?;
    if let (Some(a), false) = (p.adapter(), quiet) {
        eprintln!("vpl: GPU: {a}");
    }
    let r = pool.install(|| p.render(&sc, &camera, frame as u64, frame as f32 / 30.0));
    r.image.write_exr(out).map_err(|e| e.to_string())?;
    r.image.write_png(preview_path(out), exposure).map_err(|e| e.to_string())?;
    if !quiet {
        let t = r.timings;
        let m = r.image.mean();
        if !r.sampler_report.is_empty() {
            eprintln!("vpl: {}", r.sampler_report);
            eprintln!(
                "vpl: visibility {}: {} maps rebuilt, {:.1} MiB; clamp {}",
                p.visibility.name(),
                r.visibility.rebuilt,
                r.visibility.memory_bytes as f64 / (1 << 20) as f64,
                clamp.map_or("off".to_string(), |c| format!("G_max = {:.3} 1/m^2", c.g_max))
            );
        }
        eprintln!(
            "vpl: {} {}x{} in {:.1} ms (G-buffer {:.1}, sampling {:.1}, visibility {:.1}, {} shading {:.1}, direct {:.1}), mean RGB {:.5} {:.5} {:.5} -> {}",
            sc.name,
            camera.resolution.0,
            camera.resolution.1,
            t.total_ms,
            t.gbuffer_ms,
            t.sampling_ms,
            t.visibility_ms,
            p.shader.name(),
            t.shading_ms,
            t.direct_ms,
            m[0],
            m[1],
            m[2],
            out.display()
        );
    }
    Ok(())
}

/// `vpl bench-gpu`.
#[cfg(feature = "gpu")]
fn bench_gpu(scenes: &[String], size: (u32, u32), vpls: usize, frames: u32, threads: Option<usize>, out: Option<&Path>) -> Res<()> {
    if frames == 0 || vpls == 0 {
        return Err("--frames and --vpls must be at least 1".into());
    }
    for s in scenes {
        SceneSetup::load(s).map_err(|e| format!("--scene: {e}"))?;
    }
    let pool = pool(threads)?;
    let gpu = vpl_gpu::Gpu::new().map_err(|e| e.to_string())?;
    let adapter = gpu.ctx().describe();
    eprintln!("vpl: bench-gpu on {adapter}");
    let mut rows = Vec::new();
    for s in scenes {
        eprintln!("vpl: bench-gpu: {s} ({vpls} VPLs, {}x{}, {frames} frames)", size.0, size.1);
        let start = vpl_bench::table1::rows::row(s).map_or(0, |r| r.quick_frames.start);
        rows.push(pool.install(|| vpl_bench::gpu_bench::bench_scene(&gpu, s, size, vpls, start, frames))?);
    }
    let md = vpl_bench::gpu_bench::report(&adapter, &rows, frames, pool.current_num_threads());
    println!("{md}");
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        vpl_core::image::write_atomic(&dir.join("gpu_bench.md"), md.as_bytes()).map_err(|e| e.to_string())?;
        let json = serde_json::json!({ "adapter": adapter, "frames": frames, "threads": pool.current_num_threads(), "rows": rows });
        let text = serde_json::to_string_pretty(&json).map_err(|e| e.to_string())?;
        vpl_core::image::write_atomic(&dir.join("gpu_bench.json"), text.as_bytes()).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// `vpl bench-gpu` without the GPU backend.
#[cfg(not(feature = "gpu"))]
fn bench_gpu(_: &[String], _: (u32, u32), _: usize, _: u32, _: Option<usize>, _: Option<&Path>) -> Res<()> {
    Err("bench-gpu: this build has no GPU backend (build vpl-bench with its default feature `gpu`)".into())
}

/// `vpl render --method progressive`.
#[allow(clippy::too_many_arguments)]
fn render_progressive(
    scene: &str,
    frame: u32,
    size: Option<Size>,
    seed: u64,
    max_depth: u32,
    clamp: Option<ClampArg>,
    vpls: usize,
    p: &ProgressiveArgs,
    out: &Path,
    stderr: Option<&Path>,
    exposure: f32,
    quiet: bool,
    pool: &rayon::ThreadPool,
) -> Res<()> {
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
        culling,
        clamp: clamp.unwrap_or(ClampArg::Auto).resolve(vpls, sc.surface_area()),
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
    let passes = p.passes.unwrap_or(if p.seconds.is_some() { u64::MAX } else { 64 });
    if let Some(d) = &p.snapshots {
        std::fs::create_dir_all(d).map_err(|e| format!("cannot create {}: {e}", d.display()))?;
    }
    let bar = if quiet {
        ProgressBar::hidden()
    } else if passes == u64::MAX {
        ProgressBar::new_spinner()
    } else {
        ProgressBar::new(passes)
    };
    let template = if passes == u64::MAX { "{spinner} {elapsed_precise} pass {pos} ({per_sec}) {msg}" } else { "{elapsed_precise} [{bar:40}] pass {pos}/{len} ({per_sec}) {msg}, eta {eta}" };
    bar.set_style(ProgressStyle::with_template(template).unwrap().progress_chars("=> "));
    let start = Instant::now();
    let mut last = vpl_progressive::PassStats::default();
    while r.passes() < passes {
        last = pool.install(|| r.pass());
        bar.set_message(format!("{} VPLs, {} photons", last.stored, last.photons));
        bar.inc(1);
        if let (Some(k), Some(d)) = (p.snapshot_every, &p.snapshots) {
            if r.passes() % k == 0 {
                r.image().write_exr(d.join(format!("pass_{:06}.exr", r.passes()))).map_err(|e| e.to_string())?;
            }
        }
        if p.seconds.is_some_and(|t| start.elapsed().as_secs_f64() >= t) {
            break;
        }
    }
    bar.finish_and_clear();
    let secs = start.elapsed().as_secs_f64();
    let img = r.image();
    img.write_exr(out).map_err(|e| e.to_string())?;
    img.write_png(preview_path(out), exposure).map_err(|e| e.to_string())?;
    if let Some(s) = stderr {
        r.stderr().write_exr(s).map_err(|e| e.to_string())?;
    }
    if !quiet {
        let m = img.mean();
        let (w, h) = r.camera().resolution;
        eprintln!(
            "vpl: {} {w}x{h} progressive, {} passes in {secs:.2} s ({:.2} passes/s; last pass {} of {} VPLs stored, {} photons of which {} caustic, map coverage {:.1} %, {:.0} ms), mean RGB {:.5} {:.5} {:.5} -> {}",
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
            out.display()
        );
    }
    Ok(())
}
