//! Settings of the progressive renderer, with the paper's defaults (§7).

use crate::error::ProgressiveError;
use vpl_core::GeometryClamp;

/// Stochastic VPL culling (§5.1.1): before a VPL is stored, shadow rays test
/// it against a Halton-chosen subset of the pass's eye vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Culling {
    /// Every VPL is stored.
    Off,
    /// A VPL that no representative sees is still kept with probability
    /// `accept`, its flux divided by `accept`: the expected image is unchanged.
    Unbiased {
        /// Acceptance probability of an unseen VPL, in (0, 1].
        accept: f32,
    },
    /// A VPL that no representative sees is dropped (biased, darker where
    /// the representatives miss).
    Deterministic,
}

/// How the pass's VPLs are gathered at each eye vertex (§5.1, Fig. 3c).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Gathering {
    /// Every stored VPL at every eye vertex (the paper's).
    Exhaustive,
    /// A stochastic lightcut a vertex (`crate::lightcut`): `cut` VPLs
    /// sampled through a light tree over the pass's VPLs, each term divided
    /// by its probability (and `cut` of the sun's and the sky's VPLs, drawn
    /// uniformly).
    /// Unbiased against [`Gathering::Exhaustive`]; what lets a pass hold
    /// 64K–1M VPLs (many light paths) at a cost that grows with `cut`.
    Lightcuts {
        /// Surface VPLs sampled a vertex (at least 1).
        cut: usize,
    },
}

impl Gathering {
    /// The cut of `lightcuts` without a number.
    pub const DEFAULT_CUT: usize = 32;
}

impl std::fmt::Display for Gathering {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Gathering::Exhaustive => f.write_str("exhaustive"),
            Gathering::Lightcuts { cut } => write!(f, "lightcuts:{cut}"),
        }
    }
}

impl std::str::FromStr for Gathering {
    type Err = ProgressiveError;
    /// `exhaustive`, `lightcuts` (cut [`Gathering::DEFAULT_CUT`]) or `lightcuts:N`, N ≥ 1.
    fn from_str(s: &str) -> Result<Gathering, ProgressiveError> {
        match s {
            "exhaustive" => Ok(Gathering::Exhaustive),
            "lightcuts" => Ok(Gathering::Lightcuts { cut: Gathering::DEFAULT_CUT }),
            _ => match s.strip_prefix("lightcuts:").map(str::parse::<usize>) {
                Some(Ok(cut)) if cut >= 1 => Ok(Gathering::Lightcuts { cut }),
                _ => {
                    Err(ProgressiveError::Config(format!("gathering '{s}' must be 'exhaustive', 'lightcuts' or 'lightcuts:N' with N ≥ 1")))
                }
            },
        }
    }
}

/// Which bins a caustic photon falls into (§5.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinRule {
    /// The closest bin only, if the photon lies within its radius (the
    /// paper's rule: bins never overlap; biased dark where they would).
    Closest,
    /// Every bin whose radius reaches the photon (overlapping disks, each
    /// bin an unclipped disk average).
    AllWithin,
}

/// The disjoint path classes of §3 and which ones a render adds.
///
/// Every path E(S|D)*L belongs to exactly one class; summing the images of
/// the four classes gives the full image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Techniques {
    /// ES*L: eye paths that reach a light through specular vertices only (or directly).
    pub direct: bool,
    /// EDL and EDD(S|D)*L: VPLs at eye vertices seen directly.
    pub vpl: bool,
    /// EDS(S|D)*L: caustic histograms at eye vertices seen directly.
    pub caustics: bool,
    /// ES+D(S|D)*L: VPLs and caustic histograms at eye vertices seen through
    /// specular bounces (specular gathering, §5.2).
    pub specular_gathering: bool,
}

impl Techniques {
    /// All four classes: the full image.
    pub const ALL: Techniques = Techniques { direct: true, vpl: true, caustics: true, specular_gathering: true };
    /// No class.
    pub const NONE: Techniques = Techniques { direct: false, vpl: false, caustics: false, specular_gathering: false };

    /// Parses a comma-separated list of `direct`, `vpl`, `caustics`,
    /// `specular` (or `all`).
    pub fn parse(s: &str) -> Result<Techniques, ProgressiveError> {
        let mut t = Techniques::NONE;
        for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            match part {
                "all" => t = Techniques::ALL,
                "direct" => t.direct = true,
                "vpl" => t.vpl = true,
                "caustics" => t.caustics = true,
                "specular" => t.specular_gathering = true,
                other => {
                    return Err(ProgressiveError::Config(format!(
                        "unknown technique '{other}' (known: direct, vpl, caustics, specular, all)"
                    )));
                }
            }
        }
        if t == Techniques::NONE {
            return Err(ProgressiveError::Config("no technique selected".into()));
        }
        Ok(t)
    }
}

/// Settings of [`crate::Progressive`].
#[derive(Clone, Debug, PartialEq)]
pub struct ProgressiveConfig {
    /// Longest path in segments (Mitsuba 3's convention, as everywhere in the toolkit).
    pub max_depth: u32,
    /// VPL light paths per pass (§7: 16).
    pub vpl_paths: usize,
    /// Caustic photon paths per pass (§7: 100 000).
    pub caustic_paths: usize,
    /// Stochastic VPL culling (§5.1.1).
    pub culling: Culling,
    /// Eye vertices the culling tests against (§5.1.1: 256).
    pub representatives: usize,
    /// Clamp of the geometry term between an eye vertex and a non-primary
    /// VPL (§8: the bias of bounding G); `None` keeps the estimate unbiased.
    pub clamp: Option<GeometryClamp>,
    /// Vertices after which Russian roulette ends eye and light paths.
    pub rr_depth: u32,
    /// Aim caustic photons with projection maps (§5.3.1).
    pub projection_maps: bool,
    /// Projection map size (rows over θ, columns over φ; §5.3.1: 128 × 256).
    pub map_size: (usize, usize),
    /// Emit caustic photons from every VPL, not only the primary ones on the
    /// lights. §8 makes these indirect caustics (EDS+D+L) optional; they are
    /// on by default here so that the sum of the techniques is the full
    /// image.
    pub indirect_caustics: bool,
    /// Lazy spectral rendering of dispersive materials (§6).
    pub spectral: bool,
    /// Which bins a caustic photon falls into (§5.3: the closest).
    pub bins: BinRule,
    /// Which path classes the image gets.
    pub techniques: Techniques,
    /// How the VPLs are gathered at the eye vertices.
    pub gathering: Gathering,
    /// Seed of every random stream.
    pub seed: u64,
}

impl Default for ProgressiveConfig {
    fn default() -> Self {
        Self {
            max_depth: 5,
            vpl_paths: 16,
            caustic_paths: 100_000,
            culling: Culling::Unbiased { accept: 0.125 },
            representatives: 256,
            clamp: None,
            rr_depth: 5,
            projection_maps: true,
            map_size: (128, 256),
            indirect_caustics: true,
            spectral: true,
            bins: BinRule::Closest,
            techniques: Techniques::ALL,
            gathering: Gathering::Exhaustive,
            seed: 0,
        }
    }
}

impl ProgressiveConfig {
    /// Checks the settings.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > y)` is meant: a NaN fails the test
    pub fn validate(&self) -> Result<(), ProgressiveError> {
        let bad = |m: &str| Err(ProgressiveError::Config(m.into()));
        if self.max_depth == 0 {
            return bad("max_depth must be at least 1");
        }
        if self.vpl_paths == 0 {
            return bad("vpl_paths must be at least 1");
        }
        if let Culling::Unbiased { accept } = self.culling {
            if !(accept > 0.0 && accept <= 1.0) {
                return bad("the culling acceptance probability must lie in (0, 1]");
            }
        }
        if self.culling != Culling::Off && self.representatives == 0 {
            return bad("culling needs at least one representative eye vertex");
        }
        if self.map_size.0 < 2 || self.map_size.1 < 4 || self.map_size.0 * self.map_size.1 > 1 << 22 {
            return bad("projection maps need 2..=4M cells, at least 2 rows and 4 columns");
        }
        if self.gathering == (Gathering::Lightcuts { cut: 0 }) {
            return bad("a lightcut gathers at least one VPL");
        }
        if let Some(c) = self.clamp {
            if !(c.g_max > 0.0) {
                return bad("the geometry clamp must be positive");
            }
        }
        Ok(())
    }
}
