//! Table 2 of Hedman et al.: milliseconds per stage of an SMC frame, per
//! scene, in the paper's columns (`vpl table2`).

use crate::error::BenchError;
use crate::pipeline::{BackendKind, ShadingSpec, VisibilitySpec};
use crate::smc_step::{SmcPlace, SmcStep};
use crate::stages::median;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;
use vpl_core::image::write_atomic;
use vpl_core::{Budget, CoreError, Frame, GBuffer, GeometryClamp};
use vpl_sampling::SmcConfig;

/// The paper's Table 2 rows: scene, its stand-in here, triangles, VPLs, then
/// the ten timing columns of [`Table2Row::columns`] (GTX Titan X, 1920×1080).
pub const PAPER: [(&str, &str, &str, usize, [f64; 10]); 4] = [
    ("Epic Citadel", "courtyard", "373K", 2048, [3.3, 3.0, 1.6, 11.0, 2.6, 21.5, 8.7, 20.0, 28.7, 50.2]),
    ("Soda Hall", "office", "551K", 2048, [2.3, 2.2, 1.2, 7.8, 1.7, 15.2, 15.9, 19.1, 35.0, 50.2]),
    ("Crytek Sponza", "atrium", "262K", 2048, [2.7, 2.5, 2.0, 9.8, 1.6, 18.6, 6.0, 24.4, 30.4, 49.0]),
    ("Maze", "maze", "471K", 512, [2.2, 1.6, 1.1, 6.8, 1.6, 13.3, 11.7, 10.5, 22.2, 35.5]),
];

/// Column names of Table 2.
pub const COLUMNS: [&str; 10] = [
    "cand. sampling",
    "cand. resampling",
    "indirect visibility",
    "radiosity",
    "kNN",
    "sampling total",
    "shadow maps",
    "interl. shading",
    "rendering total",
    "total",
];

/// One scene's medians in milliseconds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Table2Row {
    /// Built-in scene.
    pub scene: String,
    /// The paper's scene it stands in for.
    pub paper_scene: String,
    /// Triangles.
    pub triangles: usize,
    /// VPL budget.
    pub vpls: usize,
    /// Camera points, candidate rays, undersampled regions, replacement.
    pub cand_sampling: f64,
    /// Drawing candidates from the weighted hits.
    pub cand_resampling: f64,
    /// Mailboxes and rays toward unverified VPLs.
    pub indirect_visibility: f64,
    /// Radiosity of new VPLs.
    pub radiosity: f64,
    /// k-d trees and kNN densities.
    pub knn: f64,
    /// The sampler's whole step.
    pub sampling_total: f64,
    /// Shadow maps of the VPLs that moved.
    pub shadow_maps: f64,
    /// G-buffer, interleaved gathering and the filter.
    pub interleaved_shading: f64,
    /// Shadow maps and shading.
    pub rendering_total: f64,
    /// The indirect frame.
    pub total: f64,
    /// Median VPLs moved per frame.
    pub moved: f64,
}

impl Table2Row {
    /// The ten timing columns in the paper's order.
    pub fn columns(&self) -> [f64; 10] {
        [
            self.cand_sampling,
            self.cand_resampling,
            self.indirect_visibility,
            self.radiosity,
            self.knn,
            self.sampling_total,
            self.shadow_maps,
            self.interleaved_shading,
            self.rendering_total,
            self.total,
        ]
    }
}

/// One scene of Table 2.
#[derive(Clone, Copy, Debug)]
pub struct Table2Spec<'a> {
    /// Built-in scene.
    pub scene: &'a str,
    /// The paper's scene it stands in for.
    pub paper_scene: &'a str,
    /// Image size.
    pub size: (u32, u32),
    /// VPL budget.
    pub vpls: usize,
    /// First frame of the scene's sequence.
    pub start: u32,
    /// Frames timed (after the first).
    pub frames: u32,
    /// Where the G-buffer, shadow maps and shading run.
    pub backend: BackendKind,
    /// Where SMC runs ([`SmcPlace::Device`] needs the GPU backend).
    pub smc: SmcPlace,
}

/// Times `frames` SMC frames of `scene`'s sequence from frame `start` at
/// `size` with budget `vpls` (after the first frame, whose warm-up and
/// full set of shadow maps are not timed): the sampler's steps, the shadow
/// maps of moved VPLs (128²) and interleaved shading with the filter.
pub fn time_scene(spec: &Table2Spec) -> Result<(Table2Row, Option<String>), BenchError> {
    let Table2Spec { scene: scene_name, paper_scene, size, vpls, start, frames, backend, smc: place } = *spec;
    let setup = vpl_scene_io::load(scene_name)?;
    let count = setup.sequence.as_ref().map_or(1, |s| s.frame_count());
    let clamp = GeometryClamp::for_view(vpls, &setup.scene, &setup.camera);
    let config = SmcConfig { vpls, ..SmcConfig::default() };
    let (backend, mut smc) = sampler(backend, place, config)?;
    let budget = Budget::new(vpls, 5);
    let mut sm = backend.visibility(VisibilitySpec::ShadowMaps(vpl_visibility::DEFAULT_RESOLUTION), &budget)?;
    let mut shader = backend.shader(ShadingSpec::Interleaved { filter: true }, Some(clamp), 0)?;
    backend.check_size(size)?;
    let mut rows: Vec<[f64; 9]> = Vec::new();
    for k in 0..=frames {
        let f = (start + k).min(count - 1);
        let (scene, camera) = setup.frame(f)?;
        let camera = camera.with_resolution(size)?;
        let t0 = std::time::Instant::now();
        let gbuf: GBuffer = backend.gbuffer(&scene, &camera)?;
        let gbuffer_ms = t0.elapsed().as_secs_f64() * 1e3;
        let frame =
            Frame { scene: &scene, camera: &camera, time: f as f32 / 30.0, index: f as u64, seed: 0, gbuffer: &gbuf, previous: None };
        let set = smc.next_frame(&frame).clone();
        let st = smc.timings();
        let t0 = std::time::Instant::now();
        sm.update(&scene, &set);
        let sm_ms = t0.elapsed().as_secs_f64() * 1e3;
        let t0 = std::time::Instant::now();
        std::hint::black_box(shader.shade(&gbuf, &set, sm.as_ref()));
        let shade_ms = t0.elapsed().as_secs_f64() * 1e3 + gbuffer_ms;
        if k > 0 {
            rows.push([
                st.candidates_ms,
                st.resampling_ms,
                st.visibility_ms,
                st.radiosity_ms,
                st.knn_ms,
                st.total_ms,
                sm_ms,
                shade_ms,
                set.moved_count() as f64,
            ]);
        }
    }
    let col = |i: usize| median(rows.iter().map(|r| r[i]).collect());
    let (sampling, maps, shading) = (col(5), col(6), col(7));
    let row = Table2Row {
        scene: scene_name.into(),
        paper_scene: paper_scene.into(),
        triangles: setup.scene.geometry.triangles.len(),
        vpls,
        cand_sampling: col(0),
        cand_resampling: col(1),
        indirect_visibility: col(2),
        radiosity: col(3),
        knn: col(4),
        sampling_total: sampling,
        shadow_maps: maps,
        interleaved_shading: shading,
        rendering_total: maps + shading,
        total: sampling + maps + shading,
        moved: col(8),
    };
    Ok((row, backend.device()))
}

/// The backend and the sampler of a run: SMC on the host with the
/// backend's services, or on the device of the GPU backend.
fn sampler(backend: BackendKind, place: SmcPlace, config: SmcConfig) -> Result<(Box<dyn vpl_render::Backend>, SmcStep), BenchError> {
    match place {
        SmcPlace::Host => {
            let backend = backend.instantiate()?;
            let smc = SmcStep::host(config, &backend.services())?;
            Ok((backend, smc))
        }
        SmcPlace::Device => device_sampler(backend, config),
    }
}

#[cfg(feature = "gpu")]
fn device_sampler(backend: BackendKind, config: SmcConfig) -> Result<(Box<dyn vpl_render::Backend>, SmcStep), BenchError> {
    if backend != BackendKind::Gpu {
        return Err(vpl_render::RenderError::Invalid("--smc device needs --backend gpu".into()).into());
    }
    let gpu = vpl_gpu::backend()?;
    let smc = SmcStep::device(gpu.gpu(), config)?;
    Ok((Box::new(gpu), smc))
}

#[cfg(not(feature = "gpu"))]
fn device_sampler(_: BackendKind, _: SmcConfig) -> Result<(Box<dyn vpl_render::Backend>, SmcStep), BenchError> {
    Err(vpl_render::RenderError::Invalid("--smc device needs the GPU backend (build vpl-bench with its default feature `gpu`)".into())
        .into())
}

/// Writes `table2.md`, `table2.csv` and `table2.json` into `dir`.
/// `device` says where the stages ran, in words.
pub fn write(dir: &Path, rows: &[Table2Row], size: (u32, u32), frames: u32, device: &str) -> Result<(), CoreError> {
    let mut md = String::from("# Table 2: milliseconds per stage of an SMC frame\n\n");
    let _ = writeln!(
        md,
        "Medians over {frames} frames of each scene's camera walk after the first (warm-up) frame, {}×{} pixels, 128² shadow maps, \
         4×4 interleaved shading with the filter, on {device}. The paper's figures (GTX Titan X, \
         1920×1080) in the second table. Interleaved shading includes the G-buffer, as in the paper; the sampler's columns add up \
         to its total only roughly (the remainder is bookkeeping).\n",
        size.0, size.1
    );
    let head = |first: &str| {
        let mut h = format!("| {first} | triangles | VPLs |");
        for c in COLUMNS {
            let _ = write!(h, " {c} |");
        }
        h.push_str("\n| --- | ---: | ---: |");
        h.push_str(&" ---: |".repeat(COLUMNS.len()));
        h
    };
    let _ = writeln!(md, "## This toolkit (moved VPLs per frame in brackets)\n\n{}", head("scene"));
    for r in rows {
        let _ = write!(md, "| `{}` ({}, {:.0} moved) | {} | {} |", r.scene, r.paper_scene, r.moved, r.triangles, r.vpls);
        for v in r.columns() {
            let _ = write!(md, " {v:.1} |");
        }
        md.push('\n');
    }
    let _ = writeln!(md, "\n## The paper\n\n{}", head("scene"));
    for (p, ours, tris, vpls, cols) in PAPER {
        let _ = write!(md, "| {p} (`{ours}`) | {tris} | {vpls} |");
        for v in cols {
            let _ = write!(md, " {v:.1} |");
        }
        md.push('\n');
    }
    let mut csv = String::from("scene,paper_scene,triangles,vpls,moved");
    for c in COLUMNS {
        let _ = write!(csv, ",{}_ms", c.replace(['.', ' '], "_").replace("__", "_"));
    }
    csv.push('\n');
    for r in rows {
        let _ = write!(csv, "{},{},{},{},{}", r.scene, r.paper_scene, r.triangles, r.vpls, r.moved);
        for v in r.columns() {
            let _ = write!(csv, ",{v:.3}");
        }
        csv.push('\n');
    }
    write_atomic(&dir.join("table2.md"), md.as_bytes())?;
    write_atomic(&dir.join("table2.csv"), csv.as_bytes())?;
    let json = serde_json::to_string_pretty(rows).map_err(|e| CoreError::Invalid(e.to_string()))?;
    write_atomic(&dir.join("table2.json"), json.as_bytes())?;
    Ok(())
}
