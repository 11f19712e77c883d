//! Rendering images and tracked pixels: rayon over tiles, one random stream
//! per pixel, so the result is bit-identical for any thread count.

use crate::integrator::PathTracer;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;
use vpl_core::glam::Vec3;
use vpl_core::{Camera, Image, Purpose, RngStream, Scene, stream};

/// Side of the square tiles work is split into.
pub const TILE: u32 = 16;

/// Sampling settings of a render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderSettings {
    /// Samples (paths) per pixel, ≥ 1.
    pub spp: u32,
    /// Seed of every random stream.
    pub seed: u64,
    /// Frame index (part of the stream key).
    pub frame: u64,
}

/// A rendered image with its per-pixel standard error and counts.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// Mean radiance per pixel (box filter over the pixel).
    pub image: Image,
    /// Standard error of the per-pixel mean, per channel.
    pub stderr: Image,
    /// Paths traced (pixels × spp).
    pub paths: u64,
    /// Wall time in seconds.
    pub seconds: f64,
}

/// Errors of the renderer.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Samples per pixel must be at least one.
    #[error("spp must be at least 1")]
    ZeroSpp,
    /// Paths gave NaN or infinite radiance at some pixels (a scene value the
    /// load-time checks let through, or a defect): the image is refused.
    #[error("path tracing produced {0} non-finite pixel(s)")]
    NonFinite(usize),
    /// The render was cancelled before it finished ([`render_cancellable`]).
    #[error("the render was cancelled")]
    Cancelled,
    /// A thread pool could not be built.
    #[error("cannot start {0} threads: {1}")]
    Threads(usize, String),
}

/// Renders `scene` through `camera` with `pt`. `progress(done, total)` is
/// called with counts of finished pixels as tiles complete.
pub fn render(
    scene: &Scene,
    camera: &Camera,
    pt: &PathTracer,
    s: RenderSettings,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<RenderOutput, RenderError> {
    render_cancellable(scene, camera, pt, s, progress, &AtomicBool::new(false))
}

/// [`render`] that stops early once `cancel` is set (from another thread:
/// a Ctrl-C handler, a viewer's camera move), checked before every pixel,
/// and then returns [`RenderError::Cancelled`]. The image of an uncancelled
/// render is the same bits as [`render`]'s.
pub fn render_cancellable(
    scene: &Scene,
    camera: &Camera,
    pt: &PathTracer,
    s: RenderSettings,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: &AtomicBool,
) -> Result<RenderOutput, RenderError> {
    render_streamed(scene, camera, pt, s, progress, &|_| {}, cancel)
}

/// A finished tile of a render: its place in the image and the mean
/// radiance of its pixels, row by row.
#[derive(Clone, Copy, Debug)]
pub struct Tile<'a> {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` means, row-major.
    pub mean: &'a [Vec3],
}

/// [`render_cancellable`] that hands every tile to `on_tile` as it ends
/// (from the thread that rendered it, in no fixed order), so that a viewer
/// can show the image as it fills. The image is [`render`]'s bit for bit.
pub fn render_streamed(
    scene: &Scene,
    camera: &Camera,
    pt: &PathTracer,
    s: RenderSettings,
    progress: &(dyn Fn(u64, u64) + Sync),
    on_tile: &(dyn Fn(Tile<'_>) + Sync),
    cancel: &AtomicBool,
) -> Result<RenderOutput, RenderError> {
    if s.spp == 0 {
        return Err(RenderError::ZeroSpp);
    }
    let start = Instant::now();
    let (w, h) = camera.resolution;
    let tiles_x = w.div_ceil(TILE);
    let tiles: Vec<(u32, u32)> = (0..h.div_ceil(TILE)).flat_map(|ty| (0..tiles_x).map(move |tx| (tx, ty))).collect();
    let total = w as u64 * h as u64;
    let done = AtomicU64::new(0);
    let results: Vec<Vec<(Vec3, Vec3)>> = tiles
        .par_iter()
        .map(|&(tx, ty)| {
            let (x0, y0) = (tx * TILE, ty * TILE);
            let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
            let mut out = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
            for y in y0..y1 {
                for x in x0..x1 {
                    if cancel.load(Ordering::Relaxed) {
                        return out;
                    }
                    out.push(pixel(scene, camera, pt, x, y, s));
                }
            }
            let mean: Vec<Vec3> = out.iter().map(|p| p.0).collect();
            on_tile(Tile { x: x0, y: y0, width: x1 - x0, height: y1 - y0, mean: &mean });
            let d = done.fetch_add(out.len() as u64, Ordering::Relaxed) + out.len() as u64;
            progress(d, total);
            out
        })
        .collect();
    if cancel.load(Ordering::Relaxed) {
        return Err(RenderError::Cancelled);
    }
    let mut image = Image::new(w, h);
    let mut stderr = Image::new(w, h);
    for (&(tx, ty), px) in tiles.iter().zip(results) {
        let (x0, y0) = (tx * TILE, ty * TILE);
        let x1 = (x0 + TILE).min(w);
        for (i, (m, e)) in px.into_iter().enumerate() {
            let (x, y) = (x0 + i as u32 % (x1 - x0), y0 + i as u32 / (x1 - x0));
            image.set(x, y, m);
            stderr.set(x, y, e);
        }
    }
    let bad = image.data.iter().zip(&stderr.data).filter(|(m, e)| !(m.is_finite() && e.is_finite())).count();
    if bad > 0 {
        return Err(RenderError::NonFinite(bad));
    }
    Ok(RenderOutput { image, stderr, paths: total * s.spp as u64, seconds: start.elapsed().as_secs_f64() })
}

/// Mean and standard error of `s.spp` paths through pixel (x, y).
#[inline]
pub fn pixel(scene: &Scene, camera: &Camera, pt: &PathTracer, x: u32, y: u32, s: RenderSettings) -> (Vec3, Vec3) {
    let index = y as u64 * camera.resolution.0 as u64 + x as u64;
    let mut rng = stream(s.seed, s.frame, Purpose::PIXEL, index);
    let mut acc = Accumulator::default();
    for _ in 0..s.spp {
        let (u, v) = rng.next_2d();
        let lens = rng.next_2d();
        let ray = camera.ray(x as f32 + u, y as f32 + v, lens);
        acc.add(pt.li(scene, ray, &mut rng));
    }
    (acc.mean(), acc.stderr())
}

/// Running sums for a mean and its standard error (f64).
#[derive(Clone, Copy, Debug, Default)]
pub struct Accumulator {
    n: u64,
    sum: [f64; 3],
    sum_sq: [f64; 3],
}

impl Accumulator {
    /// Adds one sample.
    #[inline]
    pub fn add(&mut self, v: Vec3) {
        self.n += 1;
        for (c, x) in [v.x, v.y, v.z].into_iter().enumerate() {
            let x = x as f64;
            self.sum[c] += x;
            self.sum_sq[c] += x * x;
        }
    }

    /// An accumulator of `n` samples whose channels sum to `sum` and whose
    /// squares sum to `sum_sq` (partial sums made elsewhere, a device's).
    pub fn from_sums(n: u64, sum: [f64; 3], sum_sq: [f64; 3]) -> Self {
        Self { n, sum, sum_sq }
    }

    /// The channels' sums and the sums of their squares.
    pub fn sums(&self) -> ([f64; 3], [f64; 3]) {
        (self.sum, self.sum_sq)
    }

    /// The estimate at `pixel`: mean, standard error and count.
    pub fn tracked(&self, pixel: (u32, u32)) -> TrackedPixel {
        TrackedPixel { pixel, mean: self.mean(), stderr: self.stderr(), samples: self.count() }
    }

    /// Merges another accumulator.
    pub fn merge(&mut self, o: &Accumulator) {
        self.n += o.n;
        for c in 0..3 {
            self.sum[c] += o.sum[c];
            self.sum_sq[c] += o.sum_sq[c];
        }
    }

    /// Number of samples.
    pub fn count(&self) -> u64 {
        self.n
    }

    /// Sample mean.
    pub fn mean(&self) -> Vec3 {
        let n = self.n.max(1) as f64;
        Vec3::new((self.sum[0] / n) as f32, (self.sum[1] / n) as f32, (self.sum[2] / n) as f32)
    }

    /// Standard error of the mean, sqrt(s² / n) with the unbiased sample variance s².
    pub fn stderr(&self) -> Vec3 {
        if self.n < 2 {
            return Vec3::ZERO;
        }
        let n = self.n as f64;
        let se = |c: usize| {
            let m = self.sum[c] / n;
            let var = ((self.sum_sq[c] - n * m * m) / (n - 1.0)).max(0.0);
            (var / n).sqrt() as f32
        };
        Vec3::new(se(0), se(1), se(2))
    }
}

/// A tracked pixel's estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackedPixel {
    /// Pixel position.
    pub pixel: (u32, u32),
    /// Mean radiance.
    pub mean: Vec3,
    /// Standard error of the mean.
    pub stderr: Vec3,
    /// Samples taken.
    pub samples: u64,
}

/// Samples per work item of [`track`]; fixed so results do not depend on threads.
pub const TRACK_BATCH: u32 = 4096;

/// Where in a pixel the camera rays of [`track_with`] start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Footprint {
    /// Uniformly over the pixel's square (a box-filtered pixel, as [`render`] makes).
    Box,
    /// Through the pixel's centre only: the radiance leaving the one surface
    /// point a G-buffer stores for the pixel, which is what a VPL renderer shades.
    Centre,
}

/// Many samples at a few pixels (the papers' per-pixel ground truth), with
/// standard errors. Work is split into batches of [`TRACK_BATCH`] samples,
/// each with its own stream, and reduced in a fixed order.
pub fn track(scene: &Scene, camera: &Camera, pt: &PathTracer, pixels: &[(u32, u32)], spp: u32, seed: u64, frame: u64) -> Vec<TrackedPixel> {
    track_with(scene, camera, pt, &TrackRequest { pixels, spp, seed, frame, footprint: Footprint::Box })
}

/// What [`track_with`] samples: which pixels, how many samples at each,
/// the seed and frame that key their streams, and where in each pixel the
/// camera rays start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TrackRequest<'a> {
    /// The pixels, (x, y).
    pub pixels: &'a [(u32, u32)],
    /// Samples at each pixel.
    pub spp: u32,
    /// The seed of the streams.
    pub seed: u64,
    /// The frame of the streams.
    pub frame: u64,
    /// Where in the pixel the rays start.
    pub footprint: Footprint,
}

/// [`track`] with a choice of where in the pixel the camera rays start.
pub fn track_with(scene: &Scene, camera: &Camera, pt: &PathTracer, request: &TrackRequest) -> Vec<TrackedPixel> {
    tracked(scene, camera, pt, request, &|_, _| {}, &AtomicBool::new(false))
}

/// [`track_with`] that reports `progress(batches done, batches)` as batches
/// of [`TRACK_BATCH`] samples end, and stops early once `cancel` is set
/// (from another thread), checked before every batch, and then returns
/// [`RenderError::Cancelled`]. An uncancelled run is [`track_with`]'s
/// result bit for bit.
pub fn track_cancellable(
    scene: &Scene,
    camera: &Camera,
    pt: &PathTracer,
    request: &TrackRequest,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: &AtomicBool,
) -> Result<Vec<TrackedPixel>, RenderError> {
    let out = tracked(scene, camera, pt, request, progress, cancel);
    if cancel.load(Ordering::Relaxed) {
        return Err(RenderError::Cancelled);
    }
    Ok(out)
}

/// The batches of [`track_cancellable`]; those begun after `cancel` is set
/// take no samples.
fn tracked(
    scene: &Scene,
    camera: &Camera,
    pt: &PathTracer,
    request: &TrackRequest,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: &AtomicBool,
) -> Vec<TrackedPixel> {
    let &TrackRequest { pixels, spp, seed, frame, footprint } = request;
    let batches = spp.div_ceil(TRACK_BATCH);
    let total = pixels.len() as u64 * batches as u64;
    let done = AtomicU64::new(0);
    let items: Vec<(usize, u32)> = (0..pixels.len()).flat_map(|p| (0..batches).map(move |b| (p, b))).collect();
    let accs: Vec<Accumulator> = items
        .par_iter()
        .map(|&(p, b)| {
            let (x, y) = pixels[p];
            let n = TRACK_BATCH.min(spp - b * TRACK_BATCH);
            let mut rng = stream(seed, frame, Purpose::TRACKED, ((p as u64) << 32) | b as u64);
            let mut acc = Accumulator::default();
            if cancel.load(Ordering::Relaxed) {
                return acc;
            }
            for _ in 0..n {
                acc.add(tracked_sample(scene, camera, pt, (x, y), footprint, &mut rng));
            }
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            acc
        })
        .collect();
    pixels
        .iter()
        .enumerate()
        .map(|(p, &pixel)| {
            let mut acc = Accumulator::default();
            for a in &accs[p * batches as usize..(p + 1) * batches as usize] {
                acc.merge(a);
            }
            acc.tracked(pixel)
        })
        .collect()
}

/// Samples per chunk of [`track_chunk`]: few enough that a device spreads a
/// pixel's samples over thousands of threads, and that one thread's loops
/// stay within what software devices allow (llvmpipe stops a thread after
/// 65,535 loop iterations in all, BVH traversals included).
pub const TRACK_CHUNK: u32 = 8;

/// Chunk `chunk` of the samples [`TrackRequest`] asks at its pixel number
/// `p`: samples `chunk · TRACK_CHUNK ..` (at most [`TRACK_CHUNK`], fewer in
/// the last chunk) drawn from stream `(p · 2³² + chunk)` under
/// [`Purpose::TRACKED_CHUNK`], each as [`track_with`] draws one (the point
/// in the pixel for [`Footprint::Box`], the lens sample, the path). The
/// reference of a device's tracked pixels (`vpl_gpu::GpuTracker`), which
/// computes each chunk in one thread: the same estimator as [`track_with`]
/// over other streams.
pub fn track_chunk(scene: &Scene, camera: &Camera, pt: &PathTracer, request: &TrackRequest, p: usize, chunk: u32) -> Accumulator {
    let mut acc = Accumulator::default();
    let Some(&(x, y)) = request.pixels.get(p) else { return acc };
    let n = TRACK_CHUNK.min(request.spp.saturating_sub(chunk.saturating_mul(TRACK_CHUNK)));
    let mut rng = stream(request.seed, request.frame, Purpose::TRACKED_CHUNK, ((p as u64) << 32) | chunk as u64);
    for _ in 0..n {
        acc.add(tracked_sample(scene, camera, pt, (x, y), request.footprint, &mut rng));
    }
    acc
}

/// One sample of pixel (x, y): the point in the pixel ([`Footprint`]), the
/// lens sample, then the path, drawn from `rng` in that order.
#[inline]
fn tracked_sample(scene: &Scene, camera: &Camera, pt: &PathTracer, (x, y): (u32, u32), footprint: Footprint, rng: &mut RngStream) -> Vec3 {
    let (u, v) = match footprint {
        Footprint::Box => rng.next_2d(),
        Footprint::Centre => (0.5, 0.5),
    };
    let lens = rng.next_2d();
    pt.li(scene, camera.ray(x as f32 + u, y as f32 + v, lens), rng)
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::{Mode, SceneSetup};

    /// An uncancelled render is [`render`]'s image bit for bit; a render
    /// cancelled before it starts, or by its own progress callback after the
    /// first tile, stops with [`RenderError::Cancelled`] without finishing
    /// its pixels.
    #[test]
    fn cancelling_stops_a_render_and_not_cancelling_changes_nothing() {
        let setup = SceneSetup::builtin("cornell").unwrap();
        let camera = setup.camera.with_resolution((48, 32)).unwrap();
        let pt = PathTracer::new(5, Mode::Full);
        let s = RenderSettings { spp: 4, seed: 3, frame: 0 };
        let plain = render(&setup.scene, &camera, &pt, s, &|_, _| {}).unwrap();
        let flag = AtomicBool::new(false);
        let same = render_cancellable(&setup.scene, &camera, &pt, s, &|_, _| {}, &flag).unwrap();
        assert_eq!(plain.image, same.image);
        assert_eq!(plain.stderr, same.stderr);
        flag.store(true, Ordering::Relaxed);
        assert!(matches!(render_cancellable(&setup.scene, &camera, &pt, s, &|_, _| {}, &flag), Err(RenderError::Cancelled)));
        let flag = AtomicBool::new(false);
        let seen = AtomicU64::new(0);
        let r = render_cancellable(
            &setup.scene,
            &camera,
            &pt,
            RenderSettings { spp: 64, ..s },
            &|done, _| {
                seen.fetch_max(done, Ordering::Relaxed);
                flag.store(true, Ordering::Relaxed);
            },
            &flag,
        );
        assert!(matches!(r, Err(RenderError::Cancelled)));
        // Six 16×16 tiles: after the first tile ends, each thread finishes at
        // most the pixel it is on.
        assert!(seen.load(Ordering::Relaxed) < 48 * 32, "{}", seen.load(Ordering::Relaxed));
    }

    /// An uncancelled [`track_cancellable`] is [`track_with`]'s result bit
    /// for bit; one whose flag is set before it starts takes no samples and
    /// answers [`RenderError::Cancelled`].
    #[test]
    fn cancelling_stops_tracking_and_not_cancelling_changes_nothing() {
        let setup = SceneSetup::builtin("cornell").unwrap();
        let camera = setup.camera.with_resolution((48, 32)).unwrap();
        let pt = PathTracer::new(5, Mode::Full);
        let pixels = [(3, 4), (20, 16), (47, 31)];
        let plain = track_with(
            &setup.scene,
            &camera,
            &pt,
            &TrackRequest { pixels: &pixels, spp: 5000, seed: 7, frame: 0, footprint: Footprint::Box },
        );
        let flag = AtomicBool::new(false);
        let seen = AtomicU64::new(0);
        let same = track_cancellable(
            &setup.scene,
            &camera,
            &pt,
            &TrackRequest { pixels: &pixels, spp: 5000, seed: 7, frame: 0, footprint: Footprint::Box },
            &|d, _| _ = seen.fetch_max(d, Ordering::Relaxed),
            &flag,
        )
        .unwrap();
        assert_eq!(plain, same);
        // Two batches per pixel (5000 = 4096 + 904).
        assert_eq!(seen.load(Ordering::Relaxed), 6);
        flag.store(true, Ordering::Relaxed);
        let request = TrackRequest { pixels: &pixels, spp: 5000, seed: 7, frame: 0, footprint: Footprint::Box };
        let r = track_cancellable(&setup.scene, &camera, &pt, &request, &|_, _| {}, &flag);
        assert!(matches!(r, Err(RenderError::Cancelled)));
    }

    /// The tiles [`render_streamed`] hands out cover the image once each
    /// and carry its pixels: laid into an image, they are the render's.
    #[test]
    fn streamed_tiles_cover_the_image_with_its_pixels() {
        let setup = SceneSetup::builtin("cornell").unwrap();
        let camera = setup.camera.with_resolution((40, 20)).unwrap();
        let pt = PathTracer::new(5, Mode::Full);
        let s = RenderSettings { spp: 2, seed: 9, frame: 0 };
        let laid = std::sync::Mutex::new((Image::new(40, 20), vec![0u32; 800]));
        let out = render_streamed(
            &setup.scene,
            &camera,
            &pt,
            s,
            &|_, _| {},
            &|t| {
                let mut l = laid.lock().unwrap();
                for (i, m) in t.mean.iter().enumerate() {
                    let (x, y) = (t.x + i as u32 % t.width, t.y + i as u32 / t.width);
                    l.0.set(x, y, *m);
                    l.1[(y * 40 + x) as usize] += 1;
                }
            },
            &AtomicBool::new(false),
        )
        .unwrap();
        let (img, counts) = laid.into_inner().unwrap();
        assert!(counts.iter().all(|&c| c == 1));
        assert_eq!(img, out.image);
    }
}
