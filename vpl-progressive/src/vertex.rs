//! One scattering vertex: the surface side, the wavelength and the layer a
//! path uses there, the same for eye paths, VPL paths and photons.

use vpl_core::bsdf::{choose_layer, Layer};
use vpl_core::glam::Vec3;
use vpl_core::spectral::sample_wavelength;
use vpl_core::{RngStream, Scene, SurfacePoint};

/// How a path scatters at a surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scatter {
    /// The point; opaque surfaces turned toward the known direction, transmissive ones as built.
    pub at: SurfacePoint,
    /// The chosen layer (§4: one layer per sample).
    pub layer: Layer,
    /// Index of refraction at the path's wavelength.
    pub eta: f32,
}

/// Chooses how a path that arrives at `sp` from direction `w` (away from the
/// surface) scatters: draws a wavelength first if the surface disperses and
/// the path has none yet (§6; `beta` takes the wavelength's weight), then a
/// layer. `None` where the path ends: a one-sided surface seen from behind,
/// or a black layer.
#[inline]
pub fn scatter(scene: &Scene, sp: SurfacePoint, w: Vec3, spectral: bool, lambda: &mut Option<f32>, beta: &mut Vec3, rng: &mut RngStream) -> Option<Scatter> {
    let m = scene.material(&sp);
    let layered = m.layered.as_ref();
    let transmissive = layered.is_some_and(|l| l.transmission > 0.0);
    if w.dot(sp.ng) <= 0.0 && !scene.two_sided && !transmissive {
        return None;
    }
    if spectral && lambda.is_none() && layered.is_some_and(|l| l.is_dispersive()) {
        let s = sample_wavelength(rng.next_f32());
        *lambda = Some(s.lambda);
        *beta *= s.weight;
    }
    let eta = layered.map_or(1.5, |l| l.ior_at(if spectral { *lambda } else { None }));
    let at = if transmissive { sp } else { sp.facing(w) };
    let layer = choose_layer(m, &at, w, eta, rng.next_f32())?;
    Some(Scatter { at, layer, eta })
}

/// Russian roulette on a throughput `t` (relative to the path's start):
/// survival probability min(max channel, 0.95). Returns the factor to
/// divide by, or `None` when the path ends.
#[inline]
pub fn roulette(t: Vec3, rng: &mut RngStream) -> Option<f32> {
    let q = t.max_element().min(0.95);
    if !(q > 0.0) || rng.next_f32() >= q {
        return None;
    }
    Some(q)
}
