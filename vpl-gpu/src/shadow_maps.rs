//! Paraboloid shadow maps rendered on the device for changed slots only:
//! twin of [`vpl_visibility::ShadowMaps`].

use crate::context::GpuError;
use crate::device::Gpu;
use crate::kernel::{Binding, bind, dispatch, finish, layout, pipeline, read_back, storage, storage_init, uniform};
use crate::scene::GpuScene;
use crate::scene::{BVH_WGSL, scene_layout};
use crate::visibility::DeviceVisibility;
use std::sync::{Arc, Mutex};
use vpl_core::glam::{Vec3, Vec4};
use vpl_core::{DeviceKey, LocalFrame, Receivers, Scene, VisibilityUpdate, VplSet, VplVisibility};
use vpl_visibility::{MAX_RESOLUTION, MapView, ShadowMapError};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    res: u32,
    jobs: u32,
    pad: [u32; 2],
}

/// Most maps rendered by one dispatch (the z extent of a dispatch).
const JOBS_PER_DISPATCH: usize = 65_535;

/// One slot's map as the host knows it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Header {
    /// VPL position and normal the map was rendered for.
    key: (Vec3, Vec3),
    origin: Vec3,
    frame: LocalFrame,
}

/// Hemispherical paraboloid shadow maps on the device, one per VPL slot,
/// rendered by ray casting a texel each over the device BVH.
///
/// The maps, their depth test and bias are those of
/// [`vpl_visibility::ShadowMaps`]; `update` renders the maps of the slots
/// whose VPL moved, in one dispatch, into an atlas of `res²` floats per
/// slot that [`crate::GpuInterleavedShader`] samples on the device. Host
/// queries (`visible`, `attenuate`) read the atlas back once after each
/// update.
///
/// Why ray casting rather than rasterising: a rasterised paraboloid map
/// bends straight edges, so triangles must be finely tessellated or the
/// map resampled from a cube map (six raster passes and a resampling pass
/// per VPL, as the SMC paper does); casting one ray per texel has neither
/// approximation, reuses the BVH kernel, gives the CPU twin's maps texel for
/// texel, and renders only the moved maps in a single dispatch.
pub struct GpuShadowMaps {
    gpu: Gpu,
    res: u32,
    eps: f32,
    /// Scale k of the slope-dependent depth bias (default 1), as the CPU twin's.
    bias_scale: f32,
    headers: Vec<Option<Header>>,
    /// (atlas, slots it holds, header buffer).
    device: Option<(wgpu::Buffer, usize, wgpu::Buffer)>,
    host: Mutex<Option<Vec<f32>>>,
    kernel: Option<(wgpu::BindGroupLayout, wgpu::ComputePipeline)>,
    scene: Option<Arc<GpuScene>>,
    /// Where shaders on the same device find the atlas.
    key: DeviceKey,
}

impl GpuShadowMaps {
    /// Maps of `res × res` texels on `gpu`.
    pub fn new(gpu: Gpu, res: u32) -> Result<GpuShadowMaps, ShadowMapError> {
        if res == 0 || res > MAX_RESOLUTION {
            return Err(ShadowMapError::Resolution(res));
        }
        Ok(GpuShadowMaps {
            res,
            eps: 0.0,
            bias_scale: 1.0,
            headers: Vec::new(),
            device: None,
            host: Mutex::new(None),
            kernel: None,
            scene: None,
            key: gpu.register_visibility(),
            gpu,
        })
    }

    /// Scale k of the slope-dependent depth bias (default 1).
    pub fn bias_scale(&self) -> f32 {
        self.bias_scale
    }

    /// Sets the scale k of the slope-dependent depth bias, as the CPU
    /// twin's `bias_scale`; shaders read it from the next shade on.
    pub fn set_bias_scale(&mut self, k: f32) {
        self.bias_scale = k;
        self.publish();
    }

    /// Leaves the atlas, its headers and the settings where shaders on
    /// the same device find them by this visibility's key.
    fn publish(&self) {
        let (Some(scene), Some((atlas, _, headers))) = (&self.scene, &self.device) else { return };
        let state = DeviceVisibility {
            mode: 0,
            scene: scene.clone(),
            eps: self.eps,
            res: self.res,
            bias: self.bias_scale,
            maps: Some((atlas.clone(), headers.clone())),
        };
        self.gpu.publish_visibility(self.key, state);
    }

    /// Texels per side.
    pub fn resolution(&self) -> u32 {
        self.res
    }

    /// Bytes the atlas of `slots` maps of `res²` texels needs.
    pub fn atlas_bytes(res: u32, slots: usize) -> u64 {
        res as u64 * res as u64 * 4 * slots as u64
    }

    /// Renders the maps of `jobs` into the atlas, growing it to `slots` slots.
    fn render(&mut self, scene: &Scene, slots: usize, jobs: &[u32]) -> Result<(), GpuError> {
        let ctx = self.gpu.ctx();
        let gs = self.gpu.scene(scene)?;
        self.scene = Some(gs.clone());
        let res2 = (self.res * self.res) as u64;
        if self.device.as_ref().is_none_or(|(_, n, _)| *n < slots) {
            let atlas = storage(ctx, "shadow-map atlas", res2 * 4 * slots as u64)?;
            let headers = storage(ctx, "shadow-map headers", 64 * slots as u64)?;
            if let Some((old, n, _)) = &self.device {
                let mut enc = ctx.device.create_command_encoder(&Default::default());
                enc.copy_buffer_to_buffer(old, 0, &atlas, 0, res2 * 4 * *n as u64);
                ctx.submit([enc.finish()]);
            }
            self.device = Some((atlas, slots, headers));
        }
        let (atlas, _, b_headers) = self.device.as_ref().expect("just allocated");
        let rows: Vec<Vec4> = self
            .headers
            .iter()
            .flat_map(|h| match h {
                Some(h) => [h.origin.extend(1.0), h.frame.s.extend(0.0), h.frame.t.extend(0.0), h.frame.n.extend(0.0)],
                None => [Vec4::ZERO; 4],
            })
            .collect();
        ctx.write_buffer(b_headers, 0, bytemuck::cast_slice(&rows));
        if jobs.is_empty() {
            return Ok(());
        }
        let (layout, pipeline) = self.kernel.get_or_insert_with(|| {
            let l = layout(ctx, "shadow maps", &[Binding::Uniform, Binding::Read, Binding::Read, Binding::ReadWrite]);
            let source = format!("{BVH_WGSL}\n{}", include_str!("shadow_maps.wgsl"));
            let p = pipeline(ctx, "shadow maps", &source, "main", &[&scene_layout(ctx), &l]);
            (l, p)
        });
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        let mut keep = Vec::new();
        for chunk in jobs.chunks(JOBS_PER_DISPATCH) {
            let params = Params { res: self.res, jobs: chunk.len() as u32, pad: [0; 2] };
            let b_params = uniform(ctx, "shadow-map params", &params);
            let b_jobs = storage_init(ctx, "shadow-map jobs", chunk);
            let group = bind(ctx, "shadow maps", layout, &[&b_params, b_headers, &b_jobs, atlas]);
            dispatch(&mut enc, pipeline, &[&gs.group, &group], (self.res.div_ceil(8), self.res.div_ceil(8), chunk.len() as u32));
            keep.push((b_params, b_jobs, group));
        }
        finish(ctx, enc)
    }

    /// The depths of `slot`'s map, row-major, read back from the device
    /// (`None` for an empty slot); misses read 3·10³⁸.
    pub fn depths(&self, slot: usize) -> Option<Vec<f32>> {
        self.headers.get(slot)?.as_ref()?;
        let n = (self.res * self.res) as usize;
        self.with_host(|all| all[slot * n..(slot + 1) * n].to_vec())
    }

    fn with_host<R>(&self, f: impl FnOnce(&[f32]) -> R) -> Option<R> {
        let mut host = self.host.lock().expect("host copy lock");
        if host.is_none() {
            let (atlas, slots, _) = self.device.as_ref()?;
            let n = (self.res * self.res) as usize * slots;
            let data = read_back(self.gpu.ctx(), atlas, n).unwrap_or_else(|e| panic!("shadow-map read-back: {e}"));
            *host = Some(data);
        }
        host.as_deref().map(f)
    }

    fn view<'a>(&self, h: &Header, all: &'a [f32], slot: usize) -> MapView<'a> {
        let n = (self.res * self.res) as usize;
        MapView::new(h.origin, h.frame, &all[slot * n..(slot + 1) * n], self.res, self.eps, self.bias_scale)
    }
}

impl VplVisibility for GpuShadowMaps {
    fn name(&self) -> &'static str {
        "shadowmap"
    }

    /// Renders, in one dispatch, the maps of slots whose VPL position or
    /// normal changed; a VPL whose flux alone changed keeps its map.
    ///
    /// # Panics
    /// When the device fails or the atlas exceeds the adapter's
    /// storage-buffer limit; [`GpuShadowMaps::atlas_bytes`] lets callers
    /// check sizes first.
    fn update(&mut self, scene: &Scene, vpls: &VplSet) -> VisibilityUpdate {
        self.eps = scene.epsilon();
        self.headers.resize(vpls.len(), None);
        let mut jobs = Vec::new();
        for s in 0..vpls.len() {
            match (vpls.get(s), &self.headers[s]) {
                (Some(v), Some(h)) if h.key == (v.y, v.n) => {}
                (Some(v), _) => {
                    self.headers[s] = Some(Header { key: (v.y, v.n), origin: v.y + v.n * self.eps, frame: LocalFrame::from_normal(v.n) });
                    jobs.push(s as u32);
                }
                (None, _) => self.headers[s] = None,
            }
        }
        if let Err(e) = self.render(scene, vpls.len(), &jobs) {
            panic!("GPU shadow maps: {e}");
        }
        *self.host.lock().expect("host copy lock") = None;
        self.publish();
        VisibilityUpdate { rebuilt: jobs.len(), memory_bytes: self.memory_bytes() }
    }

    fn visible(&self, slot: usize, x: Vec3, n_x: Vec3) -> f32 {
        let Some(Some(h)) = self.headers.get(slot) else { return 0.0 };
        self.with_host(|all| {
            let d = x - h.origin;
            if self.view(h, all, slot).visible(d, d.length_squared(), -n_x.dot(d)) { 1.0 } else { 0.0 }
        })
        .unwrap_or(0.0)
    }

    fn attenuate(&self, slot: usize, rx: &Receivers, w: &mut [f32]) {
        let Some(Some(h)) = self.headers.get(slot) else {
            w.iter_mut().for_each(|x| *x = 0.0);
            return;
        };
        self.with_host(|all| {
            let view = self.view(h, all, slot);
            for (i, wi) in w.iter_mut().enumerate() {
                if *wi > 0.0 {
                    let d = rx.p(i) - h.origin;
                    if !view.visible(d, d.length_squared(), -rx.n(i).dot(d)) {
                        *wi = 0.0;
                    }
                }
            }
        });
    }

    fn memory_bytes(&self) -> usize {
        self.device.as_ref().map_or(0, |(a, _, h)| (a.size() + h.size()) as usize)
    }

    fn device_key(&self) -> Option<DeviceKey> {
        Some(self.key)
    }
}

impl Drop for GpuShadowMaps {
    fn drop(&mut self) {
        self.gpu.forget_visibility(self.key);
    }
}
