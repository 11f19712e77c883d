//! The view composed on the device the frames were rendered on: the twin of
//! [`crate::view::compose`] as WGSL kernels, reading the images and the
//! G-buffer the GPU backend left there ([`vpl_gpu::DeviceFrame`]) and
//! writing the display bytes into a texture the window draws. Nothing is
//! read back; what goes up is the parameters and the overlay's VPLs (16 B
//! a VPL the camera can see), and the reference when a channel shows it.
//!
//! Both sides of a split view are rendered from one camera over one scene,
//! so their G-buffers are the same: the left side's serves both.

use crate::view::{Channel, Look, Overlay, difference_scale, flux_colour, flux_median};
use vpl_core::glam::Vec4;
use vpl_core::{Camera, VplSet};
use vpl_gpu::kernel::{Binding, bind, dispatch, finish_read, layout, pipeline, storage, storage_init, uniform};
use vpl_gpu::{DeviceFrame, Gpu, GpuError};

/// One side as the device holds it: its frame, and the VPLs and camera it
/// was rendered with (the overlay's).
#[derive(Clone, Copy)]
pub struct DeviceSide<'a> {
    /// The image and G-buffer on the device.
    pub frame: &'a DeviceFrame,
    /// The VPLs the frame was shaded with.
    pub vpls: &'a VplSet,
    /// The camera it was rendered from.
    pub camera: &'a Camera,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    width: u32,
    height: u32,
    row: u32,
    split_x: u32,
    channel: u32,
    overlay: u32,
    has_reference: u32,
    splats_left: u32,
    splats: u32,
    pick_side: u32,
    pick_class: u32,
    ring_side: u32,
    exposure: f32,
    ref_scale: f32,
    ring_x: f32,
    ring_y: f32,
    ring_dist: f32,
    pad1: [f32; 3],
}

/// A VPL of the overlay: where it falls, its distance, colour and whether it moved.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Splat {
    px: f32,
    py: f32,
    dist: f32,
    colour: u32,
}

const NONE: u32 = u32::MAX;

/// The compositing kernels and the texture they write.
pub struct DeviceView {
    layout: wgpu::BindGroupLayout,
    far: wgpu::ComputePipeline,
    splat: wgpu::ComputePipeline,
    compose: wgpu::ComputePipeline,
    target: Option<Target>,
}

/// The view's texture and the padded rows it is copied from.
struct Target {
    width: u32,
    height: u32,
    /// Bytes a row of `pixels` (a multiple of wgpu's copy alignment).
    row_bytes: u32,
    pixels: wgpu::Buffer,
    texture: wgpu::Texture,
}

impl DeviceView {
    /// Compiles the kernels on `gpu`.
    pub fn new(gpu: &Gpu) -> DeviceView {
        let ctx = gpu.ctx();
        let r = Binding::Read;
        let layout = layout(ctx, "view", &[Binding::Uniform, r, r, r, r, r, r, Binding::ReadWrite, Binding::ReadWrite]);
        let source = include_str!("present.wgsl");
        let far = pipeline(ctx, "view far", source, "far_pass", &[&layout]);
        let splat = pipeline(ctx, "view splats", source, "splat_pass", &[&layout]);
        let compose = pipeline(ctx, "view compose", source, "compose_pass", &[&layout]);
        DeviceView { layout, far, splat, compose, target: None }
    }

    fn ensure_target(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<(), GpuError> {
        if self.target.as_ref().is_none_or(|t| (t.width, t.height) != (width, height)) {
            let ctx = gpu.ctx();
            let row_bytes = (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
            let pixels = storage(ctx, "view pixels", row_bytes as u64 * height as u64)?;
            let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("view"),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                // The sRGB bytes as they are: egui draws its own textures
                // from Rgba8Unorm too.
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            self.target = Some(Target { width, height, row_bytes, pixels, texture });
        }
        Ok(())
    }

    /// The texture the last [`DeviceView::compose`] wrote (RGBA8, the
    /// display's sRGB bytes), `None` before the first.
    pub fn texture(&self) -> Option<&wgpu::Texture> {
        self.target.as_ref().map(|t| &t.texture)
    }

    /// Composes `left` (and `right`, split down the middle) as `look` asks,
    /// into [`DeviceView::texture`]: one submission, no wait. The sides
    /// must be the same size and rendered from one camera; the reference,
    /// when the channel shows it, is uploaded.
    pub fn compose(&mut self, gpu: &Gpu, left: DeviceSide, right: Option<DeviceSide>, look: &Look) -> Result<(), GpuError> {
        let (w, h) = (left.frame.width, left.frame.height);
        let right = right.filter(|r| (r.frame.width, r.frame.height) == (w, h));
        let ctx = gpu.ctx();
        let split_x = right.map(|_| w / 2);
        let reference = look.reference.filter(|r| (r.width, r.height) == (w, h));
        let shows_reference = matches!(look.channel, Channel::Reference | Channel::Difference);
        let ref_scale = reference.map_or(1.0, difference_scale);
        // The overlay's VPLs, left side's then right side's, in slot order.
        let mut splats = Vec::new();
        let mut splats_left = 0;
        if look.overlay == Overlay::Vpls {
            for (k, side) in std::iter::once(left).chain(right).enumerate() {
                splats.extend(splats_of(side, w, h));
                if k == 0 {
                    splats_left = splats.len() as u32;
                }
            }
        }
        // The picked VPL: its side's pixels of its class lit (interleave
        // overlay), and a ring where the camera sees it.
        let (mut pick_side, mut pick_class, mut ring_side, mut ring) = (NONE, NONE, NONE, (0.0, 0.0, 0.0));
        if let Some(p) = look.picked {
            pick_side = p.side as u32;
            pick_class = p.class.map_or(NONE, |c| c as u32);
            let side = match p.side {
                0 => Some(left),
                1 => Some(right.unwrap_or(left)),
                _ => None,
            };
            if let Some(side) = side
                && let Some(v) = side.vpls.get(p.slot)
                && let Some((px, py)) = side.camera.project(v.y)
            {
                ring_side = p.side as u32;
                ring = (px, py, (v.y - side.camera.origin).length());
            }
        }
        self.ensure_target(gpu, w, h)?;
        let target = self.target.as_ref().expect("made above");
        let params = Params {
            width: w,
            height: h,
            row: target.row_bytes / 4,
            split_x: split_x.unwrap_or(NONE),
            channel: Channel::ALL.iter().position(|c| *c == look.channel).unwrap_or(0) as u32,
            overlay: Overlay::ALL.iter().position(|o| *o == look.overlay).unwrap_or(0) as u32,
            has_reference: reference.is_some() as u32,
            splats_left,
            splats: splats.len() as u32,
            pick_side,
            pick_class,
            ring_side,
            exposure: look.exposure,
            ref_scale,
            ring_x: ring.0,
            ring_y: ring.1,
            ring_dist: ring.2,
            pad1: [0.0; 3],
        };
        let b_params = uniform(ctx, "view params", &params);
        let b_reference = match reference.filter(|_| shows_reference) {
            Some(r) => {
                let rows: Vec<Vec4> = r.data.iter().map(|c| c.extend(0.0)).collect();
                storage_init(ctx, "view reference", &rows)
            }
            None => storage(ctx, "no reference", 16)?,
        };
        let b_splats = if splats.is_empty() { storage(ctx, "no splats", 16)? } else { storage_init(ctx, "view splats", &splats) };
        let scratch = storage(ctx, "view scratch", 4 * (1 + w as u64 * h as u64))?;
        let g = left.frame.gbuffer();
        let image_r = right.map_or(left.frame.image(), |r| r.frame.image());
        let group = bind(
            ctx,
            "view",
            &self.layout,
            &[&b_params, left.frame.image(), image_r, g.normal(), g.albedo(), &b_reference, &b_splats, &scratch, &target.pixels],
        );
        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("view") });
        let tiles = (w.div_ceil(8), h.div_ceil(8), 1);
        if look.channel == Channel::Depth {
            dispatch(&mut enc, &self.far, &[&group], tiles);
        }
        if !splats.is_empty() {
            dispatch(&mut enc, &self.splat, &[&group], ((splats.len() as u32).div_ceil(64), 1, 1));
        }
        dispatch(&mut enc, &self.compose, &[&group], tiles);
        enc.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: &target.pixels,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(target.row_bytes), rows_per_image: Some(h) },
            },
            wgpu::TexelCopyTextureInfo {
                texture: &target.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        ctx.submit([enc.finish()]);
        Ok(())
    }

    /// The last composite's display bytes (RGBA, row-major), read back: for
    /// tests and screenshots, never per frame.
    pub fn read(&self, gpu: &Gpu) -> Result<Vec<u8>, GpuError> {
        let Some(t) = &self.target else { return Ok(Vec::new()) };
        let ctx = gpu.ctx();
        let enc = ctx.device.create_command_encoder(&Default::default());
        let rows: Vec<u8> = finish_read(ctx, enc, &t.pixels, (t.row_bytes * t.height) as usize)?;
        let row = (t.width * 4) as usize;
        Ok(rows.chunks(t.row_bytes as usize).flat_map(|r| r[..row].iter().copied()).collect())
    }
}

/// The splats of `side`'s VPLs that fall in its image, in slot order, as
/// [`crate::view::compose`] colours them (flux over the set's median).
fn splats_of(side: DeviceSide, w: u32, h: u32) -> Vec<Splat> {
    let Some(median) = flux_median(side.vpls) else { return Vec::new() };
    side.vpls
        .iter()
        .filter_map(|(slot, v)| {
            let (px, py) = side.camera.project(v.y)?;
            if !(px >= 0.0 && py >= 0.0 && px < w as f32 && py < h as f32) {
                return None;
            }
            let c = flux_colour(v.flux, median);
            let moved = side.vpls.moved(slot) as u32;
            let colour = c[0] as u32 | (c[1] as u32) << 8 | (c[2] as u32) << 16 | moved << 24;
            Some(Splat { px, py, dist: (v.y - side.camera.origin).length(), colour })
        })
        .collect()
}

/// The device view as the window draws it: the kernels, and the egui
/// texture id of the texture they write.
pub(crate) struct WindowView {
    gpu: Gpu,
    view: DeviceView,
    /// The registered texture and the size it was registered at.
    id: Option<(egui::TextureId, (u32, u32))>,
}

impl WindowView {
    pub(crate) fn new(gpu: Gpu) -> WindowView {
        let view = DeviceView::new(&gpu);
        WindowView { gpu, view, id: None }
    }

    /// Composes `sides` on the device when every one of them is there, and
    /// answers the texture to draw and the composite's layout (no pixels:
    /// [`crate::view::Composite::hdr`] is [`vpl_core::Image::on_device`]);
    /// `None` when a side is on the host (the window composes there).
    pub(crate) fn show(
        &mut self,
        device: &wgpu::Device,
        painter: &mut egui_wgpu::Renderer,
        sides: &[crate::worker::SideResult],
        look: &Look,
    ) -> Result<Option<(egui::TextureId, crate::view::Composite)>, GpuError> {
        let on_device: Option<Vec<DeviceSide>> =
            sides.iter().map(|s| s.device.as_ref().map(|frame| DeviceSide { frame, vpls: &s.out.vpls, camera: &s.camera })).collect();
        let Some(on_device) = on_device else { return Ok(None) };
        let Some(left) = on_device.first().copied() else { return Ok(None) };
        let right = on_device.get(1).copied().filter(|r| (r.frame.width, r.frame.height) == (left.frame.width, left.frame.height));
        self.view.compose(&self.gpu, left, right, look)?;
        let size = (left.frame.width, left.frame.height);
        let texture = self.view.texture().expect("composed above");
        let tv = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let id = match self.id {
            Some((id, at)) if at == size => id,
            Some((id, _)) => {
                painter.update_egui_texture_from_wgpu_texture(device, &tv, wgpu::FilterMode::Nearest, id);
                id
            }
            None => painter.register_native_texture(device, &tv, wgpu::FilterMode::Nearest),
        };
        self.id = Some((id, size));
        let composite = crate::view::Composite {
            width: size.0,
            height: size.1,
            rgba: Vec::new(),
            hdr: vpl_core::Image::on_device(size.0, size.1),
            split_x: right.map(|_| size.0 / 2),
        };
        Ok(Some((id, composite)))
    }
}
