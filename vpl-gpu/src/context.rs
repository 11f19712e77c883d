//! The wgpu device every kernel runs on.

use std::sync::atomic::{AtomicU64, Ordering};

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
    /// A kernel's answers contradict themselves: the device stopped its
    /// loops early (llvmpipe stops an invocation group's loops after 65,535
    /// iterations in all).
    #[error("the device cut {0} short: its answers are incomplete (llvmpipe stops a kernel's loops after 65,535 iterations)")]
    CutShort(&'static str),
    /// The caller cancelled the work before it ended.
    #[error("cancelled")]
    Cancelled,
}

/// An adapter, its device and queue, and the count of what crossed
/// between host and device ([`GpuContext::traffic`]).
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue. The toolkit's kernels submit through
    /// [`GpuContext::submit`] and write through [`GpuContext::write_buffer`],
    /// which count; work submitted here directly is not counted.
    pub queue: wgpu::Queue,
    /// What the adapter is.
    pub info: wgpu::AdapterInfo,
    /// The instance the adapter came from: a window's surface made from it
    /// can present what the kernels leave on this device.
    pub instance: wgpu::Instance,
    /// The adapter.
    pub adapter: wgpu::Adapter,
    counters: Counters,
}

#[derive(Default)]
struct Counters {
    bytes_up: AtomicU64,
    bytes_down: AtomicU64,
    writes: AtomicU64,
    reads: AtomicU64,
    submissions: AtomicU64,
}

/// What crossed between host and device since the context was opened (or,
/// as a difference of two readings, between them): bytes written to device
/// buffers (buffers created with contents, queue writes, uniforms
/// included), bytes read back, and queue submissions. These do not depend
/// on the device's speed: a frame moves the same bytes on lavapipe as on a
/// data-centre GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Traffic {
    /// Bytes from host to device.
    pub bytes_up: u64,
    /// Bytes from device to host.
    pub bytes_down: u64,
    /// Buffer writes from the host (each a buffer created with contents or
    /// a queue write).
    pub writes: u64,
    /// Read-backs (each a copy to a mapped buffer and a wait).
    pub reads: u64,
    /// Command buffers submitted to the queue (read-backs included).
    pub submissions: u64,
}

impl std::ops::Sub for Traffic {
    type Output = Traffic;

    /// The traffic between two readings (`later - earlier`).
    fn sub(self, earlier: Traffic) -> Traffic {
        Traffic {
            bytes_up: self.bytes_up - earlier.bytes_up,
            bytes_down: self.bytes_down - earlier.bytes_down,
            writes: self.writes - earlier.writes,
            reads: self.reads - earlier.reads,
            submissions: self.submissions - earlier.submissions,
        }
    }
}

impl std::fmt::Display for Traffic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kb = |b: u64| b as f64 / 1024.0;
        write!(
            f,
            "{:.1} KiB up in {} writes, {:.1} KiB down in {} reads, {} submissions",
            kb(self.bytes_up),
            self.writes,
            kb(self.bytes_down),
            self.reads,
            self.submissions
        )
    }
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
                Ok(adapter) => return Self::open(instance, adapter),
                Err(e) => why.push(format!("{backends:?}: {e}")),
            }
        }
        Err(GpuError::NoAdapter(why.join("; ")))
    }

    fn open(instance: wgpu::Instance, adapter: wgpu::Adapter) -> Result<GpuContext, GpuError> {
        let info = adapter.get_info();
        // Timestamps between passes, where the adapter has them: the stages
        // of a submission timed on the device (`GpuSmcSampler::profile`).
        let timestamps = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("vpl-gpu"),
            required_limits: adapter.limits(),
            required_features: adapter.features() & timestamps,
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        Ok(GpuContext { device, queue, info, instance, adapter, counters: Counters::default() })
    }

    /// Whether the device writes timestamps between the passes of an encoder.
    pub fn has_timestamps(&self) -> bool {
        self.device.features().contains(wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS)
    }

    /// What has crossed between host and device so far.
    pub fn traffic(&self) -> Traffic {
        let c = &self.counters;
        let get = |a: &AtomicU64| a.load(Ordering::Relaxed);
        Traffic {
            bytes_up: get(&c.bytes_up),
            bytes_down: get(&c.bytes_down),
            writes: get(&c.writes),
            reads: get(&c.reads),
            submissions: get(&c.submissions),
        }
    }

    /// Submits command buffers, counted.
    pub fn submit<I: IntoIterator<Item = wgpu::CommandBuffer>>(&self, buffers: I) -> wgpu::SubmissionIndex {
        let mut n = 0u64;
        let index = self.queue.submit(buffers.into_iter().inspect(|_| n += 1));
        self.counters.submissions.fetch_add(n, Ordering::Relaxed);
        index
    }

    /// Writes `data` into `buffer` at `offset` through the queue, counted.
    pub fn write_buffer(&self, buffer: &wgpu::Buffer, offset: u64, data: &[u8]) {
        self.queue.write_buffer(buffer, offset, data);
        self.note_upload(data.len() as u64);
    }

    /// Counts one host write of `bytes` made another way (a buffer created
    /// with contents).
    pub(crate) fn note_upload(&self, bytes: u64) {
        self.counters.bytes_up.fetch_add(bytes, Ordering::Relaxed);
        self.counters.writes.fetch_add(1, Ordering::Relaxed);
    }

    /// Counts one read-back of `bytes`.
    pub(crate) fn note_read(&self, bytes: u64) {
        self.counters.bytes_down.fetch_add(bytes, Ordering::Relaxed);
        self.counters.reads.fetch_add(1, Ordering::Relaxed);
    }

    /// One line naming the adapter and backend.
    pub fn describe(&self) -> String {
        format!("{} ({:?}, {:?})", self.info.name, self.info.backend, self.info.device_type)
    }
}
