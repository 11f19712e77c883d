//! VPL light paths (§5.1, Fig. 3b): a primary VPL on a light, then a random
//! walk in the manner of a particle tracer that stores a VPL at every vertex
//! whose chosen layer is diffuse. Unlike eye paths, light paths go on after
//! a diffuse vertex.

use crate::config::ProgressiveConfig;
use crate::vertex::roulette;
use vpl_core::bsdf::Layer;
use vpl_core::bsdf::scatter;
use vpl_core::glam::Vec3;
use vpl_core::{Purpose, Ray, Scene, SurfacePoint, stream};

/// What a pass VPL emits from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Emitter {
    /// A primary VPL: point `u_pos` of light `light` (as
    /// [`Scene::sample_light_index`] and [`Scene::emit_from`] map it),
    /// weighted by `scale` = 1 / (p_select · paths).
    Light {
        /// Light index.
        light: usize,
        /// The position sample.
        u_pos: (f32, f32),
        /// 1 / (selection probability · light paths of the pass).
        scale: f32,
    },
    /// A VPL at a diffuse vertex of a light path.
    Surface {
        /// The vertex (turned toward the light for opaque surfaces).
        y: SurfacePoint,
        /// Direction toward where the light came from.
        w_in: Vec3,
        /// Power arriving at y (W), over the pass's light paths.
        flux: Vec3,
        /// The diffuse layer the light path chose at y.
        layer: Layer,
        /// Index of refraction at the path's wavelength.
        eta: f32,
    },
}

/// A VPL of one pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PassVpl {
    /// Where and how it emits.
    pub emitter: Emitter,
    /// Scattering vertices from the light up to and including this one (0 for a primary VPL).
    pub depth: u32,
    /// The light path's wavelength, if it met a dispersive surface.
    pub lambda: Option<f32>,
    /// Number of the light path that made it.
    pub path: u32,
}

impl PassVpl {
    /// Whether this is a primary VPL on a light.
    pub fn is_primary(&self) -> bool {
        matches!(self.emitter, Emitter::Light { .. })
    }

    /// The VPL's position (a point light's, or the sampled point of an area
    /// light; `None` for the sun and the sky).
    pub fn position(&self, scene: &Scene) -> Option<Vec3> {
        match self.emitter {
            Emitter::Surface { y, .. } => Some(y.p),
            Emitter::Light { light, u_pos, .. } => match &scene.lights[light] {
                vpl_core::Light::Area { triangle, .. } => Some(scene.geometry.triangles[*triangle as usize].sample_point(u_pos)),
                vpl_core::Light::Point { position, .. } | vpl_core::Light::Spot { position, .. } => Some(*position),
                vpl_core::Light::Directional { .. } | vpl_core::Light::Environment { .. } => None,
            },
        }
    }
}

/// Traces light path `path` of pass `pass` and appends its VPLs to `out`.
#[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > y)` is meant: a NaN fails the test
pub fn trace_light_path(scene: &Scene, cfg: &ProgressiveConfig, pass: u64, path: u32, out: &mut Vec<PassVpl>) {
    if scene.lights.is_empty() || cfg.max_depth < 2 {
        return;
    }
    let mut rng = stream(cfg.seed, pass, Purpose::LIGHT_PATH, path as u64);
    let (light, p_select) = scene.light_distribution.sample(rng.next_f32());
    let u_pos = rng.next_2d();
    let u_dir = rng.next_2d();
    if !(p_select > 0.0) {
        return;
    }
    let scale = 1.0 / (p_select * cfg.vpl_paths as f32);
    out.push(PassVpl { emitter: Emitter::Light { light, u_pos, scale }, depth: 0, lambda: None, path });
    let Some(e) = scene.emit_from(light, u_pos, u_dir) else { return };
    let eps = scene.epsilon();
    let mut beta = e.beta * scale;
    let mut t = Vec3::ONE;
    let mut lambda = None;
    let mut ray = e.ray;
    // A VPL at depth j lights eye vertices through paths of ≥ j + 1 scattering vertices.
    let max_vertices = cfg.max_depth - 1;
    let mut j = 1u32;
    while j < max_vertices {
        let Some(hit) = scene.intersect(&ray) else { break };
        let w_in = -ray.d;
        let Some(sc) = scatter(scene, hit.point, w_in, cfg.spectral, &mut lambda, &mut beta, &mut rng) else { break };
        if sc.layer.is_diffuse() {
            out.push(PassVpl {
                emitter: Emitter::Surface { y: sc.at, w_in, flux: beta, layer: sc.layer, eta: sc.eta },
                depth: j,
                lambda,
                path,
            });
        }
        let Some(s) = sc.layer.sample(&sc.at, w_in, sc.eta, rng.next_2d()) else { break };
        beta *= s.weight;
        t *= s.weight;
        if beta.max_element() <= 0.0 {
            break;
        }
        if j >= cfg.rr_depth {
            let Some(q) = roulette(t, &mut rng) else { break };
            beta /= q;
            t /= q;
        }
        ray = Ray::new(sc.at.offset_toward(s.w, eps), s.w);
        j += 1;
    }
}
