//! What a visibility on the device leaves there for the shaders on the same
//! device: its structures, found by the visibility's
//! [`vpl_core::DeviceKey`] in the [`Gpu`]'s table, so that a shader handed
//! a `&dyn VplVisibility` reads them in place without knowing its type.

use crate::device::Gpu;
use crate::scene::GpuScene;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use vpl_core::DeviceKey;

/// The device parts of the visibility a gather reads: shadow maps (mode 0)
/// or shadow rays against the device scene (mode 1).
#[derive(Clone)]
pub(crate) struct DeviceVisibility {
    /// 0: shadow maps, 1: rays.
    pub mode: u32,
    /// The scene on the device.
    pub scene: Arc<GpuScene>,
    /// Ray offset.
    pub eps: f32,
    /// Shadow map resolution (1 for rays).
    pub res: u32,
    /// Shadow map bias scale (0 for rays).
    pub bias: f32,
    /// The maps' atlas and headers, for mode 0.
    pub maps: Option<(wgpu::Buffer, wgpu::Buffer)>,
}

impl DeviceVisibility {
    /// The maps' atlas and headers, or one empty buffer standing for both
    /// where there are none (rays: the kernels bind them but never read).
    pub(crate) fn map_buffers(&self, ctx: &crate::GpuContext) -> Result<(wgpu::Buffer, wgpu::Buffer), crate::GpuError> {
        Ok(match &self.maps {
            Some((atlas, headers)) => (atlas.clone(), headers.clone()),
            None => {
                let none = crate::kernel::storage(ctx, "no maps", 16)?;
                (none.clone(), none)
            }
        })
    }
}

/// The visibilities alive on one device, by key: `None` until a
/// visibility's first update has put its structures there.
#[derive(Default)]
pub(crate) struct Visibilities(Mutex<HashMap<DeviceKey, Option<DeviceVisibility>>>);

impl Gpu {
    /// Registers a new visibility on this device and returns its key; its
    /// owner calls [`Gpu::forget_visibility`] when dropped.
    pub(crate) fn register_visibility(&self) -> DeviceKey {
        let key = DeviceKey::unique();
        self.visibilities().0.lock().expect("visibility table lock").insert(key, None);
        key
    }

    /// Replaces what the visibility `key` holds on the device.
    pub(crate) fn publish_visibility(&self, key: DeviceKey, state: DeviceVisibility) {
        self.visibilities().0.lock().expect("visibility table lock").insert(key, Some(state));
    }

    /// Drops the visibility `key` from the table.
    pub(crate) fn forget_visibility(&self, key: DeviceKey) {
        self.visibilities().0.lock().expect("visibility table lock").remove(&key);
    }

    /// Whether `key` names a visibility alive on this device.
    pub(crate) fn holds_visibility(&self, key: DeviceKey) -> bool {
        self.visibilities().0.lock().expect("visibility table lock").contains_key(&key)
    }

    /// What the visibility `key` holds on this device: `None` for a key of
    /// another device, or before its first update.
    pub(crate) fn visibility(&self, key: DeviceKey) -> Option<DeviceVisibility> {
        self.visibilities().0.lock().expect("visibility table lock").get(&key).cloned().flatten()
    }
}
