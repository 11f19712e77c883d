//! The camera points X (line 3 of Algorithm 1) and the candidate hits cast
//! from them (line 5, §3.2.1).

use rayon::prelude::*;
use vpl_core::glam::Vec3;
use vpl_core::rng::stream_key;
use vpl_core::sampling::cosine_hemisphere;
use vpl_core::{BounceRays, Camera, CameraRays, LocalFrame, Purpose, Ray, RayCaster, Scene, SurfacePoint, stream};

/// A camera-visible point that can reflect VPL light toward the camera,
/// normals turned toward the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPoint {
    /// Position.
    pub p: Vec3,
    /// Shading normal.
    pub n: Vec3,
    /// Geometric normal.
    pub ng: Vec3,
}

/// A surface point a candidate ray hit, normals turned toward the ray's
/// origin, and the camera point it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CandidateHit {
    /// The point (its normals face `origin`).
    pub y: SurfacePoint,
    /// Index of the camera point in X that cast the ray.
    pub origin: u32,
}

/// Casts `n` camera rays through uniformly random raster positions; keeps the
/// hits that reflect light toward the camera, in ray order. Ray j draws from
/// stream (seed, iteration, CAMERA_POINTS, j); `rays` casts them.
pub fn camera_points(scene: &Scene, camera: &Camera, rays: &dyn RayCaster, n: usize, seed: u64, iteration: u64) -> Vec<CameraPoint> {
    let batch = CameraRays::new(camera, stream_key(seed, iteration, Purpose::CAMERA_POINTS), n);
    camera_points_of(scene, rays, &batch).0
}

/// The camera points of a batch of camera rays ([`camera_points`]), and the
/// index of the ray each came from.
pub fn camera_points_of(scene: &Scene, rays: &dyn RayCaster, batch: &CameraRays) -> (Vec<CameraPoint>, Vec<u32>) {
    let hits = rays.intersect_camera(scene, batch);
    batch
        .rays
        .par_iter()
        .zip(hits)
        .enumerate()
        .filter_map(|(i, (ray, hit))| {
            let (sp, _) = scene.reflecting(ray, hit?)?;
            Some((CameraPoint { p: sp.p, n: sp.n, ng: sp.ng }, i as u32))
        })
        .unzip()
}

/// One cosine-distributed ray from every camera point; keeps the hits on
/// surfaces that reflect back toward the ray's origin, in ray order. Ray j
/// draws from stream (seed, iteration, CANDIDATE, j); `rays` casts them.
pub fn candidate_hits(scene: &Scene, rays: &dyn RayCaster, xs: &[CameraPoint], seed: u64, iteration: u64) -> Vec<CandidateHit> {
    let cast = candidate_rays(scene, xs, seed, iteration);
    let batch: Vec<Ray> = cast.iter().map(|(_, r)| *r).collect();
    keep_candidates(scene, &cast, rays.intersect(scene, &batch))
}

/// [`candidate_hits`] of camera points that came from `batch` (camera
/// point j from its ray `from[j]`, as [`camera_points_of`] gives them), so
/// that a caster on a device makes the rays where it holds the camera
/// batch's hits ([`RayCaster::intersect_bounce`]). The same hits.
pub fn candidate_hits_from(
    scene: &Scene,
    rays: &dyn RayCaster,
    xs: &[CameraPoint],
    batch: &CameraRays,
    from: &[u32],
    seed: u64,
    iteration: u64,
) -> Vec<CandidateHit> {
    let cast = candidate_rays(scene, xs, seed, iteration);
    let bounce = BounceRays {
        camera: batch,
        key: stream_key(seed, iteration, Purpose::CANDIDATE),
        origins: cast.par_iter().map(|&(j, _)| (from[j as usize], j)).collect(),
        rays: cast.par_iter().map(|(_, r)| *r).collect(),
    };
    keep_candidates(scene, &cast, rays.intersect_bounce(scene, &bounce))
}

/// The candidate ray of each camera point that has one (its direction above
/// the geometric normal), with the point's index.
fn candidate_rays(scene: &Scene, xs: &[CameraPoint], seed: u64, iteration: u64) -> Vec<(u32, Ray)> {
    let eps = scene.epsilon();
    xs.par_iter()
        .enumerate()
        .filter_map(|(j, x)| {
            let mut rng = stream(seed, iteration, Purpose::CANDIDATE, j as u64);
            let (u, v) = rng.next_2d();
            let d = LocalFrame::from_normal(x.n).to_world(cosine_hemisphere(u, v));
            (d.dot(x.ng) > 0.0).then(|| (j as u32, Ray::new(x.p + x.ng * eps, d)))
        })
        .collect()
}

/// The hits of the candidate rays that reflect back toward their origin.
fn keep_candidates(scene: &Scene, cast: &[(u32, Ray)], hits: Vec<Option<vpl_core::Hit>>) -> Vec<CandidateHit> {
    cast.par_iter()
        .zip(hits)
        .filter_map(|((j, ray), hit)| {
            let (y, _) = scene.reflecting(ray, hit?)?;
            Some(CandidateHit { y, origin: *j })
        })
        .collect()
}

/// The shadow ray between camera point `x` and a VPL at `y` with normal
/// `n_y`: `Err(false)` when a cosine rules the pair out, `Err(true)` when
/// the two coincide, else the ray whose freedom decides.
#[inline]
pub fn mutual_ray(scene: &Scene, x: &CameraPoint, y: Vec3, n_y: Vec3) -> Result<Ray, bool> {
    let d = y - x.p;
    if d.dot(x.ng) <= 0.0 || d.dot(x.n) <= 0.0 || d.dot(n_y) >= 0.0 {
        return Err(false);
    }
    let eps = scene.epsilon();
    scene.shadow_ray(x.p + x.ng * eps, y + n_y * eps).ok_or(true)
}

/// Whether camera point `x` and a VPL at `y` with normal `n_y` see each
/// other with both cosines positive: the VPL can light x.
#[inline]
pub fn mutually_visible(scene: &Scene, x: &CameraPoint, y: Vec3, n_y: Vec3) -> bool {
    match mutual_ray(scene, x, y, n_y) {
        Ok(r) => !scene.occluded(&r),
        Err(v) => v,
    }
}

/// The mailbox test of §3.2.2 for many points: whether the camera still
/// sees each camera point from the side it was seen from, inside the image.
pub fn camera_sees(scene: &Scene, camera: &Camera, rays: &dyn RayCaster, xs: &[Option<CameraPoint>]) -> Vec<bool> {
    let (w, h) = (camera.resolution.0 as f32, camera.resolution.1 as f32);
    let eps = scene.epsilon();
    let tests: Vec<Result<Ray, bool>> = xs
        .iter()
        .map(|x| {
            let Some(x) = x else { return Err(false) };
            if (camera.origin - x.p).dot(x.ng) <= 0.0 {
                return Err(false);
            }
            let Some((px, py)) = camera.project(x.p) else { return Err(false) };
            if !(0.0..w).contains(&px) || !(0.0..h).contains(&py) {
                return Err(false);
            }
            scene.shadow_ray(x.p + x.ng * eps, camera.origin).ok_or(true)
        })
        .collect();
    resolve(scene, rays, tests)
}

/// Answers a list of visibility tests, casting the ones that need a ray as
/// one batch.
pub fn resolve(scene: &Scene, rays: &dyn RayCaster, tests: Vec<Result<Ray, bool>>) -> Vec<bool> {
    let batch: Vec<Ray> = tests.iter().filter_map(|t| t.as_ref().ok().copied()).collect();
    let mut blocked = rays.occluded(scene, &batch).into_iter();
    tests
        .into_iter()
        .map(|t| match t {
            Ok(_) => !blocked.next().expect("one answer per ray"),
            Err(v) => v,
        })
        .collect()
}

/// Answers visibility tests tried in rounds: entry e tries `offers[e]` in
/// order and takes the first that passes, trying the next only while the
/// earlier ones failed. Returns, per entry, the index of the test it took
/// (none when all failed), and the rays the round-by-round order casts.
///
/// Round by round (round r casts the r-th test of every entry still
/// without one) casts only the rays needed, in as many batches as rounds.
/// When `rays` [speculates](RayCaster::speculates), every round is cast in
/// one batch and each entry takes its first pass in round order. A test's
/// answer depends on its ray alone, so both give the same answers, and the
/// count returned is the round-by-round one either way.
pub fn first_passing(scene: &Scene, rays: &dyn RayCaster, offers: &[Vec<Result<Ray, bool>>]) -> (Vec<Option<usize>>, usize) {
    let mut taken: Vec<Option<usize>> = vec![None; offers.len()];
    let mut cast = 0;
    if rays.speculates() {
        let all: Vec<Result<Ray, bool>> = offers.iter().flatten().copied().collect();
        let mut seen = resolve(scene, rays, all).into_iter();
        for (e, offer) in offers.iter().enumerate() {
            for (r, test) in offer.iter().enumerate() {
                let passes = seen.next().expect("one answer per test");
                if taken[e].is_some() {
                    continue;
                }
                cast += test.is_ok() as usize;
                if passes {
                    taken[e] = Some(r);
                }
            }
        }
        return (taken, cast);
    }
    let rounds = offers.iter().map(Vec::len).max().unwrap_or(0);
    for r in 0..rounds {
        let open: Vec<usize> = (0..offers.len()).filter(|&e| taken[e].is_none() && offers[e].len() > r).collect();
        if open.is_empty() {
            break;
        }
        let tests: Vec<Result<Ray, bool>> = open.iter().map(|&e| offers[e][r]).collect();
        cast += tests.iter().filter(|t| t.is_ok()).count();
        for (e, passes) in open.into_iter().zip(resolve(scene, rays, tests)) {
            if passes {
                taken[e] = Some(r);
            }
        }
    }
    (taken, cast)
}
