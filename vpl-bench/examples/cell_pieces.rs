//! Where SMC's cell flux loses or gains light, at one frame of a scene.
//!
//! ```text
//! cargo run --release -p vpl-bench --example cell_pieces -- SCENE FRAME SEED [HOLD] [KEY=VALUE ...]
//! ```
//!
//! The default SMC (settings changed by the KEY=VALUE pairs, as `--set`)
//! is stepped along the scene's sequence as `vpl energy` steps it (every
//! 8th frame, then each of the 32 before FRAME), and then HOLD more times
//! at FRAME itself (the lights standing still). At FRAME, 32×24 pixels,
//! unclamped, ray-traced, exhaustive, indirect only, it prints over the
//! path tracer's image mean (1,024 paths a pixel, through the centres):
//!
//! - `sites`: the VPLs as the sampler gives them;
//! - `pieces`: every cell cut into its probes, each with its share of the
//!   cell's flux (`SmcSampler::cell_pieces`): no point stands for a cell;
//! - `own`: the same probes with the cells' areas, each with its own
//!   radiance now (64 paths): what the areas alone give;
//! - `cell means`: each cell's mean of those radiances, spread over it;
//! - `own pooled`: `own` with each probe's area from its nearest probe
//!   among those of every iteration held (on its side of the surface, or
//!   on its own smooth surface), scaled to the same total: areas measured
//!   at a radius about √(T/s) times shorter (T iterations held, s hits a
//!   probe).
//!
//! and the median time of SMC's step over the last 32 frames. A second
//! line sets the probes' light as 64 of the camera's points receive it,
//! Σ b L Ḡ (own radiances, Ḡ the mean geometry term to those points), against
//! an independent measure of it, ∫ L Ḡ dA by uniform points on the mesh
//! with their radiances: in all and by class of normal (up, down, side),
//! with standard errors. Its ratio is the areas' error where the image
//! takes its light from.
//!
//! `sites` against `pieces` is the error of a point standing for its cell;
//! `pieces` against `cell means` the error of the cells' mean radiances
//! (their lag under moving lights among it); `own` against 1 the error of
//! the areas.
use rayon::prelude::*;
use vpl_core::glam::Vec3;
use vpl_core::image::luminance;
use vpl_core::{
    Budget, Frame, Image, IndirectShader as _, MaterialPolicy, Mode, Params, RadiosityEstimator as _, Ray, Vpl, VplSampler, VplSet,
    VplVisibility as _,
};
use vpl_pathtrace::{Footprint, PathRadiosity, PathTracer, TrackRequest, track_with};
use vpl_sampling::{SmcConfig, SmcSampler};
use vpl_shading::{ExhaustiveShader, render_gbuffer};
use vpl_visibility::RayTraced;

fn mean(img: &Image) -> f64 {
    img.data.iter().map(|&c| luminance(c) as f64).sum::<f64>() / img.data.len().max(1) as f64
}

fn set_of(vpls: Vec<Vpl>) -> VplSet {
    let mut set = VplSet::new(vpls.len());
    for (k, v) in vpls.into_iter().enumerate() {
        set.set(k, Some(v));
    }
    set
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: cell_pieces SCENE FRAME SEED [HOLD] [KEY=VALUE ...]";
    let (Some(scene_name), Some(target), Some(seed)) = (args.first(), args.get(1), args.get(2)) else { return Err(usage.into()) };
    let (target, seed): (u32, u64) = (target.parse()?, seed.parse()?);
    let hold: usize = args.get(3).filter(|a| !a.contains('=')).map_or(Ok(0), |a| a.parse())?;
    let params = Params::parse(args.iter().skip(3).filter(|a| a.contains('=')))?;
    let config = SmcConfig::from_params(&Budget::new(2048, 5), &params)?;
    let (w, h) = (32, 24);
    let setup = vpl_scene_io::load(scene_name)?;
    let mut smc = SmcSampler::new(config)?;
    let mut steps: Vec<u32> = (0..=target).step_by(8).collect();
    steps.extend(target.saturating_sub(32)..=target);
    steps.sort_unstable();
    steps.dedup();
    steps.extend(std::iter::repeat_n(target, hold));
    let mut step_ms = Vec::new();
    for &f in &steps {
        let (scene, camera) = setup.frame(f)?;
        let camera = camera.with_resolution((w, h))?;
        let gbuffer = render_gbuffer(&scene, &camera);
        let time = setup.sequence.as_ref().map_or(0.0, |q| q.time(f));
        smc.next_frame(&Frame { scene: &scene, camera: &camera, time, index: f as u64, seed, gbuffer: &gbuffer, previous: None });
        step_ms.push((smc.timings().total_ms, smc.timings().radiosity_ms));
    }
    // The steps of the last 32 frames: their median time, radiosity apart.
    let last = &mut step_ms[steps.len().saturating_sub(32)..];
    last.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (step, radiosity) = last.get(last.len() / 2).copied().unwrap_or_default();
    let (scene, camera) = setup.frame(target)?;
    let camera = camera.with_resolution((w, h))?;
    let gbuffer = render_gbuffer(&scene, &camera);
    let shade = |set: &VplSet| {
        let mut vis = RayTraced::default();
        vis.update(&scene, set);
        mean(&ExhaustiveShader { clamp: None }.shade(&gbuffer, set, &vis))
    };
    let sites = shade(smc.vpls());
    let cut = smc.cell_pieces();
    let total = |v: &[Vpl]| v.iter().map(|v| luminance(v.flux) as f64).sum::<f64>();
    let pieces_light = total(&cut);
    let pieces = shade(&set_of(cut));
    // The probes' own radiances now, and each cell's mean of them.
    let areas = smc.cell_areas();
    let estimator = PathRadiosity { paths: 64, max_bounces: 2 };
    let own_l: Vec<Vec3> = areas
        .par_iter()
        .enumerate()
        .map(|(k, &(_, p, n, _))| match scene.intersect(&Ray::new(p + n * 1e-3, -n)) {
            Some(hit) => estimator.radiosity(&scene, &hit.point.facing(n), 0x5eed ^ k as u64),
            None => Vec3::ZERO,
        })
        .collect();
    let vpl = |k: usize, y: Vec3, n: Vec3, flux: Vec3| Vpl { y, n, flux, id: k as u64, bounce: 0 };
    let own: Vec<Vpl> = areas.iter().zip(&own_l).enumerate().map(|(k, (&(_, p, n, a), &l))| vpl(k, p, n, l * a)).collect();
    let own_light = total(&own);
    let cells = areas.iter().map(|a| a.0 + 1).max().unwrap_or(0);
    let (mut light, mut area) = (vec![Vec3::ZERO; cells], vec![0.0f32; cells]);
    for (&(i, _, _, a), &l) in areas.iter().zip(&own_l) {
        light[i] += l * a;
        area[i] += a;
    }
    let means = areas.iter().enumerate().map(|(k, &(i, p, n, a))| vpl(k, p, n, light[i] / area[i] * a)).collect();
    let (own, means) = (shade(&set_of(own)), shade(&set_of(means)));
    // The same probes and radiances with areas from each probe's nearest
    // neighbour among the probes of every iteration held (a radius about
    // √(T/s) times shorter than one iteration's hits give, s hits a probe), on its side of the surface
    // (normals within 120°) or on its own smooth surface (within 60°),
    // scaled to the cells' total area: where the areas' error comes from
    // the radius (edges, corners, density changes), it shrinks here.
    let points: Vec<Vec3> = areas.iter().map(|a| a.1).collect();
    let normals: Vec<Vec3> = areas.iter().map(|a| a.2).collect();
    let tree = vpl_density::KnnDensity::new(&points)?;
    let total_area: f64 = areas.iter().map(|a| a.3 as f64).sum();
    let pooled = |cos: f32| {
        let r2: Vec<f32> = (0..points.len())
            .into_par_iter()
            .map(|i| tree.nearest_accepted(points[i], Some(i), |j| normals[j].dot(normals[i]) > cos).map_or(0.0, |(_, d2)| d2))
            .collect();
        let scale = total_area / r2.iter().map(|&r| r as f64).sum::<f64>();
        let set: Vec<Vpl> = areas
            .iter()
            .zip(&own_l)
            .zip(&r2)
            .enumerate()
            .map(|(k, ((&(_, p, n, _), &l), &r))| vpl(k, p, n, l * (r as f64 * scale) as f32))
            .collect();
        shade(&set_of(set))
    };
    let (pooled_side, pooled_surface) = (pooled(-0.5), pooled(0.5));
    let diffuse = scene.with_material_policy(MaterialPolicy::Diffuse);
    let pixels: Vec<(u32, u32)> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).collect();
    let tracked = track_with(
        &diffuse,
        &camera,
        &PathTracer::new(5, Mode::Indirect),
        &TrackRequest { pixels: &pixels, spp: 1024, seed: 0, frame: target as u64, footprint: Footprint::Centre },
    );
    let truth = tracked.iter().map(|t| luminance(t.mean) as f64).sum::<f64>() / tracked.len().max(1) as f64;
    let viewers = viewers(&scene, &camera);
    let reach = reachable(&scene, &viewers, seed, &estimator);
    println!(
        "{scene_name} frame {target} seed {seed}: sites {:.3}, pieces {:.3}, own {:.3}, cell means {:.3}, own pooled (side) {:.3}, own pooled (surface) {:.3} of the path tracer's ({} probes; the pieces' light {:.3} of the own radiances', the candidates' {:.3}); SMC's step {step:.1} ms (radiosity {radiosity:.1}), median of the last 32",
        sites / truth,
        pieces / truth,
        own / truth,
        means / truth,
        pooled_side / truth,
        pooled_surface / truth,
        areas.len(),
        pieces_light / own_light,
        smc.stats().candidate_light / own_light
    );
    // The probes' light as the camera's points receive it, by class,
    // against the independent measure of it.
    let mut probed = [0.0f64; 3];
    let coupled: Vec<f64> = areas.par_iter().map(|&(_, p, n, _)| coupling(&scene, &viewers, p, n)).collect();
    for ((&(_, _, n, a), &l), &g) in areas.iter().zip(&own_l).zip(&coupled) {
        probed[class(n)] += a as f64 * luminance(l) as f64 * g;
    }
    let line: Vec<String> = ["up", "down", "side"]
        .iter()
        .enumerate()
        .map(|(c, name)| format!("{name}: {:.3} ({:.3} ± {:.3})", probed[c] / reach[c].0.max(1e-30), reach[c].0, reach[c].1))
        .collect();
    let all: f64 = reach.iter().map(|r| r.0).sum();
    let se_all = reach.iter().map(|r| r.1 * r.1).sum::<f64>().sqrt();
    println!(
        "  probes' light at the camera's points (Σ b L Ḡ) over the surface's (∫ L Ḡ dA, uniform points on the mesh): all {:.3} (± {:.3}); {}",
        probed.iter().sum::<f64>() / all,
        se_all / all,
        line.join("; ")
    );
    Ok(())
}

/// The class of a surface by its normal: up (n_y > 0.5), down (n_y < −0.5), side.
fn class(n: Vec3) -> usize {
    if n.y > 0.5 {
        0
    } else if n.y < -0.5 {
        1
    } else {
        2
    }
}

/// 64 points the camera sees (pixel centres of a 64×48 G-buffer, every
/// 48th of those that reflect), as (point, normal).
fn viewers(scene: &vpl_core::Scene, camera: &vpl_core::Camera) -> Vec<(Vec3, Vec3)> {
    let fine = camera.with_resolution((64, 48)).expect("a valid resolution");
    let g = render_gbuffer(scene, &fine);
    let seen: Vec<(Vec3, Vec3)> =
        g.samples.iter().filter(|s| s.depth.is_finite() && s.albedo.max_element() > 0.0).map(|s| (s.p, s.ng)).collect();
    let stride = (seen.len() / 64).max(1);
    seen.into_iter().step_by(stride).take(64).collect()
}

/// Ḡ(y): the mean geometry term between `y` (normal `n`, the side that
/// shines) and the `viewers`, with visibility: how much of y's light the
/// camera's points receive. d² is kept above (10⁻² of the scene's radius)²
/// so that a point beside a viewer does not swamp the mean.
fn coupling(scene: &vpl_core::Scene, viewers: &[(Vec3, Vec3)], y: Vec3, n: Vec3) -> f64 {
    let eps = scene.epsilon();
    let d2_min = (1e-2 * scene.radius()).powi(2);
    let mut sum = 0.0f64;
    for &(x, nx) in viewers {
        let d = y - x;
        let d2 = d.length_squared();
        let (cx, cy) = (nx.dot(d), -n.dot(d));
        if cx <= 0.0 || cy <= 0.0 || !scene.visible(x + nx * eps, y + n * eps) {
            continue;
        }
        sum += (cx * cy) as f64 / (d2 as f64 * d2.max(d2_min) as f64);
    }
    sum / viewers.len().max(1) as f64
}

/// ∫ L Ḡ dA by class ([`class`], [`coupling`]) with its standard error:
/// 131,072 points drawn uniformly by area on the mesh, each side of each
/// with its radiance (64 paths) where the viewers see it. Independent of
/// the probes: no hit, no neighbour distance.
fn reachable(scene: &vpl_core::Scene, viewers: &[(Vec3, Vec3)], seed: u64, estimator: &PathRadiosity) -> [(f64, f64); 3] {
    let tris = &scene.geometry.triangles;
    let mut cdf = Vec::with_capacity(tris.len());
    let mut acc = 0.0f64;
    for t in tris {
        acc += t.area.max(0.0) as f64;
        cdf.push(acc);
    }
    let total = acc;
    let k = 131_072usize;
    let draws: Vec<[f64; 3]> = (0..k)
        .into_par_iter()
        .map(|i| {
            let mut rng = vpl_core::rng::stream(seed, i as u64, vpl_core::rng::Purpose::TEST, 0x5eac);
            let u = rng.next_f32() as f64 * total;
            let t = cdf.partition_point(|&c| c <= u).min(tris.len() - 1);
            let (u1, u2) = rng.next_2d();
            let s = u1.sqrt();
            let (b1, b2) = (s * (1.0 - u2), s * u2);
            let tri = &tris[t];
            let y = tri.p0 + tri.e1 * b1 + tri.e2 * b2;
            let mut out = [0.0f64; 3];
            for (side, f) in [tri.ng, -tri.ng].into_iter().enumerate() {
                let g = coupling(scene, viewers, y, f);
                if g > 0.0 {
                    let point = scene.surface_point(t as u32, b1, b2).facing(f);
                    let l = luminance(estimator.radiosity(scene, &point, 0xa5ea ^ (2 * i + side) as u64)) as f64;
                    out[class(f)] += total * l * g;
                }
            }
            out
        })
        .collect();
    std::array::from_fn(|c| {
        let kf = k as f64;
        let mean = draws.iter().map(|d| d[c]).sum::<f64>() / kf;
        let var = draws.iter().map(|d| (d[c] - mean).powi(2)).sum::<f64>() / (kf - 1.0);
        (mean, (var / kf).sqrt())
    })
}
