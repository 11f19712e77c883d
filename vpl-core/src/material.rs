//! Materials: diffuse albedo and emission now, κ-layered parameters for the
//! progressive renderer (Dammertz et al. 2010, §4).

use glam::Vec3;

/// A surface material.
///
/// The VPL methods and the path tracer read `albedo` (Lambertian reflectance
/// ρ) and `emission` (radiance Le emitted along the face normal, one-sided).
/// `layered` carries the κ-layered model ([`crate::bsdf`]) that the path
/// tracer and the progressive renderer follow; the VPL samplers and shaders
/// of the real-time pipeline read the diffuse part (`albedo`) only.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name (from the MTL file or the built-in scene).
    pub name: String,
    /// Diffuse albedo ρ, linear RGB in [0, 1].
    pub albedo: Vec3,
    /// Emitted radiance Le (W / m² / sr), linear RGB.
    pub emission: Vec3,
    /// Glossy / specular / transmissive layer parameters, if any.
    pub layered: Option<Layered>,
}

/// Parameters of the κ-layered Blinn–Phong model (Dammertz et al. 2010, §4):
/// κ = 0 is Lambertian, κ = 1 a mirror, the Phong exponent is 1024κ + 1, and
/// a layer is treated as diffuse when κ < 0.2.
#[derive(Clone, Debug, PartialEq)]
pub struct Layered {
    /// Glossiness κ ∈ [0, 1].
    pub kappa: f32,
    /// Specular reflectance of the layer (linear RGB).
    pub specular: Vec3,
    /// Fraction of light transmitted (0 opaque, 1 clear glass).
    pub transmission: f32,
    /// Index of refraction at the reference wavelength (589 nm).
    pub ior: f32,
    /// Abbe number for dispersion (0 = no dispersion).
    pub abbe: f32,
}

impl Layered {
    /// Phong exponent 1024κ + 1 (Dammertz et al. 2010, §4).
    pub fn exponent(&self) -> f32 {
        1024.0 * self.kappa + 1.0
    }

    /// Whether the layer counts as diffuse (κ < 0.2).
    pub fn is_diffuse(&self) -> bool {
        self.kappa < 0.2
    }

    /// Whether the material disperses light (a transmissive layer with an
    /// Abbe number): a path that meets it draws a wavelength (§6).
    pub fn is_dispersive(&self) -> bool {
        self.abbe > 0.0 && self.transmission > 0.0
    }

    /// Index of refraction at wavelength `lambda` (nm), or at the reference
    /// wavelength for an RGB path (`None`).
    pub fn ior_at(&self, lambda: Option<f32>) -> f32 {
        match lambda {
            Some(l) => crate::spectral::cauchy_ior(self.ior, self.abbe, l),
            None => self.ior,
        }
    }
}

impl Material {
    /// A Lambertian material.
    pub fn diffuse(name: impl Into<String>, albedo: Vec3) -> Self {
        Self { name: name.into(), albedo, emission: Vec3::ZERO, layered: None }
    }

    /// A Lambertian material that also emits `emission`.
    pub fn emissive(name: impl Into<String>, albedo: Vec3, emission: Vec3) -> Self {
        Self { name: name.into(), albedo, emission, layered: None }
    }

    /// The material used where a file names none: grey 0.5.
    pub fn default_material() -> Self {
        Self::diffuse("default", Vec3::splat(0.5))
    }

    /// True when the material emits light.
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

/// Which materials a render draws: the scene's own, or their diffuse part.
///
/// The VPL pipeline reads a material's albedo only: a layered material
/// (glass, a mirror, a glossy coat) is drawn there by its Lambertian base.
/// A comparison between methods is fair when every method draws the same
/// surfaces, so the path tracer, the reference of every comparison, can
/// draw them the same way ([`MaterialPolicy::Diffuse`], `--materials
/// diffuse`), and Table 1 and the figures compute their truth so.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MaterialPolicy {
    /// Each material as the scene gives it (the path tracer and the
    /// progressive renderer follow the κ-layered model).
    #[default]
    AsIs,
    /// Each material by its albedo alone (its layers dropped), as the VPL
    /// pipeline draws it.
    Diffuse,
}
