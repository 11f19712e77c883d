//! Caustic histograms (§5.3, Fig. 3d): the pass's eye vertices are bins with
//! a radius of half a pixel's footprint, kept in a k-d tree; photons leave
//! the pass's VPLs, are discarded unless their first hit chooses a specular
//! layer, and from then on fall, at every surface they meet, into the one
//! closest bin (if it lies within that bin's radius), until a light-side
//! diffuse choice ends them. A bin's pixel receives
//! β_e · f_x(wo, w_photon) · Φ_photon / (π r²).
//!
//! The closest-bin rule ([`BinRule::Closest`], the paper's) keeps bins from
//! overlapping, but a bin whose neighbour lies closer than 2r loses the part
//! of its disk nearer to the neighbour while still dividing by πr²: caustics
//! come out darker, by an amount that shrinks with the radius.
//! [`BinRule::AllWithin`] gives a photon to every bin whose disk holds it,
//! so each bin estimates the irradiance averaged over its whole disk (blur,
//! no loss).

use crate::config::{BinRule, ProgressiveConfig};
use crate::eye::EyeVertex;
use crate::light_paths::{Emitter, PassVpl};
use crate::projection::{ProjectionMap, SpecularSet};
use crate::vertex::roulette;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::f32::consts::{FRAC_1_PI, PI};
use vpl_core::bsdf::scatter;
use vpl_core::glam::Vec3;
use vpl_core::sampling::{cosine_hemisphere, uniform_sphere};
use vpl_core::{Light, LocalFrame, Purpose, Ray, Scene, SurfacePoint, stream};

/// Cosine below which a photon's surface and a bin's are different surfaces.
const SAME_SURFACE_COS: f32 = 0.5;

/// The bins of a pass in a k-d tree.
pub struct Bins<'a> {
    vertices: Vec<&'a EyeVertex>,
    tree: Option<ImmutableKdTree<f32, 3>>,
    max_radius: f32,
}

impl<'a> Bins<'a> {
    /// Bins at `vertices`.
    pub fn new(vertices: Vec<&'a EyeVertex>) -> Bins<'a> {
        let points: Vec<[f32; 3]> = vertices.iter().map(|v| v.x.p.to_array()).collect();
        // Only fails on an empty slice.
        let tree = if points.is_empty() { None } else { ImmutableKdTree::new_from_slice(&points).ok() };
        let max_radius = vertices.iter().map(|v| v.radius).fold(0.0f32, f32::max);
        Bins { vertices, tree, max_radius }
    }

    /// Number of bins.
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// Whether there is no bin.
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// The closest bin to `p`, if `p` lies within its radius.
    #[inline]
    pub fn closest(&self, p: Vec3) -> Option<&'a EyeVertex> {
        let tree = self.tree.as_ref()?;
        let n = tree.query(&p.to_array()).nearest_one::<SquaredEuclidean<f32>>().execute();
        let v = self.vertices[n.item as usize];
        (n.distance <= v.radius * v.radius).then_some(v)
    }

    /// Calls `f` with every bin whose radius reaches `p`.
    #[inline]
    pub fn each_within(&self, p: Vec3, mut f: impl FnMut(&'a EyeVertex)) {
        let Some(tree) = self.tree.as_ref() else { return };
        let r2 = self.max_radius * self.max_radius;
        for n in tree.query(&p.to_array()).within::<SquaredEuclidean<f32>>(r2).unsorted().execute() {
            let v = self.vertices[n.item as usize];
            if n.distance <= v.radius * v.radius {
                f(v);
            }
        }
    }
}

/// What the photons of one VPL did.
#[derive(Clone, Debug, Default)]
pub struct SourceResult {
    /// (pixel, radiance) added to the pass image, in photon order.
    pub deposits: Vec<(u32, Vec3)>,
    /// Photons emitted.
    pub photons: u64,
    /// Photons whose first hit chose a specular layer.
    pub caustic: u64,
    /// Marked fraction of the sphere (1 without projection maps).
    pub coverage: f32,
}

/// The emission of a photon: its ray and power.
struct Emission {
    ray: Ray,
    power: Vec3,
}

/// Draws photon direction and power for VPL `v` (one of `n` photons).
#[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > y)` is meant: a NaN fails the test
fn emit(scene: &Scene, v: &PassVpl, map: Option<&ProjectionMap>, n: f32, rng: &mut vpl_core::RngStream) -> Option<Emission> {
    let eps = scene.epsilon();
    let u_cell = rng.next_f32();
    let u_dir = rng.next_2d();
    // A direction from the map (uniform over marked cells) or from `fallback`.
    let from_map = |fallback: &dyn Fn() -> (Vec3, f32)| -> Option<(Vec3, f32)> {
        match map {
            Some(m) => m.sample(u_cell, u_dir),
            None => Some(fallback()),
        }
    };
    match v.emitter {
        Emitter::Light { light, u_pos, scale } => match &scene.lights[light] {
            Light::Area { triangle, radiance } => {
                let t = &scene.geometry.triangles[*triangle as usize];
                let y = t.sample_point(u_pos);
                let (w, pdf) = from_map(&|| {
                    let l = cosine_hemisphere(u_dir.0, u_dir.1);
                    (LocalFrame::from_normal(t.ng).to_world(l), l.z * FRAC_1_PI)
                })?;
                let cos = w.dot(t.ng);
                if cos <= 0.0 || !(pdf > 0.0) {
                    return None;
                }
                // Intensity Le·A·cos of the light point (p_A = 1/A), over the direction's density.
                Some(Emission { ray: Ray::new(y + t.ng * eps, w), power: *radiance * (t.area * cos * scale / (pdf * n)) })
            }
            Light::Point { position, intensity } => {
                let (w, pdf) = from_map(&|| (uniform_sphere(u_dir.0, u_dir.1), 0.25 * FRAC_1_PI))?;
                Some(Emission { ray: Ray::new(*position, w), power: *intensity * (scale / (pdf * n)) })
            }
            Light::Spot { position, direction, intensity, cos_falloff_start, cos_total } => {
                let (w, pdf) = from_map(&|| (uniform_sphere(u_dir.0, u_dir.1), 0.25 * FRAC_1_PI))?;
                let f = Light::spot_falloff(w.dot(*direction), *cos_falloff_start, *cos_total);
                (f > 0.0).then(|| Emission { ray: Ray::new(*position, w), power: *intensity * (f * scale / (pdf * n)) })
            }
            // Parallel rays from a disk facing the sun or a drawn sky direction.
            Light::Directional { .. } | Light::Environment { .. } => {
                let e = scene.emit_from(light, (u_cell, rng.next_f32()), u_dir)?;
                Some(Emission { ray: e.ray, power: e.beta * (scale / n) })
            }
        },
        Emitter::Surface { y, w_in, flux, layer, eta } => {
            let (w, pdf, weight) = match map {
                Some(m) => {
                    let (w, pdf) = m.sample(u_cell, u_dir)?;
                    let f = layer.eval(&y, w, w_in, eta);
                    (w, pdf, f * y.n.dot(w).abs() / pdf)
                }
                None => {
                    let s = layer.sample(&y, w_in, eta, u_dir)?;
                    (s.w, s.pdf, s.weight)
                }
            };
            if !(pdf > 0.0) || weight.max_element() <= 0.0 {
                return None;
            }
            Some(Emission { ray: Ray::new(y.offset_toward(w, eps), w), power: flux * weight / n })
        }
    }
}

/// Which photons of a pass one VPL traces: numbers `first..first + n` of
/// pass `pass` (each its own random stream).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Photons {
    /// The pass.
    pub pass: u64,
    /// The first photon's number in the pass.
    pub first: u64,
    /// How many.
    pub n: u64,
}

/// Traces the `photons` of VPL `v` and collects their deposits into `bins`.
pub fn trace_photons(
    scene: &Scene,
    cfg: &ProgressiveConfig,
    v: &PassVpl,
    bounds: &SpecularSet,
    photons: Photons,
    bins: &Bins,
) -> SourceResult {
    let mut out = SourceResult { coverage: 1.0, ..Default::default() };
    let map = if cfg.projection_maps {
        let Some(y) = v.position(scene) else {
            // The sun or the sky: parallel photons from a disk, no map.
            return trace_with(scene, cfg, v, None, photons, bins, out);
        };
        let hemisphere = match v.emitter {
            Emitter::Light { light, .. } => match &scene.lights[light] {
                Light::Area { triangle, .. } => Some(scene.geometry.triangles[*triangle as usize].ng),
                _ => None,
            },
            Emitter::Surface { y, layer, .. } => (layer.kind != vpl_core::bsdf::LayerKind::Transmission).then_some(y.ng),
        };
        let m = ProjectionMap::build(y, hemisphere, bounds, cfg.map_size);
        out.coverage = m.coverage();
        if m.is_empty() {
            return out;
        }
        Some(m)
    } else {
        None
    };
    trace_with(scene, cfg, v, map.as_ref(), photons, bins, out)
}

fn trace_with(
    scene: &Scene,
    cfg: &ProgressiveConfig,
    v: &PassVpl,
    map: Option<&ProjectionMap>,
    photons: Photons,
    bins: &Bins,
    mut out: SourceResult,
) -> SourceResult {
    let Photons { pass, first, n } = photons;
    let eps = scene.epsilon();
    let max_vertices = cfg.max_depth.saturating_sub(1);
    for p in 0..n {
        let mut rng = stream(cfg.seed, pass, Purpose::PHOTON, first + p);
        out.photons += 1;
        let Some(e) = emit(scene, v, map, n as f32, &mut rng) else { continue };
        let mut power = e.power;
        let mut t = Vec3::ONE;
        let mut lambda = v.lambda;
        let mut ray = e.ray;
        // Specular vertices the photon has passed (m).
        let mut m = 0u32;
        while let Some(hit) = scene.intersect(&ray) {
            let w_in = -ray.d;
            if m > 0 {
                deposit(bins, cfg, &hit.point, w_in, power, m + v.depth, &mut out.deposits);
            }
            // The photon may go on only if a bin can still take it: s = 0, one more specular vertex.
            if v.depth + m + 1 + 1 > max_vertices {
                break;
            }
            let Some(sc) = scatter(scene, hit.point, w_in, cfg.spectral, &mut lambda, &mut power, &mut rng) else { break };
            if sc.layer.is_diffuse() {
                break;
            }
            if m == 0 {
                out.caustic += 1;
            }
            let Some(s) = sc.layer.sample(&sc.at, w_in, sc.eta, rng.next_2d()) else { break };
            power *= s.weight;
            t *= s.weight;
            m += 1;
            if v.depth + m >= cfg.rr_depth {
                let Some(q) = roulette(t, &mut rng) else { break };
                power /= q;
                t /= q;
            }
            ray = Ray::new(sc.at.offset_toward(s.w, eps), s.w);
        }
    }
    out
}

/// Adds a photon arriving at surface point `z` from `w_in` with `power`,
/// after `vertices` light-side scattering vertices, to its bin(s). A bin
/// takes only photons on its own surface: the same material and a normal
/// within 60° (a photon inside a glass sphere, next to a floor bin at the
/// point where the sphere rests, is not light on the floor).
#[inline]
fn deposit(bins: &Bins, cfg: &ProgressiveConfig, z: &SurfacePoint, w_in: Vec3, power: Vec3, vertices: u32, out: &mut Vec<(u32, Vec3)>) {
    let (p, ng) = (z.p, z.ng);
    let mut add = |b: &EyeVertex| {
        // Every eye vertex is a bin, so photons fall the same way whichever classes are rendered.
        let class_on = if b.specular == 0 { cfg.techniques.caustics } else { cfg.techniques.specular_gathering };
        if !class_on || b.specular + 1 + vertices > cfg.max_depth.saturating_sub(1) {
            return;
        }
        if b.x.material != z.material || b.x.ng.dot(ng).abs() < SAME_SURFACE_COS {
            return;
        }
        let f = b.layer.eval(&b.x, b.wo, w_in, b.eta);
        if f == Vec3::ZERO {
            return;
        }
        out.push((b.pixel, b.beta * f * power / (PI * b.radius * b.radius)));
    };
    match cfg.bins {
        BinRule::Closest => {
            if let Some(b) = bins.closest(p) {
                add(b);
            }
        }
        BinRule::AllWithin => bins.each_within(p, add),
    }
}
