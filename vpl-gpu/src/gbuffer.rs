//! The G-buffer on the device: rendered by a kernel (twin of
//! `vpl_shading::render_gbuffer`) or uploaded from the host.

use crate::context::{GpuContext, GpuError};
use crate::kernel::{Binding, bind, dispatch, finish, layout, pipeline, read_back, storage, storage_init, uniform};
use crate::scene::{BVH_WGSL, GpuScene, scene_layout};
use vpl_core::glam::{Vec3, Vec4};
use vpl_core::{Camera, GBuffer, GSample, Scene};

/// No-hit depth on the device.
const NO_HIT: f32 = 3.0e38;

/// A G-buffer in five device buffers of one `vec4<f32>` a pixel:
/// `pos` = (p, 1 where the point reflects, else 0), `normal` = (n, depth),
/// `ng` = (n_g, material bits), `albedo`, `emitted`.
pub struct DeviceGBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Angle between neighbouring pixel centres at the image centre.
    pub pixel_angle: f32,
    /// Camera position.
    pub eye: Vec3,
    pub(crate) pos: wgpu::Buffer,
    pub(crate) normal: wgpu::Buffer,
    pub(crate) ng: wgpu::Buffer,
    pub(crate) albedo: wgpu::Buffer,
    pub(crate) emitted: wgpu::Buffer,
}

fn pixels(gbuf_w: u32, gbuf_h: u32) -> usize {
    gbuf_w as usize * gbuf_h as usize
}

impl DeviceGBuffer {
    /// Positions (xyz) and whether the surface reflects (w: 1 or 0), one
    /// `vec4<f32>` a pixel.
    pub fn pos(&self) -> &wgpu::Buffer {
        &self.pos
    }

    /// Shading normals (xyz) and the distance along the camera ray (w; 3·10³⁸
    /// where the ray missed).
    pub fn normal(&self) -> &wgpu::Buffer {
        &self.normal
    }

    /// Diffuse albedo (xyz).
    pub fn albedo(&self) -> &wgpu::Buffer {
        &self.albedo
    }

    fn empty(ctx: &GpuContext, width: u32, height: u32, pixel_angle: f32, eye: Vec3) -> Result<DeviceGBuffer, GpuError> {
        let size = pixels(width, height) as u64 * 16;
        Ok(DeviceGBuffer {
            width,
            height,
            pixel_angle,
            eye,
            pos: storage(ctx, "g_pos", size)?,
            normal: storage(ctx, "g_normal", size)?,
            ng: storage(ctx, "g_ng", size)?,
            albedo: storage(ctx, "g_albedo", size)?,
            emitted: storage(ctx, "g_emitted", size)?,
        })
    }

    /// Uploads a host G-buffer.
    pub fn upload(ctx: &GpuContext, gbuf: &GBuffer) -> DeviceGBuffer {
        let s = &gbuf.samples;
        let v = |f: &dyn Fn(&GSample) -> Vec4| -> Vec<Vec4> { s.iter().map(f).collect() };
        let pos = v(&|g| g.p.extend(if g.reflects() { 1.0 } else { 0.0 }));
        let normal = v(&|g| g.n.extend(g.depth.min(NO_HIT)));
        let ng = v(&|g| g.ng.extend(f32::from_bits(g.material)));
        let albedo = v(&|g| g.albedo.extend(0.0));
        let emitted = v(&|g| g.emitted.extend(0.0));
        DeviceGBuffer {
            width: gbuf.width,
            height: gbuf.height,
            pixel_angle: gbuf.pixel_angle,
            eye: gbuf.eye,
            pos: storage_init(ctx, "g_pos", &pos),
            normal: storage_init(ctx, "g_normal", &normal),
            ng: storage_init(ctx, "g_ng", &ng),
            albedo: storage_init(ctx, "g_albedo", &albedo),
            emitted: storage_init(ctx, "g_emitted", &emitted),
        }
    }

    /// Reads the G-buffer back to the host.
    pub fn read(&self, ctx: &GpuContext) -> Result<GBuffer, GpuError> {
        let n = pixels(self.width, self.height);
        let pos: Vec<Vec4> = read_back(ctx, &self.pos, n)?;
        let normal: Vec<Vec4> = read_back(ctx, &self.normal, n)?;
        let ng: Vec<Vec4> = read_back(ctx, &self.ng, n)?;
        let albedo: Vec<Vec4> = read_back(ctx, &self.albedo, n)?;
        let emitted: Vec<Vec4> = read_back(ctx, &self.emitted, n)?;
        let samples = (0..n)
            .map(|i| {
                if normal[i].w >= NO_HIT {
                    return GSample::MISS;
                }
                GSample {
                    p: pos[i].truncate(),
                    n: normal[i].truncate(),
                    ng: ng[i].truncate(),
                    albedo: albedo[i].truncate(),
                    emitted: emitted[i].truncate(),
                    material: ng[i].w.to_bits(),
                    depth: normal[i].w,
                }
            })
            .collect();
        Ok(GBuffer { width: self.width, height: self.height, samples, pixel_angle: self.pixel_angle, eye: self.eye })
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CameraParams {
    origin: [f32; 4],
    forward: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    width: u32,
    height: u32,
    two_sided: u32,
    has_sky: u32,
    sky_zenith: [f32; 4],
    sky_horizon: [f32; 4],
    sky_nadir: [f32; 4],
}

/// The G-buffer kernel: one camera ray through each pixel centre, the
/// same point, normals, albedo and emission as `vpl_shading::render_gbuffer`.
pub struct GpuGBufferRenderer {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl GpuGBufferRenderer {
    /// Compiles the kernel.
    pub fn new(ctx: &GpuContext) -> GpuGBufferRenderer {
        let scene = scene_layout(ctx);
        let layout = layout(
            ctx,
            "gbuffer",
            &[Binding::Uniform, Binding::ReadWrite, Binding::ReadWrite, Binding::ReadWrite, Binding::ReadWrite, Binding::ReadWrite],
        );
        let source = format!("{BVH_WGSL}\n{}", include_str!("gbuffer.wgsl"));
        let pipeline = pipeline(ctx, "gbuffer", &source, "main", &[&scene, &layout]);
        GpuGBufferRenderer { layout, pipeline }
    }

    /// Renders the G-buffer of `scene` (uploaded as `gpu_scene`) seen by
    /// `camera`, left on the device; [`DeviceGBuffer::read`] brings it back.
    pub fn render(&self, ctx: &GpuContext, gpu_scene: &GpuScene, scene: &Scene, camera: &Camera) -> Result<DeviceGBuffer, GpuError> {
        let (w, h) = camera.resolution;
        // The pixel angle as render_gbuffer measures it.
        let c = camera.ray(w as f32 * 0.5, h as f32 * 0.5, (0.5, 0.5)).d;
        let r = camera.ray(w as f32 * 0.5 + 1.0, h as f32 * 0.5, (0.5, 0.5)).d;
        let out = DeviceGBuffer::empty(ctx, w, h, c.dot(r).clamp(-1.0, 1.0).acos(), camera.origin)?;
        let (f, right, up, sx, sy) = camera.raster_basis();
        let focus = if camera.lens_radius > 0.0 { camera.focus_distance } else { 0.0 };
        let sky = match scene.environment.map(|i| &scene.lights[i]) {
            Some(vpl_core::Light::Environment { sky }) => Some(*sky),
            _ => None,
        };
        let params = CameraParams {
            origin: camera.origin.extend(0.0).into(),
            forward: f.extend(sx).into(),
            right: right.extend(sy).into(),
            up: up.extend(focus).into(),
            width: w,
            height: h,
            two_sided: scene.two_sided as u32,
            has_sky: sky.is_some() as u32,
            sky_zenith: sky.map_or(Vec3::ZERO, |s| s.zenith).extend(0.0).into(),
            sky_horizon: sky.map_or(Vec3::ZERO, |s| s.horizon).extend(0.0).into(),
            sky_nadir: sky.map_or(Vec3::ZERO, |s| s.nadir).extend(0.0).into(),
        };
        let b_params = uniform(ctx, "camera", &params);
        let group = bind(ctx, "gbuffer", &self.layout, &[&b_params, &out.pos, &out.normal, &out.ng, &out.albedo, &out.emitted]);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        dispatch(&mut enc, &self.pipeline, &[&gpu_scene.group, &group], (w.div_ceil(8), h.div_ceil(8), 1));
        finish(ctx, enc)?;
        Ok(out)
    }
}
