//! The geometry-term clamp shared by VPL shading and the clamped path tracer.
//!
//! A VPL at y lights a point x with the geometry term
//! G(x, y) = max(0, cos θ_x) · max(0, cos θ_y) / |x − y|², which is unbounded
//! as y approaches x. Both the VPL shaders and the path tracer's clamped mode
//! (Hedman et al. 2017, §5.4) replace G by min(G, G_max): the contribution is
//! scaled by [`GeometryClamp::factor`]. One rule, one place.
//!
//! # Choosing G_max
//! A VPL closer to a receiver than 1/√G_max (facing it) is clamped. The
//! default, [`GeometryClamp::for_view`], sets that distance to the spacing
//! √(A_view / I) that I VPLs would have if they covered what the camera sees:
//! the near field that the image cannot resolve with I lights. A_view is
//! [`view_area`]: the solid angle of the view that meets a reflecting
//! surface times the median area per steradian (t² / |cos θ|) of those
//! camera rays. The median, not the sum, because the sum is dominated by
//! the few pixels that see far or grazing surfaces (a city's horizon), which
//! say nothing about the scale of what the image shows.
//!
//! The older rule, [`GeometryClamp::for_scene_area`] (G_max = I / A with A
//! the whole scene's area), is kept for comparison: on open scenes it clamps
//! at the spacing of VPLs spread over geometry the camera never sees.
//! Removed share of the indirect light (I = 2048, the scene's camera at 48
//! pixels wide): the path tracer with and without the clamp on the same
//! paths, 4 seeds × 64 paths per pixel, ± one standard error
//! (`tests/tests/clamp.rs` measures and bounds it):
//!
//! | scene | A (m²) | A_view (m²) | removed, I / A | removed, I / A_view |
//! | --- | ---: | ---: | ---: | ---: |
//! | cornell | 26 | 15 | 0.93 ± 0.03 % | 0.71 ± 0.03 % |
//! | maze | 2172 | 41 | 3.54 ± 0.07 % | 0.33 ± 0.01 % |
//! | office | 2043 | 77 | 3.51 ± 0.07 % | 0.47 ± 0.04 % |
//! | courtyard | 57357 | 239 | 6.26 ± 0.06 % | 0.28 ± 0.00 % |
//! | atrium | 3207 | 366 | 1.83 ± 0.06 % | 0.51 ± 0.03 % |
//! | corner | 312 | 39 | 0.19 ± 0.01 % | 0.07 ± 0.01 % |
//! | glass | 145 | 68 | 1.92 ± 0.11 % | 1.22 ± 0.13 % |
//! | sponza-dabrovic | 7503 | 185 | 4.39 ± 0.03 % | 1.34 ± 0.04 % |
//! | city-munich | 4.1·10⁶ | 1.4·10⁴ | 51.4 ± 0.3 % | 3.82 ± 0.07 % |
//!
//! Whatever the rule, [`GeometryClamp::factor`]'s complement 1 − G_max/G is
//! what bias compensation (Kollig and Keller 2004) adds back.

use crate::{Camera, Scene};

/// Clamp of the geometry term at `g_max` (units 1/m²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeometryClamp {
    /// Largest geometry term passed through.
    pub g_max: f32,
}

impl GeometryClamp {
    /// A clamp at `g_max`.
    pub fn new(g_max: f32) -> Self {
        Self { g_max }
    }

    /// The clamp G_max = I / A for a budget of `vpls` VPLs in a scene of
    /// total surface area `area` (m²).
    ///
    /// 1/√G_max = √(A / I) is the mean spacing of I points spread over all
    /// of the scene's surfaces. It scales with the scene (G has units 1/m²)
    /// and relaxes as I grows, but on an open scene it reads area the camera
    /// never sees: on a city of 4·10⁶ m² it clamps at 44 m and removes more
    /// than half of the indirect light. [`GeometryClamp::for_view`] is the
    /// default; this rule stays for comparison (`--clamp area`).
    pub fn for_scene_area(vpls: usize, area: f32) -> Self {
        Self { g_max: vpls as f32 / area.max(f32::MIN_POSITIVE) }
    }

    /// The toolkit's default clamp for a budget of `vpls` VPLs and the view
    /// of `camera`: G_max = I / A_view with A_view = [`view_area`].
    ///
    /// A VPL facing a receiver from closer than √(A_view / I), the spacing
    /// I VPLs would have over the surfaces the camera shows, is clamped. It
    /// depends on the scene only through what the camera sees, scales with
    /// it and relaxes as I grows. A view that shows no reflecting surface
    /// needs no clamp (G_max = ∞). For I = 2048 on `cornell` (A_view ≈ 15 m²)
    /// G_max ≈ 133 m⁻², a facing distance of 0.087 m.
    pub fn for_view(vpls: usize, scene: &Scene, camera: &Camera) -> Self {
        let a = view_area(scene, camera);
        if a > 0.0 { Self::for_scene_area(vpls, a) } else { Self { g_max: f32::INFINITY } }
    }

    /// The clamped geometry term min(G, G_max).
    #[inline]
    pub fn clamp(&self, g: f32) -> f32 {
        g.min(self.g_max)
    }

    /// The factor min(1, G_max / G) that turns a contribution computed with G
    /// into one computed with min(G, G_max).
    #[inline]
    pub fn factor(&self, g: f32) -> f32 {
        if g > self.g_max { self.g_max / g } else { 1.0 }
    }
}

/// Camera rays [`view_area`] traces across the wider image axis.
pub const VIEW_RAYS: u32 = 64;

/// The area the camera's points cover, A_view = Ω · median(t² / |cos θ|)
/// (m²): Ω the solid angle of the view whose rays meet a reflecting
/// surface, t the distance of the hit and θ the angle between the ray and
/// the surface's normal, the median weighted by each ray's solid angle.
///
/// Ω · t² / |cos θ| is the area a bundle of solid angle Ω covers at that
/// distance and slant; with the median it is the area the view would cover
/// if every ray met surfaces at the typical distance and slant of the
/// image. Rays through a grid of [`VIEW_RAYS`] columns (rows in proportion
/// to the aspect) from the centre of the lens; no randomness, independent of
/// the camera's resolution. Zero when the camera sees no reflecting surface.
pub fn view_area(scene: &Scene, camera: &Camera) -> f32 {
    let (w, h) = (camera.resolution.0.max(1) as f32, camera.resolution.1.max(1) as f32);
    let (cols, rows) = if w >= h {
        (VIEW_RAYS, ((VIEW_RAYS as f32 * h / w).round() as u32).max(1))
    } else {
        (((VIEW_RAYS as f32 * w / h).round() as u32).max(1), VIEW_RAYS)
    };
    let (_, _, _, sx, sy) = camera.raster_basis();
    // A grid cell's area on the image plane at unit distance: 2 s_x / cols × 2 s_y / rows.
    let cell = 4.0 * sx * sy / (cols * rows) as f32;
    let mut rays: Vec<(f32, f32)> = Vec::with_capacity((cols * rows) as usize);
    let mut omega = 0.0f64;
    for j in 0..rows {
        for i in 0..cols {
            let px = (i as f32 + 0.5) * w / cols as f32;
            let py = (j as f32 + 0.5) * h / rows as f32;
            let ray = camera.ray(px, py, (0.5, 0.5));
            // Solid angle of the cell: its plane area times cos³ of the ray's
            // angle to the view axis.
            let cos_axis = ray.d.dot(camera.forward()).max(0.0);
            let w_ray = cell * cos_axis * cos_axis * cos_axis;
            let Some(hit) = scene.intersect(&ray) else { continue };
            let t = hit.t;
            let Some((sp, _)) = scene.reflecting(&ray, hit) else { continue };
            let cos = sp.ng.dot(ray.d).abs().max(1e-3);
            let per_sr = t * t / cos;
            if per_sr.is_finite() && w_ray > 0.0 {
                rays.push((per_sr, w_ray));
                omega += w_ray as f64;
            }
        }
    }
    if rays.is_empty() {
        return 0.0;
    }
    rays.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half = 0.5 * omega;
    let mut acc = 0.0f64;
    let mut median = rays[rays.len() - 1].0;
    for &(a, w_ray) in &rays {
        acc += w_ray as f64;
        if acc >= half {
            median = a;
            break;
        }
    }
    (omega * median as f64) as f32
}

/// The geometry term between two oriented points (cosines clamped at zero).
#[inline]
pub fn geometry_term(cos_x: f32, cos_y: f32, dist2: f32) -> f32 {
    cos_x.max(0.0) * cos_y.max(0.0) / dist2
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FovAxis, Material, Mesh};
    use glam::Vec3;

    /// A diffuse wall of half-width `s` in the plane z = 0, facing +z.
    fn wall(s: f32) -> Scene {
        let mut mesh = Mesh::default();
        mesh.push_quad(Vec3::new(-s, -s, 0.0), Vec3::new(s, -s, 0.0), Vec3::new(s, s, 0.0), Vec3::new(-s, s, 0.0), 0);
        let light = crate::Light::Point { position: Vec3::new(0.0, 0.0, 1.0), intensity: Vec3::ONE };
        Scene::new("wall", &mesh, vec![Material::diffuse("m", Vec3::splat(0.5))], vec![light], false).unwrap()
    }

    fn camera(z: f32, fov: f32) -> Camera {
        Camera::new(Vec3::new(0.0, 0.0, z), Vec3::ZERO, Vec3::Y, fov, FovAxis::X, (160, 90)).unwrap()
    }

    #[test]
    fn the_view_area_is_the_area_of_a_wall_that_fills_the_view() {
        // A 30° view of a wall 10 m away covers 2·10·tan 15° × its 9/16 height:
        // 5.36 × 3.01 m = 16.2 m². The median ray meets the wall at about 1 / cos³
        // of the axis ray's area per steradian (the off-axis rays are longer and
        // slanted), at most 1 / cos³ 17° = 1.14 here; the midpoint rule for Ω
        // is a little low (cos³ is convex), within 1 % at 64 columns.
        let a = view_area(&wall(100.0), &camera(10.0, 30.0));
        let exact = 4.0 * 100.0 * (15f32.to_radians().tan()).powi(2) * 9.0 / 16.0;
        assert!(a >= 0.99 * exact && a <= 1.14 * exact, "{a} vs {exact}");
        // Twice as far: four times the area; G_max a quarter.
        let b = view_area(&wall(100.0), &camera(20.0, 30.0));
        assert!((b / a - 4.0).abs() < 1e-3, "{}", b / a);
        let (ca, cb) = (
            GeometryClamp::for_view(2048, &wall(100.0), &camera(10.0, 30.0)),
            GeometryClamp::for_view(2048, &wall(100.0), &camera(20.0, 30.0)),
        );
        assert!((ca.g_max / cb.g_max - 4.0).abs() < 1e-2);
    }

    #[test]
    fn far_geometry_outside_the_view_does_not_change_the_view_area() {
        // The same wall with a 1 km wide rim the camera never sees.
        let small = view_area(&wall(100.0), &camera(10.0, 30.0));
        let big = view_area(&wall(1000.0), &camera(10.0, 30.0));
        assert!((big / small - 1.0).abs() < 1e-4, "{small} vs {big}");
        assert!(wall(1000.0).surface_area() > 90.0 * wall(100.0).surface_area());
    }

    #[test]
    fn a_view_of_nothing_is_not_clamped() {
        let away = Camera::new(Vec3::new(0.0, 0.0, 10.0), Vec3::new(0.0, 0.0, 20.0), Vec3::Y, 30.0, FovAxis::X, (16, 9)).unwrap();
        assert_eq!(view_area(&wall(1.0), &away), 0.0);
        let c = GeometryClamp::for_view(2048, &wall(1.0), &away);
        assert_eq!(c.factor(1e30), 1.0);
        // The back of a one-sided wall reflects nothing either.
        let behind = Camera::new(Vec3::new(0.0, 0.0, -10.0), Vec3::ZERO, Vec3::Y, 30.0, FovAxis::X, (16, 9)).unwrap();
        assert_eq!(view_area(&wall(100.0), &behind), 0.0);
    }

    #[test]
    fn the_scene_area_rule_is_budget_over_area() {
        assert_eq!(GeometryClamp::for_scene_area(100, 4.0).g_max, 25.0);
        assert_eq!(GeometryClamp::new(2.0).factor(8.0), 0.25);
    }
}
