//! Unidirectional path tracing with next-event estimation and MIS.
//!
//! Depth and modes follow [`vpl_core::Mode`] (Mitsuba 3's convention:
//! `max_depth` counts path segments).

use std::f32::consts::FRAC_1_PI;
use vpl_core::bsdf::scatter;
use vpl_core::clamp::{GeometryClamp, geometry_term};
use vpl_core::glam::Vec3;
use vpl_core::sampling::{cosine_hemisphere, power_heuristic};
use vpl_core::{LocalFrame, Mode, Ray, RngStream, Scene, SurfacePoint};

/// Which paths a walk counts: those whose number of scattering vertices
/// lies in `min_k..=max_k`, their connections clamped by `clamp`.
#[derive(Clone, Copy, Debug)]
struct Counted {
    min_k: u32,
    max_k: u32,
    clamp: Option<GeometryClamp>,
}

/// A path tracer configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathTracer {
    /// Largest number of path segments (Mitsuba's `max_depth`, ≥ 1).
    pub max_depth: u32,
    /// Which paths count.
    pub mode: Mode,
    /// Clamp of the geometry term of the segment that leaves the primary hit,
    /// except connections straight to a light (Hedman et al. 2017, §5.4).
    pub clamp: Option<GeometryClamp>,
    /// Scattering vertices after which Russian roulette starts (Mitsuba: 5).
    pub rr_depth: u32,
}

impl PathTracer {
    /// A path tracer with no clamping and Mitsuba's Russian-roulette depth.
    pub fn new(max_depth: u32, mode: Mode) -> Self {
        Self { max_depth, mode, clamp: None, rr_depth: 5 }
    }

    /// Range of scattering-vertex counts k included by the mode.
    #[inline]
    fn k_range(&self) -> (u32, u32) {
        self.mode.k_range(self.max_depth)
    }

    /// Russian roulette after `k` scattering vertices: from [`PathTracer::rr_depth`]
    /// on, the path survives with probability min(max channel of β, 0.95)
    /// and β is divided by it. Returns whether the path goes on.
    #[inline]
    fn survives(&self, k: u32, beta: &mut Vec3, rng: &mut RngStream) -> bool {
        if k < self.rr_depth {
            return true;
        }
        let q = beta.max_element().min(0.95);
        if rng.next_f32() >= q {
            return false;
        }
        *beta /= q;
        true
    }

    /// Radiance arriving along the camera ray `ray`.
    #[inline]
    pub fn li(&self, scene: &Scene, ray: Ray, rng: &mut RngStream) -> Vec3 {
        let (min_k, max_k) = self.k_range();
        if self.max_depth == 0 || min_k > max_k {
            return Vec3::ZERO;
        }
        let Some(hit) = scene.intersect(&ray) else {
            // The environment seen directly: a path without scattering vertices.
            return if min_k == 0 { scene.environment_radiance(ray.d) } else { Vec3::ZERO };
        };
        let mut l = Vec3::ZERO;
        if min_k == 0 {
            l += scene.emitted(&hit.point, -ray.d);
        }
        l + self.walk(scene, hit.point, -ray.d, 0, Counted { min_k, max_k, clamp: self.clamp }, rng)
    }

    /// Exitant radiance (emission excluded) of surface point `y` toward `wo`,
    /// counting paths that leave `y` with at most `max_bounces` further
    /// scattering vertices after `y` (0 = direct light at `y` only).
    #[inline]
    pub fn reflected(&self, scene: &Scene, y: &SurfacePoint, wo: Vec3, max_bounces: u32, rng: &mut RngStream) -> Vec3 {
        self.walk(scene, *y, wo, 0, Counted { min_k: 1, max_k: 1 + max_bounces, clamp: None }, rng)
    }

    /// Continues a path that has reached surface point `sp` from direction
    /// `wo` (pointing away from `sp`) after `k` scattering vertices; returns
    /// the radiance the rest of the path brings, counting paths whose total
    /// number of scattering vertices lies in `min_k..=max_k`.
    #[allow(clippy::collapsible_if)] // each condition of next-event estimation on its own line, as the estimator reads
    fn walk(&self, scene: &Scene, mut sp: SurfacePoint, mut wo: Vec3, mut k: u32, counted: Counted, rng: &mut RngStream) -> Vec3 {
        let Counted { min_k, max_k, clamp } = counted;
        let eps = scene.epsilon();
        let mut l = Vec3::ZERO;
        let mut beta = Vec3::ONE;
        loop {
            // Scatter at sp: it becomes scattering vertex k + 1.
            if k + 1 > max_k {
                break;
            }
            if scene.material(&sp).layered.is_some() {
                // From here on the path follows the κ-layered model (one layer per vertex).
                return l + self.walk_layered(scene, (sp, wo, k), counted, beta, rng);
            }
            if wo.dot(sp.ng) <= 0.0 {
                if !scene.two_sided {
                    break; // one-sided BSDF seen from behind: black (Mitsuba's diffuse)
                }
                sp = sp.facing(wo);
            }
            let albedo = scene.material(&sp).albedo;
            if albedo.max_element() <= 0.0 {
                break;
            }
            let f = albedo * FRAC_1_PI;
            let (u_sel, u_l0, u_l1, u_b0, u_b1) = (rng.next_f32(), rng.next_f32(), rng.next_f32(), rng.next_f32(), rng.next_f32());
            // At the last vertex a BSDF-sampled ray could only find an emitter;
            // light sampling alone (MIS weight 1) covers those paths without it.
            let last = k + 1 == max_k;
            // Next-event estimation: a path with k + 1 scattering vertices.
            if k + 1 >= min_k {
                if let Some((ls, p_sel)) = scene.sample_light(sp.p, u_sel, (u_l0, u_l1)) {
                    let cos = sp.n.dot(ls.wi);
                    if cos > 0.0 && ls.wi.dot(sp.ng) > 0.0 {
                        if scene.light_unoccluded(sp.p, sp.ng, &ls) {
                            if ls.delta {
                                l += beta * f * ls.li * (cos / p_sel);
                            } else {
                                let pdf_light = p_sel * ls.pdf;
                                let w = if last { 1.0 } else { power_heuristic(pdf_light, cos * FRAC_1_PI) };
                                l += beta * f * ls.li * (cos * w / pdf_light);
                            }
                        }
                    }
                }
            }
            if last {
                break;
            }
            // Cosine-weighted BSDF sample: f·cos/pdf = ρ.
            let local = cosine_hemisphere(u_b0, u_b1);
            let wi = LocalFrame::from_normal(sp.n).to_world(local);
            if wi.dot(sp.ng) <= 0.0 {
                break;
            }
            let pdf_bsdf = local.z * FRAC_1_PI;
            beta *= albedo;
            let origin = sp.p + sp.ng * eps;
            let Some(hit) = scene.intersect(&Ray::new(origin, wi)) else {
                // Leaving the scene: the environment ends a path with k + 1 vertices, weighted against NEE.
                if k + 1 >= min_k {
                    let le = scene.environment_radiance(wi);
                    if le != Vec3::ZERO {
                        l += beta * le * power_heuristic(pdf_bsdf, scene.environment_pdf(wi));
                    }
                }
                break;
            };
            k += 1;
            let next = hit.point;
            // Emission at the next vertex: a path with k scattering vertices, weighted against NEE.
            if k >= min_k {
                let le = scene.emitted(&next, -wi);
                if le != Vec3::ZERO {
                    let w = power_heuristic(pdf_bsdf, scene.light_pdf(sp.p, &next));
                    l += beta * le * w;
                }
            }
            // Clamp the segment leaving the primary hit for everything beyond it.
            if k == 1 {
                if let Some(c) = clamp {
                    let g = geometry_term(local.z, next.n.dot(-wi).abs(), hit.t * hit.t);
                    beta *= c.factor(g);
                }
            }
            if !self.survives(k, &mut beta, rng) {
                break;
            }
            sp = next;
            wo = -wi;
        }
        l
    }

    /// [`PathTracer::walk`] for paths that meet κ-layered materials
    /// ([`vpl_core::bsdf`]): at every vertex one layer is chosen from `wo`;
    /// delta layers (mirrors, clear glass) are followed without next-event
    /// estimation, the others get light samples with MIS against their own
    /// lobe. A path that meets a dispersive surface draws a wavelength there
    /// and keeps it (lazy spectral rendering, Dammertz et al. 2010, §6).
    fn walk_layered(
        &self,
        scene: &Scene,
        (mut sp, mut wo, mut k): (SurfacePoint, Vec3, u32),
        counted: Counted,
        mut beta: Vec3,
        rng: &mut RngStream,
    ) -> Vec3 {
        let Counted { min_k, max_k, clamp } = counted;
        let eps = scene.epsilon();
        let mut l = Vec3::ZERO;
        let mut lambda: Option<f32> = None;
        loop {
            if k + 1 > max_k {
                break;
            }
            let Some(sc) = scatter(scene, sp, wo, true, &mut lambda, &mut beta, rng) else { break };
            let (u_sel, u_l0, u_l1, u_b0, u_b1) = (rng.next_f32(), rng.next_f32(), rng.next_f32(), rng.next_f32(), rng.next_f32());
            let (at, layer, eta) = (sc.at, sc.layer, sc.eta);
            let last = k + 1 == max_k;
            if !layer.is_delta() && k + 1 >= min_k {
                if let Some((ls, p_sel)) = scene.sample_light(at.p, u_sel, (u_l0, u_l1)) {
                    let f = layer.eval(&at, wo, ls.wi, eta);
                    let cos = at.n.dot(ls.wi).abs();
                    let origin_side = if ls.wi.dot(at.ng) >= 0.0 { at.ng } else { -at.ng };
                    if f != Vec3::ZERO && scene.light_unoccluded(at.p, origin_side, &ls) {
                        if ls.delta {
                            l += beta * f * ls.li * (cos / p_sel);
                        } else {
                            let pdf_light = p_sel * ls.pdf;
                            let w = if last { 1.0 } else { power_heuristic(pdf_light, layer.pdf(&at, wo, ls.wi, eta)) };
                            l += beta * f * ls.li * (cos * w / pdf_light);
                        }
                    }
                }
            }
            if last {
                break;
            }
            let Some(s) = layer.sample(&at, wo, eta, (u_b0, u_b1)) else { break };
            beta *= s.weight;
            if beta.max_element() <= 0.0 {
                break;
            }
            let origin = at.offset_toward(s.w, eps);
            let Some(hit) = scene.intersect(&Ray::new(origin, s.w)) else {
                if k + 1 >= min_k {
                    let le = scene.environment_radiance(s.w);
                    if le != Vec3::ZERO {
                        let w = if s.delta { 1.0 } else { power_heuristic(s.pdf, scene.environment_pdf(s.w)) };
                        l += beta * le * w;
                    }
                }
                break;
            };
            k += 1;
            let next = hit.point;
            if k >= min_k {
                let le = scene.emitted(&next, -s.w);
                if le != Vec3::ZERO {
                    let w = if s.delta { 1.0 } else { power_heuristic(s.pdf, scene.light_pdf(at.p, &next)) };
                    l += beta * le * w;
                }
            }
            if k == 1 {
                if let Some(c) = clamp {
                    let g = geometry_term(at.n.dot(s.w).abs(), next.n.dot(-s.w).abs(), hit.t * hit.t);
                    beta *= c.factor(g);
                }
            }
            if !self.survives(k, &mut beta, rng) {
                break;
            }
            sp = next;
            wo = -s.w;
        }
        l
    }
}
