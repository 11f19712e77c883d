//! The window and what draws into it: the surface, egui's painter, and the
//! device view when the window shares the renderer's device.

use super::*;

/// The window and what draws into it.
pub(super) struct Gfx {
    pub(super) window: Arc<Window>,
    pub(super) surface: wgpu::Surface<'static>,
    pub(super) device: wgpu::Device,
    pub(super) queue: wgpu::Queue,
    pub(super) config: wgpu::SurfaceConfiguration,
    pub(super) egui: egui_winit::State,
    pub(super) painter: egui_wgpu::Renderer,
    /// The view composed on the renderer's device, when the window shares it.
    #[cfg(feature = "gpu")]
    pub(super) device_view: Option<crate::present::WindowView>,
}

impl Gfx {
    /// The window, on `shared` (the renderer's device) when a surface of
    /// the window can present from it, else on a device of its own.
    pub(super) fn new(el: &ActiveEventLoop, size: (u32, u32), title: &str, shared: Option<&SharedGpu>) -> Result<Gfx, ViewerError> {
        let attrs = Window::default_attributes().with_title(title).with_inner_size(winit::dpi::PhysicalSize::new(size.0, size.1));
        let window = Arc::new(el.create_window(attrs).map_err(|e| ViewerError::NoDisplay(crate::display::reason(&e)))?);
        #[cfg(feature = "gpu")]
        if let Some(gpu) = shared {
            let ctx = gpu.ctx();
            if let Ok(surface) = ctx.instance.create_surface(window.clone())
                && ctx.adapter.is_surface_supported(&surface)
            {
                let mut g = Gfx::on(window, surface, &ctx.adapter, ctx.device.clone(), ctx.queue.clone())?;
                g.device_view = Some(crate::present::WindowView::new(gpu.clone()));
                return Ok(g);
            }
        }
        #[cfg(not(feature = "gpu"))]
        let _ = shared;
        let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY | wgpu::Backends::GL);
        let instance = wgpu::Instance::new(&wgpu::InstanceDescriptor { backends, ..Default::default() });
        let surface = instance.create_surface(window.clone()).map_err(|e| ViewerError::Surface(e.to_string()))?;
        let adapter = pollster::block_on(
            instance.request_adapter(&wgpu::RequestAdapterOptions { compatible_surface: Some(&surface), ..Default::default() }),
        )
        .map_err(|e| ViewerError::NoAdapter(e.to_string()))?;
        let (device, queue) =
            pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor { label: Some("vpl-viewer"), ..Default::default() }))
                .map_err(|e| ViewerError::NoAdapter(e.to_string()))?;
        Gfx::on(window, surface, &adapter, device, queue)
    }

    pub(super) fn on(
        window: Arc<Window>,
        surface: wgpu::Surface<'static>,
        adapter: &wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Gfx, ViewerError> {
        let caps = surface.get_capabilities(adapter);
        let format = egui_wgpu::preferred_framebuffer_format(&caps.formats).map_err(|e| ViewerError::Surface(e.to_string()))?;
        let inner = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: inner.width.max(1),
            height: inner.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
        };
        surface.configure(&device, &config);
        let ctx = egui::Context::default();
        let max_side = device.limits().max_texture_dimension_2d as usize;
        let egui = egui_winit::State::new(ctx, egui::ViewportId::ROOT, &window, Some(window.scale_factor() as f32), None, Some(max_side));
        let painter = egui_wgpu::Renderer::new(&device, format, egui_wgpu::RendererOptions::default());
        Ok(Gfx {
            window,
            surface,
            device,
            queue,
            config,
            egui,
            painter,
            #[cfg(feature = "gpu")]
            device_view: None,
        })
    }

    pub(super) fn resize(&mut self, w: u32, h: u32) {
        if w > 0 && h > 0 {
            self.config.width = w;
            self.config.height = h;
            self.surface.configure(&self.device, &self.config);
        }
    }

    /// Draws egui's primitives into `target`.
    pub(super) fn paint(
        &mut self,
        target: &wgpu::TextureView,
        prims: &[egui::ClippedPrimitive],
        sd: &egui_wgpu::ScreenDescriptor,
    ) -> wgpu::CommandEncoder {
        let mut enc = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("vpl-viewer") });
        let extra = self.painter.update_buffers(&self.device, &self.queue, &mut enc, prims, sd);
        self.queue.submit(extra);
        {
            let mut pass = enc
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("egui"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: target,
                        resolve_target: None,
                        depth_slice: None,
                        ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                })
                .forget_lifetime();
            self.painter.render(&mut pass, prims, sd);
        }
        enc
    }

    /// The window's pixels as RGB (egui drawn into a texture like the surface's).
    pub(super) fn capture(
        &mut self,
        prims: &[egui::ClippedPrimitive],
        sd: &egui_wgpu::ScreenDescriptor,
    ) -> Result<(u32, u32, Vec<u8>), String> {
        let (w, h) = (self.config.width, self.config.height);
        let extent = wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 };
        let texture = self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("vpl-viewer screenshot"),
            size: extent,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: self.config.format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let mut enc = self.paint(&view, prims, sd);
        let row = (w * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl-viewer screenshot"),
            size: row as u64 * h as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo { texture: &texture, mip_level: 0, origin: wgpu::Origin3d::ZERO, aspect: wgpu::TextureAspect::All },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(h) },
            },
            extent,
        );
        self.queue.submit([enc.finish()]);
        let slice = buffer.slice(..);
        let (tx, rx) = mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| e.to_string())?;
        rx.recv().map_err(|e| e.to_string())?.map_err(|e| e.to_string())?;
        let data = slice.get_mapped_range();
        let bgra = matches!(self.config.format, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb);
        let mut rgb = Vec::with_capacity((w * h * 3) as usize);
        for y in 0..h {
            let line = &data[(y * row) as usize..(y * row + w * 4) as usize];
            for p in line.chunks_exact(4) {
                if bgra { rgb.extend([p[2], p[1], p[0]]) } else { rgb.extend([p[0], p[1], p[2]]) }
            }
        }
        drop(data);
        buffer.unmap();
        Ok((w, h, rgb))
    }
}
