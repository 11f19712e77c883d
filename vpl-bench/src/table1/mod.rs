//! Table 1 of Hedman et al. (SMC instant radiosity, §5.2): how far each
//! sampler's indirect light at eight tracked pixels lies from path-traced
//! ground truth (|E|) and how much that error flickers from frame to frame
//! (|E′|), over five animated sequences, with every method given the same
//! budget, shadow maps, interleaved shading and filter.
//!
//! The work is split into units that can run anywhere and in any order:
//! one per (sequence, method), which renders the sequence's frames with
//! that sampler and records the tracked pixels, and one per (sequence,
//! frame) of ground truth. Each unit writes one JSON file under the output
//! folder; [`merge`] reads them all and writes the tables and plots. A run
//! split with `--shard i/n` (unit k goes to shard k mod n) therefore merges
//! to exactly the bits of an unsplit one.

pub mod estimate;
pub mod report;
pub mod rows;
pub mod stats;
pub mod truth;

use crate::metrics::{TemporalError, tone_mapped_luminance, tone_mapped_stderr};
use crate::pipeline::{BackendKind, PipelineSpec, ShadingSpec, VisibilitySpec};
use crate::sequence::run_sequence;
use rows::Row;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;
use vpl_core::glam::Vec3;
use vpl_core::image::write_atomic;
use vpl_core::{Budget, CoreError, Mode, Params};
use vpl_sampling::Registry;

/// Errors of a Table 1 run.
#[derive(Debug, thiserror::Error)]
pub enum Table1Error {
    /// A scene, file or image problem.
    #[error(transparent)]
    Core(#[from] CoreError),
    /// A scene file could not be read.
    #[error(transparent)]
    SceneIo(#[from] vpl_scene_io::SceneIoError),
    /// A setting is invalid.
    #[error("{0}")]
    Invalid(String),
    /// The output folder holds units of a run with other settings.
    #[error("{0} holds results of a run with other settings ({1}); use another --out or remove it")]
    SpecMismatch(PathBuf, String),
    /// A unit file was made with other settings than the run's.
    #[error("{0} was made with other settings than this run ({1}); remove it or use another --out")]
    UnitMismatch(PathBuf, String),
    /// Units are missing when merging.
    #[error("{missing} of {total} units are missing in {dir} (first: {first}); run the shards that make them")]
    Missing {
        /// The folder.
        dir: PathBuf,
        /// Missing units.
        missing: usize,
        /// All units.
        total: usize,
        /// The first missing unit's file.
        first: String,
    },
    /// A unit file could not be read.
    #[error("{0}: {1}")]
    Unit(PathBuf, String),
    /// A plot failed.
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
}

/// The frames of one row that a run renders.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RowRun {
    /// Row id ([`rows::Row::id`]).
    pub id: String,
    /// First frame.
    pub start: u32,
    /// One past the last frame.
    pub end: u32,
}

/// Everything that fixes the numbers of a run: two runs with equal specs
/// give equal unit files.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Table1Spec {
    /// `quick`, `full` or `custom`.
    pub profile: String,
    /// Rows and their frames.
    pub rows: Vec<RowRun>,
    /// Sampler registry names.
    pub methods: Vec<String>,
    /// Image size.
    pub size: (u32, u32),
    /// Path-traced samples per tracked pixel and frame of ground truth.
    pub truth_spp: u32,
    /// Longest path in segments (5: three indirect bounces, as the paper).
    pub max_depth: u32,
    /// Shadow-map side in texels (the paper's 128).
    pub shadow_map_res: u32,
    /// Seed of every stream: method runs use `seed`, `seed + 1`, …,
    /// `seed + seeds − 1`; the ground truth and the bootstrap use `seed`.
    pub seed: u64,
    /// Independent runs of every method (the confidence intervals' seeds).
    #[serde(default = "one")]
    pub seeds: u32,
    /// Where the VPL stages and the ground truth run ([`truth::Truth`]).
    #[serde(default)]
    pub backend: BackendKind,
}

impl Table1Spec {
    /// A fingerprint of every setting (FNV-1a, 64 bits, over the spec's
    /// JSON): every unit file records it, and a unit whose fingerprint
    /// differs from the run's is refused.
    pub fn hash(&self) -> String {
        let text = serde_json::to_string(self).unwrap_or_default();
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in text.bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        format!("{h:016x}")
    }

    /// The settings in which `other` differs from this spec, as
    /// `key: theirs (this run: ours)`, joined by `; `.
    pub fn differences(&self, other: &Table1Spec) -> String {
        let (a, b) = (serde_json::to_value(self).unwrap_or_default(), serde_json::to_value(other).unwrap_or_default());
        let short = |v: Option<&serde_json::Value>| {
            let t = v.map_or("absent".to_string(), |v| v.to_string());
            if t.chars().count() > 60 { format!("{}…", t.chars().take(60).collect::<String>()) } else { t }
        };
        let mut out = Vec::new();
        if let (Some(a), Some(b)) = (a.as_object(), b.as_object()) {
            for key in a.keys().chain(b.keys().filter(|k| !a.contains_key(*k))) {
                if a.get(key) != b.get(key) {
                    out.push(format!("{key}: {} (this run: {})", short(b.get(key)), short(a.get(key))));
                }
            }
        }
        if out.is_empty() { "no setting differs".into() } else { out.join("; ") }
    }
}

fn one() -> u32 {
    1
}

/// Seeds per method in the quick and full profiles.
pub const PROFILE_SEEDS: u32 = 3;

/// The paper's ground-truth sample count per pixel (§5.2).
pub const PAPER_TRUTH_SPP: u32 = 692_100;

/// The methods of the table: the paper's four, RR, and SMC with the paper's
/// kNN flux (`smc-knn`, eq. 5 and 7) beside the default flux (the cell's
/// light as the VPL shows it to the camera, `voronoi-near`).
pub const METHODS: [&str; 6] = ["ir", "rr", "mir-resample", "tcas", "smc", "smc-knn"];

/// Whether `method` is SMC under another flux or setting (`smc-…`, or
/// `smc` with settings): a variant of the method the target compares, not
/// one of its rivals.
pub fn is_smc_variant(method: &str) -> bool {
    method.starts_with("smc-") || method.starts_with("smc:")
}

/// A method of the table: a registry name, then any settings of it, each
/// after a colon (`smc:flux=knn-calibrated:placement=centroid`).
#[derive(Clone, Debug, PartialEq)]
pub struct MethodSpec {
    /// The registry name.
    pub sampler: String,
    /// Its settings, in order.
    pub settings: Vec<(String, String)>,
}

impl MethodSpec {
    /// Parses `method`; a setting without `=` is an error.
    pub fn parse(method: &str) -> Result<MethodSpec, Table1Error> {
        let mut parts = method.split(':');
        let sampler = parts.next().unwrap_or_default().to_string();
        let settings = parts
            .map(|kv| match kv.split_once('=') {
                Some((k, v)) if !k.is_empty() => Ok((k.to_string(), v.to_string())),
                _ => Err(Table1Error::Invalid(format!("method '{method}': '{kv}' is not KEY=VALUE"))),
            })
            .collect::<Result<_, _>>()?;
        Ok(MethodSpec { sampler, settings })
    }

    /// The method's file name in `units/` (colons are not allowed in every file system).
    pub fn file_stem(method: &str) -> String {
        method.replace(':', "+")
    }
}

/// Frames of the quick profile's window per row.
impl Table1Spec {
    /// The quick profile: every row's `quick_frames`, 65 536 truth samples.
    pub fn quick() -> Self {
        Self::with_frames("quick", 65_536, |r| Ok(r.quick_frames.clone())).expect("the built-in rows load")
    }

    /// The paper's settings: whole sequences, 692 100 truth samples.
    pub fn full() -> Result<Self, Table1Error> {
        Self::with_frames("full", PAPER_TRUTH_SPP, |r| Ok(0..r.frame_count()?))
    }

    fn with_frames(
        profile: &str,
        truth_spp: u32,
        frames: impl Fn(&Row) -> Result<std::ops::Range<u32>, vpl_scene_io::SceneIoError>,
    ) -> Result<Self, Table1Error> {
        // Rows on real geometry whose models are not here are left out
        // ([`skipped_rows`] says which and why; the report lists them).
        let rows = rows::rows()
            .iter()
            .filter(|r| r.missing().is_none())
            .map(|r| {
                let f = frames(r)?;
                Ok(RowRun { id: r.id.to_string(), start: f.start, end: f.end })
            })
            .collect::<Result<_, Table1Error>>()?;
        Ok(Table1Spec {
            profile: profile.into(),
            rows,
            methods: METHODS.iter().map(|s| s.to_string()).collect(),
            size: (320, 240),
            truth_spp,
            max_depth: 5,
            shadow_map_res: 128,
            seed: 0,
            seeds: PROFILE_SEEDS,
            backend: BackendKind::Cpu,
        })
    }

    /// Checks names (methods against `registry`), frames and settings;
    /// says what is wrong in one line.
    pub fn validate(&self, registry: &Registry) -> Result<(), Table1Error> {
        self.validate_settings()?;
        for m in &self.methods {
            let spec = MethodSpec::parse(m)?;
            if !registry.contains(&spec.sampler) {
                return Err(Table1Error::Invalid(format!("unknown method '{}' (methods: {})", spec.sampler, registry.names().join(", "))));
            }
        }
        Ok(())
    }

    /// [`Table1Spec::validate`] without the methods: sequences, frames, sizes.
    pub fn validate_settings(&self) -> Result<(), Table1Error> {
        if self.rows.is_empty() || self.methods.is_empty() {
            return Err(Table1Error::Invalid("a run needs at least one sequence and one method".into()));
        }
        // Each (row, method, seed) is a unit and a column of the report;
        // a spec of 10,000 methods would plan and merge 10,000 of each.
        if self.methods.len() > MAX_METHODS || self.rows.len() > MAX_ROWS {
            return Err(Table1Error::Invalid(format!(
                "{} methods and {} sequences: a run takes at most {MAX_METHODS} methods and {MAX_ROWS} sequences",
                self.methods.len(),
                self.rows.len()
            )));
        }
        for (i, m) in self.methods.iter().enumerate() {
            if self.methods[..i].contains(m) {
                return Err(Table1Error::Invalid(format!("the method '{m}' is listed twice")));
            }
        }
        for (i, r) in self.rows.iter().enumerate() {
            if self.rows[..i].iter().any(|q| q.id == r.id) {
                return Err(Table1Error::Invalid(format!("the sequence '{}' is listed twice", r.id)));
            }
        }
        for r in &self.rows {
            let row = rows::row(&r.id)
                .ok_or_else(|| Table1Error::Invalid(format!("unknown sequence '{}' (sequences: {})", r.id, row_ids().join(", "))))?;
            let n = row.frame_count()?;
            if r.start >= r.end || r.end > n {
                return Err(Table1Error::Invalid(format!("frames {}..{} do not fit {} ({n} frames)", r.start, r.end, r.id)));
            }
        }
        if self.truth_spp == 0 || self.size.0 == 0 || self.size.1 == 0 {
            return Err(Table1Error::Invalid("truth samples and image size must be positive".into()));
        }
        if self.seeds == 0 || self.seeds > 64 {
            return Err(Table1Error::Invalid(format!("{} seeds: a run needs 1 to 64", self.seeds)));
        }
        Ok(())
    }

    /// The units of the run: every (row, method, seed) sequence, then every
    /// (row, frame) of ground truth.
    pub fn units(&self) -> Vec<Unit> {
        let mut u = Vec::new();
        for (r, _) in self.rows.iter().enumerate() {
            for (m, _) in self.methods.iter().enumerate() {
                for seed in 0..self.seeds {
                    u.push(Unit::Method { row: r, method: m, seed });
                }
            }
        }
        for (r, run) in self.rows.iter().enumerate() {
            for f in run.start..run.end {
                u.push(Unit::Truth { row: r, frame: f });
            }
        }
        u
    }

    /// The file of `unit`, relative to the output folder.
    pub fn unit_file(&self, unit: Unit) -> String {
        match unit {
            Unit::Method { row, method, seed } => {
                format!("units/{}/{}_seed{seed}.json", self.rows[row].id, MethodSpec::file_stem(&self.methods[method]))
            }
            Unit::Truth { row, frame } => format!("units/{}/truth_{frame:05}.json", self.rows[row].id),
        }
    }

    /// Frames a unit renders (the progress bar's measure of work: a truth
    /// frame counts as one).
    pub fn unit_weight(&self, unit: Unit) -> u64 {
        match unit {
            Unit::Method { row, .. } => (self.rows[row].end - self.rows[row].start) as u64,
            Unit::Truth { .. } => 1,
        }
    }
}

/// Row ids of the table.
pub fn row_ids() -> Vec<&'static str> {
    rows::rows().iter().map(|r| r.id).collect()
}

/// The rows that cannot run here, with the reason (a model that is not there).
pub fn skipped_rows() -> Vec<(&'static str, String)> {
    rows::rows().iter().filter_map(|r| r.missing().map(|why| (r.id, why))).collect()
}

/// One piece of work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// A sequence rendered with one method and one seed.
    Method {
        /// Index into [`Table1Spec::rows`].
        row: usize,
        /// Index into [`Table1Spec::methods`].
        method: usize,
        /// Which of the run's seeds (0..[`Table1Spec::seeds`]).
        seed: u32,
    },
    /// Ground truth of one frame of a sequence.
    Truth {
        /// Index into [`Table1Spec::rows`].
        row: usize,
        /// Frame.
        frame: u32,
    },
}

/// Shard `index` of `count`: the units k with k mod count = index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, 0-based.
    pub index: u32,
    /// Number of shards.
    pub count: u32,
}

impl Shard {
    /// The whole run.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Whether unit number `k` belongs to this shard.
    pub fn owns(&self, k: usize) -> bool {
        k as u64 % self.count as u64 == self.index as u64
    }
}

impl std::str::FromStr for Shard {
    type Err = Table1Error;
    fn from_str(s: &str) -> Result<Shard, Table1Error> {
        let bad = |m: String| Table1Error::Invalid(m);
        let (a, b) = s.split_once('/').ok_or_else(|| bad(format!("'{s}' is not a shard (expected I/N, e.g. 0/4)")))?;
        let index: u32 = a.trim().parse().map_err(|_| bad(format!("'{a}' is not a shard index")))?;
        let count: u32 = b.trim().parse().map_err(|_| bad(format!("'{b}' is not a shard count")))?;
        if count == 0 || index >= count {
            return Err(bad(format!("shard {index}/{count}: the index must be below the count")));
        }
        Ok(Shard { index, count })
    }
}

/// Ground truth of one frame: the tracked pixels' indirect radiance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TruthUnit {
    /// The settings it was made with and their [`Table1Spec::hash`]
    /// (absent in units of older versions, which are refused).
    #[serde(default)]
    pub settings: Option<UnitSettings>,
    /// Row id.
    pub row: String,
    /// Frame.
    pub frame: u32,
    /// Mean radiance per tracked pixel.
    pub mean: Vec<[f32; 3]>,
    /// Its standard error per channel.
    pub stderr: Vec<[f32; 3]>,
    /// Samples per pixel.
    pub samples: u64,
    /// Wall time of the unit in seconds (0 in units of older versions).
    #[serde(default)]
    pub seconds: f64,
    /// The part of [`TruthUnit::seconds`] that does not grow with the
    /// samples: loading the scene, the upload to a device (0 in units of
    /// older versions).
    #[serde(default)]
    pub setup_seconds: f64,
    /// The adapter that path-traced it (`--backend gpu`); `None` on the CPU
    /// and in units of older versions.
    #[serde(default)]
    pub device: Option<String>,
}

/// One method's run of a sequence.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MethodUnit {
    /// The settings it was made with and their [`Table1Spec::hash`]
    /// (absent in units of older versions, which are refused).
    #[serde(default)]
    pub settings: Option<UnitSettings>,
    /// Row id.
    pub row: String,
    /// Method.
    pub method: String,
    /// The seed its renderer ran with.
    #[serde(default)]
    pub seed: u64,
    /// Frames rendered.
    pub frames: Vec<u32>,
    /// Indirect radiance per frame and tracked pixel.
    pub tracked: Vec<Vec<[f32; 3]>>,
    /// VPL slots moved per frame.
    pub moved: Vec<usize>,
    /// Milliseconds per frame: G-buffer, sampling, visibility, shading, total.
    pub ms: Vec<[f64; 5]>,
    /// Wall time of the unit in seconds.
    pub seconds: f64,
}

/// The record of the settings a unit was made with.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UnitSettings {
    /// [`Table1Spec::hash`] of `spec`.
    pub hash: String,
    /// The whole spec, so a refusal can name the setting that differs.
    pub spec: Table1Spec,
}

impl UnitSettings {
    fn of(spec: &Table1Spec) -> UnitSettings {
        UnitSettings { hash: spec.hash(), spec: spec.clone() }
    }
}

/// The most methods one run compares (the registry has a dozen).
pub const MAX_METHODS: usize = 64;
/// The most sequences one run holds (Table 1 has seven).
pub const MAX_ROWS: usize = 64;

/// Refuses a unit whose numbers are not finite: JSON numbers beyond the
/// range of `f32` read as infinities, and would print as `inf` and `NaN`
/// in the table.
fn check_finite<'a>(path: &Path, what: &str, values: impl IntoIterator<Item = &'a [f32; 3]>) -> Result<(), Table1Error> {
    match values.into_iter().position(|v| !v.iter().all(|x| x.is_finite())) {
        Some(i) => Err(Table1Error::Unit(path.into(), format!("{what} {i} is not a finite single-precision number"))),
        None => Ok(()),
    }
}

/// Checks that the unit at `path` (with record `settings`) was made with `spec`.
fn check_unit(path: &Path, settings: &Option<UnitSettings>, spec: &Table1Spec) -> Result<(), Table1Error> {
    match settings {
        None => Err(Table1Error::UnitMismatch(path.into(), "it records no settings: an older version made it".into())),
        Some(u) if u.hash != spec.hash() || &u.spec != spec => Err(Table1Error::UnitMismatch(path.into(), spec.differences(&u.spec))),
        Some(_) => Ok(()),
    }
}

/// Reads the unit at `path` (truth or method, as its kind says) and checks its settings.
fn check_unit_file(path: &Path, unit: Unit, spec: &Table1Spec) -> Result<(), Table1Error> {
    match unit {
        Unit::Truth { .. } => check_unit(path, &read_json::<TruthUnit>(path)?.settings, spec),
        Unit::Method { .. } => check_unit(path, &read_json::<MethodUnit>(path)?.settings, spec),
    }
}

/// Progress of a run, for a progress bar.
#[derive(Clone, Debug, PartialEq)]
pub struct Progress {
    /// Work done (frames; a truth frame counts one).
    pub done: u64,
    /// All work of the shard.
    pub total: u64,
    /// What is being done.
    pub message: String,
}

/// What a shard did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunSummary {
    /// Units computed.
    pub ran: usize,
    /// Units found already done and kept.
    pub kept: usize,
    /// Units of the whole run.
    pub total_units: usize,
    /// Wall time in seconds.
    pub seconds: f64,
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T, Table1Error> {
    let text = vpl_scene_io::input::read_text(path, vpl_scene_io::input::MAX_TEXT_BYTES)
        .map_err(|e| Table1Error::Unit(path.into(), e.to_string()))?;
    serde_json::from_str(&text).map_err(|e| Table1Error::Unit(path.into(), e.to_string()))
}

fn write_json<T: Serialize>(path: &Path, v: &T) -> Result<(), Table1Error> {
    if let Some(d) = path.parent() {
        std::fs::create_dir_all(d).map_err(|e| CoreError::Write { path: d.into(), reason: e.to_string() })?;
    }
    let text = serde_json::to_string_pretty(v).map_err(|e| Table1Error::Invalid(e.to_string()))?;
    write_atomic(path, text.as_bytes())?;
    Ok(())
}

/// Runs the units of `shard` into `dir`, the methods from `registry` (skipping units whose files exist:
/// an interrupted run resumes). Writes `spec.json` first; refuses a folder
/// whose `spec.json` differs.
pub fn run(
    registry: &Registry,
    spec: &Table1Spec,
    dir: &Path,
    shard: Shard,
    progress: &mut dyn FnMut(&Progress),
) -> Result<RunSummary, Table1Error> {
    spec.validate(registry)?;
    let start = Instant::now();
    let spec_path = dir.join("spec.json");
    if spec_path.exists() {
        let old: Table1Spec = read_json(&spec_path)?;
        if &old != spec {
            return Err(Table1Error::SpecMismatch(dir.into(), spec.differences(&old)));
        }
    }
    let units = spec.units();
    // Units already in the folder (of any shard) must have been made with
    // this spec, even when spec.json was removed or units were copied in.
    for unit in &units {
        let path = dir.join(spec.unit_file(*unit));
        if path.exists() {
            check_unit_file(&path, *unit, spec)?;
        }
    }
    if !spec_path.exists() {
        write_json(&spec_path, spec)?;
    }
    let mine: Vec<(usize, Unit)> = units.iter().copied().enumerate().filter(|(k, _)| shard.owns(*k)).collect();
    let total: u64 = mine.iter().map(|(_, u)| spec.unit_weight(*u)).sum();
    let mut summary = RunSummary { total_units: units.len(), ..RunSummary::default() };
    let mut done = 0u64;
    let mut truth = truth::Truth::new();
    for (_, unit) in mine {
        let path = dir.join(spec.unit_file(unit));
        let w = spec.unit_weight(unit);
        if path.exists() {
            summary.kept += 1;
            done += w;
            continue;
        }
        match unit {
            Unit::Method { row, method, seed } => {
                let r = rows::row(&spec.rows[row].id).expect("validated");
                let name = &spec.methods[method];
                let base = done;
                let seed = spec.seed.wrapping_add(seed as u64);
                let u = run_method(registry, spec, &r, &spec.rows[row], name, seed, &mut |f| {
                    progress(&Progress { done: base + f, total, message: format!("{} {name} (seed {seed})", r.id) });
                })?;
                write_json(&path, &u)?;
            }
            Unit::Truth { row, frame } => {
                let r = rows::row(&spec.rows[row].id).expect("validated");
                progress(&Progress { done, total, message: format!("{} ground truth", r.id) });
                write_json(&path, &truth.unit(spec, &r, frame)?)?;
            }
        }
        summary.ran += 1;
        done += w;
        progress(&Progress { done, total, message: String::new() });
    }
    summary.seconds = start.elapsed().as_secs_f64();
    Ok(summary)
}

/// The renderer every method gets: indirect light only, the paper's depth,
/// shadow maps, 4×4 interleaved shading with the cross-bilateral filter,
/// the geometry clamp G_max = I / A_view of each frame's view (resolved again whenever the camera
/// moves: [`vpl_render::Clamp::Auto`]), and IR with new paths every frame (the baseline without
/// temporal coherence).
pub fn pipeline_spec(spec: &Table1Spec, method: &str, vpls: usize, seed: u64) -> Result<PipelineSpec, Table1Error> {
    let method = MethodSpec::parse(method)?;
    let mut params = Params::new();
    params.offer("fresh-paths", true);
    for (k, v) in &method.settings {
        params.insert(k, v.clone()).map_err(|e| Table1Error::Invalid(format!("method '{}': {e}", method.sampler)))?;
    }
    Ok(PipelineSpec {
        sampler: method.sampler,
        params,
        budget: Budget::new(vpls, spec.max_depth),
        visibility: VisibilitySpec::ShadowMaps(spec.shadow_map_res),
        shading: ShadingSpec::Interleaved { filter: true },
        clamp: vpl_render::Clamp::Auto,
        compensation: 0,
        mode: Mode::Indirect,
        direct_samples: 1,
        seed,
        backend: spec.backend.name().into(),
    })
}

fn run_method(
    registry: &Registry,
    spec: &Table1Spec,
    row: &Row,
    run: &RowRun,
    method: &str,
    seed: u64,
    on_frame: &mut dyn FnMut(u64),
) -> Result<MethodUnit, Table1Error> {
    let start = Instant::now();
    let setup = row.setup()?;
    let mut renderer = pipeline_spec(spec, method, row.vpls, seed)?
        .build(registry, &crate::pipeline::backends(), &setup.scene)
        .map_err(|e| Table1Error::Invalid(e.to_string()))?;
    renderer.backend().check_size(spec.size).map_err(|e| Table1Error::Invalid(e.to_string()))?;
    let mut k = 0u64;
    let frames = run_sequence(&setup, run.start..run.end, Some(spec.size), &mut renderer, &row.pixels(spec.size), None, &mut |_, _| {
        k += 1;
        on_frame(k);
        Ok(())
    })
    .map_err(|e| Table1Error::Invalid(e.to_string()))?;
    let mut u = MethodUnit {
        settings: Some(UnitSettings::of(spec)),
        row: row.id.into(),
        method: method.into(),
        seed,
        frames: Vec::new(),
        tracked: Vec::new(),
        moved: Vec::new(),
        ms: Vec::new(),
        seconds: 0.0,
    };
    for f in frames {
        let t = f.timings;
        u.frames.push(f.index);
        u.tracked.push(f.tracked.iter().map(|c| c.to_array()).collect());
        u.moved.push(f.moved);
        u.ms.push([t.gbuffer_ms, t.sampling_ms, t.visibility_ms, t.shading_ms, t.total_ms]);
    }
    u.seconds = start.elapsed().as_secs_f64();
    Ok(u)
}

/// One method's errors on one row.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MethodResult {
    /// Method name.
    pub method: String,
    /// |E|, |E′| and the bias over every seed, frame and tracked pixel.
    pub error: TemporalError,
    /// Their 95 % confidence intervals ([`stats`]).
    pub intervals: stats::Intervals,
    /// The mean squared error split into bias² and noise (`None` with one seed).
    pub split: Option<stats::ErrorSplit>,
    /// |E| of each seed's run alone.
    pub e_per_seed: Vec<f64>,
    /// Tone-mapped luminance per seed, frame and tracked pixel.
    pub luminance: Vec<Vec<Vec<f64>>>,
    /// Median VPL slots moved per frame (after the first, over all seeds).
    pub median_moved: f64,
}

/// SMC against another method on one row: 95 % intervals of SMC − other.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// The other method.
    pub method: String,
    /// Intervals of the differences of |E|, |E′| and the bias.
    pub smc_minus: stats::Intervals,
}

/// One row's results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RowResult {
    /// Row id.
    pub id: String,
    /// Built-in scene.
    pub scene: String,
    /// VPL budget.
    pub vpls: usize,
    /// Frames `start..end`.
    pub frames: (u32, u32),
    /// Tracked pixels (in the run's image) and their labels.
    pub pixels: Vec<((u32, u32), String)>,
    /// Ground truth: tone-mapped luminance per frame and pixel.
    pub truth: Vec<Vec<f64>>,
    /// Mean standard error of the tone-mapped ground truth.
    pub truth_stderr: f64,
    /// Per method.
    pub methods: Vec<MethodResult>,
    /// SMC against each other method (empty when SMC did not run).
    pub comparisons: Vec<Comparison>,
}

/// The merged run: what `table1.json` holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Table1Results {
    /// The settings.
    pub spec: Table1Spec,
    /// Per row.
    pub rows: Vec<RowResult>,
}

/// Reads every unit of the run in `dir` and computes the table; errs
/// naming a missing unit.
/// Also returns the method units and what the full profile would take on
/// the machine of this run, from its measured costs (`None` where the full
/// profile's sequences cannot be read, or share none with the run).
pub fn collect(dir: &Path) -> Result<(Table1Results, Vec<MethodUnit>, Option<estimate::FullEstimate>), Table1Error> {
    let spec: Table1Spec = read_json(&dir.join("spec.json"))?;
    spec.validate_settings()?;
    let units = spec.units();
    let missing: Vec<String> = units.iter().map(|u| spec.unit_file(*u)).filter(|f| !dir.join(f).exists()).collect();
    if let Some(first) = missing.first() {
        return Err(Table1Error::Missing { dir: dir.into(), missing: missing.len(), total: units.len(), first: first.clone() });
    }
    let mut rows_out = Vec::new();
    let mut runs = Vec::new();
    let mut truth_seconds: estimate::TruthSeconds = Vec::new();
    let mut truth_device: Option<String> = None;
    for (ri, run) in spec.rows.iter().enumerate() {
        let mut row_truth = Some((0.0, 0.0));
        let row = rows::row(&run.id).expect("validated");
        let mut truth = Vec::new();
        let mut se_sum = 0.0;
        let mut se_n = 0usize;
        for f in run.start..run.end {
            let path = dir.join(spec.unit_file(Unit::Truth { row: ri, frame: f }));
            let t: TruthUnit = read_json(&path)?;
            check_unit(&path, &t.settings, &spec)?;
            check_finite(&path, "mean", &t.mean)?;
            check_finite(&path, "stderr", &t.stderr)?;
            if t.mean.len() != row.tracked.len() || t.stderr.len() != row.tracked.len() {
                return Err(Table1Error::Unit(
                    path,
                    format!("it holds {} pixels, the sequence tracks {}", t.mean.len(), row.tracked.len()),
                ));
            }
            let setup = t.setup_seconds.clamp(0.0, t.seconds);
            row_truth = row_truth.filter(|_| t.seconds > 0.0).map(|(a, b)| (a + setup, b + t.seconds - setup));
            truth_device = truth_device.or(t.device);
            truth.push(t.mean.iter().map(|m| tone_mapped_luminance(Vec3::from(*m))).collect::<Vec<f64>>());
            for (m, s) in t.mean.iter().zip(&t.stderr) {
                se_sum += tone_mapped_stderr(Vec3::from(*m), Vec3::from(*s));
                se_n += 1;
            }
        }
        truth_seconds.push(row_truth);
        let pixels = row.tracked.len();
        let draws = stats::Draws::new(spec.seeds as usize, pixels, spec.seed, ri as u64);
        let mut methods = Vec::new();
        let mut sums = Vec::new();
        for (mi, name) in spec.methods.iter().enumerate() {
            let mut lum = Vec::new();
            let mut err = Vec::new();
            let mut moved = Vec::new();
            for seed in 0..spec.seeds {
                let path = dir.join(spec.unit_file(Unit::Method { row: ri, method: mi, seed }));
                let u: MethodUnit = read_json(&path)?;
                check_unit(&path, &u.settings, &spec)?;
                check_finite(&path, "tracked value", u.tracked.iter().flatten())?;
                if !(u.seconds.is_finite() && u.ms.iter().flatten().all(|x| x.is_finite())) {
                    return Err(Table1Error::Unit(path, "a time is not a finite number".into()));
                }
                if u.frames.len() != truth.len() || u.tracked.iter().any(|f| f.len() != pixels) {
                    return Err(Table1Error::Unit(path, "frame or pixel count differs from the spec".into()));
                }
                let l: Vec<Vec<f64>> =
                    u.tracked.iter().map(|fr| fr.iter().map(|c| tone_mapped_luminance(Vec3::from(*c))).collect()).collect();
                err.push(l.iter().zip(&truth).map(|(a, b)| a.iter().zip(b).map(|(x, y)| x - y).collect::<Vec<f64>>()).collect::<Vec<_>>());
                lum.push(l);
                moved.extend(u.moved.iter().skip(1).map(|&m| m as f64));
                runs.push(u);
            }
            let series = stats::SeriesSums::new(&err).ok_or_else(|| Table1Error::Invalid(format!("{}: {name} has no errors", run.id)))?;
            let point = series.point();
            let e_per_seed = (0..series.seeds()).map(|k| series.seed(k).e).collect();
            let frames = truth.len();
            let seeds = spec.seeds as usize;
            let error = TemporalError {
                e: point.e,
                e_prime: point.e_prime,
                bias: point.bias,
                count: seeds * frames * pixels,
                count_prime: seeds * frames.saturating_sub(1) * pixels,
            };
            methods.push(MethodResult {
                method: name.clone(),
                error,
                intervals: draws.intervals(&series),
                split: stats::ErrorSplit::new(&err),
                e_per_seed,
                luminance: lum,
                median_moved: crate::stages::median(moved),
            });
            sums.push(series);
        }
        let comparisons = match spec.methods.iter().position(|m| m == "smc") {
            Some(k) => spec
                .methods
                .iter()
                .enumerate()
                .filter(|(i, m)| *i != k && !is_smc_variant(m))
                .map(|(i, m)| Comparison { method: m.clone(), smc_minus: draws.differences(&sums[k], &sums[i]) })
                .collect(),
            None => Vec::new(),
        };
        rows_out.push(RowResult {
            id: run.id.clone(),
            scene: row.scene.into(),
            vpls: row.vpls,
            frames: (run.start, run.end),
            pixels: row.pixels(spec.size).into_iter().zip(row.tracked.iter().map(|t| t.label.to_string())).collect(),
            truth,
            truth_stderr: if se_n > 0 { se_sum / se_n as f64 } else { 0.0 },
            methods,
            comparisons,
        });
    }
    let full_estimate = Table1Spec::full()
        .ok()
        .and_then(|full| estimate::estimate(&spec, &runs, &truth_seconds, &full))
        .map(|e| estimate::FullEstimate { truth_device, ..e });
    Ok((Table1Results { spec, rows: rows_out }, runs, full_estimate))
}

/// Units done and in all of one shard of a run ([`status`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardStatus {
    /// The shard.
    pub shard: Shard,
    /// Its units whose files are in the folder.
    pub done: usize,
    /// Its units.
    pub total: usize,
}

/// How far each of `count` shards of the run in `dir` has come: its units
/// whose files are written (a unit is written whole, atomically, so a
/// file is a finished unit).
pub fn status(dir: &Path, count: u32) -> Result<Vec<ShardStatus>, Table1Error> {
    if count == 0 {
        return Err(Table1Error::Invalid("a run has at least one shard".into()));
    }
    let spec: Table1Spec = read_json(&dir.join("spec.json"))?;
    let mut out: Vec<ShardStatus> = (0..count).map(|index| ShardStatus { shard: Shard { index, count }, done: 0, total: 0 }).collect();
    for (k, unit) in spec.units().into_iter().enumerate() {
        let s = &mut out[k % count as usize];
        s.total += 1;
        s.done += dir.join(spec.unit_file(unit)).is_file() as usize;
    }
    Ok(out)
}

/// Merges the run in `dir` and writes `table1.md`, `table1.csv`,
/// `table1.json`, `fig7_<row>.png` and `fig7.csv` there (the same bits
/// from any sharding), and the wall times: `runs.csv` and `cost.md`.
pub fn merge(dir: &Path) -> Result<Table1Results, Table1Error> {
    Ok(merge_with_cost(dir)?.0)
}

/// [`merge`], also returning the estimate of the full profile written to `cost.md`.
pub fn merge_with_cost(dir: &Path) -> Result<(Table1Results, Option<estimate::FullEstimate>), Table1Error> {
    let (results, runs, cost) = collect(dir)?;
    report::write(dir, &results, &runs, cost.as_ref())?;
    Ok((results, cost))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn methods_take_settings_after_colons() {
        let m = MethodSpec::parse("smc:flux=knn-calibrated:placement=centroid").unwrap();
        assert_eq!(m.sampler, "smc");
        assert_eq!(m.settings, vec![("flux".into(), "knn-calibrated".into()), ("placement".into(), "centroid".into())]);
        assert_eq!(MethodSpec::parse("ir").unwrap().settings, vec![]);
        assert!(MethodSpec::parse("smc:flux").is_err() && MethodSpec::parse("smc:=x").is_err());
        assert_eq!(MethodSpec::file_stem("smc:flux=knn"), "smc+flux=knn");
        assert!(is_smc_variant("smc:flux=knn") && is_smc_variant("smc-knn") && !is_smc_variant("smc"));
        assert_eq!(report::display_name("smc:flux=knn:placement=centroid"), "SMC (flux=knn, placement=centroid)");
        // A setting the sampler does not read is refused when the renderer is built.
        let spec = Table1Spec::quick();
        let p = pipeline_spec(&spec, "smc:flux=voronoi-site", 64, 0).unwrap();
        assert_eq!(p.sampler, "smc");
        let scene = vpl_core::SceneSetup::builtin("cornell").unwrap().scene;
        assert!(p.build(&Registry::builtin(), &crate::pipeline::backends(), &scene).is_ok());
        let bad = pipeline_spec(&spec, "ir:flux=knn", 64, 0).unwrap();
        assert!(bad.build(&Registry::builtin(), &crate::pipeline::backends(), &scene).is_err());
    }
}
