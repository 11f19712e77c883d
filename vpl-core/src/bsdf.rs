//! The κ-layered scattering model of the progressive renderer (Dammertz et
//! al. 2010, §4), shared by it and by the reference path tracer.
//!
//! A [`Material`] with [`Layered`] parameters has up to three layers:
//!
//! | layer | lobe | tint | chosen with weight |
//! | --- | --- | --- | --- |
//! | [`LayerKind::Reflection`] | Blinn–Phong, exponent 1024κ + 1 | `specular` | F |
//! | [`LayerKind::Transmission`] | the same lobe control around Snell's direction | `specular` | (1 − F)·T |
//! | [`LayerKind::Base`] | Lambertian | `albedo` | (1 − F)·(1 − T) |
//!
//! F is Schlick's approximation of the Fresnel term (Schlick 1994) for the
//! material's index of refraction, taken at the cosine on the outer side of
//! the interface (so a ray and its refraction agree on F), and 1 under total
//! internal reflection; T is `transmission`. A material without base (black
//! albedo, T = 0) is a metal: its reflection layer takes every sample.
//!
//! κ = 0 is Lambertian (reflection, or two-sided diffuse transmission for
//! curtains), κ = 1 is a perfect mirror or perfect refraction, and a layer
//! with κ < 0.2 counts as diffuse ([`Layer::is_diffuse`]): the progressive
//! renderer lights it with VPLs and caustic histograms, and extends eye paths
//! through the others (specular gathering).
//!
//! Each sample evaluates one layer, chosen at random with the weights above
//! (§4: "each sample evaluates only one material layer"). As the weights are
//! the selection probabilities, a layer's estimate carries only its tint.
//! The weights are read from the direction a path arrives from, so the model
//! is not reciprocal where the weights change with angle; §4 notes that a
//! partitioned path space does not need reciprocity. The glossy reflection
//! lobe itself is symmetric (Ashikhmin–Shirley's max(cos θ_i, cos θ_o)
//! normalisation); a glossy transmission lobe is centred on the refraction of
//! whichever direction is known, so light paths and eye paths through rough
//! glass each follow their own lobe.
//!
//! Directions point away from the surface. `wo` is the eye side and `wi` the
//! light side: radiance leaving along `wo` is ∫ f(wo, wi) L(wi) |cos θ_i| dwi.
//!
//! ```
//! use vpl_core::bsdf::{choose_layer, LayerKind};
//! use vpl_core::{glam::Vec3, Layered, Material, SurfacePoint};
//!
//! let mut glass = Material::diffuse("glass", Vec3::ZERO);
//! glass.layered = Some(Layered { kappa: 1.0, specular: Vec3::ONE, transmission: 1.0, ior: 1.5, abbe: 0.0 });
//! let sp = SurfacePoint { p: Vec3::ZERO, ng: Vec3::Y, n: Vec3::Y, triangle: 0, material: 0 };
//! // Seen head-on, Schlick's F is 0.04: most samples refract.
//! let layer = choose_layer(&glass, &sp, Vec3::Y, 1.5, 0.5).unwrap();
//! assert_eq!(layer.kind, LayerKind::Transmission);
//! let s = layer.sample(&sp, Vec3::Y, 1.5, (0.3, 0.7)).unwrap();
//! assert!(s.delta && (s.w + Vec3::Y).length() < 1e-5);
//! ```

use crate::material::{Layered, Material};
use crate::ray::LocalFrame;
use crate::rng::RngStream;
use crate::sampling::cosine_hemisphere;
use crate::scene::Scene;
use crate::spectral::sample_wavelength;
use crate::surface::SurfacePoint;
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

/// κ at or above which a layer is a perfect mirror or refraction.
pub const KAPPA_DELTA: f32 = 1.0;

/// What a layer does with light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerKind {
    /// Reflection about the (shading) normal.
    Reflection,
    /// Transmission through the surface, refracted by Snell's law.
    Transmission,
    /// The Lambertian base (albedo ρ).
    Base,
}

/// One layer of a material, as chosen for one sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layer {
    /// Reflection, transmission or base.
    pub kind: LayerKind,
    /// Glossiness κ ∈ [0, 1].
    pub kappa: f32,
    /// Colour the layer multiplies by (its reflectance).
    pub tint: Vec3,
}

/// A direction drawn from a layer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayerSample {
    /// The sampled direction (away from the surface).
    pub w: Vec3,
    /// f · |cos θ| / pdf, the throughput factor of the sample.
    pub weight: Vec3,
    /// Solid-angle density of `w` (0 for a delta layer).
    pub pdf: f32,
    /// Whether the layer is a perfect mirror or refraction.
    pub delta: bool,
}

/// Schlick's approximation F0 + (1 − F0)(1 − cos)^5 with F0 = ((η − 1)/(η + 1))².
#[inline]
pub fn schlick(cos: f32, eta: f32) -> f32 {
    let f0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
    let m = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (1.0 - f0) * m
}

/// The Fresnel weight of a dielectric interface with index `eta` (outside 1)
/// for a direction `w` whose cosine with the outward normal is `cos_n`
/// (negative when `w` is inside): Schlick's F at the outer-side cosine, 1
/// under total internal reflection.
#[inline]
pub fn fresnel(cos_n: f32, eta: f32) -> f32 {
    if cos_n >= 0.0 {
        return schlick(cos_n, eta);
    }
    let c = -cos_n;
    let sin2_t = eta * eta * (1.0 - c * c);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    schlick((1.0 - sin2_t).sqrt(), eta)
}

/// Refracts `w` (pointing away from the surface, on the side of `n`) through
/// an interface with relative index `eta` = η(side of w) / η(other side).
/// `None` under total internal reflection.
#[inline]
pub fn refract(w: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = w.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-w * eta + n * (eta * cos_i - cos_t)).normalize())
}

/// Mirror reflection of `w` about `n`.
#[inline]
pub fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    n * (2.0 * w.dot(n)) - w
}

/// Whether a material has the layered model (and so needs [`choose_layer`]).
#[inline]
pub fn is_layered(m: &Material) -> bool {
    m.layered.is_some()
}

/// The layer weights (reflection, transmission, base) of `l` for a direction
/// whose cosine with the outward geometric normal is `cos_n`.
#[inline]
pub fn layer_weights(m: &Material, l: &Layered, cos_n: f32, eta: f32) -> (f32, f32, f32) {
    let metal = l.transmission <= 0.0 && m.albedo.max_element() <= 0.0;
    if metal {
        return (1.0, 0.0, 0.0);
    }
    // An opaque coat is seen from its outer side only; a dielectric from both.
    let f = if l.transmission > 0.0 { fresnel(cos_n, eta) } else { schlick(cos_n.abs(), eta) };
    let t = l.transmission.clamp(0.0, 1.0);
    (f, (1.0 - f) * t, (1.0 - f) * (1.0 - t))
}

/// Chooses the layer of material `m` that one sample at `sp` evaluates,
/// with `u` ∈ [0, 1), for a path arriving from direction `w` (away from the
/// surface). `sp` carries the triangle's own normals (not turned toward `w`),
/// so the inside of a closed dielectric is known. `eta` is the index of
/// refraction to use (the material's, or its value at the path's wavelength).
/// A material without layers always gives its Lambertian base.
/// `None` when the chosen layer is black.
#[inline]
pub fn choose_layer(m: &Material, sp: &SurfacePoint, w: Vec3, eta: f32, u: f32) -> Option<Layer> {
    let Some(l) = &m.layered else {
        return (m.albedo.max_element() > 0.0).then_some(Layer { kind: LayerKind::Base, kappa: 0.0, tint: m.albedo });
    };
    let (wr, wt, _) = layer_weights(m, l, w.dot(sp.n), eta);
    let layer = if u < wr {
        Layer { kind: LayerKind::Reflection, kappa: l.kappa, tint: l.specular }
    } else if u < wr + wt {
        Layer { kind: LayerKind::Transmission, kappa: l.kappa, tint: l.specular }
    } else {
        Layer { kind: LayerKind::Base, kappa: 0.0, tint: m.albedo }
    };
    (layer.tint.max_element() > 0.0).then_some(layer)
}

/// How a path scatters at a surface point: the side, the layer and the index of refraction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scatter {
    /// The point; opaque surfaces turned toward the known direction, transmissive ones as built.
    pub at: SurfacePoint,
    /// The chosen layer (one layer per sample).
    pub layer: Layer,
    /// Index of refraction at the path's wavelength.
    pub eta: f32,
}

/// Chooses how a path that arrives at `sp` (the triangle's own normals)
/// from direction `w` (away from the surface) scatters, for eye paths and
/// light paths alike: with `spectral`, it first draws a wavelength if the
/// surface disperses and the path has none yet (lazy spectral rendering,
/// Dammertz et al. §6; `beta` takes the wavelength's weight), then a layer
/// ([`choose_layer`]). Draws at most two numbers from `rng`, in that order.
/// `None` where the path ends: an opaque surface of a one-sided scene seen
/// from behind, or a black layer.
#[inline]
pub fn scatter(
    scene: &Scene,
    sp: SurfacePoint,
    w: Vec3,
    spectral: bool,
    lambda: &mut Option<f32>,
    beta: &mut Vec3,
    rng: &mut RngStream,
) -> Option<Scatter> {
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
    // Opaque surfaces of a two-sided scene reflect on the side they are seen from.
    let at = if transmissive { sp } else { sp.facing(w) };
    let layer = choose_layer(m, &at, w, eta, rng.next_f32())?;
    Some(Scatter { at, layer, eta })
}

/// Normalised Blinn–Phong density (k + 1)/(2π) cos^k of a direction at
/// cosine `c` from the lobe axis (zero behind it).
#[inline]
fn phong_lobe(c: f32, k: f32) -> f32 {
    if c <= 0.0 { 0.0 } else { (k + 1.0) * 0.5 * FRAC_1_PI * c.powf(k) }
}

/// A direction about `axis` with density [`phong_lobe`].
#[inline]
fn sample_phong(axis: Vec3, k: f32, u: (f32, f32)) -> Vec3 {
    let c = u.0.powf(1.0 / (k + 1.0));
    let s = (1.0 - c * c).max(0.0).sqrt();
    let phi = 2.0 * PI * u.1;
    LocalFrame::from_normal(axis).to_world(Vec3::new(s * phi.cos(), s * phi.sin(), c))
}

impl Layer {
    /// Phong exponent 1024κ + 1 (§4).
    #[inline]
    pub fn exponent(&self) -> f32 {
        1024.0 * self.kappa + 1.0
    }

    /// Whether the layer counts as diffuse (κ < 0.2, §4).
    #[inline]
    pub fn is_diffuse(&self) -> bool {
        self.kappa < 0.2
    }

    /// Whether the layer is a perfect mirror or refraction (κ = 1).
    #[inline]
    pub fn is_delta(&self) -> bool {
        self.kappa >= KAPPA_DELTA
    }

    /// Whether the layer is Lambertian (κ = 0).
    #[inline]
    fn is_lambertian(&self) -> bool {
        self.kind == LayerKind::Base || self.kappa <= 0.0
    }

    /// The shading frame for a known direction `w`: the shading normal
    /// turned to w's side, and the relative index of refraction across the
    /// surface seen from that side.
    #[inline]
    fn side(sp: &SurfacePoint, w: Vec3, eta: f32) -> (Vec3, Vec3, f32) {
        if w.dot(sp.ng) >= 0.0 { (sp.n, sp.ng, 1.0 / eta) } else { (-sp.n, -sp.ng, eta) }
    }

    /// Draws the other direction for a path that knows `w` (the eye side
    /// for an eye path, the light side for a light path); `u` ∈ [0, 1)².
    /// `None` when the sample leaves through the wrong side or meets total
    /// internal reflection.
    #[inline]
    pub fn sample(&self, sp: &SurfacePoint, w: Vec3, eta: f32, u: (f32, f32)) -> Option<LayerSample> {
        let (n, ng, eta_rel) = Self::side(sp, w, eta);
        let transmit = self.kind == LayerKind::Transmission;
        let (out, weight, pdf) = if self.is_lambertian() {
            let local = cosine_hemisphere(u.0, u.1);
            let axis = if transmit { -n } else { n };
            (LocalFrame::from_normal(axis).to_world(local), self.tint, local.z * FRAC_1_PI)
        } else if self.is_delta() {
            let out = if transmit { refract(w, n, eta_rel)? } else { reflect(w, n) };
            (out, self.tint, 0.0)
        } else if transmit {
            let axis = refract(w, n, eta_rel)?;
            let k = self.exponent();
            let out = sample_phong(axis, k, u);
            (out, self.tint, phong_lobe(out.dot(axis), k))
        } else {
            let k = self.exponent();
            let h = sample_phong(n, k, u);
            let out = reflect(w, h);
            let (ci, co) = (out.dot(n), w.dot(n));
            if ci <= 0.0 || co <= 0.0 {
                return None;
            }
            let pdf = phong_lobe(h.dot(n), k) / (4.0 * w.dot(h).abs());
            (out, self.tint * (ci / ci.max(co)), pdf)
        };
        // The geometric normal decides the side (no light leaks through shading normals).
        let through = out.dot(ng) < 0.0;
        if through != transmit || (!transmit && out.dot(n) <= 0.0) {
            return None;
        }
        Some(LayerSample { w: out, weight, pdf, delta: self.is_delta() })
    }

    /// The layer's BSDF value f(wo, wi) (eye side `wo`, light side `wi`),
    /// without the cosine; zero for a delta layer and for directions on the
    /// wrong sides. A glossy transmission lobe is centred on the refraction
    /// of `wo`.
    #[inline]
    pub fn eval(&self, sp: &SurfacePoint, wo: Vec3, wi: Vec3, eta: f32) -> Vec3 {
        self.tint * self.density(sp, wo, wi, eta).1
    }

    /// Density with which [`Layer::sample`] draws `w_other` given `w` (0 for a delta layer).
    #[inline]
    pub fn pdf(&self, sp: &SurfacePoint, w: Vec3, w_other: Vec3, eta: f32) -> f32 {
        self.density(sp, w, w_other, eta).0
    }

    /// (pdf of `b` given `a`, f(a, b) / tint).
    #[inline]
    fn density(&self, sp: &SurfacePoint, a: Vec3, b: Vec3, eta: f32) -> (f32, f32) {
        if self.is_delta() {
            return (0.0, 0.0);
        }
        let (n, ng, eta_rel) = Self::side(sp, a, eta);
        let transmit = self.kind == LayerKind::Transmission;
        let through = b.dot(ng) < 0.0;
        if through != transmit {
            return (0.0, 0.0);
        }
        let cb = b.dot(n);
        let cb_abs = cb.abs();
        if cb_abs <= 0.0 || (!transmit && cb <= 0.0) {
            return (0.0, 0.0);
        }
        if self.is_lambertian() {
            return (cb_abs * FRAC_1_PI, FRAC_1_PI);
        }
        let k = self.exponent();
        if transmit {
            let Some(axis) = refract(a, n, eta_rel) else { return (0.0, 0.0) };
            let p = phong_lobe(b.dot(axis), k);
            return (p, p / cb_abs);
        }
        let ca = a.dot(n);
        if ca <= 0.0 {
            return (0.0, 0.0);
        }
        let h = (a + b).normalize_or_zero();
        if h == Vec3::ZERO {
            return (0.0, 0.0);
        }
        let d = phong_lobe(h.dot(n), k);
        let ah = a.dot(h).abs().max(1e-6);
        (d / (4.0 * ah), d / (4.0 * ah * ca.max(cb)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::{Purpose, stream};

    fn point() -> SurfacePoint {
        SurfacePoint { p: Vec3::ZERO, ng: Vec3::Z, n: Vec3::Z, triangle: 0, material: 0 }
    }

    fn layer(kind: LayerKind, kappa: f32) -> Layer {
        Layer { kind, kappa, tint: Vec3::ONE }
    }

    /// Sampling weights agree with eval·|cos|/pdf, and the density integrates
    /// to the fraction of samples that survive (a furnace check of each lobe).
    #[test]
    fn sample_weight_matches_eval_over_pdf() {
        let sp = point();
        let wo = Vec3::new(0.4, -0.2, 0.8).normalize();
        for (kind, kappa) in [
            (LayerKind::Base, 0.0),
            (LayerKind::Reflection, 0.05),
            (LayerKind::Reflection, 0.15),
            (LayerKind::Reflection, 0.5),
            (LayerKind::Transmission, 0.0),
            (LayerKind::Transmission, 0.3),
        ] {
            let l = layer(kind, kappa);
            let mut rng = stream(1, 0, Purpose::TEST, 0);
            for _ in 0..2000 {
                let u = rng.next_2d();
                let Some(s) = l.sample(&sp, wo, 1.5, u) else { continue };
                let pdf = l.pdf(&sp, wo, s.w, 1.5);
                assert!((pdf - s.pdf).abs() <= 1e-3 * pdf.max(1.0), "{kind:?} κ={kappa}: pdf {pdf} vs {}", s.pdf);
                let f = l.eval(&sp, wo, s.w, 1.5);
                let w = f * s.w.dot(sp.n).abs() / s.pdf;
                assert!(
                    (w - s.weight).abs().max_element() <= 2e-3 * s.weight.max_element().max(1.0),
                    "{kind:?} κ={kappa}: {w} vs {}",
                    s.weight
                );
            }
        }
    }

    /// Albedo of each lobe by Monte Carlo integration of f·|cos| over the
    /// sphere with uniform directions: ≤ 1, and 1 for the Lambertian ones.
    #[test]
    fn lobes_conserve_energy() {
        let sp = point();
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        let n = 200_000;
        for (kind, kappa, exact) in [
            (LayerKind::Base, 0.0, Some(1.0)),
            (LayerKind::Transmission, 0.0, Some(1.0)),
            (LayerKind::Reflection, 0.1, None),
            (LayerKind::Reflection, 0.19, None),
        ] {
            let l = layer(kind, kappa);
            let mut rng = stream(2, 0, Purpose::TEST, 1);
            let mut sum = 0.0f64;
            for _ in 0..n {
                let (u, v) = rng.next_2d();
                let w = crate::sampling::uniform_sphere(u, v);
                sum += (l.eval(&sp, wo, w, 1.5).x * w.z.abs() * 4.0 * PI) as f64;
            }
            let albedo = sum / n as f64;
            match exact {
                Some(a) => assert!((albedo - a).abs() < 0.02, "{kind:?} κ={kappa}: albedo {albedo}"),
                None => assert!(albedo <= 1.02 && albedo > 0.5, "{kind:?} κ={kappa}: albedo {albedo}"),
            }
        }
    }

    #[test]
    fn refraction_obeys_snell_and_fresnel_is_symmetric() {
        let sp = point();
        let w = Vec3::new(0.6, 0.0, 0.8);
        let t = layer(LayerKind::Transmission, 1.0).sample(&sp, w, 1.5, (0.5, 0.5)).unwrap().w;
        let sin_i = 0.6f32;
        let sin_t = (1.0 - t.z * t.z).sqrt();
        assert!((sin_i - 1.5 * sin_t).abs() < 1e-5);
        // Refracting back out returns the original direction, and F agrees on both sides.
        let back = layer(LayerKind::Transmission, 1.0).sample(&sp, t, 1.5, (0.5, 0.5)).unwrap().w;
        assert!((back - w).length() < 1e-5);
        assert!((fresnel(w.z, 1.5) - fresnel(t.z, 1.5)).abs() < 1e-5);
        // Total internal reflection beyond the critical angle.
        let grazing_inside = Vec3::new(0.9, 0.0, -(1.0f32 - 0.81).sqrt());
        assert_eq!(fresnel(grazing_inside.z, 1.5), 1.0);
        assert!(layer(LayerKind::Transmission, 1.0).sample(&sp, grazing_inside, 1.5, (0.5, 0.5)).is_none());
    }

    #[test]
    fn layer_choice_follows_the_weights() {
        let sp = point();
        let mut m = Material::diffuse("coat", Vec3::splat(0.5));
        m.layered = Some(Layered { kappa: 0.5, specular: Vec3::ONE, transmission: 0.0, ior: 1.5, abbe: 0.0 });
        let wo = Vec3::Z;
        let n = 100_000;
        let mut rng = stream(3, 0, Purpose::TEST, 2);
        let refl = (0..n).filter(|_| choose_layer(&m, &sp, wo, 1.5, rng.next_f32()).unwrap().kind == LayerKind::Reflection).count();
        let p = refl as f64 / n as f64;
        // F(1) = 0.04; binomial s.e. √(0.04·0.96/n) = 6.2e-4: 5 s.e.
        assert!((p - 0.04).abs() < 5.0 * 6.2e-4, "{p}");
        // A metal reflects always.
        m.albedo = Vec3::ZERO;
        assert_eq!(choose_layer(&m, &sp, wo, 1.5, 0.99).unwrap().kind, LayerKind::Reflection);
    }
}
