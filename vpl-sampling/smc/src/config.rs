//! Settings of the SMC sampler, with the paper's defaults.

use crate::ball_area::ProbeArea;
use crate::flux::{AreaProbes, FluxEstimator, ProbeWindow, flux_param};
use crate::placement::Placement;
use crate::relight::Relight;
use vpl_core::{Budget, ParamError, ParamKey, Params};
use vpl_density::rendering_k;

/// Settings of [`crate::SmcSampler`]. The defaults are the paper's (§3.2, §4):
/// I = 2048, M_max = 16, 16:1 resampling with at most 8 retries, 16 radiosity
/// paths, k from eq. (8), 100 warm-up iterations, V = 16 visibility rays in
/// two iterations, and the 95 % quantile of eq. (9).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmcConfig {
    /// The VPL budget I.
    pub vpls: usize,
    /// M_max: VPLs allowed to move per frame (line 13 of Algorithm 1).
    pub m_max: usize,
    /// Ray hits per candidate: 16·I hits are resampled to I candidates (§3.2.1).
    pub resample_ratio: usize,
    /// Retries of a resampling draw that lands on a hit already taken.
    pub max_retries: u32,
    /// Paths per radiosity estimate (§3.2.3).
    pub radiosity_paths: u32,
    /// Scattering vertices after y in those paths: `max_depth − 3`
    /// (2 for three indirect bounces).
    pub radiosity_bounces: u32,
    /// k of the densities that weight rendered VPLs; `None`: eq. (8),
    /// `max(1, ⌊√(I/32)⌋)`.
    pub knn_k: Option<usize>,
    /// Iterations run before the first frame.
    pub warmup: u32,
    /// V: rays toward each VPL whose mailbox point the camera lost, per iteration (§3.2.2).
    pub visibility_rays: usize,
    /// Iterations of those rays per frame.
    pub visibility_iterations: u32,
    /// Candidates stronger than this quantile of the VPL intensities are
    /// counted as M_strong (eq. 9).
    pub strong_quantile: f32,
    /// The area each VPL stands for in its flux ([`FluxEstimator`]).
    pub flux: FluxEstimator,
    /// T: iterations of candidate-ray hits that measure the Voronoi cells.
    pub probe_iterations: usize,
    /// Area probes kept per VPL and iteration, of the resample ratio's
    /// hits (all of them when it is at least the ratio).
    pub probes_per_vpl: usize,
    /// How the T iterations of probes are weighted ([`ProbeWindow`]).
    pub probe_window: ProbeWindow,
    /// What a probe's ball stands for ([`ProbeArea`]).
    pub probe_area: ProbeArea,
    /// Where in its Voronoi cell a VPL shines from ([`Placement`]).
    pub placement: Placement,
    /// How the cells' mean radiances follow moving lights ([`Relight`]).
    pub relight: Relight,
    /// Paths of each candidate's relighting estimate ([`Relight::Candidates`]).
    pub relight_paths: u32,
    /// Bounces after the candidate in those paths (0: its direct light);
    /// `None`: the radiosity paths' (`radiosity_bounces`).
    pub relight_bounces: Option<u32>,
}

impl Default for SmcConfig {
    fn default() -> Self {
        SmcConfig {
            vpls: 2048,
            m_max: 16,
            resample_ratio: 16,
            max_retries: 8,
            radiosity_paths: 16,
            radiosity_bounces: 2,
            knn_k: None,
            warmup: 100,
            visibility_rays: 16,
            visibility_iterations: 2,
            strong_quantile: 0.95,
            flux: FluxEstimator::default(),
            probe_iterations: 16,
            probes_per_vpl: 3,
            probe_window: ProbeWindow::default(),
            probe_area: ProbeArea::default(),
            placement: Placement::default(),
            relight: Relight::default(),
            relight_paths: 1,
            relight_bounces: None,
        }
    }
}

impl SmcConfig {
    /// The k of rendered VPLs' densities: the configured one or eq. (8).
    pub fn k(&self) -> usize {
        self.knn_k.unwrap_or_else(|| rendering_k(self.vpls))
    }

    /// Whether the sampler measures Voronoi cells with area probes: for the
    /// flux ([`FluxEstimator::probes`]) or for the placement.
    pub fn probes(&self) -> bool {
        self.flux.probes() || self.placement != Placement::Site
    }

    /// Bytes the sampler keeps beyond its VPLs: the area probes of the
    /// Voronoi cells, T iterations of I × min(probes per VPL, resample
    /// ratio) hits and the I candidates (none for the kNN flux at the sites).
    pub fn probe_memory(&self) -> u64 {
        if !self.probes() {
            return 0;
        }
        (self.vpls as u64)
            .saturating_mul(self.probes_per_vpl.min(self.resample_ratio) as u64 + 1)
            .saturating_mul(self.probe_iterations as u64)
            .saturating_mul(AreaProbes::BYTES_PER_PROBE)
    }

    /// Bounces of the candidates' relighting paths: the configured ones or
    /// the radiosity paths'.
    pub fn relight_bounces(&self) -> u32 {
        self.relight_bounces.unwrap_or(self.radiosity_bounces)
    }

    /// Area probes kept per iteration.
    pub fn probes_per_iteration(&self) -> usize {
        self.vpls.saturating_mul(self.probes_per_vpl)
    }

    /// Checks the settings.
    pub fn validate(&self) -> Result<(), SmcError> {
        if self.vpls == 0 {
            return Err(SmcError::Invalid("the VPL budget must be at least 1"));
        }
        if self.resample_ratio == 0 {
            return Err(SmcError::Invalid("the resample ratio must be at least 1"));
        }
        if self.radiosity_paths == 0 {
            return Err(SmcError::Invalid("radiosity needs at least 1 path"));
        }
        if self.knn_k == Some(0) {
            return Err(SmcError::Invalid("k must be at least 1"));
        }
        if !(self.strong_quantile > 0.0 && self.strong_quantile <= 1.0) {
            return Err(SmcError::Invalid("the strong quantile must be in (0, 1]"));
        }
        if self.probe_iterations == 0 {
            return Err(SmcError::Invalid("the area probes need at least 1 iteration"));
        }
        if self.relight_paths == 0 {
            return Err(SmcError::Invalid("relighting needs at least 1 path"));
        }
        if self.probes_per_vpl == 0 {
            return Err(SmcError::Invalid("the area probes need at least 1 probe per VPL"));
        }
        if self.flux == FluxEstimator::VoronoiNear && self.placement != Placement::Site {
            return Err(SmcError::Invalid("flux=voronoi-near measures its cells at the VPLs' own points: it needs placement=site"));
        }
        if self.vpls.checked_mul(self.resample_ratio).is_none_or(|n| n > 1 << 28) {
            return Err(SmcError::Invalid("I times the resample ratio must be at most 2^28"));
        }
        Ok(())
    }
}

/// Errors of [`crate::SmcSampler::new`].
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum SmcError {
    /// A setting is out of range.
    #[error("invalid SMC settings: {0}")]
    Invalid(&'static str),
}

impl SmcConfig {
    /// The keys [`SmcConfig::from_params`] reads.
    pub const KEYS: &'static [ParamKey] = &[
        ParamKey { key: "m-max", default: "16", about: "M_max: VPLs allowed to move per frame (Alg. 1, line 13)" },
        ParamKey { key: "resample-ratio", default: "16", about: "candidate-ray hits per candidate (16·I hits resampled to I)" },
        ParamKey { key: "radiosity-paths", default: "16", about: "path-traced NEE paths per radiosity estimate" },
        ParamKey { key: "knn-k", default: "max(1, ⌊√(I/32)⌋)", about: "k of the rendered VPLs' densities (eq. 8)" },
        ParamKey { key: "warmup", default: "100", about: "iterations before the first frame" },
        ParamKey { key: "max-retries", default: "8", about: "retries of a resampling draw that lands on a taken hit" },
        ParamKey { key: "visibility-rays", default: "16", about: "V: rays toward a VPL whose mailbox point was lost" },
        ParamKey { key: "visibility-iterations", default: "2", about: "rounds of those rays per frame" },
        ParamKey {
            key: "strong-quantile",
            default: "0.95",
            about: "quantile of the VPL intensities above which a candidate is strong (eq. 9)",
        },
        ParamKey {
            key: "flux",
            default: "voronoi-near (voronoi with a placement other than site)",
            about: "area per VPL in its flux: voronoi (cells measured by candidate hits), voronoi-near (the cell's probes, each standing for the area of those near the VPL), voronoi-site (the cell's area times the VPL's own radiance), knn (the paper's eq. 7) or knn-calibrated",
        },
        ParamKey { key: "probe-iterations", default: "16", about: "T: iterations of candidate hits that measure the Voronoi cells" },
        ParamKey {
            key: "probes-per-vpl",
            default: "4",
            about: "candidate hits per VPL and iteration kept as area probes (all of them from the resample ratio up)",
        },
        ParamKey {
            key: "probe-area",
            default: "disk",
            about: "what a probe's ball to its nearest neighbour stands for: disk (π r², exact on a plane), surface (the scene's surface inside the ball, exact at edges and in corners too) or smooth (neighbours and surface on the probe's own smooth surface, within 60°)",
        },
        ParamKey {
            key: "probe-window",
            default: "triangle",
            about: "weights of the T iterations of probes: triangle (rising and falling, a cell changes smoothly) or box (all alike)",
        },
        ParamKey {
            key: "placement",
            default: "site",
            about: "where a VPL shines from in its Voronoi cell: site (its own point, the paper's), centroid (the cell's probe nearest its centroid) or random (a probe of its cell drawn by area when it joins)",
        },
        ParamKey {
            key: "relight",
            default: "candidates",
            about: "how the cells' radiances follow moving lights: candidates (by the change of their candidates' short estimates), ratio (by their VPL's change) or none",
        },
        ParamKey { key: "relight-paths", default: "1", about: "paths of each candidate's relighting estimate" },
        ParamKey {
            key: "relight-bounces",
            default: "the radiosity paths'",
            about: "bounces after the candidate in those paths (0: its direct light alone)",
        },
    ];

    /// [`SmcConfig::from_params`] with the paper's flux estimator: the kNN
    /// densities (eq. 5 and 7) at the VPLs' own points, unless `p` sets
    /// `flux` or `placement` (the `smc-knn` sampler's settings).
    pub fn paper_from_params(budget: &Budget, p: &Params) -> Result<SmcConfig, ParamError> {
        let mut config = SmcConfig::from_params(budget, p)?;
        config.flux = p.get_or("flux", FluxEstimator::Knn)?;
        config.placement = p.get_or("placement", Placement::Site)?;
        Ok(config)
    }

    /// The settings of `budget` (I and the radiosity paths' bounces,
    /// `max_depth − 3`) with the paper's defaults, changed by `p`'s keys
    /// ([`SmcConfig::KEYS`]).
    pub fn from_params(budget: &Budget, p: &Params) -> Result<SmcConfig, ParamError> {
        let d = SmcConfig::default();
        let strong_quantile = p.get_or("strong-quantile", d.strong_quantile)?;
        if !(strong_quantile > 0.0 && strong_quantile <= 1.0) {
            return Err(p.out_of_range("strong-quantile", strong_quantile, "in (0, 1]"));
        }
        let knn_k = p.get::<usize>("knn-k")?;
        let placement = p.get_or("placement", d.placement)?;
        if knn_k == Some(0) {
            return Err(p.out_of_range("knn-k", 0, "at least 1"));
        }
        Ok(SmcConfig {
            vpls: budget.vpls,
            m_max: p.get_or("m-max", d.m_max)?,
            resample_ratio: p.count_or("resample-ratio", d.resample_ratio, 1)?,
            max_retries: p.get_or("max-retries", d.max_retries)?,
            radiosity_paths: p.count_or("radiosity-paths", d.radiosity_paths, 1)?,
            radiosity_bounces: budget.radiosity_bounces(),
            knn_k,
            warmup: p.get_or("warmup", d.warmup)?,
            visibility_rays: p.get_or("visibility-rays", d.visibility_rays)?,
            visibility_iterations: p.get_or("visibility-iterations", d.visibility_iterations)?,
            strong_quantile,
            flux: flux_param(p, placement)?,
            probe_iterations: p.count_or("probe-iterations", d.probe_iterations, 1)?,
            probes_per_vpl: p.count_or("probes-per-vpl", d.probes_per_vpl, 1)?,
            probe_window: p.get_or("probe-window", d.probe_window)?,
            probe_area: p.get_or("probe-area", d.probe_area)?,
            placement,
            relight: p.get_or("relight", d.relight)?,
            relight_paths: p.count_or("relight-paths", d.relight_paths, 1)?,
            relight_bounces: match p.get::<u32>("relight-bounces")? {
                Some(b) => Some(p.count_or("relight-bounces", b, 0)?),
                None => None,
            },
        })
    }
}
