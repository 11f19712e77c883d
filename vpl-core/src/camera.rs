//! Pinhole and thin-lens cameras.
//!
//! Conventions: right-handed world; image right = `normalize(target − origin) × up`;
//! pixel (0,0) is the top-left pixel and covers raster `[0,1)×[0,1)`; row `y`
//! counts downward. The field of view is the *full* angle in degrees across
//! the axis named by [`FovAxis`].

use crate::error::{CoreError, Result};
use crate::ray::Ray;
use crate::sampling::concentric_disk;
use glam::Vec3;
use rayon::prelude::*;

/// Largest image side accepted (keeps a typo in a scene file from allocating terabytes).
pub const MAX_RESOLUTION: u32 = 16384;

/// Which image axis the field of view spans.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FovAxis {
    /// Horizontal.
    X,
    /// Vertical.
    Y,
    /// Whichever image side is smaller (Mitsuba's default).
    Smaller,
}

/// A camera description and the frame derived from it.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub origin: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up hint.
    pub up: Vec3,
    /// Full field of view in degrees.
    pub fov_deg: f32,
    /// Axis the field of view spans.
    pub fov_axis: FovAxis,
    /// Image size in pixels (width, height).
    pub resolution: (u32, u32),
    /// Thin-lens aperture radius (0 = pinhole).
    pub lens_radius: f32,
    /// Distance to the plane in focus.
    pub focus_distance: f32,
    forward: Vec3,
    right: Vec3,
    true_up: Vec3,
    sx: f32,
    sy: f32,
}

impl Camera {
    /// A pinhole camera. Errors on a degenerate frame, a field of view outside
    /// (0°, 180°) or a zero-sized image.
    pub fn new(origin: Vec3, target: Vec3, up: Vec3, fov_deg: f32, fov_axis: FovAxis, resolution: (u32, u32)) -> Result<Camera> {
        Self::make(origin, target, up, fov_deg, fov_axis, resolution, (0.0, 1.0))
    }

    /// The same camera as a thin lens of aperture radius `lens_radius`
    /// focused at `focus_distance` (radius 0: a pinhole). Errors on a
    /// negative radius, a focus distance that is not positive, or either
    /// beyond the scene's coordinate bound.
    pub fn with_lens(&self, lens_radius: f32, focus_distance: f32) -> Result<Camera> {
        Self::make(self.origin, self.target, self.up, self.fov_deg, self.fov_axis, self.resolution, (lens_radius, focus_distance))
    }

    /// The camera of these settings; `lens` is (aperture radius, focus distance).
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > y)` is meant: a NaN fails the test
    fn make(
        origin: Vec3,
        target: Vec3,
        up: Vec3,
        fov_deg: f32,
        fov_axis: FovAxis,
        resolution: (u32, u32),
        (lens_radius, focus_distance): (f32, f32),
    ) -> Result<Camera> {
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return Err(CoreError::Camera(format!("field of view must be in (0, 180) degrees, got {fov_deg}")));
        }
        if resolution.0 == 0 || resolution.1 == 0 {
            return Err(CoreError::Camera(format!("image size must be positive, got {}x{}", resolution.0, resolution.1)));
        }
        if resolution.0 > MAX_RESOLUTION || resolution.1 > MAX_RESOLUTION {
            return Err(CoreError::Camera(format!("image size {}x{} exceeds {MAX_RESOLUTION} on a side", resolution.0, resolution.1)));
        }
        if !(lens_radius >= 0.0) || !(focus_distance > 0.0) {
            return Err(CoreError::Camera("lens radius must be ≥ 0 and focus distance > 0".into()));
        }
        // Lens points and focus points are scene positions: within the
        // scene's coordinate bound, so that the distance between two of them
        // squares to a finite f32 (a lens radius of 10²⁰ gave rays of zero
        // direction, whose traversal never ended).
        let bound = crate::validate::MAX_COORDINATE;
        if lens_radius > bound || focus_distance > bound {
            return Err(CoreError::Camera(format!(
                "lens radius {lens_radius} and focus distance {focus_distance} must be at most {bound:e} (the scene's coordinate bound)"
            )));
        }
        if !(origin.is_finite() && target.is_finite() && up.is_finite()) {
            return Err(CoreError::Camera("camera origin, target and up must be finite".into()));
        }
        if origin.abs().max_element() > bound || target.abs().max_element() > bound {
            return Err(CoreError::Camera(format!("camera origin and target must lie within ±{bound:e} on every axis")));
        }
        let forward = (target - origin).normalize_or_zero();
        let right = forward.cross(up).normalize_or_zero();
        if forward == Vec3::ZERO || right == Vec3::ZERO {
            return Err(CoreError::Camera("camera target equals origin or up is parallel to the view direction".into()));
        }
        let true_up = right.cross(forward);
        let mut cam = Camera {
            origin,
            target,
            up,
            fov_deg,
            fov_axis,
            resolution,
            lens_radius,
            focus_distance,
            forward,
            right,
            true_up,
            sx: 0.0,
            sy: 0.0,
        };
        cam.update_scale();
        Ok(cam)
    }

    fn update_scale(&mut self) {
        let (w, h) = (self.resolution.0 as f32, self.resolution.1 as f32);
        let t = (0.5 * self.fov_deg.to_radians()).tan();
        let axis_x = match self.fov_axis {
            FovAxis::X => true,
            FovAxis::Y => false,
            FovAxis::Smaller => w <= h,
        };
        if axis_x {
            self.sx = t;
            self.sy = t * h / w;
        } else {
            self.sy = t;
            self.sx = t * w / h;
        }
    }

    /// The same camera rendering `resolution` pixels (field of view kept on its axis).
    pub fn with_resolution(&self, resolution: (u32, u32)) -> Result<Camera> {
        Self::make(self.origin, self.target, self.up, self.fov_deg, self.fov_axis, resolution, (self.lens_radius, self.focus_distance))
    }

    /// The same camera moved to `origin` looking at `target`.
    pub fn looking(&self, origin: Vec3, target: Vec3) -> Result<Camera> {
        Self::make(origin, target, self.up, self.fov_deg, self.fov_axis, self.resolution, (self.lens_radius, self.focus_distance))
    }

    /// Unit view direction.
    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// The raster basis of [`Camera::ray`]: (forward, right, up, s_x, s_y),
    /// the unnormalised direction through NDC (x, y) being
    /// forward + right·(x·s_x) + up·(y·s_y). For kernels that make camera
    /// rays themselves.
    pub fn raster_basis(&self) -> (Vec3, Vec3, Vec3, f32, f32) {
        (self.forward, self.right, self.true_up, self.sx, self.sy)
    }

    /// The primary ray through raster position (`px`, `py`) (pixel units, y down),
    /// with lens sample `u_lens` (ignored for a pinhole).
    #[inline]
    pub fn ray(&self, px: f32, py: f32, u_lens: (f32, f32)) -> Ray {
        let (w, h) = (self.resolution.0 as f32, self.resolution.1 as f32);
        let ndc_x = 2.0 * px / w - 1.0;
        let ndc_y = 1.0 - 2.0 * py / h;
        let d = self.forward + self.right * (ndc_x * self.sx) + self.true_up * (ndc_y * self.sy);
        if self.lens_radius > 0.0 {
            // Point in focus lies on the plane at focus_distance along `forward`.
            let focus = self.origin + d * self.focus_distance;
            let l = concentric_disk(u_lens.0, u_lens.1) * self.lens_radius;
            let o = self.origin + self.right * l.x + self.true_up * l.y;
            Ray::new(o, (focus - o).normalize())
        } else {
            Ray::new(self.origin, d.normalize())
        }
    }

    /// Raster position of world point `p`, if it is in front of the camera
    /// (pinhole projection).
    pub fn project(&self, p: Vec3) -> Option<(f32, f32)> {
        let v = p - self.origin;
        let z = v.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let x = v.dot(self.right) / (z * self.sx);
        let y = v.dot(self.true_up) / (z * self.sy);
        let (w, h) = (self.resolution.0 as f32, self.resolution.1 as f32);
        Some(((x + 1.0) * 0.5 * w, (1.0 - y) * 0.5 * h))
    }
}

/// `count` rays of a camera through uniformly random raster positions:
/// ray j draws (u, v) and then the lens sample from stream j under `key`
/// ([`keyed_stream`](crate::rng::keyed_stream)) and is
/// `camera.ray(u·w, v·h, lens)`. The rays are made on the host; a
/// [`RayCaster`](crate::RayCaster) on a device may make them there instead
/// of moving them ([`RayCaster::intersect_camera`](crate::RayCaster::intersect_camera)).
#[derive(Clone, Debug)]
pub struct CameraRays<'a> {
    /// The camera.
    pub camera: &'a Camera,
    /// The key of the rays' streams.
    pub key: u64,
    /// The rays, in order.
    pub rays: Vec<Ray>,
}

impl<'a> CameraRays<'a> {
    /// The `count` rays of `camera` under `key`, made in parallel.
    pub fn new(camera: &'a Camera, key: u64, count: usize) -> CameraRays<'a> {
        let rays = (0..count).into_par_iter().map(|j| Self::ray(camera, key, j as u64)).collect();
        CameraRays { camera, key, rays }
    }

    /// Ray `j` of `camera` under `key`.
    pub fn ray(camera: &Camera, key: u64, j: u64) -> Ray {
        let (w, h) = (camera.resolution.0 as f32, camera.resolution.1 as f32);
        let mut rng = crate::rng::keyed_stream(key, j);
        let (u, v) = rng.next_2d();
        camera.ray(u * w, v * h, rng.next_2d())
    }
}

/// Rays cosine-distributed about the shading normals of points a
/// [`CameraRays`] batch found: ray k leaves the hit of camera ray
/// `origins[k].0` (normals turned toward the camera, offset along the
/// geometric normal by the scene's epsilon) in direction
/// `LocalFrame::from_normal(n).to_world(cosine_hemisphere(u, v))`, (u, v) the
/// first two draws of stream `origins[k].1` under `key`. The rays are made
/// on the host; a [`RayCaster`](crate::RayCaster) on a device that still
/// holds the camera batch's hits may make them there
/// ([`RayCaster::intersect_bounce`](crate::RayCaster::intersect_bounce)).
#[derive(Clone, Debug)]
pub struct BounceRays<'a> {
    /// The camera batch whose hits the rays leave.
    pub camera: &'a CameraRays<'a>,
    /// The key of the rays' streams.
    pub key: u64,
    /// Per ray: the camera ray whose hit it leaves, and its stream's index.
    pub origins: Vec<(u32, u32)>,
    /// The rays, in order.
    pub rays: Vec<Ray>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_mitsuba_cornell_camera() {
        // camera.json of the Mitsuba Cornell box: the ray through the top-centre
        // edge has direction (0, 0.336337, -0.941742); right-centre (0.336337, 0, -0.941742).
        let c = Camera::new(Vec3::new(0.0, 0.0, 3.9), Vec3::ZERO, Vec3::Y, 39.3077, FovAxis::Smaller, (256, 256)).unwrap();
        let top = c.ray(128.0, 0.0, (0.0, 0.0)).d;
        let right = c.ray(256.0, 128.0, (0.0, 0.0)).d;
        assert!((top - Vec3::new(0.0, 0.336337, -0.941742)).length() < 1e-5, "{top}");
        assert!((right - Vec3::new(0.336337, 0.0, -0.941742)).length() < 1e-5, "{right}");
        let (px, py) = c.project(Vec3::new(0.0, 0.0, -1.0)).unwrap();
        assert!((px - 128.0).abs() < 1e-3 && (py - 128.0).abs() < 1e-3);
    }

    #[test]
    fn fov_axis_and_errors() {
        let c = Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 90.0, FovAxis::X, (200, 100)).unwrap();
        let r = c.ray(200.0, 50.0, (0.0, 0.0)).d;
        assert!((r.x - std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-5);
        assert!(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 0.0, FovAxis::X, (2, 2)).is_err());
        assert!(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, -5.0, FovAxis::X, (2, 2)).is_err());
        assert!(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0, FovAxis::X, (0, 2)).is_err());
        assert!(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0, FovAxis::X, (2, MAX_RESOLUTION + 1)).is_err());
        assert!(Camera::new(Vec3::Z, Vec3::Z, Vec3::Y, 40.0, FovAxis::X, (2, 2)).is_err());
    }

    /// A lens of radius 10²⁰ made lens points whose distance to the focus
    /// point squares past f32: rays of zero direction. Such lenses, and
    /// cameras beyond the scene's coordinate bound, are refused; every ray
    /// of the largest allowed lens has a unit direction.
    #[test]
    fn lenses_and_positions_beyond_the_coordinate_bound_are_refused() {
        let lens = |r: f32, f: f32| Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0, FovAxis::X, (4, 4)).and_then(|c| c.with_lens(r, f));
        for (r, f) in [(1e20, 1.0), (1.0, 1e20), (f32::INFINITY, 1.0)] {
            let e = lens(r, f).unwrap_err().to_string();
            assert!(e.contains("lens radius") && e.contains("coordinate bound") || e.contains("≥ 0"), "{r} {f}: {e}");
        }
        let far = Camera::new(Vec3::new(0.0, 0.0, 1e11), Vec3::ZERO, Vec3::Y, 40.0, FovAxis::X, (2, 2)).unwrap_err();
        assert!(far.to_string().contains("within ±"), "{far}");
        let widest = lens(crate::validate::MAX_COORDINATE, 1.0).unwrap();
        for u in [(0.0, 0.0), (0.99, 0.5), (0.5, 0.99)] {
            let d = widest.ray(1.0, 3.0, u).d;
            assert!(d.is_finite() && (d.length() - 1.0).abs() < 1e-3, "{d}");
        }
    }
}
