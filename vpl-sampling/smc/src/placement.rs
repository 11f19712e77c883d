//! Where in its Voronoi cell a VPL shines from.
//!
//! With the cell fluxes of [`crate::FluxEstimator::Voronoi`], the set
//! renders the quadrature
//!
//! ```text
//! Σ_i Φ_i f(x) G(x, y_i)  ≈  Σ_i ∫_{V_i} L(y) f(x) G(x, y) dA(y),        (1)
//! ```
//!
//! whose error, cell by cell, is Φ_i times the difference between the value
//! of f G at the point y_i and its mean over the cell's light. Taylor's
//! expansion of f G about the cell's centre of light c_i,
//!
//! ```text
//! f G(y_i) − mean_{V_i} f G  =  ∇(f G) · (y_i − c_i)  +  O(|V_i|),        (2)
//! ```
//!
//! has a first-order term that vanishes only when the VPL stands at the
//! centroid. The VPL's own point (the particle y_i, [`Placement::Site`]) is
//! the site that generated the cell, not its centroid: cells are cut by the
//! edges of surfaces and by what the probes see, so a site near an edge has
//! most of its cell on one side. Where cells are small against the changes
//! of f G (rooms lit by 2048 VPLs) the term is small; on the Munich blocks
//! the sites lie 8 m from their cells' centroids on average (cells are
//! about 22 m across) and the image came out 5 % too bright with the cells'
//! fluxes right.
//!
//! [`Placement::Centroid`] removes the first-order term: the VPL shines
//! from the probe of its cell nearest the centroid of the cell's part on
//! the VPL's own smooth surface
//!
//! ```text
//! c_i = Σ_{h ∈ V_i, n_h · n_i > ½} b_h p_h / Σ_{h ∈ V_i, n_h · n_i > ½} b_h       (3)
//! ```
//!
//! (probes h at p_h with normals n_h, each standing for the area b_h; a
//! probe, so that the VPL stays on a surface with that surface's normal;
//! the own surface, because the centroid of a cell that turns a corner lies
//! in the air and the probe nearest it on the corner's edge, from where the
//! VPL lights neither face; a first version that took the whole cell left
//! Dabrovic's Sponza 3.7 % dark). The centroid is taken by area: the
//! cell's flux is its area times its mean candidate radiance, so its light
//! is spread as its area is.
//!
//! Measured with the cells that partition the probes (see `flux`'s
//! "Which cell"; unclamped, ray-traced, exhaustive indirect image over
//! path tracing's, I = 2048 after the 100-iteration warm-up, frame 0,
//! `tests/tests/smc.rs`; sites then centroids): `cornell` (64×64, 3
//! seeds) 0.992 and 1.000; `office` (64×48) 1.014 and 1.011; `atrium`
//! (64×48) 1.025 and 1.025; at the centroids, Dabrovic's Sponza (96×72, 4
//! seeds) 1.002 ± 0.004 and the Munich blocks (96×72, 16 seeds) 1.038 ±
//! 0.013, whose seeds spread widely (a VPL beside a façade lights the
//! pixels near it at 1/d²: 0.990 to 1.165). Before the partition, when
//! probes no tried VPL saw were dropped, Sponza was 0.978 and the Munich
//! blocks 1.020 ± 0.015 (20 seeds); the sites on Munich 1.060 ± 0.009. In
//! Table 1 neither placement won on both |E| and |E′| when it was last
//! measured (the differences lay within the intervals), so the site stays
//! the default.
//!
//! With 4 probes a VPL and the triangle window (`vpl energy --scene munich
//! --checkpoints 0 --seeds 16 --size 48x36 --spp 256`), the Munich blocks
//! at frame 0 came out 1.109 ± 0.016 at the sites (median 1.104) and, at
//! the centroids, a median of 1.025 but a mean of 1.19 ± 0.14: one seed in
//! 16 gave 3.25. Its image is one VPL's: a cell of some 2,000 m² on a far
//! façade, measured by a few sparse probes, carries 150 times the flux of
//! any other VPL, and from its centroid's probe it lights, a few metres
//! away, a façade the view sees in the distance. A point stands for such a
//! cell's light only far from it. The sites' offset (eq. 2) makes most
//! seeds bright; the centroids remove it but leave the tail, which here
//! made their mean the worse. (Spreading each VPL as a disc of its cell's
//! area, 1/(d² + |V_i|/π) in place of 1/d², removed the tail but lost a
//! fifth of the light, 0.80: that approximation of a disc does not
//! conserve energy.)
//!
//! [`Placement::Random`] makes the quadrature right in expectation instead
//! of to first order: when a VPL joins, it draws the point it shines from
//! among its cell's probes by the area each stands for, y ~ dA / |V_i| over
//! the cell, so E[f G(y)] is the mean of f G over the cell and eq. (1)'s
//! error has expectation zero for a cell of any shape and size (with the
//! cell's light spread evenly over it, as the cell flux has it). The draw
//! comes from a stream keyed by the VPL's id and is kept for the VPL's
//! life, so it moves nothing from frame to frame and costs no share of
//! M_max. Where the far façade's huge cell above made the centroid's mean
//! the worse, the drawn point is as likely anywhere in the cell: its error
//! is variance, not bias. At frame 0 of the Munich blocks (32×24, seeds
//! 0–3, the `cell_pieces` example of vpl-bench) the images came out 1.029,
//! 0.963, 0.926 and 1.034 of the path tracer's, against 1.438, 1.127,
//! 1.016 and 1.114 at the sites, and 1.031, 1.067, 1.003 and 1.027 with
//! every cell spread over all of its probes. With `vpl energy` (48×36, the
//! truth at 256 paths a pixel; sequences with 3 seeds and 3 checkpoints,
//! stepped every 8th frame and at each of the 32 before) the Munich
//! blocks at frame 0 came out 1.023 ± 0.024 over 16 seeds (median 0.990;
//! at the sites 1.109 ± 0.016), and along their sequence 1.070 ± 0.028
//! (the sites 1.130 ± 0.021). On the built-in scenes the drawn points
//! show the cells' own errors, which the sites' offset partly hid:
//! `atrium` at frame 0 0.949 ± 0.011 (the sites 0.994 ± 0.010; its cells
//! spread over their probes gave 0.969 and 0.943 for two seeds at 32×24),
//! `courtyard` 0.997 and along its sequence 1.001 (1.007 and 1.014); and
//! one seed's image spreads more (`building`'s frame 0: ± 0.033 against ±
//! 0.013).
//!
//! The particle keeps its own point for every decision of Algorithm 1
//! (densities, intensities, mailboxes); only the VPL handed to the renderer
//! moves. A VPL that joins the set shines from its cell's probe at once.
//! Later, to keep the image stable, it keeps the point it shines from until
//! a probe lies nearer the centroid by more than [`KEEP_WITHIN`] of the
//! cell's radius √(|V_i| / π) (the probes that measure a cell turn over
//! every T iterations, and its centroid wanders with them and with its
//! neighbours' arrivals), and such moves share Algorithm 1's budget: at
//! most M_max VPLs move in a frame, replaced ones included, those whose
//! probe gains the most first ([`settle`]). On a static `office` view the
//! sites alone move 1.4 VPLs a frame and about 20 move with this placement
//! (M_max = 16 is the cap whenever Algorithm 1 replaces fewer).

use vpl_core::glam::Vec3;
use vpl_core::params::FromParam;

/// Where a VPL shines from inside its Voronoi cell.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Placement {
    /// The particle's own point y, as in the paper.
    #[default]
    Site,
    /// The probe of its cell nearest the cell's centroid (see the module
    /// text); the site where the cell has no probes.
    Centroid,
    /// A probe of its cell drawn by area when the VPL joins (see the module
    /// text), kept for its life; the site where the cell has no probes.
    Random,
}

impl Placement {
    /// Every placement, the default last.
    pub const ALL: [Placement; 3] = [Placement::Site, Placement::Centroid, Placement::Random];

    /// The parameter value naming the placement.
    pub fn name(self) -> &'static str {
        match self {
            Placement::Site => "site",
            Placement::Centroid => "centroid",
            Placement::Random => "random",
        }
    }
}

impl FromParam for Placement {
    const EXPECTED: &'static str = "site, centroid or random";
    fn from_param(text: &str) -> Option<Self> {
        Placement::ALL.into_iter().find(|e| e.name() == text.trim())
    }
}

impl std::fmt::Display for Placement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The share of a cell's radius √(|V| / π) by which a probe must lie
/// nearer the cell's centroid than the point a VPL shines from before the
/// VPL moves to it.
pub const KEEP_WITHIN: f32 = 0.25;

/// The point a VPL shines from: position and normal (on its lit side).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shown {
    /// The VPL's id: a slot's point belongs to the VPL it was chosen for.
    pub id: u64,
    /// Position.
    pub p: Vec3,
    /// Shading normal, on the lit side.
    pub n: Vec3,
}

/// What VPL `id`, at `site` (position and normal), should shine from this
/// frame, given `previous` (the point it shone from, if it is the same
/// VPL's), its cell's `centroid` and `area`, and `nearest`, the cell's
/// probe nearest the centroid:
///
/// - a VPL new to the slot moves to `nearest`, or to its site when the cell
///   has no probe ([`Choice::Move`] with an infinite gain: it moves anyway);
/// - otherwise [`Choice::Keep`] while the previous point lies no farther
///   from the centroid than the nearest probe plus [`KEEP_WITHIN`] ·
///   √(area / π), or when the cell has no probe;
/// - [`Choice::Move`] to the probe otherwise, with how much nearer the
///   centroid it is, in cell radii.
pub fn choose(id: u64, site: (Vec3, Vec3), previous: Option<Shown>, centroid: Vec3, area: f64, nearest: Option<(Vec3, Vec3)>) -> Choice {
    let (p, n) = nearest.unwrap_or(site);
    let to = Shown { id, p, n };
    match previous {
        Some(s) if s.id == id => {
            if nearest.is_none() {
                return Choice::Keep(s);
            }
            let radius = (area / std::f64::consts::PI).sqrt() as f32;
            let gain = (s.p - centroid).length() - (p - centroid).length();
            if gain <= KEEP_WITHIN * radius { Choice::Keep(s) } else { Choice::Move { to, gain: gain / radius } }
        }
        _ => Choice::Move { to, gain: f32::INFINITY },
    }
}

/// The outcome of [`choose`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Choice {
    /// The VPL keeps the point it shone from.
    Keep(Shown),
    /// The VPL would move to `to`, which lies `gain` cell radii nearer
    /// the centroid.
    Move {
        /// The new point.
        to: Shown,
        /// How much nearer the centroid, in cell radii.
        gain: f32,
    },
}

/// Resolves the [`choose`] of every slot (`None`: an empty slot): VPLs new
/// to their slot move, and of the others at most `budget` move, those of
/// largest gain first (ties by slot); the rest keep their point. Returns
/// each slot's point.
pub fn settle(choices: Vec<Option<Choice>>, previous: &[Option<Shown>], budget: usize) -> Vec<Option<Shown>> {
    let mut movers: Vec<(f32, usize)> = choices
        .iter()
        .enumerate()
        .filter_map(|(s, c)| match c {
            Some(Choice::Move { gain, .. }) if gain.is_finite() => Some((*gain, s)),
            _ => None,
        })
        .collect();
    movers.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut allowed = vec![false; choices.len()];
    movers.iter().take(budget).for_each(|&(_, s)| allowed[s] = true);
    choices
        .into_iter()
        .enumerate()
        .map(|(s, c)| match c? {
            Choice::Keep(at) => Some(at),
            Choice::Move { to, gain } if !gain.is_finite() || allowed[s] => Some(to),
            Choice::Move { .. } => previous.get(s).copied().flatten(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for p in Placement::ALL {
            assert_eq!(Placement::from_param(p.name()), Some(p));
            assert_eq!(p.to_string(), p.name());
        }
        assert_eq!(Placement::from_param("middle"), None);
        assert_eq!(Placement::default(), Placement::Site);
    }

    #[test]
    fn a_vpl_keeps_its_point_while_the_probe_is_not_much_nearer_the_centroid() {
        let (n, area) = (Vec3::Y, std::f64::consts::PI * 16.0); // radius 4: keep within 1
        let site = (Vec3::new(-1.0, 0.0, 0.0), n);
        let was = Shown { id: 7, p: Vec3::ZERO, n };
        let probe = |x: f32| Some((Vec3::new(x, 0.0, 0.0), n));
        let centroid = Vec3::new(2.0, 0.0, 0.0);
        // The probe is 0.9 nearer the centroid: kept.
        assert_eq!(choose(7, site, Some(was), centroid, area, probe(0.9)), Choice::Keep(was));
        // 1.1 nearer: it would move, by a gain of 1.1 / 4 radii.
        let Choice::Move { to, gain } = choose(7, site, Some(was), centroid, area, probe(1.1)) else { panic!("no move") };
        assert_eq!(to.p, Vec3::new(1.1, 0.0, 0.0));
        assert!((gain - 1.1 / 4.0).abs() < 1e-6);
        // A centroid in the air above a corner: the nearest probe stays far
        // from it, and the VPL keeps its point as long as no probe is nearer.
        let corner = Vec3::new(0.0, 3.0, 0.0);
        assert_eq!(choose(7, site, Some(was), corner, area, probe(0.5)), Choice::Keep(was));
        // Another VPL in the slot never inherits the point, and always moves.
        let new = Choice::Move { to: Shown { id: 8, p: Vec3::ZERO, n }, gain: f32::INFINITY };
        assert_eq!(choose(8, site, Some(was), centroid, area, probe(0.0)), new);
        // No probe: the point it had, or (new) its site.
        assert_eq!(choose(7, site, Some(was), centroid, area, None), Choice::Keep(was));
        let at_site = Choice::Move { to: Shown { id: 8, p: site.0, n }, gain: f32::INFINITY };
        assert_eq!(choose(8, site, Some(was), centroid, area, None), at_site);
        assert_eq!(choose(8, site, None, centroid, area, None), at_site);
    }

    #[test]
    fn at_most_the_budget_moves_largest_gain_first_and_newcomers_always() {
        let at = |id: u64, x: f32| Shown { id, p: Vec3::new(x, 0.0, 0.0), n: Vec3::Y };
        let previous = vec![Some(at(0, 0.0)), Some(at(1, 0.0)), Some(at(2, 0.0)), None, Some(at(4, 0.0))];
        let choices = vec![
            Some(Choice::Move { to: at(0, 1.0), gain: 0.3 }),
            Some(Choice::Move { to: at(1, 1.0), gain: 0.9 }),
            Some(Choice::Keep(at(2, 0.0))),
            Some(Choice::Move { to: at(3, 1.0), gain: f32::INFINITY }),
            Some(Choice::Move { to: at(4, 1.0), gain: 0.5 }),
        ];
        let got = settle(choices.clone(), &previous, 1);
        assert_eq!(got, vec![Some(at(0, 0.0)), Some(at(1, 1.0)), Some(at(2, 0.0)), Some(at(3, 1.0)), Some(at(4, 0.0))]);
        let got = settle(choices, &previous, 2);
        assert_eq!(got[4], Some(at(4, 1.0)));
        assert_eq!(got[0], Some(at(0, 0.0)));
    }
}
