//! The wgpu device every kernel runs on.

/// Errors of the GPU path.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter of any backend was found.
    #[error("no GPU adapter (install a Vulkan driver, e.g. mesa-vulkan-drivers for lavapipe): {0}")]
    NoAdapter(String),
    /// The adapter refused a device.
    #[error("cannot open the GPU device: {0}")]
    Device(String),
    /// A buffer could not be read back.
    #[error("GPU read-back failed: {0}")]
    ReadBack(String),
    /// The input does not fit the kernel.
    #[error("{0}")]
    Invalid(String),
}

/// An adapter, its device and queue.
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the adapter is.
    pub info: wgpu::AdapterInfo,
}

impl GpuContext {
    /// The default adapter: Vulkan, Metal or DX12 first, then GL (EGL) as
    /// the fallback. `WGPU_BACKEND` (e.g. `gl`, `vulkan`) restricts the
    /// choice, which is how the GL path is tested.
    pub fn new() -> Result<GpuContext, GpuError> {
        let tries = match wgpu::Backends::from_env() {
            Some(b) => vec![b],
            None => vec![wgpu::Backends::PRIMARY, wgpu::Backends::GL],
        };
        let mut why = Vec::new();
        for backends in tries {
            let instance = wgpu::Instance::new(&wgpu::InstanceDescriptor { backends, ..Default::default() });
            match pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default())) {
                Ok(adapter) => return Self::open(adapter),
                Err(e) => why.push(format!("{backends:?}: {e}")),
            }
        }
        Err(GpuError::NoAdapter(why.join("; ")))
    }

    fn open(adapter: wgpu::Adapter) -> Result<GpuContext, GpuError> {
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("vpl-gpu"),
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        Ok(GpuContext { device, queue, info })
    }

    /// One line naming the adapter and backend.
    pub fn describe(&self) -> String {
        format!("{} ({:?}, {:?})", self.info.name, self.info.backend, self.info.device_type)
    }
}
