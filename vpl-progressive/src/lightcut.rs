//! Stochastic lightcuts over a pass's VPLs ([`Gathering::Lightcuts`]):
//! Yuksel's estimator (*Stochastic Lightcuts*, HPG 2019) in place of the
//! sum over every stored VPL at an eye vertex (§5.1, Fig. 3c).
//!
//! Every VPL with a position (the surface VPLs, and the primary ones on
//! area, point and spot lights, one a light path) goes into a light tree
//! ([`vpl_lighttree::LightTree`]) built for the pass: a surface VPL with
//! the luminance of its flux as power, a primary one with its light's power
//! Φ times its weight 1 / (p_select · paths). The primary VPLs of the sun
//! and the sky have no position: when there are more than N of them, N are
//! drawn uniformly (with replacement), each weighted by their count over N;
//! else each is gathered. At an eye vertex x a
//! cut of at most N nodes is chosen and one VPL y drawn below each node
//! with probability p_y ([`LightTree::cut`], [`LightTree::sample_below`]),
//! and the vertex gets Σ_cut C(x, y) / p_y, C the exhaustive sum's term
//! ([`contribution`]: both BSDFs, the clamped geometry term, a shadow
//! ray). Each cut node's term is an unbiased estimate of the sum of C over
//! its VPLs, so the vertex's light is one of the exhaustive gather's,
//! provided every VPL that can light x has p_y > 0.
//!
//! That is why the importance here bounds no cosine: an eye vertex may
//! transmit (a thin or rough dielectric layer), and a VPL's layer may too,
//! so light may arrive from either side of either surface, and a spot
//! light's cone is not bounded either. A node's importance is its power over the
//! squared distance from x to the centre of its box, no less than the
//! box's half diagonal squared: positive for every node holding a VPL with
//! flux.
//!
//! [`Gathering::Lightcuts`]: crate::config::Gathering::Lightcuts

use crate::eye::EyeVertex;
use crate::gather::contribution;
use crate::light_paths::{Emitter as Source, PassVpl};
use vpl_core::glam::Vec3;
use vpl_core::image::luminance;
use vpl_core::{GeometryClamp, RngStream, Scene};
use vpl_lighttree::{Bounds, Child, Emitter, LightTree};

/// A pass's VPLs with a position in a light tree (slot k: stored VPL k,
/// empty for the VPLs of the sun and the sky), and those apart.
pub struct PassTree {
    tree: Option<LightTree>,
    slots: Vec<Option<Emitter>>,
    infinite: Vec<usize>,
}

impl PassTree {
    /// The tree over `stored`'s VPLs of `scene`.
    pub fn build(scene: &Scene, stored: &[PassVpl]) -> PassTree {
        let mut infinite = Vec::new();
        let slots: Vec<Option<Emitter>> = stored
            .iter()
            .enumerate()
            .map(|(k, v)| match v.emitter {
                Source::Surface { y, flux, .. } => Some(Emitter { p: y.p, n: y.n, power: luminance(flux) }),
                Source::Light { light, scale, .. } => {
                    let Some(p) = v.position(scene) else {
                        infinite.push(k);
                        return None;
                    };
                    let l = &scene.lights[light];
                    let area = match l {
                        vpl_core::Light::Area { triangle, .. } => scene.geometry.triangles[*triangle as usize].area,
                        _ => 0.0,
                    };
                    // The normal is not read: the importance bounds no cosine.
                    Some(Emitter { p, n: Vec3::Z, power: l.power(area, 0.0) * scale })
                }
            })
            .collect();
        // More than 2³¹ VPLs in a pass cannot fit in memory; were there, the
        // pass would gather the sun's and the sky's VPLs alone rather than panic.
        let tree = LightTree::build(&slots).ok();
        PassTree { tree, slots, infinite }
    }

    /// The lightcut estimate at eye vertex `e` of Σ_v [`contribution`] over
    /// the VPLs of `stored` that `keep` admits, with `cut` VPLs sampled from
    /// the tree (and as many of the sun's and the sky's) by `rng`.
    #[allow(clippy::too_many_arguments)] // the exhaustive sum's inputs, and the cut and its stream
    pub fn gather(
        &self,
        scene: &Scene,
        e: &EyeVertex,
        stored: &[PassVpl],
        cut: usize,
        clamp: Option<GeometryClamp>,
        keep: impl Fn(&PassVpl) -> bool,
        rng: &mut RngStream,
    ) -> Vec3 {
        let term = |v: &PassVpl| if keep(v) { contribution(scene, e, v, clamp) } else { Vec3::ZERO };
        let cut = cut.max(1);
        let mut sum = Vec3::ZERO;
        let m = self.infinite.len();
        if m <= cut {
            sum += self.infinite.iter().map(|&k| term(&stored[k])).sum::<Vec3>();
        } else {
            // Uniform picks with replacement: each term weighted m / cut.
            for _ in 0..cut {
                let k = ((rng.next_f32() * m as f32) as usize).min(m - 1);
                sum += term(&stored[self.infinite[k]]) * (m as f32 / cut as f32);
            }
        }
        let Some(tree) = &self.tree else { return sum };
        let x = e.x.p;
        let importance = |c: Child| importance(&tree.bounds(c, &self.slots), x);
        for (node, _) in tree.cut(cut, importance) {
            let Some((slot, p)) = tree.sample_below(node, importance, || rng.next_f32()) else { continue };
            if let Some(v) = stored.get(slot as usize) {
                sum += term(v) / p;
            }
        }
        sum
    }
}

/// A node's importance at x, two-sided (see the module): power over the
/// squared distance to the box's centre, no less than its half diagonal squared.
fn importance(b: &Bounds, x: Vec3) -> f32 {
    if b.power.is_nan() || b.power <= 0.0 || b.is_empty() {
        return 0.0;
    }
    let centre = (b.lo + b.hi) * 0.5;
    let r2 = (b.hi - b.lo).length_squared() * 0.25;
    b.power / (centre - x).length_squared().max(r2).max(1e-12)
}
