//! `vpl manylights`: the many-light study: error over wall time of VPL sources × gathers on a
//! scene's view, and their temporal error on one Table 1 sequence; manylights.md, .json, plots.

use super::*;
use vpl_bench::manylights::{ManyLightsSettings, Source, markdown, measure, plot, temporal, write_images};
use vpl_bench::pipeline::ShadingSpec;

/// A VPL source: `SAMPLER:VPLS`.
#[derive(Clone, Debug)]
struct SourceArg(Source);

impl std::str::FromStr for SourceArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (sampler, vpls) = s.split_once(':').ok_or_else(|| format!("source '{s}' must look like ir:65536 (SAMPLER:VPLS)"))?;
        let vpls: usize = vpls.parse().map_err(|_| format!("source '{s}': '{vpls}' is not a VPL count"))?;
        if sampler.is_empty() || vpls == 0 {
            return Err(format!("source '{s}' needs a sampler and at least one VPL"));
        }
        Ok(SourceArg(Source { sampler: sampler.into(), vpls }))
    }
}

/// The many-light study: each VPL source (sampler and budget) gathered each way (interleaved,
/// exhaustive, lightcuts:N, culled:X), its frames averaged on frame 0's view; RMSE against the
/// path tracer over wall time, a table and a plot per scene, and |E|, |E′| of the same
/// configurations on one Table 1 sequence; manylights.md, manylights.json, manylights_<scene>.png,
/// and each configuration's mean image (EXR and PNG).
#[derive(clap::Args)]
pub(super) struct Args {
    /// Scenes (comma-separated): Table 1 sequences by id (office, sponza, munich, …), built-in
    /// names, or scene files; a Table 1 sequence whose model is absent is skipped.
    #[arg(long = "scene", value_delimiter = ',', default_value = "office,sponza,munich")]
    scenes: Vec<String>,
    /// VPL sources, SAMPLER:VPLS (comma-separated).
    #[arg(long = "sources", value_delimiter = ',', default_value = "smc:2048,ir:65536,ir:1048576")]
    sources: Vec<SourceArg>,
    /// Gathers (comma-separated): interleaved, interleaved-unfiltered, exhaustive, lightcuts:N,
    /// culled:X.
    #[arg(long = "gathers", value_delimiter = ',', default_value = "interleaved,exhaustive,lightcuts:8,lightcuts:32,lightcuts:128")]
    gathers: Vec<ShadingSpec>,
    /// Image size.
    #[arg(long, default_value = "96x72")]
    size: Size,
    /// Wall-time budget of each configuration, seconds.
    #[arg(long, default_value_t = 8.0)]
    seconds: f64,
    /// Most frames a configuration averages.
    #[arg(long, default_value_t = 256)]
    max_frames: u32,
    /// Path-traced samples a pixel of the reference.
    #[arg(long, default_value_t = 4096)]
    spp: u32,
    /// Path-traced samples a tracked pixel and frame of the sequence's truth.
    #[arg(long, default_value_t = 16384)]
    truth_spp: u32,
    /// Longest path in segments.
    #[arg(long, default_value_t = 5)]
    max_depth: u32,
    /// Geometry clamp: auto (G_max = I / A_view), scene-area, off, or G_max.
    #[arg(long, default_value = "auto")]
    clamp: vpl_render::Clamp,
    /// The Table 1 sequence of the temporal error (its quick window); `none` for none.
    #[arg(long, default_value = "office")]
    sequence: String,
    /// Where the VPL stages run (the references are path traced on the CPU).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    backend: BackendArg,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Let scene files name files under this folder too (repeatable).
    #[arg(long = "allow-outside")]
    allow_outside: Vec<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// Runs `vpl manylights`.
pub(super) fn run(args: Args, registry: &Registry) -> Res<()> {
    let Args {
        scenes,
        sources,
        gathers,
        size: Size(w, h),
        seconds,
        max_frames,
        spp,
        truth_spp,
        max_depth,
        clamp,
        sequence,
        backend,
        seed,
        allow_outside,
        threads,
        out,
    } = args;
    let settings = ManyLightsSettings {
        sources: sources.into_iter().map(|s| s.0).collect(),
        gathers,
        size: (w, h),
        seconds,
        max_frames,
        reference_spp: spp,
        truth_spp,
        max_depth,
        clamp,
        backend: backend.backend(),
        seed,
    };
    if !(seconds.is_finite() && seconds > 0.0) || max_frames == 0 || spp == 0 || truth_spp == 0 {
        return Err("--seconds must be positive; --max-frames, --spp and --truth-spp at least 1".into());
    }
    for s in &settings.sources {
        if !registry.contains(&s.sampler) {
            return Err(format!("--sources: unknown sampler '{}' (samplers: {})", s.sampler, registry.names().join(", ")));
        }
    }
    let row = match sequence.as_str() {
        "none" => None,
        id => Some(vpl_bench::table1::rows::row(id).ok_or_else(|| {
            format!("--sequence: '{id}' is not a Table 1 sequence ({}, or none)", vpl_bench::table1::row_ids().join(", "))
        })?),
    };
    let (setups, mut skipped) = study_scenes(&scenes, allow_outside)?;
    let pool = pool(threads)?;
    let dir = OutDir::create("--out", &out)?;
    let mut studies = Vec::new();
    for (name, setup) in &setups {
        let name = name.as_str();
        eprintln!("vpl: manylights: {name}");
        let study = pool
            .install(|| measure(registry, name, setup, &settings, &mut |what| eprintln!("vpl: manylights: {name}: {what}")))
            .map_err(|e| e.to_string())?;
        plot(dir.path(), &study).map_err(|e| e.to_string())?;
        write_images(dir.path(), &study).map_err(|e| e.to_string())?;
        studies.push(study);
    }
    let temporal = match &row {
        Some(row) if row.missing().is_none() => Some(
            pool.install(|| temporal(registry, row, &settings, &mut |what| eprintln!("vpl: manylights: temporal: {what}")))
                .map_err(|e| e.to_string())?,
        ),
        Some(row) => {
            skipped.push(format!("the sequence {}: {}", row.id, row.missing().unwrap_or_default()));
            None
        }
        None => None,
    };
    let mut md = markdown(&studies, temporal.as_ref(), &settings);
    for why in &skipped {
        eprintln!("vpl: manylights: skipped {why}");
        md.push_str(&format!("\nSkipped {why}\n"));
    }
    let json = serde_json::json!({ "settings": settings, "scenes": studies, "temporal": temporal });
    vpl_core::image::write_atomic(&dir.path().join("manylights.md"), md.as_bytes()).map_err(|e| e.to_string())?;
    let text = serde_json::to_string_pretty(&json).map_err(|e| e.to_string())?;
    vpl_core::image::write_atomic(&dir.path().join("manylights.json"), text.as_bytes()).map_err(|e| e.to_string())?;
    dir.keep()?;
    print!("{md}");
    Ok(())
}
