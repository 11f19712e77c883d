//! Ray-casting throughput: the rays every stage of the toolkit casts, in
//! three kinds, and how fast the BVH answers them (`vpl bench-rays`).
//!
//! - **Primary**: camera rays through the pixels of an image, one per pixel
//!   in scanline order: the most coherent set (what a G-buffer casts).
//! - **Diffuse**: from each primary hit, one cosine-distributed ray: the
//!   incoherent set of a path tracer's bounces and SMC's candidate rays.
//! - **Shadow**: from each primary hit toward a point sampled on the
//!   scene's lights, as a segment: the occlusion tests of next-event
//!   estimation and of VPL visibility.
//!
//! Every ray draws from a stream keyed by the seed and its index, so a
//! set is the same on any thread count; the rates are measured on the
//! current rayon pool.
//!
//! ```
//! use vpl_bench::rays::{RaySets, closest_rate};
//! use vpl_core::SceneSetup;
//!
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! let sets = RaySets::new(&setup.scene, &setup.camera, (32, 32), 1);
//! assert_eq!(sets.primary.len(), 32 * 32);
//! let rate = closest_rate(&setup.scene.geometry.bvh, &sets.primary, 0.01);
//! assert!(rate.rays_per_second() > 0.0);
//! ```

use rayon::prelude::*;
use std::time::Instant;
use vpl_core::bvh::Bvh;
use vpl_core::glam::Vec3;
use vpl_core::sampling::cosine_hemisphere;
use vpl_core::triangle::TriangleData;
use vpl_core::{Camera, LocalFrame, Purpose, Ray, Scene, stream};

/// The three kinds of rays of one view of a scene.
#[derive(Clone, Debug, Default)]
pub struct RaySets {
    /// Camera rays, one per pixel, scanline order.
    pub primary: Vec<Ray>,
    /// One cosine-distributed ray from each primary hit.
    pub diffuse: Vec<Ray>,
    /// The primary rays' directions in tiles of 8 × 8 pixels (for
    /// [`fan_rate`]).
    pub primary_tiles: Vec<Vec<Vec3>>,
    /// The camera's centre of projection, where all primary rays start
    /// (`None` for a thin lens).
    pub eye: Option<Vec3>,
    /// One segment from each primary hit toward a light sample.
    pub shadow: Vec<Ray>,
}

impl RaySets {
    /// The rays of `camera`'s view at `size` (width, height) pixels: primary
    /// rays through pixel centres, and from their hits (found in `scene`)
    /// a diffuse ray and a shadow segment each. Draws from streams
    /// (seed, pixel, TEST, 0 and 1).
    pub fn new(scene: &Scene, camera: &Camera, size: (u32, u32), seed: u64) -> RaySets {
        let (w, h) = size;
        let sx = camera.resolution.0 as f32 / w.max(1) as f32;
        let sy = camera.resolution.1 as f32 / h.max(1) as f32;
        let primary: Vec<Ray> =
            (0..w * h).into_par_iter().map(|i| camera.ray(((i % w) as f32 + 0.5) * sx, ((i / w) as f32 + 0.5) * sy, (0.5, 0.5))).collect();
        let eps = scene.epsilon();
        let secondary: Vec<(Option<Ray>, Option<Ray>)> = primary
            .par_iter()
            .enumerate()
            .map(|(i, ray)| {
                let Some(hit) = scene.intersect(ray) else { return (None, None) };
                let x = hit.point.facing(-ray.d);
                let mut rng = stream(seed, i as u64, Purpose::TEST, 0);
                let (u, v) = rng.next_2d();
                let d = LocalFrame::from_normal(x.n).to_world(cosine_hemisphere(u, v));
                let diffuse = (d.dot(x.ng) > 0.0).then(|| Ray::new(x.p + x.ng * eps, d));
                let mut rng = stream(seed, i as u64, Purpose::TEST, 1);
                let shadow = scene.sample_light(x.p, rng.next_f32(), rng.next_2d()).and_then(|(ls, _)| {
                    let o = x.p + x.ng * eps;
                    if ls.dist.is_finite() { scene.shadow_ray(o, x.p + ls.wi * ls.dist) } else { Some(Ray::new(o, ls.wi)) }
                });
                (diffuse, shadow)
            })
            .collect();
        let diffuse = secondary.iter().filter_map(|s| s.0).collect();
        let shadow = secondary.iter().filter_map(|s| s.1).collect();
        // The primary rays' directions again, tile by tile of 8 × 8 pixels.
        let tile = 8;
        let mut primary_tiles = Vec::new();
        for y0 in (0..h).step_by(tile) {
            for x0 in (0..w).step_by(tile) {
                let t: Vec<Vec3> = (y0..(y0 + tile as u32).min(h))
                    .flat_map(|y| (x0..(x0 + tile as u32).min(w)).map(move |x| (x, y)))
                    .map(|(x, y)| primary[(y * w + x) as usize].d)
                    .collect();
                primary_tiles.push(t);
            }
        }
        let eye = (camera.lens_radius <= 0.0).then_some(camera.origin);
        RaySets { primary, diffuse, shadow, primary_tiles, eye }
    }
}

/// Closest-hit throughput of rays from one origin traced in bundles
/// ([`Bvh::closest_fan`]): `tiles` of directions from `eye`, as the fastest
/// of repeated passes over at least `min_seconds`.
pub fn fan_rate(bvh: &Bvh, eye: Vec3, tiles: &[Vec<Vec3>], min_seconds: f64) -> Rate {
    let rays = tiles.iter().map(Vec::len).sum();
    let mut best = Rate { rays, seconds: f64::INFINITY, hits: 0 };
    let start = Instant::now();
    let mut passes = 0;
    while passes < 2 || start.elapsed().as_secs_f64() < min_seconds {
        let t0 = Instant::now();
        let hits: usize = tiles
            .par_iter()
            .map(|dirs| {
                let mut out = vec![None; dirs.len()];
                bvh.closest_fan(eye, dirs, f32::INFINITY, &mut out);
                out.iter().filter(|h| h.is_some()).count()
            })
            .sum();
        let s = t0.elapsed().as_secs_f64();
        if passes > 0 && s < best.seconds {
            best = Rate { rays, seconds: s, hits };
        }
        passes += 1;
    }
    best
}

/// Rays answered in a time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rate {
    /// Rays cast.
    pub rays: usize,
    /// Wall-clock seconds they took.
    pub seconds: f64,
    /// Rays that hit (closest) or were blocked (occlusion), of the last pass.
    pub hits: usize,
}

impl Rate {
    /// Rays per second (0 when nothing was timed).
    pub fn rays_per_second(&self) -> f64 {
        if self.seconds > 0.0 { self.rays as f64 / self.seconds } else { 0.0 }
    }
}

/// Chunk of rays one task casts.
const CHUNK: usize = 256;

/// Casts `rays` in passes over the current rayon pool until `min_seconds`
/// have passed (at least two passes, the first a warm-up) and returns the
/// fastest pass.
fn best_pass(rays: &[Ray], min_seconds: f64, pass: impl Fn(&[Ray]) -> usize + Sync) -> Rate {
    let mut best = Rate { rays: rays.len(), seconds: f64::INFINITY, hits: 0 };
    let start = Instant::now();
    let mut passes = 0;
    while passes < 2 || start.elapsed().as_secs_f64() < min_seconds {
        let t0 = Instant::now();
        let hits: usize = rays.par_chunks(CHUNK).map(&pass).sum();
        let s = t0.elapsed().as_secs_f64();
        if passes > 0 && s < best.seconds {
            best = Rate { rays: rays.len(), seconds: s, hits };
        }
        passes += 1;
    }
    best
}

/// Closest-hit throughput of `bvh` on `rays` (the fastest of repeated
/// passes over at least `min_seconds`).
pub fn closest_rate(bvh: &Bvh, rays: &[Ray], min_seconds: f64) -> Rate {
    best_pass(rays, min_seconds, |chunk| chunk.iter().filter(|r| bvh.closest(r).is_some()).count())
}

/// Occlusion throughput of `bvh` on `rays` (as [`closest_rate`]).
pub fn occluded_rate(bvh: &Bvh, rays: &[Ray], min_seconds: f64) -> Rate {
    best_pass(rays, min_seconds, |chunk| chunk.iter().filter(|r| bvh.occluded(r)).count())
}

/// `copies` copies of `triangles` side by side along +x, each shifted by
/// 1.05 times the extent of the originals, the first where the originals
/// are: a scene `copies` times as large whose first copy looks as the
/// original does.
pub fn side_by_side(triangles: &[TriangleData], copies: usize) -> Vec<TriangleData> {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for t in triangles {
        for p in t.corners() {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    let step = if lo.x <= hi.x { (hi.x - lo.x) * 1.05 } else { 0.0 };
    (0..copies).flat_map(|k| triangles.iter().map(move |t| TriangleData { p0: t.p0 + Vec3::X * (step * k as f32), ..*t })).collect()
}

/// The BVH build of `triangles`: the BVH and the fastest build's seconds
/// (builds repeated for at least `min_seconds`, at most 5).
pub fn timed_build(triangles: &[TriangleData], min_seconds: f64) -> vpl_core::Result<(Bvh, f64)> {
    let start = Instant::now();
    let t0 = Instant::now();
    let mut bvh = Bvh::from_triangles(triangles)?;
    let mut best = t0.elapsed().as_secs_f64();
    for _ in 1..5 {
        if start.elapsed().as_secs_f64() >= min_seconds {
            break;
        }
        let t0 = Instant::now();
        bvh = Bvh::from_triangles(triangles)?;
        best = best.min(t0.elapsed().as_secs_f64());
    }
    Ok((bvh, best))
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::SceneSetup;

    #[test]
    fn ray_sets_are_the_same_on_any_thread_count() {
        let setup = SceneSetup::builtin("office").unwrap();
        let make = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| RaySets::new(&setup.scene, &setup.camera, (24, 16), 3))
        };
        let (a, b) = (make(1), make(2));
        assert_eq!(a.primary.len(), 24 * 16);
        assert!(a.diffuse.len() > 100 && a.shadow.len() > 100, "{} {}", a.diffuse.len(), a.shadow.len());
        for (x, y) in [(&a.primary, &b.primary), (&a.diffuse, &b.diffuse), (&a.shadow, &b.shadow)] {
            assert_eq!(x.len(), y.len());
            assert!(x.iter().zip(y).all(|(r, s)| r.o == s.o && r.d == s.d && r.t_max == s.t_max));
        }
    }

    /// Copies side by side: n times the triangles, and the first copy's
    /// rays hit what they hit in the original.
    #[test]
    fn side_by_side_copies_keep_the_first_view() {
        let setup = SceneSetup::builtin("cornell").unwrap();
        let tris = &setup.scene.geometry.triangles;
        let five = side_by_side(tris, 5);
        assert_eq!(five.len(), 5 * tris.len());
        let (bvh, seconds) = timed_build(&five, 0.0).unwrap();
        assert!(seconds > 0.0 && bvh.memory_bytes() > 0);
        // Against the originals built the same way (vertices p0, p0 + e1, p0 + e2).
        let one = Bvh::from_triangles(tris).unwrap();
        let sets = RaySets::new(&setup.scene, &setup.camera, (16, 16), 1);
        let original = closest_rate(&one, &sets.primary, 0.0);
        let copied = closest_rate(&bvh, &sets.primary, 0.0);
        assert_eq!(original.hits, copied.hits);
        for r in &sets.primary {
            assert_eq!(one.closest(r).map(|h| h.1), bvh.closest(r).map(|h| h.1));
        }
    }
}
