//! How the cells' radiances follow lights that move.
//!
//! A cell's mean radiance L̄(V_i) comes from the candidates of the last T
//! iterations ([`crate::FluxEstimator::Voronoi`]), each estimated under
//! the lights of its own iteration. Under lights that move, the mean
//! lags by about T/2 iterations, and on `building` (a lamp carried from
//! room to room) the lag is most of the error. Measured at frame 360, 40
//! frames into a carry (one seed, 32×24, the sampler stepped every 8th
//! frame and then at each of the 32 before; `SmcSampler::cell_pieces`
//! cuts each cell into its probes, each with its share of the cell's flux):
//!
//! | the cells' light, spread over their probes | image / path tracer |
//! | --- | ---: |
//! | each probe's own radiance now (64 paths), the cells' areas | 0.993 |
//! | each cell's mean of those radiances | 1.016 |
//! | the candidates as estimated in their iterations ([`Relight::None`]) | 1.286 |
//! | scaled by the VPL's own change ([`Relight::Ratio`]) | 1.350 |
//! | [`Relight::Candidates`], 1 path of the direct light alone | 1.252 |
//! | [`Relight::Candidates`], 1 path of 2 bounces | 1.094 |
//! | [`Relight::Candidates`], 4 paths of 2 bounces | 1.054 |
//!
//! and held at frame 360 for 40 iterations, the VPLs at their sites gave
//! 0.995: the areas follow the view, the radiances lag.
//!
//! [`Relight::Candidates`] (the default) moves every cell's mean by the
//! change of a short estimate of its candidates' radiance under common
//! random numbers:
//!
//! ```text
//! L̄_now(V_i) = L̄(V_i) + Σ_h w_h (D_h(now) − D_h(t_h)) / Σ_h w_h,           (1)
//! ```
//!
//! w_h the candidates' weights in the mean, t_h each candidate's
//! iteration, D_h a radiance estimate with `relight-paths` paths (1 by
//! default) of `relight-bounces` bounces after the candidate (by default
//! the radiosity paths': the light that reaches a room through a door
//! comes by more than one bounce, and the direct light alone left most of
//! the lag), drawn from the same random numbers every time (a stream keyed
//! by the candidate's id): the paths keep their vertices, and only their
//! connections to the lights change. The expectation of (1) is the mean
//! of now. Where the difference is noisy against the cell's light (a
//! cell the lamp left), (1) can fall below zero. Held at zero, such cells
//! added light: 7 % of it in the measurement above with 1 path (4 paths
//! halve that at three times the cost), and `building` 10 % bright at a
//! doorway the lamp had just passed. The cells' fluxes stay signed
//! instead, and each negative part is taken from the light of the
//! nearest cells ([`spread_deficits`], eq. 2), which adds none. Both
//! estimates of a candidate are made only at an iteration whose lights
//! changed: D_h(now) for every candidate held (T · I), and D_h(t_h) for
//! those not relit before, under the lights they were made under (the
//! sampler keeps the scene of the last change), with the same random
//! numbers, so it is the value its own iteration would have made. Where
//! the lights stand still no estimate is made; where they move every
//! frame, one iteration's D_h(t_h) (I) is made a frame late.
//!
//! Along the sequences (`vpl energy`, 48×36, 3 seeds, the sampler stepped
//! every 8th frame and at each of the 32 before 3 checkpoints; image mean
//! over the path tracer's at the checkpoints, then their mean):
//!
//! | scene | [`Relight::Ratio`] | [`Relight::Candidates`] |
//! | --- | --- | --- |
//! | `building` | 1.005, 1.111, 1.073: **1.063** | 1.028, 1.034, 1.005: **1.022** |
//! | `colonnade` | 0.981, 0.993, 1.077: **1.017** | 0.977, 0.991, 1.060: **1.010** |
//!
//! (measured while the candidates that joined the set took their VPL's
//! second estimate in their cells; with every candidate's first estimate,
//! as now, `building`'s sequence is 1.030 ± 0.007 and `colonnade`'s 1.010),
//! and the same to the last digit where the lights stand still (`office`,
//! `maze`, `courtyard`, `atrium`'s checkpoints within 0.005). The cost is
//! in the frames whose lights moved: SMC's step on `building` took 111 ms
//! against 96 ms (2 cores, I = 2048; the radiosity step 48 against 37 ms).
//!
//! Spreading the negative parts instead of holding them at zero (eq. 2),
//! measured with `vpl energy` at 64×48, 3 seeds, the same walk, 3
//! checkpoints: `building`'s checkpoint at frame 360, a doorway the lamp
//! has just passed, went from 1.110, 1.098, 1.122 to 0.898, 1.050, 1.069
//! (1.000, 1.052, 1.073 with the nearest 8 cells alone, which left part
//! of the negative light unplaced), and its sequence from 1.040 to 1.004:
//! right on average, more uneven between seeds. With 8 seeds at that
//! checkpoint, by how far a deficit may travel, at the job's 64×48 and
//! at the energy test's 48×36 (truths of 512 and 256 paths a pixel):
//!
//! | rings taken from | 64×48: frame 360, seeds 0–7 | mean | sequence | 48×36: frame 360 | mean | sequence |
//! | --- | --- | ---: | ---: | --- | ---: | ---: |
//! | the nearest 8 | 1.000 1.052 1.073 1.057 1.061 1.078 1.007 0.910 | 1.030 | 1.009 | 0.940 0.920 1.018 0.935 1.005 1.051 0.979 1.024 | 0.984 | 0.990 |
//! | then up to the 32nd | 0.934 1.050 1.069 1.045 1.046 1.073 0.975 0.851 | 1.005 | 1.001 | 0.872 0.878 1.009 0.915 0.999 1.039 0.962 1.015 | 0.961 | 0.983 |
//! | then up to the 128th (the default) | 0.898 1.050 1.069 1.044 1.045 1.073 0.975 0.846 | 1.000 | 1.000 | 0.860 0.865 1.001 0.912 0.990 0.976 0.919 1.015 | 0.942 | 0.977 |
//!
//! The seeds that come out dark are dark with the nearest ring alone
//! too; the outer rings darken them further. At 64×48 the rings remove
//! the 3 % the first ring leaves; at 48×36 they take 4 % more than it.
//! Taking a channel's deficit only from cells whose relit light fell in
//! it (the cells that share the overshoot's cause) changed nothing at
//! 48×36 (0.942, sequence 0.976), so the light the rings take from
//! cells the lamp did not leave is not the cause. Every sequence mean
//! above is within 3 %, and the view dependence at this checkpoint is
//! left open: the first ring is nearer 1 on the mean of the two views
//! (1.007 against 0.971), the rings on the view the job renders.
//! A bound on how far a deficit travels would land between the first
//! row and the last.
//! The other scenes whose
//! lights move (`atrium`, `corner`, `colonnade`, `courtyard-sun`, Sponza and the
//! Munich blocks) moved by 0.001 at most; where the lights stand still no
//! cell is negative, and the VPLs are the same bit for bit.
//!
//! [`Relight::Ratio`] scales each cell's mean by how its own VPL's radiance
//! changed over the same iterations ([`crate::Cell::current_radiance`]):
//! one estimate a cell, and no cost, but one point stands for the whole
//! cell, and where the light comes near (a lamp carried past a wall) the
//! VPL's change is not the cell's. [`Relight::None`] keeps the candidates
//! as estimated.

use vpl_core::glam::Vec3;
use vpl_core::params::FromParam;
use vpl_density::KnnDensity;

/// How the cells' mean radiances follow moving lights (see the module text).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Relight {
    /// The candidates as estimated in their iterations: the mean lags.
    None,
    /// Each cell's mean scaled by its VPL's change of radiance.
    Ratio,
    /// Each cell's mean moved by the change of short estimates of its
    /// candidates' radiances under common random numbers (eq. 1).
    #[default]
    Candidates,
}

impl Relight {
    /// Every way, the default last.
    pub const ALL: [Relight; 3] = [Relight::None, Relight::Ratio, Relight::Candidates];

    /// The parameter value naming it.
    pub fn name(self) -> &'static str {
        match self {
            Relight::None => "none",
            Relight::Ratio => "ratio",
            Relight::Candidates => "candidates",
        }
    }
}

impl FromParam for Relight {
    const EXPECTED: &'static str = "none, ratio or candidates";
    fn from_param(text: &str) -> Option<Self> {
        Relight::ALL.into_iter().find(|r| r.name() == text.trim())
    }
}

impl std::fmt::Display for Relight {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Cells whose light each cell's negative part is taken from first
/// ([`spread_deficits`]).
pub const DEFICIT_NEIGHBOURS: usize = 8;

/// The rings of nearest cells a negative part is taken from, one after the
/// other while some of it is left: the nearest [`DEFICIT_NEIGHBOURS`], then
/// up to the 32nd, then up to the 128th.
const DEFICIT_RINGS: [usize; 3] = [DEFICIT_NEIGHBOURS, 32, 128];

/// Makes the cells' relit light Φ_i = L̄_now(V_i) · A(V_i) non-negative
/// without adding light: eq. (1) is right in expectation, but where a
/// cell's light fell (the lamp left it) its noisy change can overshoot, and
/// Φ_i comes out below zero. Holding such a cell at zero adds the light of
/// its negative part: a bias up wherever the lights move away, which held
/// `building` 10 % bright at a doorway the lamp had just passed (frame 360,
/// 64×48, 3 seeds: 1.110; with the signed fluxes 0.986, but single seeds
/// from 0.83 to 1.08, a negative VPL beside the camera).
///
/// Instead, channel by channel, each cell's negative part −Φ_i is taken
/// from the light of its [`DEFICIT_NEIGHBOURS`] nearest cells on its side
/// of the surface (sites whose normals lie within 120° of its own), in
/// proportion to their light:
///
/// ```text
/// Φ_j ← Φ_j (1 − min(−Φ_i, Σ_k Φ_k) / Σ_k Φ_k),   j among those cells,     (2)
/// Φ_i ← 0,
/// ```
///
/// and what those hold too little for from the next ring of cells (up to
/// the 32nd nearest, then the 128th): where the lamp has left a whole
/// region, its cells are all near zero, and the first ring alone left 5 %
/// of the negative light unplaced along `building`'s doorway (frames 330
/// to 360, 512 VPLs). The sum over the cell and the cells it took from
/// keeps its expectation; the light moves by up to about √128 ≈ 11 cells'
/// width where the outer ring is needed, a few where the first suffices.
/// Cells are taken in index order (the result does not depend on threads).
/// Fluxes that are all at
/// zero or above come back unchanged, bit for bit. Returns what was
/// spread ([`Spread`]).
pub fn spread_deficits(points: &[Vec3], normals: &[Vec3], flux: &mut [Vec3]) -> Spread {
    let deficits: Vec<(usize, Vec3)> = flux
        .iter_mut()
        .enumerate()
        .filter_map(|(i, f)| {
            let d = (-*f).max(Vec3::ZERO);
            *f = f.max(Vec3::ZERO);
            (d != Vec3::ZERO && d.is_finite()).then_some((i, d))
        })
        .collect();
    let light: f64 = deficits.iter().map(|&(_, d)| vpl_core::image::luminance(d) as f64).sum();
    let mut spread = Spread { cells: deficits.len(), light, unplaced: light };
    if deficits.is_empty() || points.len() != flux.len() || normals.len() != flux.len() {
        return spread;
    }
    let Ok(tree) = KnnDensity::new(points) else { return spread };
    let mut unplaced = 0.0f64;
    for (i, d) in deficits {
        let side = |j: usize| normals[j].dot(normals[i]) > -0.5;
        let mut left = d;
        let mut taken_from = 0;
        for ring in DEFICIT_RINGS {
            if left.max_element() <= 0.0 {
                break;
            }
            let near = tree.nearest_accepted_n(points[i], Some(i), side, ring);
            let Some(near) = near.get(taken_from..) else { break };
            taken_from = ring;
            for c in 0..3 {
                let available: f32 = near.iter().map(|&(j, _)| flux[j][c]).sum();
                let take = left[c].min(available);
                if take > 0.0 {
                    let keep = 1.0 - take / available;
                    near.iter().for_each(|&(j, _)| flux[j][c] *= keep);
                    left[c] -= take;
                }
            }
        }
        unplaced += vpl_core::image::luminance(left.max(Vec3::ZERO)) as f64;
    }
    spread.unplaced = unplaced;
    spread
}

/// What [`spread_deficits`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spread {
    /// Cells whose light was below zero in some channel.
    pub cells: usize,
    /// The luminance of their negative parts, −Φ_i: the light that holding
    /// them at zero would have added.
    pub light: f64,
    /// The part of it that their neighbours had too little light to take,
    /// so it stays added (the bias left).
    pub unplaced: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cell's negative part leaves its neighbours' light in proportion
    /// to it, the total over them is kept, the far side of a wall and
    /// cells beyond the nearest 8 keep theirs when those 8 have enough,
    /// and fluxes at zero or above are not touched.
    #[test]
    fn deficits_are_taken_from_the_nearest_cells_on_their_side() {
        // A row of cells on a floor, one of them negative in red, and a
        // cell just under the floor facing down.
        let mut points: Vec<Vec3> = (0..12).map(|k| Vec3::new(k as f32, 0.0, 0.0)).collect();
        let mut normals = vec![Vec3::Y; 12];
        points.push(Vec3::new(0.0, -0.01, 0.0));
        normals.push(-Vec3::Y);
        let mut flux: Vec<Vec3> = (0..13).map(|k| Vec3::new(1.0 + k as f32, 2.0, 3.0)).collect();
        flux[0] = Vec3::new(-10.0, 1.0, 1.0);
        let before = flux.clone();
        let spread = spread_deficits(&points, &normals, &mut flux);
        assert_eq!((spread.cells, spread.unplaced), (1, 0.0));
        assert!((spread.light - vpl_core::image::luminance(Vec3::new(10.0, 0.0, 0.0)) as f64).abs() < 1e-5);
        assert_eq!(flux[0], Vec3::new(0.0, 1.0, 1.0));
        // Cells 1..=8 (red 2..=9, Σ 44) lose 10/44 of their red each.
        for j in 1..=8 {
            let want = before[j].x * (1.0 - 10.0 / 44.0);
            assert!((flux[j].x - want).abs() < 1e-5, "{j}: {} against {want}", flux[j].x);
            assert_eq!((flux[j].y, flux[j].z), (2.0, 3.0));
        }
        let total = |f: &[Vec3]| f.iter().map(|v| v.x as f64).sum::<f64>();
        assert!((total(&flux) - total(&before)).abs() < 1e-4);
        // Cells 9..=11 are not among the nearest 8, and the far side of the floor faces away.
        assert_eq!(&flux[9..], &before[9..]);
        // Nothing negative: nothing changes.
        let mut plain = before[1..].to_vec();
        let copy = plain.clone();
        assert_eq!(spread_deficits(&points[1..], &normals[1..], &mut plain), Spread::default());
        assert_eq!(plain, copy);
    }

    /// Where the neighbours hold less light than the deficit, all of theirs
    /// goes and the rest is reported as unplaced.
    #[test]
    fn a_deficit_larger_than_the_neighbours_light_empties_them() {
        let points = [Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)];
        let normals = [Vec3::Y; 3];
        let mut flux = [Vec3::splat(-5.0), Vec3::ONE, Vec3::splat(2.0)];
        let spread = spread_deficits(&points, &normals, &mut flux);
        assert_eq!(flux, [Vec3::ZERO; 3]);
        assert!((spread.unplaced - 2.0).abs() < 1e-5 && (spread.light - 5.0).abs() < 1e-5, "{spread:?}");
    }

    /// What the nearest 8 cannot take comes from the next ring, in
    /// proportion to its cells' light, and the total is kept.
    #[test]
    fn what_the_nearest_cannot_take_comes_from_the_next_ring() {
        let points: Vec<Vec3> = (0..20).map(|k| Vec3::new(k as f32, 0.0, 0.0)).collect();
        let normals = vec![Vec3::Y; 20];
        let mut flux = vec![Vec3::ONE; 20];
        flux[0] = Vec3::new(-11.0, 0.0, 0.0);
        let spread = spread_deficits(&points, &normals, &mut flux);
        assert_eq!(spread.unplaced, 0.0);
        for (j, f) in flux.iter().enumerate().skip(1) {
            if j <= 8 {
                assert_eq!(*f, Vec3::new(0.0, 1.0, 1.0), "{j}");
            } else {
                assert!((f.x - 8.0 / 11.0).abs() < 1e-6, "{j}: {}", f.x);
            }
        }
        let red: f32 = flux.iter().map(|f| f.x).sum();
        assert!((red - 8.0).abs() < 1e-5, "{red}");
    }

    #[test]
    fn names_round_trip() {
        for r in Relight::ALL {
            assert_eq!(Relight::from_param(r.name()), Some(r));
            assert_eq!(r.to_string(), r.name());
        }
        assert_eq!(Relight::from_param("later"), None);
        assert_eq!(Relight::default(), Relight::Candidates);
    }
}
