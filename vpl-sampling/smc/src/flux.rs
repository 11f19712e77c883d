//! The flux each VPL carries: the light of the piece of surface it stands for.
//!
//! A VPL at y with flux Φ lights a point x with Φ f(x) G(x, y), so the set Y
//! estimates the integral over the surfaces the VPLs lie on,
//!
//! ```text
//! Σ_i Φ_i f(x) G(x, y_i)  ≈  ∫ L(y) f(x) G(x, y) dA(y).                 (1)
//! ```
//!
//! ## The paper's estimator and its bias
//!
//! The paper (eq. 5) sets Φ = L(y) / (n p(y)) with p from the k nearest VPLs
//! (eq. 7): Φ = L(y) π r_k(y)² / k, each VPL standing for the area π r_k² / k
//! ([`FluxEstimator::Knn`]). For independently drawn points that is right
//! on average: among Poisson points n p π r_k² is Gamma(k)-distributed, so
//! E[π r_k² / k] = 1 / (n p). SMC's set is not drawn independently, and
//! unclamped, ray-traced images at I = 2048 come out 15 % too bright on
//! `cornell`, 32 % on `atrium`, 25 % on Dabrovic's Sponza and 19 % on the
//! Munich blocks. Two causes, measured apart:
//!
//! 1. **The areas.** SMC removes the weakest VPLs (the densest) and adds
//!    candidates where the set is sparse, so the set is more regular than a
//!    random one, and in a regular set the k-th neighbour lies further out:
//!    on a hexagonal lattice with k = 8, π r_8² / 8 is 1.36 times the area
//!    per point (on a square lattice 0.79: the error has no fixed sign).
//!    The balls also spill over the edges of surfaces and take in other
//!    surfaces at corners. Summed over the set, the kNN areas are 0.87 (on
//!    `atrium`) to 1.8 (the Munich blocks) times the area the Voronoi cells
//!    below tile.
//! 2. **Where in its piece of surface a VPL sits.** The set is denser where
//!    L is larger, so a VPL's neighbours lie more on its bright side than on
//!    its dark side: its cell reaches further into the dark, and L(y) at the
//!    VPL exceeds the cell's mean radiance. Even with the cells' areas, the
//!    VPL's own radiance ([`FluxEstimator::VoronoiSite`]) leaves images too
//!    bright by 16 % on `atrium`, 7 % on `office`, 6 % on `courtyard`.
//!
//! ## The cell estimator
//!
//! [`FluxEstimator::Voronoi`] gives each VPL the light of its cell,
//! whatever point of the cell it sits on (the default,
//! [`FluxEstimator::VoronoiNear`], builds on it: "Seen from the VPL" below):
//!
//! ```text
//! Φ_i = |V_i| · L̄(V_i),                                                  (2)
//! ```
//!
//! |V_i| the area of the VPL's Voronoi cell on the surfaces the camera
//! points' rays reach, L̄ the mean radiance of the candidates that fell in
//! it. The cells tile those surfaces, so the fluxes sum to the surfaces'
//! total light for any arrangement of the set, and (1) becomes a quadrature
//! whose only error is how much f G varies inside a cell, and so where in
//! its cell the VPL shines from: [`crate::Placement`] puts it near the
//! cell's centroid, which removes that error's first-order term.
//!
//! Both parts are measured with probes, the candidate-ray hits of the last
//! T iterations ([`AreaProbes`]):
//!
//! - **Area.** The N hits of one iteration are independent draws from some
//!   density p_h over the surfaces the rays reach; hit h stands for
//!   b_h = π r_1² (N − 1) / N, r_1 the distance to the nearest other hit on
//!   the same side of the surface, whose expectation is 1 / (N p_h): for
//!   N − 1 Poisson points, (N − 1) p_h π r_1² is Exp(1)-distributed. k = 1
//!   keeps r_1, and the error where p_h changes or the surface ends within
//!   it, as small as the hits allow. |V_i| sums b over the cell's probes and
//!   takes a weighted mean over the T iterations ([`ProbeWindow`]: by
//!   default a parabola, (b + 1)(T − b), so that each iteration comes in
//!   and goes out gradually, with the least frame-to-frame change of any
//!   such window; the weights sum to 1, so the sum stays unbiased
//!   and the cells still partition it). With every hit kept each cell is
//!   measured by about 16·T hits. Fewer probes per VPL (`probes-per-vpl`
//!   below the resample ratio; 3 by default) keep every s-th hit, each
//!   standing for s b (the hits come in the random order of their camera
//!   points, so the sum stays unbiased), and the candidates among the
//!   others for their radiance alone. 4 a VPL cut the cells' cost on
//!   `office` (I = 2048, 2 cores) from 25 to 8 ms a frame, and 3 saves
//!   another 2–4 ms of the step (6,144 new probes an iteration, not 8,192;
//!   the image means the same within their errors, `docs/performance.md`;
//!   the flicker test 0.965 % a frame with the triangle window against
//!   0.93 % with 4, and 0.878 % with the parabola); with equal
//!   weights the noisier areas made a static view's image change by 0.87 %
//!   a frame (every hit: 0.61 %; `cornell`, 1024 VPLs, 20 frame pairs),
//!   near SMC's 1 %, and the triangle takes it to 0.68 % (every hit:
//!   0.53 %). Pooling instead groups of 4 near hits on one surface into one
//!   probe standing for their summed b (exact total area, 0.80 % a frame)
//!   brightened the images: `atrium` 1.030 and the Munich blocks 1.141 of
//!   path tracing against 1.025 and 1.038, as a group's whole area follows
//!   the visibility and the cell of its first hit.
//! - **Radiance.** Candidates are drawn from the hits with weights w_h =
//!   r_1² (line 6, r_1 to the nearest other hit in 3D), meant to spread
//!   them evenly over area, but without replacement: a draw that lands on a
//!   hit already taken is drawn again, so a heavy hit (a sparse region) is
//!   taken once however often it is hit and its share goes to light ones.
//!   Their plain mean is no area mean: over one iteration's candidates,
//!   times the hits' area, it gave 0.78–1.45 of Σ_h b_h L_h (`atrium`,
//!   Sponza). Each draw's *first* landing, though, is a draw with
//!   probability w_h / Σw, and always lands on a candidate; with c_h the
//!   first landings on candidate h, Σ_h c_h b_h L_h Σw / (draws · w_h)
//!   (= Σ_h c_h b_h L_h / (draws · p_h))
//!   estimates ∫ L dA without bias (Horvitz–Thompson with replacement;
//!   [`vpl_core::resample::resample_counted`]; the light the candidates
//!   carry, [`AreaProbes::candidate_light`]). A cell's L̄ is the same
//!   weighting inside the cell: Σ c_h b_h L_h / w_h over Σ c_h b_h / w_h,
//!   a ratio estimate of the cell's mean radiance over area. Every
//!   candidate counts, chosen or not, with the estimate it was drawn with:
//!   the weights do not depend on the radiances, so the candidates' light
//!   summed over all of them is unbiased whichever were kept. (Giving the
//!   candidates that joined the set their VPL's second estimate instead,
//!   as the kept ones' first estimates run high, took that excess out and
//!   left the rest's deficit: the cells' light came out 1–5 % under the
//!   probes' own radiances on `maze`, whose sequence was 0.967 of path
//!   tracing and is 0.989 without it.) A cell no weighted candidate fell in takes their plain
//!   mean, and one no candidate fell in the VPL's own radiance. The
//!   candidates keep the radiance of the lighting they were estimated in:
//!   under moving lights L̄ lags by T/2 iterations on average, while the
//!   VPL's own radiance is estimated anew at once, as the paper does, with
//!   the same random numbers each frame. So the cell's mean is brought
//!   to the lights of now ([`crate::Relight`]): by default each cell moves
//!   by the change of its candidates' short radiance estimates under common
//!   random numbers ([`Cell::relit_radiance`]), which took `building`'s
//!   sequence, whose lamp is carried from room to room, from 1.063 to 1.022
//!   of path tracing; scaling the mean by its VPL's own change,
//!   L̄ · Y_i(now) / Ȳ_i(then) ([`Cell::current_radiance`]), gave 1.063
//!   (a VPL that joined within the window has no record of the iterations
//!   before it, and one point does not change as its cell does).
//!   Σ Φ then
//!   equals the candidates' light and an independent estimate of ∫ L dA
//!   within their standard errors on every built-in scene and both real
//!   ones (`tests/tests/smc_flux.rs`); with the plain mean it was 2.8 %
//!   over on `atrium` (frame 360) and 3.7 % on Sponza (frame 0), 5 and 4
//!   standard errors.
//! - **Which cell.** A probe joins the nearest VPL on the same side of the
//!   surface *that it can see* (one shadow ray), trying first the VPLs on
//!   its own smooth surface (normals within 60°), then those around an edge
//!   (within 120°), four of each, and last the VPLs that own its nearest
//!   owned neighbours (four probes of its iteration on its own surface),
//!   in rounds until a round adds no probe (at most 16), so that a cell
//!   grows along its surface around what hides it: the four nearest VPLs
//!   can all stand behind a column or a balustrade while the one whose cell
//!   holds the surface next to the probe sees it. A probe that sees none
//!   of these joins the cell of its nearest owned probe on its surface
//!   (unseen: the light stays where the surface is), else its nearest VPL
//!   on its side of the surface, else its nearest VPL, so the cells
//!   **partition** the probes: every usable probe
//!   (a hit with an area) belongs to exactly one cell, the cells' areas sum
//!   to the probes' area and their light to the light the candidates
//!   carry, for any set (tested). Without the last step 2.4 % of the
//!   candidates' light on Dabrovic's Sponza and 5 % on the Munich blocks
//!   (frame 0, I = 2048) belonged to no cell and was lost; with the VPLs
//!   at their cells' centroids ([`crate::Placement::Centroid`]) Sponza's
//!   image was 0.970 of the path tracer's, 0.978 with the neighbours, and
//!   1.002 ± 0.004 with the whole partition (the Munich blocks 1.038 ±
//!   0.013; with the nearest VPL on the side as the last step instead of
//!   the nearest owned probe's cell, 1.008 and 1.045: the light of a probe
//!   whose owner cannot see it is conserved, but shines from the owner's
//!   place). Without the sides, the back of a thin
//!   wall, lit from a room, would take a corridor VPL's cell; without the
//!   visibility, the floor of a room behind a wall, which the camera
//!   glimpses through a door, would lend its area to a corridor VPL beside
//!   the wall (`office` 9 % too bright); without trying the own surface
//!   first, a box's side would fall to the VPLs on its top, hidden behind
//!   the edge, and be lost (`cornell` 3 % too dark).
//!
//! ## Seen from the VPL
//!
//! The cells make Σ Φ right; the image needs more. With W(y) the mean over
//! the pixels of f(x) G(x, y) V(x, y), what a VPL of unit flux at y adds to
//! the image mean, the set renders Σ_i Φ_i W(y_i) against the truth
//! ∫ L W dA, and the cell flux leaves, cell by cell,
//!
//! ```text
//! ∫_{V_i} L(y) (W(y_i) − W(y)) dA(y).                                     (3)
//! ```
//!
//! SMC puts its VPLs where W is large (they come from the camera points'
//! rays), so a VPL sits on the side of its cell where W is larger, and its
//! cell reaches into the sparser part where W is smaller: (3) is positive
//! for most cells, and most on scenes whose W changes much across a cell
//! (the Munich blocks: 1.109 ± 0.016 of the path tracer's image mean at
//! frame 0 over 16 seeds, while their fluxes sum to ∫ L dA).
//!
//! The probes measure W. The candidate rays leave the camera points X
//! cosine-distributed, so their hits have the area density
//! p_h(y) = Σ_x cos θ_x cos θ_y V(x, y) / (π |X| |x − y|²), which is W up
//! to the camera points' albedo and one constant. A probe stands for
//! b_h ≈ 1 / (N p_h): where hits are dense, probes stand for little area.
//! So a cell whose n_i probes each stood for the area b(y_i) of the probes
//! at its VPL,
//!
//! ```text
//! Φ_i = L̄(V_i) · n_i · b(y_i),   Φ_i W(y_i) ∝ L̄(V_i) · n_i / N ≈ L̄(V_i) ∫_{V_i} p_h dA,   (4)
//! ```
//!
//! shows the camera the light of its cell weighted by W over the cell, not
//! by W at its VPL: (3) vanishes to the extent L̄ and W do not vary together
//! inside the cell. [`FluxEstimator::VoronoiNear`] takes b(y_i) as the
//! weighted mean area of the [`NEAR_SHARE`] of the cell's area probes
//! nearest the VPL (at least [`NEAR_MIN`]): the cell's flux (2) times the
//! ratio of that mean to the cell's mean ([`AreaProbes::near_ratios`]),
//! blended over the VPL's frames ([`NEAR_BLEND`]) so that the image stays
//! as still as the cells keep it. Where
//! hits are spread evenly over a cell the ratio is 1 and the flux the
//! cell's. The probes near the VPL are its cell's, so an edge or an
//! occluder bounds them as it bounds the cell (a kNN ball around the VPL
//! would spill over both). The fluxes no longer sum to ∫ L dA: their
//! weighted sum Σ Φ_i W(y_i) is what they keep, which is the image mean.
//!
//! Measured (`vpl energy`, 16 seeds, frame 0, 48×36, the truth at 256 paths
//! a pixel; unclamped, ray-traced, exhaustive, indirect only; the cell
//! flux, then this one): the Munich blocks 1.109 ± 0.016 and 0.996 ±
//! 0.017, Dabrovic's Sponza 1.023 ± 0.007 and 1.000 ± 0.004, `atrium`
//! 1.004 ± 0.005 and 0.983 ± 0.005, `office` 1.020 ± 0.009 and 0.989 ±
//! 0.005, `glass` 1.016 and 1.018, `colonnade` 0.976 and 0.975, and within
//! 0.7 % of each other on `cornell`, `corner`, `building`, `maze` and
//! `courtyard`.
//!
//! Only the output flux uses the cells; every keep, remove and add decision
//! still uses the paper's kNN intensities (eq. 6), so the set evolves as
//! the paper's does.

use crate::ball_area::ProbeArea;
use crate::points::{first_passing, resolve};
use rayon::prelude::*;
use std::collections::{HashSet, VecDeque};
use vpl_core::ParamError;
use vpl_core::glam::{DVec3, Vec3};
use vpl_core::params::FromParam;
use vpl_core::{Ray, RayCaster, Scene, SurfacePoint};
use vpl_density::KnnDensity;

/// How the sampler turns a VPL's radiance L(y) into flux Φ = L(y) · A(y).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FluxEstimator {
    /// The paper's (eq. 5 and 7): Φ = L(y) / (n p̂), p̂ = k / (n π r_k²).
    Knn,
    /// The paper's kNN fluxes, all scaled by one factor so that their sum
    /// equals [`FluxEstimator::Voronoi`]'s: the kNN weights' smoothness with
    /// the cells' total.
    KnnCalibrated,
    /// Φ = L(y) · |V(y)|, the radiance at the VPL times the area of its
    /// Voronoi cell: right for any arrangement of the set, but biased when
    /// the VPLs sit on the bright side of their cells (see the module text).
    VoronoiSite,
    /// Φ = |V(y)| · L̄(V(y)), the cell's area times the mean radiance of the
    /// candidates that fell in it: the cell's flux, whatever point of the
    /// cell the VPL sits on.
    Voronoi,
    /// Φ = L̄(V(y)) · Σ_{h ∈ V(y)} b̄_near(y): the cell's light as its VPL
    /// shows it to the camera, each of the cell's probes standing for the
    /// area that the probes *near the VPL* stand for (see the module text,
    /// "Seen from the VPL"). Needs [`crate::Placement::Site`]. The default.
    #[default]
    VoronoiNear,
}

impl FluxEstimator {
    /// Every estimator, the default last.
    pub const ALL: [FluxEstimator; 5] =
        [FluxEstimator::Knn, FluxEstimator::KnnCalibrated, FluxEstimator::VoronoiSite, FluxEstimator::Voronoi, FluxEstimator::VoronoiNear];

    /// The parameter value naming the estimator.
    pub fn name(self) -> &'static str {
        match self {
            FluxEstimator::Knn => "knn",
            FluxEstimator::KnnCalibrated => "knn-calibrated",
            FluxEstimator::VoronoiSite => "voronoi-site",
            FluxEstimator::Voronoi => "voronoi",
            FluxEstimator::VoronoiNear => "voronoi-near",
        }
    }

    /// Whether the estimator needs the area probes.
    pub fn probes(self) -> bool {
        self != FluxEstimator::Knn
    }
}

impl FromParam for FluxEstimator {
    const EXPECTED: &'static str = "knn, knn-calibrated, voronoi-site or voronoi";
    fn from_param(text: &str) -> Option<Self> {
        FluxEstimator::ALL.into_iter().find(|e| e.name() == text.trim())
    }
}

impl std::fmt::Display for FluxEstimator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl ProbeWindow {
    /// The parameter value naming the window.
    pub fn name(self) -> &'static str {
        match self {
            ProbeWindow::Box => "box",
            ProbeWindow::Triangle => "triangle",
            ProbeWindow::Parabola => "parabola",
        }
    }
}

impl FromParam for ProbeWindow {
    const EXPECTED: &'static str = "box, triangle or parabola";
    fn from_param(text: &str) -> Option<Self> {
        [ProbeWindow::Box, ProbeWindow::Triangle, ProbeWindow::Parabola].into_iter().find(|w| w.name() == text.trim())
    }
}

impl std::fmt::Display for ProbeWindow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Reads `flux` from parameters (for [`crate::SmcConfig::from_params`]).
/// With `placement`: [`FluxEstimator::VoronoiNear`] where the VPLs shine
/// from their own points, the cell flux [`FluxEstimator::Voronoi`] where a
/// placement moves them (the areas near a VPL are measured at its point).
pub(crate) fn flux_param(p: &vpl_core::Params, placement: crate::Placement) -> Result<FluxEstimator, ParamError> {
    let default = if placement == crate::Placement::Site { FluxEstimator::VoronoiNear } else { FluxEstimator::Voronoi };
    p.get_or("flux", default)
}

/// Which VPL a probe belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Owner {
    /// Not assigned yet (a new probe, or its VPL left the set).
    Unassigned,
    /// The VPL of this id, in this slot of the sampler.
    Vpl {
        /// The VPL's id.
        id: u64,
        /// Its slot (stable for its life).
        slot: u32,
    },
    /// No VPL on its side of the surface sees it, or it stands for no
    /// area: it belongs to no cell.
    Nobody,
}

/// One probe: a point of the surfaces (geometric normal toward the ray
/// that found it), the area it stands for (m²), where its candidate's
/// radiance is kept if the hit became one, and its cell.
///
/// What only candidates carry lies in a table beside the batch
/// ([`Carried`]): the walks over all probes (owners, cells) then read 64
/// bytes a probe instead of 104.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Probe {
    p: Vec3,
    n: Vec3,
    /// Shading normal, on the side of `n` (where a VPL shines from here).
    ns: Vec3,
    area: f32,
    /// Index of its candidate's [`Carried`] in its batch's table
    /// ([`NOT_CARRIED`]: not a candidate).
    carried: u32,
    owner: Owner,
}

// The size the text of `Probe` states.
const _: () = assert!(std::mem::size_of::<Probe>() == 64);

/// [`Probe::carried`] of a probe that carries no radiance.
const NOT_CARRIED: u32 = u32::MAX;

/// What a probe whose hit became a candidate carries.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Carried {
    /// The radiance estimated there.
    radiance: Vec3,
    /// The radiance's weight in its cell's mean: the area of its hit over
    /// the hit's share of the resampling draws (see [`AreaProbes::push`]).
    weight: f32,
    /// A candidate's relighting estimates (D(t), D(now))
    /// ([`crate::Relight::Candidates`]; `None` until D(t) is made, and
    /// where an estimate was not finite).
    track: Option<(Vec3, Vec3)>,
}

impl Probe {
    /// Whether the probe counts in a cell: it stands for area or carries
    /// a candidate's radiance.
    #[inline]
    fn counts(&self) -> bool {
        self.area > 0.0 || self.carried != NOT_CARRIED
    }

    /// Its candidate's radiance, weight and relighting estimates, if any.
    #[inline]
    fn carried<'a>(&self, table: &'a [Carried]) -> Option<&'a Carried> {
        table.get(self.carried as usize)
    }

    /// Whether the probe lies on `site`'s own smooth surface (normals
    /// within 60°).
    #[inline]
    fn on_surface_of(&self, site: &Site) -> bool {
        site.n.dot(self.n) > SAME_SURFACE_COS
    }

    /// Whether the probe lies on `other`'s own smooth surface.
    #[inline]
    fn on_surface_of_probe(&self, other: &Probe) -> bool {
        other.n.dot(self.n) > SAME_SURFACE_COS
    }
}

/// A candidate of one iteration as the probes take it: its hit's index
/// among the iteration's hits, its radiance, its first landings over its
/// draw probability ([`vpl_core::resample::resample_counted`]) and its id
/// (the VPL's, if it joins the set).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeCandidate {
    /// Index of its hit.
    pub hit: usize,
    /// Its estimated radiance.
    pub radiance: Vec3,
    /// First landings of the resampling draws on it over the probability
    /// of one draw landing on it, c / p.
    pub draws: f32,
    /// Its id.
    pub id: u64,
    /// Its point, where the candidate is relit ([`crate::Relight::Candidates`];
    /// `None`: it is not). Its short relighting estimate D(t) under this
    /// iteration's lights is made only when the lights change
    /// ([`AreaProbes::relight`]): under lights that stand still it is never needed.
    pub track: Option<SurfacePoint>,
}

/// Estimates a radiance for each (point, id) pair, with random numbers
/// keyed by the id ([`AreaProbes::relight`]).
pub type Track<'a> = dyn FnMut(&[(SurfacePoint, u64)]) -> Vec<Vec3> + 'a;

/// A candidate held for relighting: its [`Carried`] in its batch's table,
/// its id (which keys its estimates' random numbers) and its point.
#[derive(Clone, Copy, Debug)]
struct Tracked {
    carried: u32,
    id: u64,
    y: SurfacePoint,
    /// Whether D(t) is still to be estimated, under the lights of the
    /// candidate's iteration.
    pending: bool,
}

/// One iteration's candidate-ray hits for [`AreaProbes::push`].
#[derive(Debug)]
pub struct ProbeHits<'a> {
    /// The hits' points.
    pub hits: &'a [Vec3],
    /// Their geometric normals, facing the rays that found them.
    pub normals: &'a [Vec3],
    /// Their shading normals, on the same side.
    pub shading: &'a [Vec3],
    /// A tree over the points.
    pub tree: KnnDensity,
    /// Each point's nearest other point in 3D, as the resampling weights
    /// use them ([`KnnDensity::member_nearest`]).
    pub nearest: &'a [Option<(usize, f32)>],
    /// The hits that became candidates.
    pub candidates: &'a [ProbeCandidate],
    /// One over the draws of the resampling: with a candidate's `draws`,
    /// its Horvitz–Thompson factor.
    pub draw_scale: f64,
    /// The scene the hits lie in, for [`ProbeArea::Surface`] (without it,
    /// or under [`ProbeArea::Disk`], each hit stands for its disk).
    pub scene: Option<&'a Scene>,
}

/// A Voronoi cell as the probes measured it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Cell {
    /// Area, m²: the probes' areas, a weighted mean over the iterations held ([`ProbeWindow`]).
    pub area: f64,
    /// Centroid of the part of the cell on the site's own smooth surface
    /// (probes whose normals lie within 60° of the site's): their positions
    /// weighted by their areas; the site's position where there are none.
    pub centroid: Vec3,
    /// Sum of the radiances of the candidates that fell in the cell.
    pub radiance_sum: Vec3,
    /// How many candidates fell in the cell.
    pub candidates: u32,
    /// Σ w L over the candidates in the cell, w each candidate's weight
    /// (its hit's area over its share of the resampling draws).
    pub weighted_radiance: Vec3,
    /// Σ w over the candidates in the cell.
    pub radiance_weight: f32,
    /// Σ w Y_i(t) over the candidates in the cell: the luminance Y_i of the
    /// cell's VPL as recorded with each candidate's iteration t (its
    /// luminance now where that iteration has no record of it).
    pub history_luminance: f32,
    /// Σ w over the candidates that count in `history_luminance`.
    pub history_weight: f32,
    /// The luminance of the cell's VPL under the newest iteration's lights,
    /// if recorded ([`AreaProbes::record`]).
    pub luminance_now: Option<f32>,
    /// Σ w D(t) over the cell's relit candidates: their relighting
    /// estimates under the lights of their iterations.
    pub track_then: Vec3,
    /// Σ w D(now) over the same candidates.
    pub track_now: Vec3,
}

impl Cell {
    /// [`Cell::mean_radiance`] brought forward to the lights of the newest
    /// iteration: the candidates' radiances were estimated over the last T
    /// iterations, under lights that may since have moved, so the mean is
    /// scaled by how the cell's own VPL changed over the same iterations
    /// and weights,
    ///
    /// ```text
    /// L̄_now(V_i) = L̄(V_i) · Y_i(now) / (Σ_h w_h Y_i(t_h) / Σ_h w_h),
    /// ```
    ///
    /// Y_i(t) the VPL's luminance under iteration t's lights (a ratio
    /// estimate; the sampler estimates Y_i with the same random numbers at
    /// every frame, so their noise cancels in the ratio). Under lights that
    /// do not move the records are equal and this is the mean itself; the
    /// mean is kept where the VPL's past luminance is zero.
    pub fn current_radiance(&self, fallback: Vec3) -> Vec3 {
        let mean = self.mean_radiance(fallback);
        match self.luminance_now {
            Some(now) if self.history_weight > 0.0 && self.history_luminance > 0.0 && now.is_finite() => {
                let factor = now * self.history_weight / self.history_luminance;
                if factor.is_finite() { mean * factor } else { mean }
            }
            _ => mean,
        }
    }

    /// [`Cell::mean_radiance`] brought to the lights of now by the change
    /// of its candidates' relighting estimates, (Σ w D(now) − Σ w D(t)) / Σ w
    /// (eq. 1 of [`crate::Relight`]'s module); the mean itself where no
    /// candidate has a weight. Signed: where the cell's light fell, the
    /// noisy change can overshoot below zero, and the sampler takes that
    /// part from the neighbouring cells' light
    /// ([`crate::relight::spread_deficits`]) rather than adding it.
    pub fn relit_radiance(&self, fallback: Vec3) -> Vec3 {
        let mean = self.mean_radiance(fallback);
        if self.radiance_weight <= 0.0 {
            return mean;
        }
        let l = mean + (self.track_now - self.track_then) / self.radiance_weight;
        if l.is_finite() { l } else { mean }
    }

    /// The cell's mean radiance under the lights of now as `relight` brings
    /// it there ([`Cell::current_radiance`], [`Cell::relit_radiance`] or
    /// [`Cell::mean_radiance`]), `fallback` the cell's VPL's own radiance.
    pub fn radiance(&self, relight: crate::Relight, fallback: Vec3) -> Vec3 {
        match relight {
            crate::Relight::Ratio => self.current_radiance(fallback),
            crate::Relight::Candidates => self.relit_radiance(fallback),
            crate::Relight::None => self.mean_radiance(fallback),
        }
    }

    /// The cell's mean radiance over area: the candidates' radiances
    /// weighted by their hits' areas over their shares of the draws (a
    /// ratio estimate; see the module text), their plain mean where none
    /// has a weight, or `fallback` when no candidate fell in the cell.
    pub fn mean_radiance(&self, fallback: Vec3) -> Vec3 {
        if self.radiance_weight > 0.0 {
            self.weighted_radiance / self.radiance_weight
        } else if self.candidates == 0 {
            fallback
        } else {
            self.radiance_sum / self.candidates as f32
        }
    }
}

/// A VPL as the cells see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Site {
    /// The VPL's stable id.
    pub id: u64,
    /// Its slot in the sampler (stable for its life).
    pub slot: u32,
    /// Position.
    pub p: Vec3,
    /// Geometric normal, on the lit side.
    pub n: Vec3,
}

/// The sites of one call, found by slot.
struct Live<'a> {
    sites: &'a [Site],
    by_slot: Vec<u32>,
}

impl<'a> Live<'a> {
    fn new(sites: &'a [Site]) -> Live<'a> {
        let len = sites.iter().map(|s| s.slot as usize + 1).max().unwrap_or(0);
        let mut by_slot = vec![u32::MAX; len];
        for (i, s) in sites.iter().enumerate() {
            by_slot[s.slot as usize] = i as u32;
        }
        Live { sites, by_slot }
    }

    /// The index of the site that owns a probe, if that VPL is still there.
    #[inline]
    fn get(&self, owner: Owner) -> Option<usize> {
        let Owner::Vpl { id, slot } = owner else { return None };
        let i = *self.by_slot.get(slot as usize)?;
        (i != u32::MAX && self.sites[i as usize].id == id).then_some(i as usize)
    }

    fn owner(&self, i: usize) -> Owner {
        Owner::Vpl { id: self.sites[i].id, slot: self.sites[i].slot }
    }
}

/// The candidate-ray hits of the last T iterations, each standing for a
/// piece of surface and belonging to one VPL's cell; the hits that became
/// candidates carry their radiance.
///
/// A probe joins the cell of the nearest VPL on the same side of the
/// surface that it can see (see the module text). It keeps its cell until
/// it expires or its VPL leaves the set; a VPL that joins takes, from its
/// neighbours' cells, the probes nearer to it that see it. The cells
/// always tile the probes.
#[derive(Debug, Default)]
pub struct AreaProbes {
    batches: VecDeque<Vec<Probe>>,
    /// Per batch, 1 / draws of its resampling: with a candidate's weight,
    /// the Horvitz–Thompson factor of its radiance ([`AreaProbes::candidate_light`]).
    draw_scales: VecDeque<f64>,
    /// A k-d tree over each batch's probes, for the probes near a VPL that joins.
    trees: VecDeque<KnnDensity>,
    /// The VPLs of the last [`AreaProbes::assign`].
    known: HashSet<u64>,
    depth: usize,
    /// Area probes kept per iteration (at least; all hits when fewer).
    per_iteration: usize,
    /// Iterations pushed, which rotate the hits kept.
    pushed: usize,
    /// How the iterations held are weighted ([`ProbeWindow`]).
    window: ProbeWindow,
    /// What each probe's ball stands for.
    ball: ProbeArea,
    /// Per iteration held, the luminance of each slot's VPL as the sampler
    /// estimated it under that iteration's lights, by slot (with its id):
    /// what [`Cell::current_radiance`] brings the cells' radiances forward with.
    records: VecDeque<Option<Record>>,
    /// Per iteration held, its candidates that are relit ([`AreaProbes::relight`]).
    tracked: VecDeque<Vec<Tracked>>,
    /// Per iteration held, what its candidates' probes carry ([`Probe::carried`]).
    carried: VecDeque<Vec<Carried>>,
}

/// The luminance of each slot's VPL (with its id) under one iteration's lights.
type Record = Vec<Option<(u64, f32)>>;

/// How [`AreaProbes`] weighs the iterations it holds in the cells' areas
/// and radiances. Either way the weights sum to 1, so every sum stays an
/// unbiased estimate and the cells still partition the light.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ProbeWindow {
    /// Every iteration alike: each frame the newest comes in at 1/T and
    /// the oldest goes out at 1/T.
    Box,
    /// A triangle, w_b ∝ min(b + 1, T − b) from the oldest b = 0: each
    /// iteration's weight rises and falls by about 4/T² a frame, so a cell
    /// changes by a fraction of what one iteration in and one out make it
    /// change (the frame-to-frame variance of a cell's area falls by about
    /// 8/T, to a half at T = 16, while the variance of its level rises by a
    /// third: it averages 3T/4 iterations' worth of probes). Its centre is
    /// the box's, so a moving light lags as far.
    Triangle,
    /// A parabola, w_b ∝ (b + 1)(T − b): of all windows over T iterations
    /// that sum to 1 and come in and go out from 0, the one of least
    /// Σ_b (w_b − w_{b−1})², the frame-to-frame variance of a cell's area
    /// over that of one iteration's (its second difference is constant,
    /// the discrete Euler–Lagrange condition). At T = 16 that sum is 0.79
    /// of the triangle's (1632 / 816² against 16 / 72²), and Σ w_b², the
    /// variance of the level, 0.90 of it (0.0711 against 0.0787): both
    /// lower at no cost. Its centre is the box's, so a moving light lags as
    /// far.
    #[default]
    Parabola,
}

impl AreaProbes {
    /// Bytes per probe: the probe, its batch's k-d tree (the point twice,
    /// the set's copy and the tree's, and an index: 28 B) and the lists of
    /// an assignment (about 20 B). Measured on `office` with 8192 VPLs:
    /// a peak of 242 to 252 MiB above the kNN flux's, 224 MiB estimated for
    /// the probes (the whole render: 288–298 MiB against 298 MiB).
    pub const BYTES_PER_PROBE: u64 = (std::mem::size_of::<Probe>() + 48) as u64;

    /// Probes that keep every hit of the last `depth` iterations (at least 1).
    pub fn new(depth: usize) -> AreaProbes {
        AreaProbes {
            batches: VecDeque::new(),
            draw_scales: VecDeque::new(),
            trees: VecDeque::new(),
            known: HashSet::new(),
            depth: depth.max(1),
            per_iteration: usize::MAX,
            pushed: 0,
            window: ProbeWindow::default(),
            ball: ProbeArea::default(),
            records: VecDeque::new(),
            tracked: VecDeque::new(),
            carried: VecDeque::new(),
        }
    }

    /// Measures each probe's ball by `ball` ([`ProbeArea`]).
    pub fn with_ball(mut self, ball: ProbeArea) -> AreaProbes {
        self.ball = ball;
        self
    }

    /// Weighs the iterations held by `window`.
    pub fn with_window(mut self, window: ProbeWindow) -> AreaProbes {
        self.window = window;
        self
    }

    /// The weight of each iteration held, oldest first, summing to 1.
    fn weights(&self) -> Vec<f64> {
        let t = self.batches.len();
        let raw: Vec<f64> = match self.window {
            ProbeWindow::Box => vec![1.0; t],
            ProbeWindow::Triangle => (0..t).map(|b| (b + 1).min(t - b) as f64).collect(),
            ProbeWindow::Parabola => (0..t).map(|b| ((b + 1) * (t - b)) as f64).collect(),
        };
        let sum: f64 = raw.iter().sum();
        raw.into_iter().map(|w| w / sum).collect()
    }

    /// Keeps about `n` of each iteration's hits as area probes (at least
    /// 1; all of them when there are fewer), every s-th hit with
    /// s = ⌈N / n⌉, each standing for s times its area, and every
    /// candidate besides for its radiance ([`AreaProbes::push`]).
    pub fn with_per_iteration(mut self, n: usize) -> AreaProbes {
        self.per_iteration = n.max(1);
        self
    }

    /// Forgets every probe.
    pub fn clear(&mut self) {
        self.batches.clear();
        self.draw_scales.clear();
        self.trees.clear();
        self.known.clear();
        self.records.clear();
        self.tracked.clear();
        self.carried.clear();
    }

    /// Iterations held.
    pub fn len(&self) -> usize {
        self.batches.len()
    }

    /// Whether no iteration is held.
    pub fn is_empty(&self) -> bool {
        self.batches.is_empty()
    }

    /// Adds one iteration's hits ([`ProbeHits`]), the candidates among
    /// them with their radiances and weights. Each hit stands for
    /// π r_1² (N − 1) / N, r_1 from [`surface_neighbour_sq`]; hits without a
    /// finite positive radius stand for nothing. The oldest iteration goes
    /// when `depth` are held.
    ///
    /// With fewer probes per iteration than hits
    /// ([`AreaProbes::with_per_iteration`]), every s-th hit is kept, from
    /// an offset that turns with the iterations, and stands for s times its
    /// area (the hits come in the random order of their camera points, so
    /// the kept ones are a uniform subset and the areas' sum stays
    /// unbiased); the candidates not among them are kept for their
    /// radiance only (area 0), so that every candidate still counts in its
    /// cell's mean.
    pub fn push(&mut self, iteration: ProbeHits) {
        let ProbeHits { hits, normals, shading, tree, nearest, candidates, draw_scale, scene } = iteration;
        let n = hits.len();
        if n < 2 || normals.len() != n || shading.len() != n || nearest.len() != n || tree.len() != n {
            return;
        }
        // Each hit's candidate, if it became one (the last, were a hit given twice).
        let mut candidate_of = vec![u32::MAX; n];
        for (i, c) in candidates.iter().enumerate() {
            if c.hit < n {
                candidate_of[c.hit] = i as u32;
            }
        }
        let candidate = |h: usize| candidates.get(candidate_of[h] as usize);
        let radiance = |h: usize| candidate(h).map(|c| c.radiance).filter(|l| l.is_finite());
        let stride = n.div_ceil(self.per_iteration).max(1);
        let offset = self.pushed % stride;
        self.pushed = self.pushed.wrapping_add(1);
        // The hits kept (every stride-th, then the other candidates), and
        // how many of them stand for area.
        let mut kept: Vec<usize> = (offset..n).step_by(stride).collect();
        let area_probes = kept.len();
        if stride > 1 {
            kept.extend((0..n).filter(|&h| h % stride != offset && radiance(h).is_some()));
        }
        let accept = if self.ball == ProbeArea::Smooth { SAME_SURFACE_COS } else { SAME_SIDE_COS };
        let mut r1_sq = neighbour_sq_within(&tree, hits, normals, nearest, &kept, accept);
        // Under ProbeArea::Surface each ball stands for the surface inside
        // it, A(r_1), written here as the r² of a disk of that area.
        if let (ProbeArea::Surface | ProbeArea::Smooth, Some(scene)) = (self.ball, scene) {
            r1_sq = kept
                .par_iter()
                .zip(&r1_sq)
                .map_init(Vec::new, |scratch, (&h, &r2)| {
                    if !r2.is_finite() {
                        return r2;
                    }
                    crate::ball_area::surface_in_ball(scene, hits[h], normals[h], r2.sqrt(), accept, scratch) / std::f32::consts::PI
                })
                .collect();
        }
        let own_area = std::f32::consts::PI * (n - 1) as f32 / n as f32;
        let scale = own_area * (n as f32 / area_probes as f32);
        let mut carried: Vec<Carried> = Vec::new();
        let mut tracked: Vec<Tracked> = Vec::new();
        let batch: Vec<Probe> = kept
            .iter()
            .enumerate()
            .map(|(t, &h)| {
                let area = if t < area_probes { scale * r1_sq[t] } else { 0.0 };
                let placed = hits[h].is_finite() && normals[h].is_finite();
                let stands = placed && area.is_finite() && area > 0.0;
                let radiance = radiance(h).filter(|_| placed);
                // The hit's own area over its share of the draws.
                let drawn = candidate(h).map_or(0.0, |c| if c.draws.is_finite() && c.draws > 0.0 { c.draws } else { 0.0 });
                let weight = drawn * own_area * r1_sq[t];
                let at = match radiance {
                    Some(radiance) => {
                        if let Some(&ProbeCandidate { track: Some(y), id, .. }) = candidate(h) {
                            tracked.push(Tracked { carried: carried.len() as u32, id, y, pending: true });
                        }
                        carried.push(Carried { radiance, weight: if weight.is_finite() { weight } else { 0.0 }, track: None });
                        carried.len() as u32 - 1
                    }
                    None => NOT_CARRIED,
                };
                Probe {
                    p: hits[h],
                    n: normals[h],
                    ns: if shading[h].is_finite() { shading[h] } else { normals[h] },
                    area: if stands { area } else { 0.0 },
                    carried: at,
                    owner: if stands || radiance.is_some() { Owner::Unassigned } else { Owner::Nobody },
                }
            })
            .collect();
        let tree = if stride == 1 {
            tree
        } else {
            let points: Vec<Vec3> = batch.iter().map(|q| q.p).collect();
            // The kept points are finite hits, or the tree of all hits
            // would not have been made.
            match KnnDensity::new(&points) {
                // Built now, on every thread: the first search of it
                // (a newcomer's, next frame) would build it on one while
                // the other waits.
                Ok(t) => t.prepared(),
                Err(_) => return,
            }
        };
        if self.batches.len() == self.depth {
            self.batches.pop_front();
            self.draw_scales.pop_front();
            self.trees.pop_front();
            self.records.pop_front();
            self.tracked.pop_front();
            self.carried.pop_front();
        }
        self.tracked.push_back(tracked);
        self.carried.push_back(carried);
        self.batches.push_back(batch);
        self.records.push_back(None);
        self.draw_scales.push_back(draw_scale);
        self.trees.push_back(tree);
    }

    /// The light the candidates carry, Σ_h c_h b_h L_h / (draws p_h)
    /// over the candidates of each iteration held (c_h their first
    /// landings, p_h = w_h / Σw their draw probabilities), averaged over the
    /// iterations: an unbiased estimate of ∫ L dA over the surfaces the
    /// hits reach, whatever the cells (by luminance).
    pub fn candidate_light(&self) -> f64 {
        if self.batches.is_empty() {
            return 0.0;
        }
        // Per iteration in parallel, then summed in order.
        let per_batch: Vec<f64> = self
            .carried
            .par_iter()
            .zip(&self.draw_scales)
            .zip(self.weights())
            .map(|((c, &k), w)| w * k * c.iter().map(|c| c.weight as f64 * vpl_core::image::luminance(c.radiance) as f64).sum::<f64>())
            .collect();
        per_batch.into_iter().sum()
    }

    /// Brings the candidates held to new lights ([`crate::Relight::Candidates`]),
    /// every iteration's but the newest's (estimated under these lights).
    /// `then` estimates D(t) of each (point, id) under the lights the
    /// candidates not yet relit were made under, the lights of the last
    /// change before this one (made only now: under lights that stand
    /// still no estimate is needed); `now` estimates D(now) under the new
    /// lights. Both take the random numbers each id keys, so D(t) is the
    /// estimate its own iteration would have made. Each cell's mean
    /// radiance then moves by its candidates' (Σ w D(now) − Σ w D(t)) / Σ w
    /// ([`Cell::relit_radiance`]). Returns the estimates made; an estimator
    /// that answers short changes nothing.
    pub fn relight(&mut self, then: &mut Track, now: &mut Track) -> usize {
        let older = self.tracked.len().saturating_sub(1);
        let pending: Vec<(SurfacePoint, u64)> =
            self.tracked.iter().take(older).flatten().filter(|k| k.pending).map(|k| (k.y, k.id)).collect();
        let mut made = 0;
        if !pending.is_empty() {
            let d_then = then(&pending);
            if d_then.len() != pending.len() {
                return 0;
            }
            made += d_then.len();
            let mut d_then = d_then.into_iter();
            for (carried, tracked) in self.carried.iter_mut().zip(self.tracked.iter_mut()).take(older) {
                for k in tracked.iter_mut().filter(|k| k.pending) {
                    let d = d_then.next().unwrap_or(Vec3::NAN);
                    k.pending = false;
                    if let Some(c) = carried.get_mut(k.carried as usize) {
                        c.track = d.is_finite().then_some((d, d));
                    }
                }
            }
        }
        let mut jobs: Vec<(SurfacePoint, u64)> = Vec::new();
        for (carried, tracked) in self.carried.iter().zip(&self.tracked).take(older) {
            let relit = tracked.iter().filter(|k| carried.get(k.carried as usize).is_some_and(|c| c.track.is_some()));
            jobs.extend(relit.map(|k| (k.y, k.id)));
        }
        if jobs.is_empty() {
            return made;
        }
        let d_now = now(&jobs);
        if d_now.len() != jobs.len() {
            return made;
        }
        let mut d_now = d_now.into_iter();
        for (carried, tracked) in self.carried.iter_mut().zip(&self.tracked).take(older) {
            for k in tracked {
                if let Some((d_then, d)) = carried.get_mut(k.carried as usize).and_then(|c| c.track.as_mut()) {
                    let n = d_now.next().unwrap_or(Vec3::NAN);
                    *d = if n.is_finite() { n } else { *d_then };
                }
            }
        }
        made + jobs.len()
    }

    /// Records the radiance of each VPL of the set, `(slot, id, L)`, under
    /// the lights of the newest iteration held (once; later calls before
    /// the next [`AreaProbes::push`] change nothing). The cells compare
    /// each VPL's radiance now with its radiance when their candidates were
    /// estimated ([`Cell::current_radiance`]).
    pub fn record(&mut self, vpls: &[(u32, u64, Vec3)]) {
        let Some(slot @ None) = self.records.back_mut() else { return };
        let len = vpls.iter().map(|v| v.0 as usize + 1).max().unwrap_or(0);
        let mut by_slot = vec![None; len];
        for &(s, id, l) in vpls {
            let y = vpl_core::image::luminance(l);
            by_slot[s as usize] = (y.is_finite() && y >= 0.0).then_some((id, y));
        }
        *slot = Some(by_slot);
    }

    /// The surface area the probes cover, m²: the mean over iterations of
    /// their summed areas.
    pub fn total_area(&self) -> f64 {
        if self.batches.is_empty() {
            return 0.0;
        }
        self.batches.iter().zip(self.weights()).map(|(b, w)| w * b.iter().map(|q| q.area as f64).sum::<f64>()).sum()
    }

    /// Brings the cells up to date with the set `sites`: the probes of VPLs
    /// that left, and new probes, join the nearest site on their side of
    /// the surface that they see; VPLs that joined take the probes nearer
    /// to them that see them. Returns the shadow rays cast (by `rays`).
    pub fn assign(&mut self, scene: &Scene, rays: &dyn RayCaster, sites: &[Site]) -> usize {
        let points: Vec<Vec3> = sites.iter().map(|s| s.p).collect();
        let Ok(tree) = KnnDensity::new(&points) else { return 0 };
        let live = Live::new(sites);
        let mut cast = 0;
        if !tree.is_empty() {
            cast += self.take_for_newcomers(scene, rays, &live, &tree);
        }
        self.known = sites.iter().map(|s| s.id).collect();
        let todo: Vec<(usize, usize)> = self
            .batches
            .par_iter_mut()
            .enumerate()
            .flat_map_iter(|(b, batch)| {
                let mut mine = Vec::new();
                for (k, q) in batch.iter_mut().enumerate() {
                    if q.owner != Owner::Nobody && live.get(q.owner).is_none() {
                        q.owner = Owner::Unassigned;
                        mine.push((b, k));
                    }
                }
                mine
            })
            .collect();
        if todo.is_empty() || tree.is_empty() {
            return cast;
        }
        // In chunks, so that the rays and lists of a first assignment of
        // many probes stay small.
        for chunk in todo.chunks(ASSIGN_CHUNK) {
            cast += self.own(scene, rays, &live, &tree, chunk);
        }
        cast
    }

    /// Gives each probe of `todo` its owner among `live`'s sites (`tree`
    /// over their positions), or none. Returns the rays cast.
    fn own(&mut self, scene: &Scene, rays: &dyn RayCaster, live: &Live, tree: &KnnDensity, todo: &[(usize, usize)]) -> usize {
        let sites = live.sites;
        let mut cast = 0;
        // The nearest sites on the probe's own smooth surface (normals within
        // 60°) are tried first, nearest first; then those around an edge
        // (within 120°). The first the probe sees owns it.
        let mut owner: Vec<Option<usize>> = vec![None; todo.len()];
        // The sites' normals side by side: the walks ask for them at every
        // nearer site.
        let site_n: Vec<Vec3> = sites.iter().map(|s| s.n).collect();
        let same_surface = |n: Vec3, i: usize| site_n[i].dot(n) > SAME_SURFACE_COS;
        let around_edge = |q: &Probe, i: usize| {
            let c = site_n[i].dot(q.n);
            c > SAME_SIDE_COS && c <= SAME_SURFACE_COS
        };
        // The nearest site on the probe's surface first (usually the owner;
        // the probes near one another ask together, which took a third less
        // time than one walk each), then, for the probes that do not see it,
        // the next ones on its surface and those around an edge, in that
        // order: in rounds, or in one batch when `rays` speculates (only the
        // few that fail the first try, so that speculating costs few rays).
        // The newest iteration's probes, most of those of a frame, walk as the
        // tree that iteration has already; the others as a tree of their own.
        // (When they are at least half of it: the walk answers for all of it.)
        let newest = self.batches.len().saturating_sub(1);
        let batch = &self.batches[newest];
        let with_batch_tree =
            self.trees[newest].len() == batch.len() && 2 * todo.iter().filter(|&&(b, _)| b == newest).count() >= batch.len();
        let (of_newest, rest): (Vec<usize>, Vec<usize>) = (0..todo.len()).partition(|&t| with_batch_tree && todo[t].0 == newest);
        let mut nearest: Vec<Option<(usize, f32)>> = vec![None; todo.len()];
        if with_batch_tree {
            let normals: Vec<Vec3> = batch.iter().map(|q| q.n).collect();
            let each = tree.nearest_accepted_each_of(&self.trees[newest], |k, i| same_surface(normals[k], i));
            for &t in &of_newest {
                nearest[t] = each[todo[t].1];
            }
        }
        let (points, normals): (Vec<Vec3>, Vec<Vec3>) = rest
            .iter()
            .map(|&t| {
                let q = &self.batches[todo[t].0][todo[t].1];
                (q.p, q.n)
            })
            .unzip();
        for (&t, found) in rest.iter().zip(tree.nearest_accepted_each(&points, |r, i| same_surface(normals[r], i))) {
            nearest[t] = found;
        }
        let first: Vec<(usize, usize)> = nearest.iter().enumerate().filter_map(|(t, found)| found.map(|(i, _)| (t, i))).collect();
        // One try each: one batch of rays, and no list per probe.
        let (seen, rays_cast) = self.see(scene, rays, sites, first.iter().map(|&(t, i)| (todo[t], i)));
        cast += rays_cast;
        for (&(t, i), seen) in first.iter().zip(seen) {
            if seen {
                owner[t] = Some(i);
            }
        }
        let open: Vec<usize> = (0..todo.len()).filter(|&t| owner[t].is_none()).collect();
        let batches = &self.batches;
        let more: Vec<(usize, Vec<usize>)> = open
            .par_iter()
            .map(|&t| {
                let q = &batches[todo[t].0][todo[t].1];
                let on_surface = tree.nearest_accepted_n(q.p, None, |i| same_surface(q.n, i), OWNER_TRIES).into_iter().skip(1);
                let round_edge = tree.nearest_accepted_n(q.p, None, |i| around_edge(q, i), OWNER_TRIES);
                (t, on_surface.chain(round_edge).map(|(i, _)| i).collect())
            })
            .collect();
        cast += self.own_first_seen(scene, rays, sites, todo, &more, &mut owner);
        self.write_owners(live, todo, &owner);
        // The probes still without an owner try the VPLs whose cells hold
        // the probes next to them, round by round, so that a cell reaches
        // across a band of any width. How far each looks among its
        // iteration's probes is found once for all the rounds.
        let mut reach: Vec<Option<f32>> = vec![None; todo.len()];
        for _ in 0..NEIGHBOUR_ROUNDS {
            let (joined, rays_cast) = self.own_through_neighbours(scene, rays, live, todo, &mut reach, &mut owner);
            cast += rays_cast;
            if joined == 0 {
                break;
            }
            self.write_owners(live, todo, &owner);
        }
        // Last, so that the cells partition the probes: a probe that sees
        // none of the VPLs it tried joins the cell of its nearest owned
        // probe on its surface, else its nearest VPL on its side of the
        // surface, else its nearest VPL. Every usable probe then belongs to
        // exactly one cell, and the cells' areas sum to the probes' area
        // (their light to the candidates' light) for any set.
        let open: Vec<usize> = (0..todo.len()).filter(|&t| owner[t].is_none()).collect();
        let batches = &self.batches;
        let last: Vec<Option<usize>> = open
            .par_iter()
            .map(|&t| {
                let q = &batches[todo[t].0][todo[t].1];
                // The cell of its nearest owned neighbour on its surface
                // keeps its light where the surface is.
                let neighbour = self.neighbour_owners(live, todo[t], 1, reach[t]).0.first().copied();
                neighbour.or_else(|| {
                    let same_side = tree.nearest_accepted(q.p, None, |i| site_n[i].dot(q.n) > SAME_SIDE_COS);
                    same_side.or_else(|| tree.nearest_accepted(q.p, None, |_| true)).map(|(i, _)| i)
                })
            })
            .collect();
        for (&t, o) in open.iter().zip(last) {
            owner[t] = o;
        }
        self.write_owners(live, todo, &owner);
        cast
    }

    /// The owners of the `m` nearest owned probes of probe `(b, k)`'s
    /// iteration on its own smooth surface, each VPL once, nearest first,
    /// only VPLs on the probe's side of the surface, among its iteration's
    /// 512 nearest probes (`reach_sq`: how far that is, if an earlier
    /// [`KnnDensity::nearest_accepted_n_reach`] found it; handed back).
    fn neighbour_owners(&self, live: &Live, (b, k): (usize, usize), m: usize, reach_sq: Option<f32>) -> (Vec<usize>, Option<f32>) {
        let (batch, q) = (&self.batches[b], &self.batches[b][k]);
        let owned_here = |o: &Probe| live.get(o.owner).filter(|&i| live.sites[i].n.dot(q.n) > SAME_SIDE_COS);
        let accept = |j: usize| batch[j].on_surface_of_probe(q) && owned_here(&batch[j]).is_some();
        let (near, reach_sq) = match reach_sq {
            Some(r2) => (self.trees[b].nearest_accepted_n_within(q.p, Some(k), accept, m, r2), Some(r2)),
            None => self.trees[b].nearest_accepted_n_reach(q.p, Some(k), accept, m),
        };
        let mut owners: Vec<usize> = Vec::with_capacity(near.len());
        for i in near.into_iter().filter_map(|(j, _)| owned_here(&batch[j])) {
            if !owners.contains(&i) {
                owners.push(i);
            }
        }
        (owners, reach_sq)
    }

    /// Records the owners found for `todo` (none: no cell).
    fn write_owners(&mut self, live: &Live, todo: &[(usize, usize)], owner: &[Option<usize>]) {
        for (&(b, k), o) in todo.iter().zip(owner) {
            self.batches[b][k].owner = o.map_or(Owner::Nobody, |i| live.owner(i));
        }
    }

    /// Each probe of `todo` without an owner tries the owners of its
    /// [`OWNER_TRIES`] nearest owned probes of the same iteration on its own
    /// smooth surface (nearest first, each VPL once, only VPLs on its side),
    /// and joins the first it sees. Returns the probes that joined a cell
    /// and the rays cast.
    ///
    /// The nearest VPLs a probe tries first can all stand behind something
    /// (the far side of a column, a balustrade, a window's frame) while the
    /// VPL that owns the surface next to the probe, and sees the probe, lies
    /// further away. The cell that holds the probe's neighbours is where its
    /// light belongs; without this step it is lost (`Owner::Nobody`).
    fn own_through_neighbours(
        &self,
        scene: &Scene,
        rays: &dyn RayCaster,
        live: &Live,
        todo: &[(usize, usize)],
        reach: &mut [Option<f32>],
        owner: &mut [Option<usize>],
    ) -> (usize, usize) {
        let sites = live.sites;
        let open: Vec<usize> = (0..todo.len()).filter(|&t| owner[t].is_none()).collect();
        let found: Vec<(Vec<usize>, Option<f32>)> =
            open.par_iter().map(|&t| self.neighbour_owners(live, todo[t], OWNER_TRIES, reach[t])).collect();
        let mut offers: Vec<(usize, Vec<usize>)> = Vec::with_capacity(open.len());
        for (&t, (list, r)) in open.iter().zip(found) {
            reach[t] = r;
            offers.push((t, list));
        }
        let cast = self.own_first_seen(scene, rays, sites, todo, &offers, owner);
        (open.iter().filter(|&&t| owner[t].is_some()).count(), cast)
    }

    /// Probe `todo[t]` becomes the site of the first entry of its list, in
    /// order, that it sees, for each (t, list) of `offers`
    /// ([`first_passing`]: round by round, or in one batch when `rays`
    /// speculates). Returns the rays the rounds cast.
    fn own_first_seen(
        &self,
        scene: &Scene,
        rays: &dyn RayCaster,
        sites: &[Site],
        todo: &[(usize, usize)],
        offers: &[(usize, Vec<usize>)],
        owner: &mut [Option<usize>],
    ) -> usize {
        let tests: Vec<Vec<Result<Ray, bool>>> =
            offers.iter().map(|(t, list)| list.iter().map(|&i| self.shadow_test(scene, todo[*t], &sites[i])).collect()).collect();
        let (taken, cast) = first_passing(scene, rays, &tests);
        for ((t, list), r) in offers.iter().zip(taken) {
            if let Some(r) = r {
                owner[*t] = Some(list[r]);
            }
        }
        cast
    }

    /// The shadow ray between probe (batch, index) and site `s`, or whether
    /// they see each other without one.
    fn shadow_test(&self, scene: &Scene, (b, k): (usize, usize), s: &Site) -> Result<Ray, bool> {
        let eps = scene.epsilon();
        let q = self.batches[b][k];
        scene.shadow_ray(q.p + q.n * eps, s.p + s.n * eps).ok_or(true)
    }

    /// Whether each probe (batch, index) and site see each other, and the
    /// shadow rays that took.
    fn see(
        &self,
        scene: &Scene,
        rays: &dyn RayCaster,
        sites: &[Site],
        pairs: impl Iterator<Item = ((usize, usize), usize)>,
    ) -> (Vec<bool>, usize) {
        let tests: Vec<Result<Ray, bool>> = pairs.map(|(q, i)| self.shadow_test(scene, q, &sites[i])).collect();
        let cast = tests.iter().filter(|t| t.is_ok()).count();
        (resolve(scene, rays, tests), cast)
    }

    /// The probes a VPL that joined the set takes from its neighbours: those
    /// within twice the distance of its 4th nearest VPL that lie nearer to it
    /// than to their owner, on a surface it may own (its own, or around an
    /// edge when their owner is also around one), and that see it (and
    /// probes of no cell that it may own and that see it). Returns the rays
    /// cast.
    fn take_for_newcomers(&mut self, scene: &Scene, rays: &dyn RayCaster, live: &Live, tree: &KnnDensity) -> usize {
        if self.known.is_empty() {
            return 0;
        }
        let sites = live.sites;
        let newcomers: Vec<usize> = (0..sites.len()).filter(|&i| !self.known.contains(&sites[i].id)).collect();
        // Every (probe, newcomer) that may take it with their squared
        // distance, then for each probe the nearest newcomer (ties to the
        // lower index).
        let batches = &self.batches;
        let mut all: Vec<(usize, usize, f32, usize)> = newcomers
            .par_iter()
            .flat_map_iter(|&i| {
                let s = sites[i];
                let reach = tree.radius_sq(s.p, 5.min(sites.len())).unwrap_or(0.0) * 4.0;
                let mut mine = Vec::new();
                for (b, batch_tree) in self.trees.iter().enumerate() {
                    for (k, d2) in batch_tree.within(s.p, reach) {
                        let q = batches[b][k];
                        if !q.counts() {
                            continue;
                        }
                        let c = s.n.dot(q.n);
                        let takes = match live.get(q.owner) {
                            Some(o) => {
                                let owner = sites[o];
                                d2 < (q.p - owner.p).length_squared()
                                    && (c > SAME_SURFACE_COS || (c > SAME_SIDE_COS && owner.n.dot(q.n) <= SAME_SURFACE_COS))
                            }
                            None => q.owner == Owner::Nobody && c > SAME_SIDE_COS,
                        };
                        if takes {
                            mine.push((b, k, d2, i));
                        }
                    }
                }
                mine
            })
            .collect();
        all.sort_unstable_by(|x, y| (x.0, x.1).cmp(&(y.0, y.1)).then(x.2.total_cmp(&y.2)).then(x.3.cmp(&y.3)));
        all.dedup_by_key(|x| (x.0, x.1));
        let offers: Vec<((usize, usize), usize)> = all.into_iter().map(|(b, k, _, i)| ((b, k), i)).collect();
        let (seen, cast) = self.see(scene, rays, sites, offers.iter().copied());
        for (&((b, k), i), v) in offers.iter().zip(seen) {
            if v {
                self.batches[b][k].owner = live.owner(i);
            }
        }
        cast
    }

    /// The cell of each site, in the order given: the areas of its probes
    /// averaged over the iterations held, and the candidates among them
    /// ([`AreaProbes::assign`] first). `None` without probes.
    pub fn cells(&self, sites: &[Site]) -> Option<Vec<Cell>> {
        self.cells_and(sites, false).map(|(cells, _)| cells)
    }

    /// [`AreaProbes::cells`], and with `near` each site's near ratio
    /// ([`AreaProbes::near_ratios`]), from one pass over the probes.
    pub(crate) fn cells_and(&self, sites: &[Site], near: bool) -> Option<(Vec<Cell>, Option<Vec<f64>>)> {
        if self.batches.is_empty() {
            return None;
        }
        let live = Live::new(sites);
        // Per batch, in parallel, then added in batch order (the same sums
        // on any thread count); the first moments in f64.
        let weights = self.weights();
        // Each site's radiance (luminance) as recorded with an iteration,
        // or now (the newest record) where that iteration has none for it.
        let recorded = |rec: Option<&Record>, i: usize| -> Option<f32> {
            let s = &sites[i];
            rec?.get(s.slot as usize).copied().flatten().filter(|&(id, _)| id == s.id).map(|(_, y)| y)
        };
        let newest = self.records.back().and_then(|r| r.as_ref());
        let now: Vec<Option<f32>> = (0..sites.len()).map(|i| recorded(newest, i)).collect();
        let per_batch: Vec<(Vec<CellSums>, Option<NearBatch>)> = self
            .batches
            .par_iter()
            .zip(&self.carried)
            .zip(&weights)
            .zip(&self.records)
            .map(|(((batch, carried), &w), rec)| {
                let mut cells = vec![(Cell::default(), DVec3::ZERO, 0.0); sites.len()];
                let mut nears = Vec::new();
                let wf = w as f32;
                let then: Vec<Option<f32>> = (0..sites.len()).map(|i| recorded(rec.as_ref(), i).or(now[i])).collect();
                for q in batch {
                    let Some(i) = live.get(q.owner) else { continue };
                    if near && q.area > 0.0 && w > 0.0 {
                        nears.push((i as u32, (q.p - sites[i].p).length_squared(), q.area));
                    }
                    let (c, m, own) = &mut cells[i];
                    let a = w * q.area as f64;
                    c.area += a;
                    if q.on_surface_of(&sites[i]) {
                        *m += q.p.as_dvec3() * a;
                        *own += a;
                    }
                    if let Some(&Carried { radiance: l, weight, track }) = q.carried(carried) {
                        c.radiance_sum += l;
                        c.candidates += 1;
                        c.weighted_radiance += l * (wf * weight);
                        c.radiance_weight += wf * weight;
                        if let Some(y) = then[i] {
                            c.history_luminance += wf * weight * y;
                            c.history_weight += wf * weight;
                        }
                        if let Some((d_then, d_now)) = track {
                            c.track_then += wf * weight * d_then;
                            c.track_now += wf * weight * d_now;
                        }
                    }
                }
                (cells, near.then(|| NearBatch::by_cell(sites.len(), &nears)))
            })
            .collect();
        let (per_batch, nears): (Vec<_>, Vec<_>) = per_batch.into_iter().unzip();
        let near = near.then(|| near_ratios_of(sites.len(), &nears.into_iter().flatten().collect::<Vec<_>>(), &weights));
        // Each cell's sums over the batches, in batch order (the cells in parallel).
        let cells: Vec<CellSums> = (0..sites.len())
            .into_par_iter()
            .map(|i| {
                let (mut c, mut m, mut own) = (Cell::default(), DVec3::ZERO, 0.0);
                for (b, bm, bown) in per_batch.iter().map(|batch| &batch[i]) {
                    c.area += b.area;
                    m += *bm;
                    own += *bown;
                    c.radiance_sum += b.radiance_sum;
                    c.candidates += b.candidates;
                    c.weighted_radiance += b.weighted_radiance;
                    c.radiance_weight += b.radiance_weight;
                    c.history_luminance += b.history_luminance;
                    c.history_weight += b.history_weight;
                    c.track_then += b.track_then;
                    c.track_now += b.track_now;
                }
                (c, m, own)
            })
            .collect();
        let cells = cells
            .into_iter()
            .zip(sites)
            .zip(now)
            .map(|(((mut c, m, own), s), now)| {
                c.centroid = if own > 0.0 { (m / own).as_vec3() } else { s.p };
                c.luminance_now = now;
                c
            })
            .collect();
        Some((cells, near))
    }

    /// Per site, the mean area of the probes near it over its cell's mean
    /// (1 for a cell without area probes), for [`FluxEstimator::VoronoiNear`]:
    /// the [`NEAR_SHARE`] of its cell's area probes nearest the VPL, at
    /// least [`NEAR_MIN`], each weighted as the cells weigh it
    /// ([`ProbeWindow`]). Ties in distance go to the earlier probe, so the
    /// ratios are the same on any thread count.
    pub fn near_ratios(&self, sites: &[Site]) -> Vec<f64> {
        match self.cells_and(sites, true) {
            Some((_, Some(near))) => near,
            _ => vec![1.0; sites.len()],
        }
    }

    /// Every cell cut into its probes: each probe that stands for area, at
    /// its point and shading normal, with its share of its cell's flux,
    /// `weight · area · radiance[i]` (`radiance[i]` the radiance site `i`'s
    /// cell carries), so the pieces of a cell sum to `|V_i| · radiance[i]`.
    /// Each piece is (its site's index, point, shading normal, flux); a set
    /// of them renders the cells' light spread as the probes spread it,
    /// with no point standing for a whole cell.
    pub fn pieces(&self, sites: &[Site], radiance: &[Vec3]) -> Vec<(usize, Vec3, Vec3, Vec3)> {
        let live = Live::new(sites);
        let mut out = Vec::new();
        for (batch, w) in self.batches.iter().zip(self.weights()) {
            for q in batch {
                let Some(i) = live.get(q.owner) else { continue };
                let Some(&l) = radiance.get(i) else { continue };
                if q.area > 0.0 {
                    out.push((i, q.p, q.ns, l * (w as f32 * q.area)));
                }
            }
        }
        out
    }

    /// For each site whose `u[i]` is given (a uniform number in [0, 1)),
    /// a probe of its cell drawn by the area it stands for (weighted over
    /// the iterations held, as the cell's area is; `cells` are the sites'
    /// [`AreaProbes::cells`]): its point and shading normal; `None` where
    /// `u[i]` is `None` or the cell stands for no area. The same answer on
    /// any thread count (one pass in batch order).
    pub fn drawn_probes(&self, sites: &[Site], cells: &[Cell], u: &[Option<f32>]) -> Vec<Option<(Vec3, Vec3)>> {
        let live = Live::new(sites);
        let weights = self.weights();
        let mut left: Vec<Option<f64>> = (0..sites.len())
            .map(|i| {
                let area = cells.get(i).map_or(0.0, |c| c.area);
                u.get(i).copied().flatten().filter(|_| area > 0.0).map(|u| u as f64 * area)
            })
            .collect();
        let mut out = vec![None; sites.len()];
        for (batch, &w) in self.batches.iter().zip(&weights) {
            for q in batch {
                let Some(i) = live.get(q.owner) else { continue };
                let Some(l) = left[i].as_mut() else { continue };
                if q.area <= 0.0 {
                    continue;
                }
                // The last probe with area stands in for rounding short of the total.
                out[i] = Some((q.p, q.ns));
                *l -= w * q.area as f64;
                if *l < 0.0 {
                    left[i] = None;
                }
            }
        }
        out
    }

    /// For each site, the probe of its cell on its own smooth surface
    /// (normals within 60°) nearest `targets[i]` (its position and shading
    /// normal), `None` for a cell without such probes that stand for area.
    /// Ties go to the older iteration and the earlier hit, so the answer is
    /// the same on any thread count.
    pub fn nearest_probes(&self, sites: &[Site], targets: &[Vec3]) -> Vec<Option<(Vec3, Vec3)>> {
        let live = Live::new(sites);
        let per_batch: Vec<Vec<Option<(f32, Vec3, Vec3)>>> = self
            .batches
            .par_iter()
            .map(|batch| {
                let mut best: Vec<Option<(f32, Vec3, Vec3)>> = vec![None; sites.len()];
                for q in batch {
                    let Some(i) = live.get(q.owner) else { continue };
                    let Some(&t) = targets.get(i) else { continue };
                    if q.area <= 0.0 || !q.on_surface_of(&sites[i]) {
                        continue;
                    }
                    let d2 = (q.p - t).length_squared();
                    if best[i].is_none_or(|(b, _, _)| d2 < b) {
                        best[i] = Some((d2, q.p, q.ns));
                    }
                }
                best
            })
            .collect();
        let mut best: Vec<Option<(f32, Vec3, Vec3)>> = vec![None; sites.len()];
        for batch in per_batch {
            for (b, c) in best.iter_mut().zip(batch) {
                if c.is_some_and(|c| b.is_none_or(|(d, _, _)| c.0 < d)) {
                    *b = c;
                }
            }
        }
        best.into_iter().map(|b| b.map(|(_, p, n)| (p, n))).collect()
    }
}

/// Sites a probe tries on its own surface, and then around an edge,
/// before it belongs to no cell.
/// A cell's sums of one batch: the cell, its probes' first moment of
/// position and their area on the VPL's own surface (for the centroid).
type CellSums = (Cell, DVec3, f64);

/// An area probe of a cell for [`AreaProbes::near_ratios`]: (cell,
/// squared distance to its VPL, area).
type NearProbe = (u32, f32, f32);

/// One batch's area probes for [`AreaProbes::near_ratios`], grouped by
/// cell in the batch's order: cell `i`'s (squared distance, area) are
/// `probes[start[i]..start[i + 1]]`. Each batch groups its own, in
/// parallel with the others.
struct NearBatch {
    start: Vec<u32>,
    probes: Vec<(f32, f32)>,
}

impl NearBatch {
    /// `nears` (of `cells` cells) grouped by cell, by counting.
    fn by_cell(cells: usize, nears: &[NearProbe]) -> NearBatch {
        let mut start = vec![0u32; cells + 1];
        for &(i, ..) in nears {
            start[i as usize + 1] += 1;
        }
        for i in 0..cells {
            start[i + 1] += start[i];
        }
        let mut at = start.clone();
        let mut probes = vec![(0.0f32, 0.0f32); nears.len()];
        for &(i, d, a) in nears {
            probes[at[i as usize] as usize] = (d, a);
            at[i as usize] += 1;
        }
        NearBatch { start, probes }
    }

    /// Cell `i`'s probes (none when the batch holds no near probes).
    fn cell(&self, i: usize) -> &[(f32, f32)] {
        match (self.start.get(i), self.start.get(i + 1)) {
            (Some(&s), Some(&e)) => &self.probes[s as usize..e as usize],
            _ => &[],
        }
    }
}

/// A thread's lists for [`near_ratios_of`]: a cell's near probes
/// (squared distance, weight, weighted area) and their order by distance.
type NearScratch = (Vec<(f32, f64, f64)>, Vec<(f32, u32)>);

/// The near ratio of each of `cells` cells from its area probes, grouped
/// per batch in batch order, each batch weighted by `weights`
/// ([`AreaProbes::near_ratios`]).
fn near_ratios_of(cells: usize, per_batch: &[NearBatch], weights: &[f64]) -> Vec<f64> {
    (0..cells)
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(cell, order): &mut NearScratch, i| {
                // (squared distance, weight, weighted area) in batch order.
                cell.clear();
                cell.extend(per_batch.iter().zip(weights).flat_map(|(b, &w)| b.cell(i).iter().map(move |&(d, a)| (d, w, w * a as f64))));
                let (w, a) = cell.iter().fold((0.0, 0.0), |(w, a), e| (w + e.1, a + e.2));
                if cell.is_empty() || w <= 0.0 || a <= 0.0 {
                    return 1.0;
                }
                let m = ((cell.len() as f64 * NEAR_SHARE).ceil() as usize).max(NEAR_MIN).min(cell.len());
                // The m nearest, the earlier probe first among equal distances
                // (the order the grouping kept), summed nearest first: chosen
                // in linear time, and only they are sorted.
                order.clear();
                order.extend(cell.iter().enumerate().map(|(j, e)| (e.0, j as u32)));
                let by_distance = |x: &(f32, u32), y: &(f32, u32)| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1));
                if m < order.len() {
                    order.select_nth_unstable_by(m, by_distance);
                }
                let near = &mut order[..m];
                near.sort_unstable_by(by_distance);
                let (near_w, near_a) = near.iter().fold((0.0, 0.0), |(w, a), &(_, j)| (w + cell[j as usize].1, a + cell[j as usize].2));
                let ratio = (near_a / near_w) / (a / w);
                if ratio.is_finite() && ratio > 0.0 { ratio } else { 1.0 }
            },
        )
        .collect()
}

const OWNER_TRIES: usize = 4;

/// The share of a cell's area probes, nearest its VPL, whose mean area
/// [`FluxEstimator::VoronoiNear`] takes for the area a probe stands for at
/// the VPL.
pub const NEAR_SHARE: f64 = 0.25;

/// The fewest probes that mean is taken over (all of a cell's when it has
/// fewer).
pub const NEAR_MIN: usize = 8;

/// How much of a frame's near ratio a VPL takes in: its ratio moves this
/// share of the way to each frame's measurement (1/8: the last eight or so
/// frames count). A quarter of a cell's probes is a few dozen, and the
/// probes that come and go each frame move their mean: taken anew each
/// frame, a static view of `cornell` (1024 VPLs) changed by 1.16 % a frame
/// against 0.87 % with the cell flux; blended, 0.93 % (0.96 % with 1/4).
/// A VPL new to its slot takes its first measurement whole.
pub const NEAR_BLEND: f64 = 0.125;

/// Rounds in which probes without an owner try their neighbours' owners
/// (each reaches as far as a probe's 512 nearest of its iteration).
const NEIGHBOUR_ROUNDS: usize = 16;

/// Probes given owners at a time.
const ASSIGN_CHUNK: usize = 1 << 18;

/// Least cosine between the normals of a probe and the sites it tries
/// first: the same smooth surface (within 60°).
pub(crate) const SAME_SURFACE_COS: f32 = 0.5;

/// Least cosine between the normals of two points on "the same surface".
/// (above −0.5: within 120°, so a right-angled edge is kept but the back
/// of a thin wall is not).
pub(crate) const SAME_SIDE_COS: f32 = -0.5;

/// Squared distance from every point to its nearest other point *on the
/// same side of the surface*: normals within 120°
/// ([`KnnDensity::nearest_accepted`]). The nearest point in 3D may lie on
/// the back of a thin wall, lit from a room the camera hardly sees, where
/// it would make that room's sparse hits stand for almost no area.
/// Infinite for a point with no such neighbour among its 512 nearest.
/// `tree` is over `points`, `nearest` each point's nearest other point in
/// 3D ([`KnnDensity::member_nearest`]), which is the answer when it lies on
/// the same side.
pub fn surface_neighbour_sq(tree: &KnnDensity, points: &[Vec3], normals: &[Vec3], nearest: &[Option<(usize, f32)>]) -> Vec<f32> {
    let all: Vec<usize> = (0..points.len()).collect();
    surface_neighbour_sq_of(tree, points, normals, nearest, &all)
}

/// [`surface_neighbour_sq`] of the points `of` only, in that order.
fn surface_neighbour_sq_of(
    tree: &KnnDensity,
    points: &[Vec3],
    normals: &[Vec3],
    nearest: &[Option<(usize, f32)>],
    of: &[usize],
) -> Vec<f32> {
    neighbour_sq_within(tree, points, normals, nearest, of, SAME_SIDE_COS)
}

/// The squared distance from each point of `of` to its nearest other point
/// whose normal is within `accept` (a cosine) of its own.
fn neighbour_sq_within(
    tree: &KnnDensity,
    points: &[Vec3],
    normals: &[Vec3],
    nearest: &[Option<(usize, f32)>],
    of: &[usize],
    accept: f32,
) -> Vec<f32> {
    of.par_iter()
        .map(|&i| {
            let (p, n) = (points[i], normals[i]);
            let same_side = |j: usize| normals[j].dot(n) >= accept;
            match nearest[i] {
                Some((j, d2)) if same_side(j) => d2,
                _ => tree.nearest_accepted(p, Some(i), same_side).map_or(f32::INFINITY, |(_, d2)| d2),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::material::Material;
    use vpl_core::mesh::Mesh;
    use vpl_core::rng::{Purpose, stream};
    use vpl_core::{CpuRays, Light};

    /// The unit square of the floor (y = 0, x and z in [0, 1]), lit from
    /// above, and a thin wall across it at x = 0.5 when `wall`.
    fn floor(wall: bool) -> Scene {
        let mut mesh = Mesh::default();
        mesh.push_quad(Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0), 0);
        if wall {
            mesh.push_quad(Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.5, 1.0, 0.0), Vec3::new(0.5, 1.0, 1.0), Vec3::new(0.5, 0.0, 1.0), 0);
        }
        let sun = Light::Directional { direction: Vec3::NEG_Y, irradiance: Vec3::ONE };
        Scene::new("floor", &mesh, vec![Material::diffuse("m", Vec3::splat(0.5))], vec![sun], true).unwrap()
    }

    /// `n` independent uniform points on the floor's unit square.
    fn uniform(n: usize, seed: u64, index: u64) -> Vec<Vec3> {
        let mut rng = stream(seed, index, Purpose::TEST, 0);
        (0..n)
            .map(|_| {
                let (u, v) = rng.next_2d();
                Vec3::new(u, 0.0, v)
            })
            .collect()
    }

    /// Pushes one iteration whose candidates each had as many first
    /// landings as their draw probability (c / p = 1: their radiances count
    /// by their hits' areas alone).
    fn push(a: &mut AreaProbes, hits: &[Vec3], normals: &[Vec3], candidates: &[(usize, Vec3)]) {
        let weighted: Vec<(usize, Vec3, f32)> = candidates.iter().map(|&(h, l)| (h, l, 1.0)).collect();
        push_weighted(a, hits, normals, &weighted);
    }

    fn push_weighted(a: &mut AreaProbes, hits: &[Vec3], normals: &[Vec3], candidates: &[(usize, Vec3, f32)]) {
        let tree = KnnDensity::new(hits).unwrap();
        let nearest = tree.member_nearest();
        let candidates: Vec<ProbeCandidate> = candidates
            .iter()
            .map(|&(hit, radiance, draws)| ProbeCandidate { hit, radiance, draws, id: 100 + hit as u64, track: None })
            .collect();
        a.push(ProbeHits {
            hits,
            normals,
            shading: normals,
            tree,
            nearest: &nearest,
            candidates: &candidates,
            draw_scale: 1.0,
            scene: None,
        });
    }

    /// A cell's mean radiance weighs each candidate by its hit's area over
    /// its share of the draws: two candidates in one cell, the same area,
    /// one drawn (first) three times as often per unit of weight.
    #[test]
    fn the_cell_mean_weighs_candidates_by_area_over_their_draws() {
        let scene = floor(false);
        let mut a = AreaProbes::new(1);
        let hits = [Vec3::new(0.1, 0.0, 0.1), Vec3::new(0.2, 0.0, 0.1), Vec3::new(0.9, 0.0, 0.9)];
        push_weighted(&mut a, &hits, &[Vec3::Y; 3], &[(0, Vec3::splat(1.0), 1.0), (1, Vec3::splat(5.0), 3.0)]);
        let s = sites(&[Vec3::new(0.15, 0.0, 0.1), Vec3::new(0.9, 0.0, 0.9)]);
        a.assign(&scene, &CpuRays, &s);
        let cells = a.cells(&s).unwrap();
        assert_eq!(cells[0].candidates, 2);
        // Both hits stand for the same area (their nearest other hits are 0.1 apart).
        let mean = cells[0].mean_radiance(Vec3::ZERO);
        assert!((mean - Vec3::splat((1.0 + 3.0 * 5.0) / 4.0)).abs().max_element() < 1e-5, "{mean}");
        // The plain mean stays: (1 + 5) / 2.
        assert_eq!(cells[0].radiance_sum / cells[0].candidates as f32, Vec3::splat(3.0));
    }

    /// Relighting estimates D(now) anew for the candidates of the older
    /// iterations (the newest's stay at D(t)), and a cell's mean moves by
    /// its candidates' weighted change, below zero where it overshoots.
    #[test]
    fn relighting_moves_each_cell_by_the_change_of_its_candidates_estimates() {
        let scene = floor(false);
        let s = sites(&[Vec3::new(0.15, 0.0, 0.1), Vec3::new(0.9, 0.0, 0.9)]);
        let point = |p: Vec3| SurfacePoint { p, ng: Vec3::Y, n: Vec3::Y, triangle: 0, material: 0 };
        let mut a = AreaProbes::new(2);
        let hits = [Vec3::new(0.1, 0.0, 0.1), Vec3::new(0.2, 0.0, 0.1), Vec3::new(0.9, 0.0, 0.9)];
        let tracked =
            |hit: usize, l: f32, id: u64| ProbeCandidate { hit, radiance: Vec3::splat(l), draws: 1.0, id, track: Some(point(hits[hit])) };
        let push = |a: &mut AreaProbes, candidates: &[ProbeCandidate]| {
            let tree = KnnDensity::new(&hits).unwrap();
            let nearest = tree.member_nearest();
            let normals = [Vec3::Y; 3];
            a.push(ProbeHits {
                hits: &hits,
                normals: &normals,
                shading: &normals,
                tree,
                nearest: &nearest,
                candidates,
                draw_scale: 1.0,
                scene: None,
            });
        };
        // The older iteration: candidates 1 (L 2, D 1) and 2 (L 4, D 3) in
        // the first cell, 3 (L 8, D 6) in the second; the newer: candidate
        // 4 (L 10) in the first.
        push(&mut a, &[tracked(0, 2.0, 1), tracked(1, 4.0, 2), tracked(2, 8.0, 3)]);
        push(&mut a, &[tracked(0, 10.0, 4)]);
        a.assign(&scene, &CpuRays, &s);
        let before = a.cells(&s).unwrap();
        assert_eq!(before[0].relit_radiance(Vec3::ZERO), before[0].mean_radiance(Vec3::ZERO));
        // D then as above, D now: candidate 1 gains 3, candidate 2 loses 1,
        // candidate 3 loses 20. The newest iteration's candidate is asked
        // for neither (its change is zero).
        let (mut asked_then, mut asked_now) = (Vec::new(), Vec::new());
        let made = a.relight(
            &mut |jobs| {
                asked_then.extend(jobs.iter().map(|&(y, id)| (y.p, id)));
                jobs.iter().map(|&(_, id)| Vec3::splat([1.0, 3.0, 6.0][id as usize - 1])).collect()
            },
            &mut |jobs| {
                asked_now.extend(jobs.iter().map(|&(y, id)| (y.p, id)));
                jobs.iter().map(|&(_, id)| Vec3::splat([4.0, 2.0, -14.0][id as usize - 1])).collect()
            },
        );
        assert_eq!(made, 6);
        assert_eq!(asked_then, vec![(hits[0], 1), (hits[1], 2), (hits[2], 3)]);
        assert_eq!(asked_now, asked_then);
        let cells = a.cells(&s).unwrap();
        // The first cell's three candidates weigh alike (hits 0.1 from their
        // nearest, iterations of equal weight): its mean (2 + 4 + 10) / 3
        // moves by (3 − 1 + 0) / 3, to 6.
        let c = cells[0];
        assert!((c.mean_radiance(Vec3::ZERO) - Vec3::splat(16.0 / 3.0)).abs().max_element() < 1e-5);
        assert!((c.relit_radiance(Vec3::ZERO) - Vec3::splat(6.0)).abs().max_element() < 1e-5, "{}", c.relit_radiance(Vec3::ZERO));
        // The second cell's mean falls below zero, 8 − 20 = −12: it stays
        // signed ([`crate::relight::spread_deficits`] takes it from its neighbours).
        assert!((cells[1].relit_radiance(Vec3::ZERO) - Vec3::splat(-12.0)).abs().max_element() < 1e-5);
        // D(t) is made once: the next change asks only for D(now).
        let mut asked_again = 0;
        let made = a.relight(
            &mut |jobs| {
                asked_again += jobs.len();
                jobs.iter().map(|_| Vec3::ZERO).collect()
            },
            &mut |jobs| jobs.iter().map(|&(_, id)| Vec3::splat([4.0, 2.0, -14.0][id as usize - 1])).collect(),
        );
        assert_eq!((made, asked_again), (3, 0));
        assert_eq!(a.cells(&s).unwrap(), cells);
        // An estimator that answers short changes nothing.
        assert_eq!(a.relight(&mut |_| Vec::new(), &mut |_| Vec::new()), 0);
        assert_eq!(a.cells(&s).unwrap(), cells);
    }

    /// A drawn probe lies in the site's own cell, and u walks the cell's
    /// probes in order of their areas: the probe drawn at u is the one whose
    /// running share of the cell's area first passes u, so a uniform u picks
    /// each probe with the share of the area it stands for.
    #[test]
    fn a_drawn_probe_is_one_of_the_cell_by_its_share_of_the_area() {
        let scene = floor(false);
        let mut a = AreaProbes::new(2);
        for k in 0..2 {
            let hits = uniform(200, 5, k);
            push(&mut a, &hits, &vec![Vec3::Y; hits.len()], &[]);
        }
        let s = sites(&[Vec3::new(0.25, 0.0, 0.5), Vec3::new(0.75, 0.0, 0.5)]);
        a.assign(&scene, &CpuRays, &s);
        let cells = a.cells(&s).unwrap();
        // The probes of the first cell in batch order, with their weighted areas.
        let weights = a.weights();
        let own: Vec<(Vec3, f64)> = a
            .batches
            .iter()
            .zip(&weights)
            .flat_map(|(b, &w)| {
                b.iter().filter(|q| q.owner == Owner::Vpl { id: 100, slot: 0 } && q.area > 0.0).map(move |q| (q.p, w * q.area as f64))
            })
            .collect();
        let total: f64 = own.iter().map(|o| o.1).sum();
        assert!((total - cells[0].area).abs() < 1e-9 * total.max(1.0));
        for u in [0.0f32, 0.1, 0.37, 0.5, 0.8, 0.999] {
            let drawn = a.drawn_probes(&s, &cells, &[Some(u), None]);
            assert_eq!(drawn[1], None);
            let (p, n) = drawn[0].expect("a probe");
            assert_eq!(n, Vec3::Y);
            // Its running share: the areas before it at most u, with it above.
            let k = own.iter().position(|o| o.0 == p).expect("a probe of the first cell");
            let before: f64 = own[..k].iter().map(|o| o.1).sum();
            assert!(before <= u as f64 * total + 1e-9 && before + own[k].1 > u as f64 * total - 1e-9, "u {u}: {before} of {total}");
            assert!(p.x < 0.5 + 1e-6, "{p}");
        }
    }

    /// The triangle window weighs the iterations 1, 2, …, 2, 1 and the
    /// parabola (b + 1)(T − b) (each summing to 1); a cell's area is that
    /// weighted mean of its iterations' areas, and the cells still sum to
    /// the probes' area.
    #[test]
    fn the_windows_weigh_the_middle_iterations_most() {
        let scene = floor(false);
        let s = sites(&[Vec3::new(0.25, 0.0, 0.5), Vec3::new(0.75, 0.0, 0.5)]);
        // Four iterations: uniform points on the square's left part up to x = 0.25 (k + 1).
        let mut areas = [Vec::new(), Vec::new(), Vec::new()];
        for (w, window) in [ProbeWindow::Box, ProbeWindow::Triangle, ProbeWindow::Parabola].into_iter().enumerate() {
            let mut a = AreaProbes::new(4).with_window(window);
            for k in 0..4 {
                let x1 = 0.25 * (k + 1) as f32;
                let hits: Vec<Vec3> = uniform(4000, 9, k).into_iter().map(|p| Vec3::new(x1 * p.x, 0.0, p.z)).collect();
                push(&mut a, &hits, &vec![Vec3::Y; hits.len()], &[]);
            }
            let weights = a.weights();
            let expect: [f64; 4] = match window {
                ProbeWindow::Box => [0.25; 4],
                ProbeWindow::Triangle => [1.0 / 6.0, 2.0 / 6.0, 2.0 / 6.0, 1.0 / 6.0],
                ProbeWindow::Parabola => [0.2, 0.3, 0.3, 0.2],
            };
            assert!(weights.iter().zip(expect).all(|(w, e)| (w - e).abs() < 1e-12), "{window}: {weights:?}");
            a.assign(&scene, &CpuRays, &s);
            let cells = a.cells(&s).unwrap();
            let sum: f64 = cells.iter().map(|c| c.area).sum();
            assert!((sum - a.total_area()).abs() < 1e-9 * sum, "{window}: {sum} against {}", a.total_area());
            areas[w] = cells.iter().map(|c| c.area).collect();
        }
        // The right cell holds area only in the later iterations (x > 0.5):
        // 0.25 and 0.5 of the square in the last two; box (0 + 0 + 0.25 + 0.5) / 4,
        // triangle (2 · 0.25 + 0.5) / 6, 12 % apart, parabola 0.3 · 0.25 +
        // 0.2 · 0.5 = 0.175. Each hit's area
        // π r_1² (N − 1) / N has a relative spread of about 1, so a cell of
        // some 1000 hits an iteration is measured to about 3 %; the bound is
        // 8 %.
        assert!((areas[0][1] / 0.1875 - 1.0).abs() < 0.08, "box: {:?}", areas[0]);
        assert!((areas[1][1] * 6.0 - 1.0).abs() < 0.08, "triangle: {:?}", areas[1]);
        assert!((areas[2][1] / 0.175 - 1.0).abs() < 0.08, "parabola: {:?}", areas[2]);
    }

    /// A cell's radiance is brought forward by its VPL's own change: the
    /// candidates were estimated when the VPL's luminance was 1, it is 2
    /// now, so the cell's radiance doubles; with equal records, or no
    /// record of the VPL then, the mean stays as it is.
    #[test]
    fn the_cells_radiance_follows_its_vpls_change() {
        let scene = floor(false);
        let s = sites(&[Vec3::new(0.25, 0.0, 0.5), Vec3::new(0.75, 0.0, 0.5)]);
        let hits: Vec<Vec3> = uniform(400, 3, 0);
        let normals = vec![Vec3::Y; hits.len()];
        let run = |then: Option<f32>, now: f32| {
            let mut a = AreaProbes::new(2);
            push(&mut a, &hits, &normals, &[(0, Vec3::splat(3.0))]);
            if let Some(y) = then {
                a.record(&[(0, 100, Vec3::splat(y)), (1, 101, Vec3::splat(y))]);
            }
            push(&mut a, &hits, &normals, &[]);
            a.record(&[(0, 100, Vec3::splat(now)), (1, 101, Vec3::splat(now))]);
            // A second record of the same iteration changes nothing.
            a.record(&[(0, 100, Vec3::splat(50.0)), (1, 101, Vec3::splat(50.0))]);
            a.assign(&scene, &CpuRays, &s);
            let cells = a.cells(&s).unwrap();
            let owner = if hits[0].x < 0.5 { 0 } else { 1 };
            (cells[owner].mean_radiance(Vec3::ZERO), cells[owner].current_radiance(Vec3::ZERO))
        };
        let (mean, now) = run(Some(1.0), 2.0);
        assert!(
            (mean - Vec3::splat(3.0)).abs().max_element() < 1e-5 && (now - Vec3::splat(6.0)).abs().max_element() < 1e-4,
            "{mean} {now}"
        );
        let (mean, now) = run(Some(2.0), 2.0);
        assert!((now - mean).abs().max_element() < 1e-5, "{mean} {now}");
        let (mean, now) = run(None, 2.0);
        assert!((now - mean).abs().max_element() < 1e-5, "{mean} {now}");
    }

    fn probes(depth: usize, n: usize, seed: u64) -> AreaProbes {
        let mut a = AreaProbes::new(depth);
        for t in 0..depth {
            push(&mut a, &uniform(n, seed, t as u64), &vec![Vec3::Y; n], &[]);
        }
        a
    }

    fn sites(points: &[Vec3]) -> Vec<Site> {
        points.iter().enumerate().map(|(i, &p)| Site { id: 100 + i as u64, slot: i as u32, p, n: Vec3::Y }).collect()
    }

    fn areas(a: &mut AreaProbes, scene: &Scene, s: &[Site]) -> Vec<f64> {
        a.assign(scene, &CpuRays, s);
        a.cells(s).unwrap().iter().map(|c| c.area).collect()
    }

    /// The probes measure the unit square. Each iteration's total is a sum
    /// of N nearly independent Exp(1)-like areas of mean 1/N, so its relative
    /// standard error is about √(1/N); over 8 × 4096 probes that is 0.55 %,
    /// and the test allows 4 of them (2.2 %) plus the edge effect: a hit
    /// within r_1 of the square's edge sees neighbours on one side only, so
    /// its r_1 is larger (about 2 % of the hits, by up to 2×).
    #[test]
    fn probes_measure_the_area_they_cover() {
        let a = probes(8, 4096, 3);
        let total = a.total_area();
        assert!((total - 1.0).abs() < 0.022 + 0.02, "{total}");
    }

    /// `n` independent points on the floor's unit square with the density
    /// p(x, z) = 3x² (x = u^⅓).
    fn steep(n: usize, seed: u64, index: u64) -> Vec<Vec3> {
        uniform(n, seed, index).into_iter().map(|p| Vec3::new(p.x.cbrt(), 0.0, p.z)).collect()
    }

    /// Where hits, and so the VPLs, are denser on one side (p = 3x²), the
    /// VPLs sit on the dense side of their cells. With W = p (what the hits'
    /// density measures) and L = 1, the image mean Σ Φ_i W(y_i) should be
    /// ∫ W dA = 1: the cells' areas overshoot it, and the areas near the
    /// VPLs (eq. 4) keep it. Each of 16 seeds: 64 VPLs and 8 iterations of
    /// 4096 hits, both drawn from p.
    ///
    /// Bounds: the areas near the VPLs within 2 % (the probes' own excess
    /// at the square's edges, see `probes_measure_the_area_they_cover`)
    /// plus 3 standard errors over the seeds of 1; the cells past 1.05 by
    /// more than 3 of theirs, so that the test sees the bias it removes.
    /// Measured: 1.010 ± 0.003 and 1.100 ± 0.011.
    #[test]
    fn areas_near_the_vpl_keep_the_light_the_camera_sees() {
        let scene = floor(false);
        let (mut cell, mut near) = (Vec::new(), Vec::new());
        for seed in 0..16 {
            let mut a = AreaProbes::new(8);
            for t in 0..8 {
                push(&mut a, &steep(4096, seed, t), &vec![Vec3::Y; 4096], &[]);
            }
            let s = sites(&steep(64, seed, 100));
            let areas = areas(&mut a, &scene, &s);
            let ratios = a.near_ratios(&s);
            let w = |i: usize| 3.0 * (s[i].p.x as f64).powi(2);
            cell.push((0..s.len()).map(|i| areas[i] * w(i)).sum::<f64>());
            near.push((0..s.len()).map(|i| areas[i] * ratios[i] * w(i)).sum::<f64>());
        }
        let stats = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
            (m, (var / v.len() as f64).sqrt())
        };
        let ((c, c_se), (n, n_se)) = (stats(&cell), stats(&near));
        eprintln!("image mean over the truth: cells {c:.3} ± {c_se:.3}, areas near the VPLs {n:.3} ± {n_se:.3}");
        assert!((n - 1.0).abs() < 0.02 + 3.0 * n_se, "areas near the VPLs: {n:.3} ± {n_se:.3}");
        assert!(c - 1.0 > 0.05 + 3.0 * c_se, "cells: {c:.3} ± {c_se:.3}: the bias this test guards against is gone");
    }

    /// Voronoi cells of a regular lattice are all 1/n of the square; the
    /// kNN area of the same lattice depends on its arrangement.
    #[test]
    fn cells_of_a_lattice_are_equal_and_tile_the_square() {
        let side = 16;
        let points: Vec<Vec3> = (0..side * side)
            .map(|i| Vec3::new(((i % side) as f32 + 0.5) / side as f32, 0.0, ((i / side) as f32 + 0.5) / side as f32))
            .collect();
        let mut a = probes(16, 8192, 5);
        let cells = areas(&mut a, &floor(false), &sites(&points));
        let sum: f64 = cells.iter().sum();
        assert!((sum - a.total_area()).abs() < 1e-9 * sum, "{sum}");
        // Each cell holds about 16 × 8192 / 256 = 512 probes: relative standard
        // error about √(2/512) = 6 % (count and area noise); 5 of them.
        let mean = sum / cells.len() as f64;
        let worst = cells.iter().map(|c| (c / mean - 1.0).abs()).fold(0.0, f64::max);
        assert!(worst < 0.31, "worst cell off by {worst}");
        // The kNN area of an interior point (k = 8): the 8th neighbour of a
        // square lattice is √2 spacings away, so π r_8² / 8 = 2π/8 = 0.785
        // cells (a hexagonal lattice gives 1.36: the bias has no fixed sign).
        let knn = KnnDensity::new(&points).unwrap().member_radii_sq(8);
        let interior = (side + 1) * 3;
        let ratio = std::f64::consts::PI * knn[interior] as f64 / 8.0 * (side * side) as f64;
        assert!((ratio - std::f64::consts::PI * 2.0 / 8.0).abs() < 1e-3, "{ratio}");
    }

    /// A wall at x = 0.5 and a site on each side, at x = 0.25 and 0.9: the
    /// floor between the wall and the midpoint x = 0.575 lies nearer the
    /// left site but cannot see it, so each cell is its side's half. Each
    /// half holds about 8 × 4096 / 2 probes (relative standard error
    /// √(2/16384) = 1.1 %); 4 of them plus 2 % for the square's edges and
    /// the wall (hits beside it see neighbours on one side only).
    #[test]
    fn a_wall_keeps_the_cells_apart() {
        let scene = floor(true);
        let mut a = probes(8, 4096, 9);
        let cells = areas(&mut a, &scene, &sites(&[Vec3::new(0.25, 0.0, 0.5), Vec3::new(0.9, 0.0, 0.5)]));
        for c in &cells {
            assert!((c - 0.5).abs() < 0.5 * (0.045 + 0.02), "{cells:?}");
        }
        // Without the wall, the cells split at the midpoint.
        let mut a = probes(8, 4096, 9);
        let cells = areas(&mut a, &floor(false), &sites(&[Vec3::new(0.25, 0.0, 0.5), Vec3::new(0.9, 0.0, 0.5)]));
        assert!((cells[0] - 0.575).abs() < 0.575 * 0.065, "{cells:?}");
    }

    /// Eight VPLs stand behind the wall at x = 0.45, one in front of it at
    /// x = 0.95, and the probes cover the floor in front (x in [0.5, 1]).
    /// For the probes along the wall the four nearest VPLs are all behind
    /// it; the owner of their neighbours sees them, so the one VPL in front
    /// owns every probe and its cell is the whole half.
    #[test]
    fn probes_behind_the_nearest_vpls_join_their_neighbours_cell() {
        let scene = floor(true);
        let mut a = AreaProbes::new(4);
        let mut hits = Vec::new();
        for t in 0..4 {
            let batch: Vec<Vec3> = uniform(4096, 13, t).into_iter().map(|p| Vec3::new(0.5 + 0.5 * p.x, 0.0, p.z)).collect();
            push(&mut a, &batch, &vec![Vec3::Y; batch.len()], &[]);
            hits.extend(batch);
        }
        let mut points: Vec<Vec3> = (0..8).map(|i| Vec3::new(0.45, 0.0, (i as f32 + 0.5) / 8.0)).collect();
        points.push(Vec3::new(0.95, 0.0, 0.5));
        let s = sites(&points);
        // The probes whose four nearest VPLs all stand behind the wall (the
        // ones the first two passes cannot place): a band along it.
        let behind = hits
            .iter()
            .filter(|q| {
                let mut d: Vec<f32> = points.iter().map(|p| (*p - **q).length_squared()).collect();
                let front = d[8];
                d.sort_by(f32::total_cmp);
                front > d[3]
            })
            .count() as f64
            / hits.len() as f64;
        assert!(behind > 0.05, "the band is only {behind} of the probes");
        let cells = areas(&mut a, &scene, &s);
        let total = a.total_area();
        assert!(cells[..8].iter().all(|&c| c == 0.0), "{cells:?}");
        assert!((cells[8] - total).abs() < 1e-9 * total, "the VPL in front owns {} of {total}", cells[8]);
        assert!(a.batches.iter().flatten().all(|q| q.owner == live_owner(&s, 8)));
    }

    /// The cells partition the probes, whatever the set: here every VPL
    /// stands behind the wall and no probe in front sees one, yet every
    /// usable probe joins a cell (its nearest VPL on its side) and the
    /// cells' areas sum to the probes' area. Before, those probes belonged
    /// to no cell and their light was lost.
    #[test]
    fn the_cells_partition_the_probes_even_when_no_vpl_is_seen() {
        let scene = floor(true);
        let mut a = AreaProbes::new(2);
        for t in 0..2 {
            let batch: Vec<Vec3> = uniform(2048, 17, t).into_iter().map(|p| Vec3::new(0.5 + 0.5 * p.x, 0.0, p.z)).collect();
            push(&mut a, &batch, &vec![Vec3::Y; batch.len()], &[]);
        }
        let points: Vec<Vec3> = (0..8).map(|i| Vec3::new(0.2 + 0.03 * i as f32, 0.0, (i as f32 + 0.5) / 8.0)).collect();
        let s = sites(&points);
        let cells = areas(&mut a, &scene, &s);
        let total = a.total_area();
        assert!(total > 0.4, "{total}");
        let sum: f64 = cells.iter().sum();
        assert!((sum - total).abs() < 1e-9 * total, "the cells hold {sum} of {total}");
        assert!(a.batches.iter().flatten().all(|q| !q.counts() || q.owner != Owner::Nobody));
    }

    fn live_owner(s: &[Site], i: usize) -> Owner {
        Owner::Vpl { id: s[i].id, slot: s[i].slot }
    }

    /// A VPL that joins takes its cell from its neighbours at once: the
    /// cells stay the Voronoi cells of the set, and tile the probes.
    #[test]
    fn a_newcomer_takes_its_cell_from_its_neighbours() {
        let scene = floor(false);
        let mut a = probes(8, 4096, 11);
        let mut s = sites(&[Vec3::new(0.25, 0.0, 0.5), Vec3::new(0.75, 0.0, 0.5)]);
        let before = areas(&mut a, &scene, &s);
        assert!((before[0] - 0.5).abs() < 0.5 * 0.065, "{before:?}");
        // A third VPL at the top edge: the cells become x < 0.5 below the line
        // z = 0.5 + (x − 0.25)… by symmetry 3/8, 3/8 and 1/4 of the square.
        s.push(Site { id: 7, slot: 2, p: Vec3::new(0.5, 0.0, 1.0), n: Vec3::Y });
        let rays = a.assign(&scene, &CpuRays, &s);
        assert!(rays > 0);
        let cells: Vec<f64> = a.cells(&s).unwrap().iter().map(|c| c.area).collect();
        let sum: f64 = cells.iter().sum();
        assert!((sum - a.total_area()).abs() < 1e-9 * sum);
        let exact = voronoi_by_grid(&[Vec3::new(0.25, 0.0, 0.5), Vec3::new(0.75, 0.0, 0.5), Vec3::new(0.5, 0.0, 1.0)]);
        for (c, e) in cells.iter().zip(&exact) {
            assert!((c - e).abs() < e * 0.08 + 0.01, "{cells:?} against {exact:?}");
        }
        // A VPL that leaves gives its probes back.
        s.remove(0);
        let cells: Vec<f64> = areas(&mut a, &scene, &s);
        assert!((cells.iter().sum::<f64>() - a.total_area()).abs() < 1e-9);
    }

    /// Two VPLs at x = 0.1 and x = 0.9 on the unit square split it at
    /// x = 0.5: their cells' centroids are (0.25, 0.5) and (0.75, 0.5),
    /// far from the sites, and the probe nearest each centroid is found
    /// among the cell's own probes, the same on one thread and on two.
    #[test]
    fn cells_know_their_centroids_and_the_probe_nearest_them() {
        let scene = floor(false);
        let mut a = probes(4, 4000, 11);
        let s = sites(&[Vec3::new(0.1, 0.0, 0.5), Vec3::new(0.9, 0.0, 0.5)]);
        a.assign(&scene, &CpuRays, &s);
        let cells = a.cells(&s).unwrap();
        // Area-weighted mean of 16,000 probes of exponential areas: within 0.02.
        for (c, want) in cells.iter().zip([Vec3::new(0.25, 0.0, 0.5), Vec3::new(0.75, 0.0, 0.5)]) {
            assert!((c.centroid - want).length() < 0.02, "centroid {} against {want}", c.centroid);
        }
        let targets: Vec<Vec3> = cells.iter().map(|c| c.centroid).collect();
        let near = a.nearest_probes(&s, &targets);
        // The brute-force nearest probe of each cell.
        let live = Live::new(&s);
        for (i, got) in near.iter().enumerate() {
            let want = a
                .batches
                .iter()
                .flatten()
                .filter(|q| live.get(q.owner) == Some(i) && q.area > 0.0)
                .min_by(|x, y| (x.p - targets[i]).length_squared().total_cmp(&(y.p - targets[i]).length_squared()))
                .unwrap();
            assert_eq!(got.unwrap(), (want.p, want.ns));
            assert!((want.p - targets[i]).length() < 0.05);
        }
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        assert_eq!(one.install(|| a.nearest_probes(&s, &targets)), near);
        assert_eq!(one.install(|| a.cells(&s)).unwrap(), cells);
        // A site without probes: its own position, and no probe.
        let mut s3 = s.clone();
        s3.push(Site { id: 9, slot: 5, p: Vec3::new(5.0, 0.0, 5.0), n: Vec3::Y });
        let cells = a.cells(&s3).unwrap();
        assert_eq!(cells[2].centroid, Vec3::new(5.0, 0.0, 5.0));
        assert_eq!(a.nearest_probes(&s3, &[Vec3::ZERO; 3])[2], None);
    }

    /// Voronoi areas of sites on the unit square, counted on a fine grid.
    fn voronoi_by_grid(sites: &[Vec3]) -> Vec<f64> {
        let n = 400;
        let mut areas = vec![0.0; sites.len()];
        for i in 0..n {
            for j in 0..n {
                let p = Vec3::new((i as f32 + 0.5) / n as f32, 0.0, (j as f32 + 0.5) / n as f32);
                let k =
                    (0..sites.len()).min_by(|a, b| (sites[*a] - p).length_squared().total_cmp(&(sites[*b] - p).length_squared())).unwrap();
                areas[k] += 1.0 / (n * n) as f64;
            }
        }
        areas
    }

    /// Fewer probes than hits: every s-th hit (from an offset that turns
    /// with the iterations) stands for s times its own area, and the other
    /// candidates are kept for their radiance alone.
    #[test]
    fn fewer_probes_keep_every_s_th_hit_and_every_candidate() {
        let hits = uniform(40, 3, 0);
        let up = vec![Vec3::Y; 40];
        let all = {
            let tree = KnnDensity::new(&hits).unwrap();
            surface_neighbour_sq(&tree, &hits, &up, &tree.member_nearest())
        };
        let own = std::f32::consts::PI * 39.0 / 40.0;
        let mut a = AreaProbes::new(2).with_per_iteration(10);
        for offset in [0, 1] {
            push(&mut a, &hits, &up, &[(1, Vec3::ONE), (2, Vec3::ONE), (4, Vec3::ONE)]);
            let (batch, carried) = (a.batches.back().unwrap(), a.carried.back().unwrap());
            let kept: Vec<usize> = (offset..40).step_by(4).collect();
            let candidates_besides = [1, 2, 4].iter().filter(|&&h| h % 4 != offset).count();
            assert_eq!(batch.len(), kept.len() + candidates_besides, "offset {offset}");
            for (q, &h) in batch.iter().zip(&kept) {
                assert_eq!(q.p, hits[h]);
                assert!((q.area - 4.0 * own * all[h]).abs() <= 1e-6 * q.area, "hit {h}: {} against 4 × {}", q.area, own * all[h]);
            }
            for q in &batch[kept.len()..] {
                assert!(q.area == 0.0 && q.carried(carried).map(|c| c.radiance) == Some(Vec3::ONE) && q.owner == Owner::Unassigned);
            }
            assert_eq!(batch.iter().filter(|q| q.carried(carried).is_some()).count(), 3);
        }
    }

    #[test]
    fn the_oldest_iteration_goes_and_bad_hits_stand_for_nothing() {
        let scene = floor(false);
        let mut a = AreaProbes::new(2);
        let hits = [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 0.0, 2.0)];
        let up = [Vec3::Y; 3];
        push(&mut a, &hits, &up, &[]);
        push(&mut a, &hits, &up, &[(0, Vec3::ONE), (1, Vec3::ONE)]);
        push(&mut a, &hits, &up, &[(0, Vec3::splat(3.0)), (9, Vec3::ONE), (2, Vec3::NAN)]);
        assert_eq!(a.len(), 2);
        // Nearest others: 1, 1 and 2 away.
        let scale = std::f64::consts::PI * 2.0 / 3.0;
        assert!((a.total_area() - scale * 6.0).abs() < 1e-5, "{}", a.total_area());
        assert_eq!(AreaProbes::new(1).cells(&[]), None);
        // Hits 0 and 1 of the second iteration and hit 0 of the third were
        // candidates (a non-finite radiance is not one).
        let s = sites(&[Vec3::ZERO, Vec3::X, Vec3::new(0.0, 0.0, 2.0)]);
        a.assign(&scene, &CpuRays, &s);
        let cells = a.cells(&s).unwrap();
        assert_eq!((cells[0].candidates, cells[1].candidates, cells[2].candidates), (2, 1, 0));
        assert_eq!(cells[0].mean_radiance(Vec3::ZERO), Vec3::splat(2.0));
        assert_eq!(cells[2].mean_radiance(Vec3::Y), Vec3::Y);
        push(&mut a, &[Vec3::ZERO], &[Vec3::Y], &[]);
        assert_eq!(a.len(), 2, "a lone hit adds nothing");
        // Coincident hits (r_1 = 0) stand for nothing and belong to no cell.
        push(&mut a, &[Vec3::ZERO, Vec3::X, Vec3::ZERO], &up, &[]);
        let last = a.batches.back().unwrap();
        assert!(last[2].area == 0.0 && last[2].owner == Owner::Nobody && last[1].area > 0.0);
        a.clear();
        assert!(a.is_empty() && a.cells(&s).is_none());
    }

    /// Behind a thin wall the nearest point faces the other way; the
    /// surface's own neighbour is taken instead. Across a right-angled edge
    /// the neighbour counts.
    #[test]
    fn neighbours_are_found_on_the_same_side() {
        // A floor point; 0.022 away, the underside of the thin floor, facing
        // down; 0.1 away a wall point facing −x (a right angle: kept); 0.5
        // away a floor point.
        let pts = [Vec3::ZERO, Vec3::new(-0.02, -0.01, 0.0), Vec3::new(0.1, 0.01, 0.0), Vec3::new(-0.5, 0.0, 0.0)];
        let ns = [Vec3::Y, Vec3::NEG_Y, Vec3::NEG_X, Vec3::Y];
        let tree = KnnDensity::new(&pts).unwrap();
        let r = surface_neighbour_sq(&tree, &pts, &ns, &tree.member_nearest());
        assert!((r[0] - (0.1f32 * 0.1 + 0.01 * 0.01)).abs() < 1e-6, "{r:?}");
        // The underside's only neighbour on its side is the wall point.
        assert!((r[1] - (0.12f32 * 0.12 + 0.02 * 0.02)).abs() < 1e-6, "{r:?}");
        let one = KnnDensity::new(&[Vec3::ZERO]).unwrap();
        assert!(surface_neighbour_sq(&one, &[Vec3::ZERO], &[Vec3::Y], &[None])[0].is_infinite());
    }

    #[test]
    fn names_parse() {
        for e in FluxEstimator::ALL {
            assert_eq!(FluxEstimator::from_param(e.name()), Some(e));
        }
        assert_eq!(FluxEstimator::from_param("area"), None);
    }

    /// The areas near a VPL are measured at its own point: a placement that
    /// moves it is refused with them, with a typed error.
    #[test]
    fn the_near_areas_need_the_vpls_own_point() {
        use crate::{Placement, SmcConfig, SmcError};
        let config = |placement| SmcConfig { flux: FluxEstimator::VoronoiNear, placement, ..SmcConfig::default() };
        assert_eq!(config(Placement::Site).validate(), Ok(()));
        for placement in [Placement::Centroid, Placement::Random] {
            assert!(matches!(config(placement).validate(), Err(SmcError::Invalid(_))), "{placement}");
        }
    }
}
