//! Stochastic lightcuts (Yuksel, *Stochastic Lightcuts*, HPG 2019) over any
//! VPL set: per pixel a cut of at most N nodes of a light tree
//! ([`vpl_lighttree::LightTree`]) and one VPL sampled from each.
//!
//! For a receiver x, the cut starts at the root and the node of largest
//! importance is split into its children until the cut holds N nodes (or
//! only lights). From each cut node C one VPL y is drawn by walking down,
//! each child taken with probability proportional to its importance at x,
//! and its term is divided by the probability p_y of that walk:
//!
//! ```text
//! L(x) = ρ/π Σ_{C ∈ cut} Φ_y G(x, y) V(x, y) / p_y ,   y ~ p within C
//! ```
//!
//! so each cut node's term is an unbiased estimate of the sum over its
//! lights, and L(x) one of the exhaustive sum Σ_y Φ_y G V (eq. 2 of the
//! SMC paper), whatever the cut, as long as every light that can reach x
//! has p_y > 0. The importance is pbrt-v4's bound of a node's light at a
//! surface point (`LightBounds::Importance`, the cosine emitter's θ_e =
//! π/2): its power over the squared distance to its box's centre (no less
//! than the box's half diagonal squared), times bounds of the cosines at
//! the light and at x from the box and the normals' cone. It is zero only
//! where no light of the node can reach x, so no light that can is ever
//! left out. The geometry term is clamped as the other shaders clamp it
//! when a clamp is set (then the estimate is of the clamped sum).

use crate::gather::clamped_g;
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use vpl_core::glam::Vec3;
use vpl_core::image::luminance;
use vpl_core::rng::{Purpose, stream};
use vpl_core::{GBuffer, GeometryClamp, Image, IndirectShader, VplSet, VplVisibility};
use vpl_lighttree::{Bounds, Child, Emitter, LightTree};

/// Stochastic lightcuts: at most `cut` VPLs a pixel, each sampled by
/// importance from its node of the cut, unbiased against
/// [`crate::ExhaustiveShader`] on the same set and visibility.
#[derive(Clone, Debug)]
pub struct LightcutShader {
    /// Geometry-term clamp (`None`: off, the estimate of the unclamped sum).
    pub clamp: Option<GeometryClamp>,
    /// Cut size N: VPLs sampled at each pixel.
    pub cut: usize,
    /// Seed of the samples; each shade draws anew (its frame count).
    pub seed: u64,
    frame: u64,
}

impl LightcutShader {
    /// A shader sampling `cut` VPLs a pixel (at least 1), with `clamp` and `seed`.
    pub fn new(cut: usize, clamp: Option<GeometryClamp>, seed: u64) -> LightcutShader {
        LightcutShader { clamp, cut: cut.max(1), seed, frame: 0 }
    }

    /// The frame number the next shade draws its streams with, and counts
    /// it as drawn: what a twin on another device (vpl-gpu's) calls for
    /// each shade it runs itself, so that its streams stay this shader's.
    pub fn take_frame(&mut self) -> u64 {
        let frame = self.frame;
        self.frame += 1;
        frame
    }

    /// The light tree a shade of `vpls` cuts, and the tree's view of each
    /// slot (position, normal, the luminance of the flux as power); `None`
    /// when no tree can be built (more slots than it addresses).
    pub fn tree(vpls: &VplSet) -> Option<(LightTree, Vec<Option<Emitter>>)> {
        let slots: Vec<Option<Emitter>> =
            vpls.slots().iter().map(|s| s.map(|v| Emitter { p: v.y, n: v.n, power: luminance(v.flux) })).collect();
        LightTree::build(&slots).ok().map(|t| (t, slots))
    }
}

impl IndirectShader for LightcutShader {
    fn set_clamp(&mut self, clamp: Option<GeometryClamp>) {
        self.clamp = clamp;
    }

    fn name(&self) -> &'static str {
        "lightcuts"
    }

    fn shade(&mut self, gbuf: &GBuffer, vpls: &VplSet, vis: &dyn VplVisibility) -> Image {
        let frame = self.take_frame();
        let mut img = Image::new(gbuf.width, gbuf.height);
        // More slots than a tree addresses (2³¹) cannot come from a VplSet
        // that fits in memory; such a set shades to black rather than panic.
        let Some((tree, slots)) = Self::tree(vpls) else { return img };
        if tree.root().is_none() {
            return img;
        }
        let g_max = self.clamp.map_or(f32::INFINITY, |c| c.g_max);
        let cut = self.cut.max(1);
        img.data.par_iter_mut().enumerate().for_each(|(pixel, out)| {
            let s = &gbuf.samples[pixel];
            // The receivers of exhaustive shading: points that reflect, with
            // their shading normals.
            if !s.reflects() {
                return;
            }
            let (x, n) = (s.p, s.n);
            let importance = |c: Child| node_importance(&tree.bounds(c, &slots), x, n);
            let mut rng = stream(self.seed, frame, Purpose::LIGHTCUT, pixel as u64);
            let mut sum = Vec3::ZERO;
            for (node, _) in tree.cut(cut, importance) {
                // One light of the node, walked down by importance.
                let Some((slot, p)) = tree.sample_below(node, importance, || rng.next_f32()) else { continue };
                let Some(v) = vpls.get(slot as usize) else { continue };
                let g = clamped_g(v, x, n, g_max);
                if g <= 0.0 {
                    continue;
                }
                let visible = vis.visible(slot as usize, x, n);
                if visible > 0.0 {
                    sum += v.flux * (g * visible / p);
                }
            }
            *out = s.albedo * FRAC_1_PI * sum;
        });
        img
    }
}

/// cos(max(0, θ_a − θ_b)) from the sines and cosines of both angles.
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 1.0 } else { cos_a * cos_b + sin_a * sin_b }
}

/// sin(max(0, θ_a − θ_b)).
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 0.0 } else { sin_a * cos_b - cos_a * sin_b }
}

fn sin_of(cos: f32) -> f32 {
    (1.0 - cos * cos).max(0.0).sqrt()
}

/// Slack under which a cosine bound counts as "cannot reach" (rounding of
/// the bounds must never exclude a light that reaches x).
const SLACK: f32 = 1e-4;

/// A node's importance at the receiver `x` with normal `n`: pbrt-v4's
/// `LightBounds::Importance` for cosine emitters, one-sided at the receiver.
fn node_importance(b: &Bounds, x: Vec3, n: Vec3) -> f32 {
    if b.power.is_nan() || b.power <= 0.0 || b.cone.is_empty() {
        return 0.0;
    }
    let centre = (b.lo + b.hi) * 0.5;
    let r2 = (b.hi - b.lo).length_squared() * 0.25;
    let to = centre - x;
    let dist2 = to.length_squared();
    // The cone of directions from x that the box's bounding sphere subtends.
    let cos_b = if dist2 <= r2 { -1.0 } else { (1.0 - r2 / dist2).max(0.0).sqrt() };
    let sin_b = sin_of(cos_b);
    let d2 = dist2.max(r2).max(1e-12);
    let dir = if dist2 > 0.0 { to / dist2.sqrt() } else { Vec3::ZERO };
    // At the light: the angle between the normals' cone and the direction to x.
    let cos_w = b.cone.axis.dot(-dir).clamp(-1.0, 1.0);
    let cos_o = b.cone.cos_theta.clamp(-1.0, 1.0);
    let cos_x = cos_sub_clamped(sin_of(cos_w), cos_w, sin_of(cos_o), cos_o);
    let sin_x = sin_sub_clamped(sin_of(cos_w), cos_w, sin_of(cos_o), cos_o);
    let cos_light = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if cos_light <= -SLACK {
        return 0.0;
    }
    // At the receiver: the angle between its normal and the direction to the box.
    let cos_i = n.dot(dir).clamp(-1.0, 1.0);
    let cos_receiver = cos_sub_clamped(sin_of(cos_i), cos_i, sin_b, cos_b);
    if cos_receiver <= -SLACK {
        return 0.0;
    }
    b.power * cos_light.max(SLACK) * cos_receiver.max(SLACK) / d2
}
