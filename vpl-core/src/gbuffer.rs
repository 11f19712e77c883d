//! The G-buffer: the camera-visible surface point of every pixel, what all
//! deferred VPL stages read, and [`Receivers`], a structure-of-arrays view of
//! some of its points for the shading loops.

use glam::Vec3;

/// What a camera ray through a pixel centre found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GSample {
    /// World-space position (meaningless when `depth` is infinite).
    pub p: Vec3,
    /// Unit shading normal, turned toward the camera.
    pub n: Vec3,
    /// Unit geometric normal, turned toward the camera.
    pub ng: Vec3,
    /// Diffuse albedo ρ; zero where the surface reflects nothing toward the
    /// camera (a one-sided surface seen from behind, a miss).
    pub albedo: Vec3,
    /// Radiance emitted toward the camera (light sources seen directly).
    pub emitted: Vec3,
    /// Material index, `u32::MAX` for a miss.
    pub material: u32,
    /// Distance along the camera ray, `f32::INFINITY` for a miss.
    pub depth: f32,
}

impl GSample {
    /// A camera ray that hit nothing.
    pub const MISS: GSample = GSample {
        p: Vec3::ZERO,
        n: Vec3::Z,
        ng: Vec3::Z,
        albedo: Vec3::ZERO,
        emitted: Vec3::ZERO,
        material: u32::MAX,
        depth: f32::INFINITY,
    };

    /// Whether the camera ray hit a surface.
    #[inline]
    pub fn hit(&self) -> bool {
        self.depth.is_finite()
    }

    /// Whether the point reflects light toward the camera (VPLs can light it).
    #[inline]
    pub fn reflects(&self) -> bool {
        self.hit() && self.albedo.max_element() > 0.0
    }
}

/// One [`GSample`] per pixel, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct GBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width·height` samples.
    pub samples: Vec<GSample>,
    /// Angle one pixel spans at the image centre (radians): with `depth` it
    /// gives a pixel's world-space footprint.
    pub pixel_angle: f32,
    /// Camera position (the centre of the lens).
    pub eye: Vec3,
}

impl GBuffer {
    /// A G-buffer of no pixels (for samplers that do not look at the camera).
    pub fn empty() -> GBuffer {
        GBuffer { width: 0, height: 0, samples: Vec::new(), pixel_angle: 0.0, eye: Vec3::ZERO }
    }

    /// A G-buffer whose samples stay on a device: its size, pixel angle and
    /// eye on the host, and no samples (`samples` is empty). A backend that
    /// keeps the frame on its device hands these to the stages that run
    /// there, and reads the samples back only when asked
    /// (`vpl_render::Backend::host_gbuffer`).
    pub fn on_device(width: u32, height: u32, pixel_angle: f32, eye: Vec3) -> GBuffer {
        GBuffer { width, height, samples: Vec::new(), pixel_angle, eye }
    }

    /// Whether the samples are on the host: one per pixel (false for
    /// [`GBuffer::on_device`] of a non-empty size).
    pub fn on_host(&self) -> bool {
        self.samples.len() == self.width as usize * self.height as usize
    }

    /// The sample of pixel (x, y).
    #[inline]
    pub fn at(&self, x: u32, y: u32) -> &GSample {
        &self.samples[(y * self.width + x) as usize]
    }

    /// The reflecting pixels among `pixels` (row-major indices), as receivers.
    pub fn receivers(&self, pixels: impl IntoIterator<Item = u32>) -> Receivers {
        let mut r = Receivers::default();
        for i in pixels {
            let s = &self.samples[i as usize];
            if s.reflects() {
                r.push(i, s.p, s.n);
            }
        }
        r
    }
}

/// Receiving points in structure-of-arrays form: the layout the VPL-major
/// shading loops stream through, one array per coordinate.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Receivers {
    /// Row-major pixel index of each point.
    pub pixel: Vec<u32>,
    /// Positions, x coordinates.
    pub px: Vec<f32>,
    /// Positions, y coordinates.
    pub py: Vec<f32>,
    /// Positions, z coordinates.
    pub pz: Vec<f32>,
    /// Unit normals, x coordinates.
    pub nx: Vec<f32>,
    /// Unit normals, y coordinates.
    pub ny: Vec<f32>,
    /// Unit normals, z coordinates.
    pub nz: Vec<f32>,
}

impl Receivers {
    /// Appends a point.
    pub fn push(&mut self, pixel: u32, p: Vec3, n: Vec3) {
        self.pixel.push(pixel);
        self.px.push(p.x);
        self.py.push(p.y);
        self.pz.push(p.z);
        self.nx.push(n.x);
        self.ny.push(n.y);
        self.nz.push(n.z);
    }

    /// Number of points.
    #[inline]
    pub fn len(&self) -> usize {
        self.pixel.len()
    }

    /// Whether there are no points.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.pixel.is_empty()
    }

    /// Position of point `i`.
    #[inline]
    pub fn p(&self, i: usize) -> Vec3 {
        Vec3::new(self.px[i], self.py[i], self.pz[i])
    }

    /// Normal of point `i`.
    #[inline]
    pub fn n(&self, i: usize) -> Vec3 {
        Vec3::new(self.nx[i], self.ny[i], self.nz[i])
    }
}
