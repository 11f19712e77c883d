//! # vpl-smc
//!
//! Sequential Monte Carlo Instant Radiosity (Hedman, Karras, Lehtinen,
//! I3D 2016 / TVCG 2017): VPLs kept on the surfaces the camera sees
//! indirectly, distributed toward their radiosity (p(y) ∝ L(y), eq. 4), and
//! evolved from frame to frame by replacing at most M_max of them, so the
//! image is stable in time.
//!
//! Every line of Algorithm 1 is here ([`SmcSampler::iterate`]), each step a
//! method named after it: `draw_camera_points`, `verify_indirect_visibility`,
//! `draw_candidates`, `choose_removals`, `fill_slots`, `refresh_radiosities`,
//! `refresh_densities`, `write_fluxes`:
//!
//! 1. camera points X, cast through random raster positions;
//! 2. indirect visibility by mailboxing (§3.2.2): a VPL stays valid while the
//!    camera sees the point it was found from; otherwise V = 16 rays from
//!    random points of X try to verify it, in two rounds;
//! 3. candidates (§3.2.1): one cosine-distributed ray from every point of X
//!    (16·I rays), the hits weighted by 1/p̂ (k = 1 among the hits) and
//!    resampled without replacement down to I candidates, at most 8 retries a draw;
//! 4. candidate radiosities L(ŷ) from 16 path-traced NEE paths seeded by the
//!    id the candidate keeps as a VPL (§3.2.3), and densities against the
//!    current VPLs with k = 1 (§3.2.4);
//! 5. M_min = min(M_max, M_strong) (eq. 9); the M_min weakest valid VPLs are
//!    invalidated when fewer are unverified; at most M_max are removed and
//!    the strongest candidates fill the free slots;
//! 6. the set's densities with k = max(1, ⌊√(I/32)⌋) (eq. 8) and its
//!    radiosities (anew only when the lights changed), and the output flux
//!    in vpl-core's convention.
//!
//! The output flux departs from the paper's L / (I·p) by default: the
//! set's regularity and the VPLs' place on the bright side of their pieces
//! of surface make that estimate 15–32 % too bright on real geometry. Each
//! VPL carries instead the light of its Voronoi cell, measured by the
//! candidate-ray hits, as the VPL shows it to the camera: each of the
//! cell's probes stands for the area of the probes near the VPL, so that a
//! VPL on the side of its cell where the camera's rays are dense does not
//! show all of the cell's light from there ([`FluxEstimator`], derivation
//! and measurements in its module); `SmcConfig { flux:
//! FluxEstimator::Knn, .. }` is the paper's. A VPL shines from its own
//! point, or (with the cell's plain light, [`FluxEstimator::Voronoi`]) with
//! [`Placement::Centroid`] from the probe of its cell nearest the cell's
//! centroid (a VPL at the edge of its cell is a quadrature point off
//! centre, which leaves the Munich blocks 6 % too bright; derivation and
//! measurements in [`Placement`]'s module). Under moving lights the cells'
//! mean radiances, measured over T iterations, are brought to the lights
//! of now ([`Relight`]).
//!
//! One departure from the paper: a VPL's flux uses a second radiosity
//! estimate, seeded apart from the one its selection used (made once when
//! it joins the set, and again when the lights change). Keeping the
//! strongest candidates and dropping the weakest VPLs on the same noisy
//! 16-path estimates the flux then uses keeps exactly the VPLs whose noise
//! came out high: on `office` that made the image 67 % brighter than path
//! tracing. Decisions still use the candidate estimates, so which VPLs move
//! is unchanged; each VPL's flux stays fixed for its life.
//!
//! The first frame runs 100 warm-up iterations. Only replaced slots (and,
//! with [`Placement::Centroid`], VPLs whose cell's centroid drifted) move,
//! at most M_max in all
//! ([`VplSet::moved`](vpl_core::VplSet::moved)), so shadow maps update
//! lazily; re-weighted VPLs change flux but keep their maps.
//!
//! ```
//! use vpl_core::{Frame, GBuffer, SceneSetup, VplSampler};
//! use vpl_smc::{SmcConfig, SmcSampler};
//!
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! let camera = setup.camera.with_resolution((64, 64)).unwrap();
//! let gbuffer = GBuffer::empty();
//! let frame = |index| Frame { scene: &setup.scene, camera: &camera, time: 0.0, index, seed: 1, gbuffer: &gbuffer, previous: None };
//! let mut smc = SmcSampler::new(SmcConfig { vpls: 128, warmup: 4, ..SmcConfig::default() }).unwrap();
//! assert_eq!(smc.next_frame(&frame(0)).stored(), 128);
//! let moved = smc.next_frame(&frame(1)).moved_count();
//! assert!(moved <= 16, "{moved} VPLs moved");
//! ```
//!
//! ## Build profile
//!
//! Debug builds of the toolkit's crates are 20–50× slower than optimised ones
//! (an SMC frame takes 9.7 s instead of 0.18 s). The toolkit's own workspace
//! optimises its dependencies, but a workspace's profile does not reach the
//! projects that depend on it. Add to your project's `Cargo.toml`:
//!
//! ```toml
//! [profile.dev.package."*"]
//! opt-level = 3
//! ```
//!
//! Your own crates stay quick to compile; every dependency, this one included,
//! is optimised.

#![warn(missing_docs)]

mod ball_area;
mod config;
mod flux;
mod placement;
mod points;
mod relight;
mod sampler;

pub use ball_area::{ProbeArea, surface_in_ball};
pub use config::{SmcConfig, SmcError};
pub use flux::{
    AreaProbes, Cell, FluxEstimator, NEAR_BLEND, NEAR_MIN, NEAR_SHARE, ProbeCandidate, ProbeHits, ProbeWindow, Site, Track,
    surface_neighbour_sq,
};
pub use placement::{Choice, KEEP_WITHIN, Placement, Shown, choose, settle};
pub use points::{
    CameraPoint, CandidateHit, camera_points, camera_points_of, camera_sees, candidate_hits, candidate_hits_from, first_passing,
    mutual_ray, mutually_visible, resolve,
};
pub use relight::{DEFICIT_NEIGHBOURS, Relight, Spread, spread_deficits};
pub use sampler::{Estimator, Particle, SmcSampler, SmcStats, SmcTimings};
pub use vpl_core::resample::{Resampled, resample, resample_counted};
