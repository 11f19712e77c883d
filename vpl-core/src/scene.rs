//! The scene: one triangle mesh with materials and lights, its BVH, and light selection.

use crate::bvh::Bvh;
use crate::distribution::Distribution1D;
use crate::error::{CoreError, Result};
use crate::light::{Light, LightSample};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::ray::Ray;
use crate::surface::{Hit, SurfacePoint};
pub use crate::triangle::TriangleData;
use glam::Vec3;
use std::sync::Arc;

/// Geometry that does not change during a sequence: triangles, shading normals, BVH.
#[derive(Debug)]
pub struct Geometry {
    /// Triangles after validation (degenerate ones removed).
    pub triangles: Vec<TriangleData>,
    /// Per-vertex shading normals of smooth triangles, three per entry.
    pub shading_normals: Vec<[Vec3; 3]>,
    /// The BVH over `triangles`.
    pub bvh: Bvh,
    /// Scene bounds (min, max).
    pub bounds: (Vec3, Vec3),
    /// Ray offset used to leave a surface, scaled with the scene's extent.
    pub epsilon: f32,
    /// Triangles dropped for zero area.
    pub degenerate: usize,
}

/// What a change of the light field is detected by: the scene's geometry
/// (by identity), materials and lights. Samplers that cache light-dependent
/// values (radiosities, reflective shadow maps) recompute them when it differs.
#[derive(Clone, Debug, PartialEq)]
pub struct LightingKey {
    geometry: usize,
    materials: Vec<Material>,
    lights: Vec<Light>,
}

impl LightingKey {
    /// The key of `scene` as it is now.
    pub fn of(scene: &Scene) -> LightingKey {
        LightingKey { geometry: Arc::as_ptr(&scene.geometry) as usize, materials: scene.materials.clone(), lights: scene.lights.clone() }
    }
}

/// A renderable scene.
///
/// Geometry is shared (`Arc`) so that a frame of an animation can change the
/// lights ([`Scene::with_lights`]) without rebuilding the BVH.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Scene name (built-in name or file stem).
    pub name: String,
    /// Shared geometry and BVH.
    pub geometry: Arc<Geometry>,
    /// Materials, indexed by `TriangleData::material`.
    pub materials: Vec<Material>,
    /// All lights: area lights (one per emissive triangle) first, then the others.
    pub lights: Vec<Light>,
    /// `tri_light[t]` is the light index of emissive triangle `t`, or `u32::MAX`.
    pub tri_light: Vec<u32>,
    /// Index of the environment light in `lights`, if there is one.
    pub environment: Option<usize>,
    /// Light selection proportional to power.
    pub light_distribution: Distribution1D,
    /// Whether diffuse surfaces reflect on both sides (`false`: back faces are black, as in Mitsuba).
    pub two_sided: bool,
    /// Warnings gathered while building (degenerate triangles, …).
    pub warnings: Vec<String>,
}

/// Statistics printed with a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneStats {
    /// Triangles kept.
    pub triangles: usize,
    /// Triangles dropped for zero area.
    pub degenerate: usize,
    /// Lights of every kind.
    pub lights: usize,
}

impl Scene {
    /// Builds a scene from a mesh, its materials and the non-area lights.
    /// Emissive materials make every triangle that uses them an area light.
    ///
    /// Errors: a non-finite vertex, no triangle of nonzero area, no light,
    /// a material index out of range.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > y)` is meant: a NaN fails the test
    pub fn new(name: impl Into<String>, mesh: &Mesh, materials: Vec<Material>, extra_lights: Vec<Light>, two_sided: bool) -> Result<Scene> {
        let name = name.into();
        for (i, p) in mesh.positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(CoreError::NonFinite { what: name.clone(), index: i, value: format!("{} {} {}", p.x, p.y, p.z) });
            }
            crate::validate::position(*p, &format!("{name}: vertex {i}"))?;
        }
        for m in &materials {
            crate::validate::material(m).map_err(|e| match e {
                CoreError::BadValue { what, reason } => CoreError::BadValue { what: format!("{name}: {what}"), reason },
                e => e,
            })?;
        }
        let mut warnings = Vec::new();
        let mut triangles = Vec::with_capacity(mesh.triangles.len());
        let mut shading_normals = Vec::new();
        let mut degenerate = 0usize;
        // The mesh's own vertex coordinates, for a watertight BVH.
        let mut vertices = Vec::with_capacity(mesh.triangles.len());
        for (ti, t) in mesh.triangles.iter().enumerate() {
            let get = |i: u32| -> Result<Vec3> {
                mesh.positions
                    .get(i as usize)
                    .copied()
                    .ok_or_else(|| CoreError::Invalid(format!("triangle {ti} of {name} refers to missing vertex {i}")))
            };
            let (p0, p1, p2) = (get(t.v[0])?, get(t.v[1])?, get(t.v[2])?);
            if t.material as usize >= materials.len() {
                return Err(CoreError::Invalid(format!("triangle {ti} of {name} uses missing material {}", t.material)));
            }
            let e1 = p1 - p0;
            let e2 = p2 - p0;
            let c = e1.cross(e2);
            let area = 0.5 * c.length();
            if !(area > 0.0) || !c.normalize_or_zero().is_normalized() {
                degenerate += 1;
                continue;
            }
            let ng = c.normalize();
            let mut normals = u32::MAX;
            if let Some(n) = t.n {
                let fetch = |i: u32| mesh.normals.get(i as usize).copied().filter(|v| v.is_finite() && v.length_squared() > 0.0);
                if let (Some(a), Some(b), Some(c)) = (fetch(n[0]), fetch(n[1]), fetch(n[2])) {
                    normals = shading_normals.len() as u32;
                    shading_normals.push([a.normalize(), b.normalize(), c.normalize()]);
                }
            }
            triangles.push(TriangleData { p0, e1, e2, ng, area, material: t.material, normals });
            vertices.push([p0, p1, p2]);
        }
        if degenerate > 0 {
            warnings.push(format!("{name}: skipped {degenerate} zero-area triangle(s)"));
        }
        if triangles.is_empty() {
            return Err(CoreError::EmptyScene(name));
        }
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in &triangles {
            for p in t.corners() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        let extent = lo.abs().max(hi.abs()).max_element().max(1.0);
        let epsilon = 1e-4 * extent;
        let bvh = Bvh::build(&vertices)?;
        let geometry = Arc::new(Geometry { triangles, shading_normals, bvh, bounds: (lo, hi), epsilon, degenerate });
        let mut scene = Scene {
            name,
            geometry,
            materials,
            lights: Vec::new(),
            tri_light: Vec::new(),
            environment: None,
            light_distribution: Distribution1D::default(),
            two_sided,
            warnings,
        };
        scene.set_lights(extra_lights)?;
        Ok(scene)
    }

    /// A copy of this scene with other non-area lights (an animated frame); shares the geometry.
    pub fn with_lights(&self, extra_lights: Vec<Light>) -> Result<Scene> {
        let mut s = self.clone();
        s.set_lights(extra_lights)?;
        Ok(s)
    }

    fn set_lights(&mut self, extra_lights: Vec<Light>) -> Result<()> {
        let g = &self.geometry;
        let mut lights = Vec::new();
        let mut tri_light = vec![u32::MAX; g.triangles.len()];
        for (i, t) in g.triangles.iter().enumerate() {
            let m = &self.materials[t.material as usize];
            if m.is_emissive() {
                tri_light[i] = lights.len() as u32;
                lights.push(Light::Area { triangle: i as u32, radiance: m.emission });
            }
        }
        for (i, l) in extra_lights.iter().enumerate() {
            crate::validate::light(l, i)?;
        }
        let skies: Vec<usize> = extra_lights
            .iter()
            .enumerate()
            .filter(|(_, l)| matches!(l, Light::Environment { .. }))
            .map(|(i, _)| lights.len() + i)
            .collect();
        if skies.len() > 1 {
            return Err(CoreError::Invalid(format!("{}: a scene has at most one environment light", self.name)));
        }
        let environment = skies.first().copied();
        lights.extend(extra_lights);
        let radius = self.radius();
        let powers: Vec<f32> = lights
            .iter()
            .map(|l| match l {
                Light::Area { triangle, .. } => l.power(g.triangles[*triangle as usize].area, radius),
                _ => l.power(0.0, radius),
            })
            .collect();
        if let Some(i) = powers.iter().position(|p| !p.is_finite()) {
            return Err(CoreError::BadValue {
                what: format!("{}: light {i}", self.name),
                reason: "its power (emission × area) overflows single precision; lower its emission or the scene's scale".into(),
            });
        }
        let total: f64 = powers.iter().map(|&p| p as f64).sum();
        if total > f32::MAX as f64 {
            return Err(CoreError::BadValue {
                what: format!("{}: lights", self.name),
                reason: format!("their total power {total:e} overflows single precision"),
            });
        }
        let dist = Distribution1D::new(&powers).ok_or_else(|| CoreError::NoLights(self.name.clone()))?;
        self.lights = lights;
        self.tri_light = tri_light;
        self.environment = environment;
        self.light_distribution = dist;
        Ok(())
    }

    /// The lights that are not emissive triangles (what [`Scene::with_lights`] replaces).
    pub fn extra_lights(&self) -> Vec<Light> {
        self.lights.iter().filter(|l| l.is_extra()).cloned().collect()
    }

    /// Names of the materials with κ-layered parameters (those the VPL
    /// pipeline draws by their albedo alone).
    pub fn layered_materials(&self) -> Vec<&str> {
        self.materials.iter().filter(|m| m.layered.is_some()).map(|m| m.name.as_str()).collect()
    }

    /// This scene drawn by `policy`: itself, or a copy whose materials keep
    /// only their albedo and emission ([`crate::material::MaterialPolicy::Diffuse`]; the
    /// geometry is shared).
    pub fn with_material_policy(&self, policy: crate::material::MaterialPolicy) -> Scene {
        let mut s = self.clone();
        if policy == crate::material::MaterialPolicy::Diffuse {
            for m in s.materials.iter_mut() {
                m.layered = None;
            }
        }
        s
    }

    /// The one-line note a renderer that draws `policy` should give about
    /// this scene (`None` when no material changes): which layered materials
    /// are drawn by their diffuse part.
    pub fn material_policy_note(&self, policy: crate::material::MaterialPolicy, who: &str) -> Option<String> {
        let names = self.layered_materials();
        if policy == crate::material::MaterialPolicy::AsIs || names.is_empty() {
            return None;
        }
        let shown: Vec<&str> = names.iter().take(5).copied().collect();
        let more = if names.len() > shown.len() { format!(" and {} more", names.len() - shown.len()) } else { String::new() };
        Some(format!("{who} draws {} layered material(s) ({}{more}) by their diffuse part only", names.len(), shown.join(", ")))
    }

    /// Radius of the bounding sphere of the scene's bounds.
    pub fn radius(&self) -> f32 {
        let (lo, hi) = self.geometry.bounds;
        0.5 * (hi - lo).length()
    }

    /// Total area of the scene's triangles (m²).
    pub fn surface_area(&self) -> f32 {
        self.geometry.triangles.iter().map(|t| t.area as f64).sum::<f64>() as f32
    }

    /// Counts for reports.
    pub fn stats(&self) -> SceneStats {
        SceneStats { triangles: self.geometry.triangles.len(), degenerate: self.geometry.degenerate, lights: self.lights.len() }
    }

    /// The material of a surface point.
    #[inline]
    pub fn material(&self, p: &SurfacePoint) -> &Material {
        &self.materials[p.material as usize]
    }

    /// The surface point at barycentrics (b1, b2) of triangle `tri`.
    #[inline]
    pub fn surface_point(&self, tri: u32, b1: f32, b2: f32) -> SurfacePoint {
        let t = &self.geometry.triangles[tri as usize];
        let p = t.p0 + t.e1 * b1 + t.e2 * b2;
        let n = if t.normals == u32::MAX {
            t.ng
        } else {
            let ns = &self.geometry.shading_normals[t.normals as usize];
            let n = (ns[0] * (1.0 - b1 - b2) + ns[1] * b1 + ns[2] * b2).normalize_or_zero();
            if n == Vec3::ZERO {
                t.ng
            } else if n.dot(t.ng) < 0.0 {
                -n
            } else {
                n
            }
        };
        SurfacePoint { p, ng: t.ng, n, triangle: tri, material: t.material }
    }

    /// Closest intersection of `ray` with the scene.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let (tri, t) = self.geometry.bvh.closest(ray)?;
        Some(self.hit_at(ray, tri, t))
    }

    /// The closest hit (triangle, t) of each ray from `o` along `dirs[i]`,
    /// into `out[i]`: [`Bvh::closest_fan`](crate::bvh::Bvh::closest_fan),
    /// which traces rays that share their origin in bundles (neighbouring
    /// directions should be neighbours in `dirs`).
    ///
    /// # Panics
    /// If `out` is shorter than `dirs`.
    #[inline]
    pub fn closest_fan(&self, o: Vec3, dirs: &[Vec3], out: &mut [Option<(u32, f32)>]) {
        self.geometry.bvh.closest_fan(o, dirs, f32::INFINITY, out)
    }

    /// The hit of `ray` with triangle `tri`, found elsewhere (a GPU) without
    /// its t: t by the CPU BVH's triangle test, so the hit is the one
    /// [`Scene::intersect`] reports whenever both found the same triangle;
    /// where that test misses (the ray grazes an edge, by rounding), where
    /// the ray meets the triangle's plane.
    #[inline]
    pub fn hit_on(&self, ray: &Ray, tri: u32) -> Hit {
        let t = self.geometry.bvh.triangle_t(ray, tri).unwrap_or_else(|| {
            let td = &self.geometry.triangles[tri as usize];
            let t = (td.p0 - ray.o).dot(td.ng) / ray.d.dot(td.ng);
            if t.is_finite() && t >= 0.0 { t.min(ray.t_max) } else { 0.0 }
        });
        self.hit_at(ray, tri, t)
    }

    /// The hit of `ray` with triangle `tri` at parameter `t`, as
    /// [`Scene::intersect`] reports it (for ray casters that find (tri, t)
    /// elsewhere, such as a GPU).
    #[inline]
    pub fn hit_at(&self, ray: &Ray, tri: u32, t: f32) -> Hit {
        let td = &self.geometry.triangles[tri as usize];
        let p = ray.at(t);
        if td.normals == u32::MAX {
            return Hit { t, point: SurfacePoint { p, ng: td.ng, n: td.ng, triangle: tri, material: td.material } };
        }
        let (b1, b2) = barycentrics(td, p);
        let mut point = self.surface_point(tri, b1, b2);
        point.p = p;
        Hit { t, point }
    }

    /// The surface `ray` meets, if it reflects light back along the ray: its
    /// normals turned toward the ray's origin and its albedo ρ. `None` on a
    /// miss, on a one-sided surface seen from behind, and on a black surface.
    #[inline]
    pub fn reflecting_hit(&self, ray: &Ray) -> Option<(SurfacePoint, Vec3)> {
        self.reflecting(ray, self.intersect(ray)?)
    }

    /// [`Scene::reflecting_hit`] for a hit of `ray` found elsewhere.
    #[inline]
    pub fn reflecting(&self, ray: &Ray, hit: Hit) -> Option<(SurfacePoint, Vec3)> {
        let wo = -ray.d;
        if wo.dot(hit.point.ng) <= 0.0 && !self.two_sided {
            return None;
        }
        let sp = hit.point.facing(wo);
        let rho = self.material(&sp).albedo;
        (rho.max_element() > 0.0).then_some((sp, rho))
    }

    /// Whether anything blocks `ray` before `ray.t_max` (early-exit shadow test).
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.geometry.bvh.occluded(ray)
    }

    /// Whether the segment from `a` to `b` is unblocked; both ends are
    /// surface points already offset by the caller, or free points.
    #[inline]
    pub fn visible(&self, a: Vec3, b: Vec3) -> bool {
        self.shadow_ray(a, b).is_none_or(|r| !self.occluded(&r))
    }

    /// The shadow ray [`Scene::visible`] casts from `a` toward `b` (stopping
    /// short of it), or `None` when the two coincide (visible).
    #[inline]
    pub fn shadow_ray(&self, a: Vec3, b: Vec3) -> Option<Ray> {
        let d = b - a;
        let len = d.length();
        if len <= 0.0 {
            return None;
        }
        Some(Ray::segment(a, d / len, len * (1.0 - 1e-4) - self.geometry.epsilon))
    }

    /// Whether light sample `ls`, drawn for receiver `x` with geometric
    /// normal `ng` (on the side the light is), is unblocked. The shadow ray
    /// starts off the surface at `x + ng·ε` and aims at the sampled point
    /// itself, stopping ε short of it: aiming along `ls.wi` from the offset
    /// origin would meet the light's own surface before the sample when the
    /// light is seen obliquely, and shadow the light by itself.
    #[inline]
    pub fn light_unoccluded(&self, x: Vec3, ng: Vec3, ls: &LightSample) -> bool {
        let eps = self.geometry.epsilon;
        let o = x + ng * eps;
        if ls.dist.is_finite() { self.visible(o, x + ls.wi * ls.dist) } else { !self.occluded(&Ray::new(o, ls.wi)) }
    }

    /// Offset that leaves a surface without self-intersection.
    #[inline]
    pub fn epsilon(&self) -> f32 {
        self.geometry.epsilon
    }

    /// Chooses a light with probability proportional to power and samples it
    /// from receiver `x`. Returns the sample and the selection probability.
    /// `None` when the sample carries no light toward `x`.
    #[inline]
    pub fn sample_light(&self, x: Vec3, u_select: f32, u: (f32, f32)) -> Option<(LightSample, f32)> {
        let (i, p_select) = self.light_distribution.sample(u_select);
        let s = self.sample_light_index(i, x, u)?;
        Some((s, p_select))
    }

    /// Samples light `i` from receiver `x`.
    #[inline]
    pub fn sample_light_index(&self, i: usize, x: Vec3, u: (f32, f32)) -> Option<LightSample> {
        match &self.lights[i] {
            Light::Area { triangle, radiance } => {
                let t = &self.geometry.triangles[*triangle as usize];
                let y = t.sample_point(u);
                let d = y - x;
                let dist2 = d.length_squared();
                if dist2 <= 0.0 {
                    return None;
                }
                let dist = dist2.sqrt();
                let wi = d / dist;
                let cos_l = -wi.dot(t.ng);
                if cos_l <= 0.0 {
                    return None;
                }
                Some(LightSample { wi, dist, li: *radiance, pdf: dist2 / (cos_l * t.area), delta: false })
            }
            Light::Point { position, intensity } => {
                let d = *position - x;
                let dist2 = d.length_squared();
                if dist2 <= 0.0 {
                    return None;
                }
                let dist = dist2.sqrt();
                Some(LightSample { wi: d / dist, dist, li: *intensity / dist2, pdf: 1.0, delta: true })
            }
            Light::Spot { position, direction, intensity, cos_falloff_start, cos_total } => {
                let d = *position - x;
                let dist2 = d.length_squared();
                if dist2 <= 0.0 {
                    return None;
                }
                let dist = dist2.sqrt();
                let wi = d / dist;
                let f = Light::spot_falloff(-wi.dot(*direction), *cos_falloff_start, *cos_total);
                if f <= 0.0 {
                    return None;
                }
                Some(LightSample { wi, dist, li: *intensity * (f / dist2), pdf: 1.0, delta: true })
            }
            Light::Directional { direction, irradiance } => {
                Some(LightSample { wi: -*direction, dist: f32::INFINITY, li: *irradiance, pdf: 1.0, delta: true })
            }
            Light::Environment { sky } => {
                let (wi, pdf) = sky.sample(u);
                if pdf.is_nan() || pdf <= 0.0 {
                    return None;
                }
                Some(LightSample { wi, dist: f32::INFINITY, li: sky.radiance(wi), pdf, delta: false })
            }
        }
    }

    /// Radiance the environment sends along a ray that leaves the scene in
    /// direction `d` (zero without an environment light).
    #[inline]
    pub fn environment_radiance(&self, d: Vec3) -> Vec3 {
        match self.environment.map(|i| &self.lights[i]) {
            Some(Light::Environment { sky }) => sky.radiance(d),
            _ => Vec3::ZERO,
        }
    }

    /// Solid-angle density with which [`Scene::sample_light`] would pick
    /// direction `d` of the environment (for MIS; zero without one).
    #[inline]
    pub fn environment_pdf(&self, d: Vec3) -> f32 {
        match self.environment.map(|i| (i, &self.lights[i])) {
            Some((i, Light::Environment { sky })) => self.light_distribution.pmf(i) * sky.pdf(d),
            _ => 0.0,
        }
    }

    /// Solid-angle density with which [`Scene::sample_light`] would pick the
    /// point `y` on emissive triangle `tri`, seen from `x` (for MIS).
    #[inline]
    pub fn light_pdf(&self, x: Vec3, y: &SurfacePoint) -> f32 {
        let li = self.tri_light[y.triangle as usize];
        if li == u32::MAX {
            return 0.0;
        }
        let t = &self.geometry.triangles[y.triangle as usize];
        let d = y.p - x;
        let dist2 = d.length_squared();
        let cos_l = -(d / dist2.sqrt()).dot(t.ng);
        if cos_l <= 0.0 {
            return 0.0;
        }
        self.light_distribution.pmf(li as usize) * dist2 / (cos_l * t.area)
    }

    /// Radiance emitted by `y` toward direction `wo` (one-sided, along the geometric normal).
    #[inline]
    pub fn emitted(&self, y: &SurfacePoint, wo: Vec3) -> Vec3 {
        let m = &self.materials[y.material as usize];
        if wo.dot(y.ng) > 0.0 { m.emission } else { Vec3::ZERO }
    }
}

/// Barycentrics (b1, b2) of point `p` in triangle `t` (weights of p1 and p2).
#[inline]
fn barycentrics(t: &TriangleData, p: Vec3) -> (f32, f32) {
    let v2 = p - t.p0;
    let d00 = t.e1.dot(t.e1);
    let d01 = t.e1.dot(t.e2);
    let d11 = t.e2.dot(t.e2);
    let d20 = v2.dot(t.e1);
    let d21 = v2.dot(t.e2);
    let denom = d00 * d11 - d01 * d01;
    let b1 = (d11 * d20 - d01 * d21) / denom;
    let b2 = (d00 * d21 - d01 * d20) / denom;
    // A long thin triangle can cancel the f32 denominator to zero: redo it in f64.
    let (b1, b2) = if b1.is_finite() && b2.is_finite() { (b1, b2) } else { barycentrics_f64(t, p) };
    // Neither is NaN now, so the clamps cannot panic.
    let b1 = b1.clamp(0.0, 1.0);
    (b1, b2.clamp(0.0, 1.0 - b1))
}

/// [`barycentrics`] in f64; the first vertex when even that cancels (a triangle
/// of zero area never reaches here: the scene skips it).
#[cold]
fn barycentrics_f64(t: &TriangleData, p: Vec3) -> (f32, f32) {
    let (e1, e2, v2) = (t.e1.as_dvec3(), t.e2.as_dvec3(), (p - t.p0).as_dvec3());
    let (d00, d01, d11, d20, d21) = (e1.dot(e1), e1.dot(e2), e2.dot(e2), v2.dot(e1), v2.dot(e2));
    let denom = d00 * d11 - d01 * d01;
    let (b1, b2) = ((d11 * d20 - d01 * d21) / denom, (d00 * d21 - d01 * d20) / denom);
    if b1.is_finite() && b2.is_finite() { (b1 as f32, b2 as f32) } else { (0.0, 0.0) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setup::SceneSetup;

    fn quad_scene(lights: Vec<Light>, emission: Vec3) -> Scene {
        let mut mesh = Mesh::default();
        mesh.push_quad(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(-1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, -1.0), 0);
        Scene::new("q", &mesh, vec![Material::emissive("m", Vec3::splat(0.5), emission)], lights, true).unwrap()
    }

    #[test]
    fn lights_are_selected_in_proportion_to_power() {
        let p = |i: f32| Light::Point { position: Vec3::Y, intensity: Vec3::splat(i) };
        let s = quad_scene(vec![p(1.0), p(3.0)], Vec3::ZERO);
        assert!((s.light_distribution.pmf(0) - 0.25).abs() < 1e-6 && (s.light_distribution.pmf(1) - 0.75).abs() < 1e-6);
        // An emissive quad of area 4 and Le = 1 has power 4π, the same as a point light of 1 W/sr.
        let s = quad_scene(vec![p(1.0)], Vec3::ONE);
        assert_eq!(s.lights.len(), 3);
        let area: f32 = (0..2).map(|i| s.light_distribution.pmf(i)).sum();
        assert!((area - 0.5).abs() < 1e-6, "{area}");
    }

    #[test]
    fn emission_is_one_sided_and_light_pdf_matches_sampling() {
        let s = quad_scene(vec![], Vec3::ONE);
        let y = s.surface_point(0, 0.2, 0.2);
        assert_eq!(s.emitted(&y, Vec3::Y), Vec3::ONE);
        assert_eq!(s.emitted(&y, -Vec3::Y), Vec3::ZERO);
        let x = Vec3::new(0.1, 2.0, 0.3);
        let (ls, p_sel) = s.sample_light(x, 0.1, (0.4, 0.3)).unwrap();
        let hit = s.intersect(&Ray::new(x, ls.wi)).unwrap();
        assert!((s.light_pdf(x, &hit.point) - p_sel * ls.pdf).abs() < 1e-4 * ls.pdf);
    }

    #[test]
    fn visibility_through_the_cornell_box() {
        let s = SceneSetup::builtin("cornell").unwrap().scene;
        // Through the tall box (x ∈ [−0.71, 0.05], z ∈ [−0.66, 0.10], y < 0.21): blocked.
        assert!(!s.visible(Vec3::new(-0.9, 0.0, -0.3), Vec3::new(0.3, 0.0, -0.3)));
        // Above it: free.
        assert!(s.visible(Vec3::new(-0.9, 0.5, -0.3), Vec3::new(0.3, 0.5, -0.3)));
    }

    /// The office's ceiling panels seen obliquely from the floor: every light
    /// sample is unblocked (a shadow ray aimed along `wi` from the offset
    /// origin used to stop inside the panel and shadow it by itself, for
    /// 59 % of these samples).
    #[test]
    fn a_light_does_not_shadow_itself() {
        let s = SceneSetup::builtin("office").unwrap().scene;
        let mut blocked = 0;
        for i in 0..2000 {
            let (u, v) = ((i as f32 * 0.618_034) % 1.0, (i as f32 * 0.754_877) % 1.0);
            let x = Vec3::new(-1.4 + 2.8 * u, 0.0, -0.5 - 4.0 * v);
            // The corridor panel over z = −2.5 (two triangles, lights 0 and 1).
            let Some(ls) = s.sample_light_index(i % 2, x, (u, v)) else { continue };
            if !s.light_unoccluded(x, Vec3::Y, &ls) {
                blocked += 1;
            }
        }
        assert_eq!(blocked, 0);
    }
}
