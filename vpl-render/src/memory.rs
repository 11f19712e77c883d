//! How much memory a render will need, estimated before it starts from the
//! settings that drive it, so a program can refuse a render that would not
//! fit ([`MemoryEstimate::check`]) instead of growing until the machine
//! stops. The estimates count the large buffers each stage allocates (sizes
//! of the real types times their counts) plus the loaded scene; they are
//! compared with the measured peak in `docs/robustness.md`.

use std::mem::size_of;
use vpl_core::{GSample, Scene, TriangleData, Vpl};

/// One buffer of an estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryItem {
    /// What it holds, with the product that sizes it.
    pub what: String,
    /// Bytes.
    pub bytes: u64,
    /// The settings that drive it (`vpls`, `shadowmap-res`, `size`, …; a
    /// command-line program shows them as flags).
    pub driver: &'static [&'static str],
}

/// The memory a render will need.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MemoryEstimate {
    /// The buffers, largest first after [`MemoryEstimate::sorted`].
    pub items: Vec<MemoryItem>,
}

/// Bytes in a human unit (KiB, MiB, GiB).
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= (1u64 << 30) as f64 {
        format!("{:.1} GiB", b / (1u64 << 30) as f64)
    } else if b >= (1u64 << 20) as f64 {
        format!("{:.1} MiB", b / (1u64 << 20) as f64)
    } else if bytes >= 1024 {
        format!("{:.0} KiB", b / 1024.0)
    } else {
        format!("{bytes} B")
    }
}

/// A refused render: the estimate, the budget and the buffer that dominates.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("this render needs about {} but the memory limit is {}: {} ({}) is the largest part, driven by `{}`", human(*.estimate), human(*.limit), human(.largest.bytes), .largest.what, .largest.driver.join("`, `"))]
pub struct OverBudget {
    /// Estimated bytes.
    pub estimate: u64,
    /// The budget.
    pub limit: u64,
    /// The largest item.
    pub largest: MemoryItem,
}

impl MemoryEstimate {
    fn add(&mut self, what: String, bytes: u64, driver: &'static [&'static str]) {
        self.items.push(MemoryItem { what, bytes, driver });
    }

    /// The estimate with one more part: what it is, its bytes, and the
    /// flags that drive it (named when it is the largest part).
    pub fn with_part(mut self, what: String, bytes: u64, driver: &'static [&'static str]) -> Self {
        self.add(what, bytes, driver);
        self.sorted()
    }

    /// The total in bytes.
    pub fn total(&self) -> u64 {
        self.items.iter().map(|i| i.bytes).fold(0u64, u64::saturating_add)
    }

    /// The items, largest first.
    pub fn sorted(mut self) -> Self {
        self.items.sort_by_key(|i| std::cmp::Reverse(i.bytes));
        self
    }

    /// Refuses an estimate above `limit` bytes, naming its largest part.
    pub fn check(&self, limit: u64) -> Result<(), OverBudget> {
        let estimate = self.total();
        if estimate <= limit {
            return Ok(());
        }
        let largest =
            self.items.iter().max_by_key(|i| i.bytes).cloned().unwrap_or(MemoryItem { what: "nothing".into(), bytes: 0, driver: &[] });
        Err(OverBudget { estimate, limit, largest })
    }

    /// The program itself (64 MiB: code, libraries, thread stacks) and the
    /// loaded scene: triangles, their BVH (about 48 bytes a triangle
    /// for the compressed wide nodes and the index arrays), shading normals
    /// and the light table.
    pub fn scene(scene: &Scene) -> MemoryEstimate {
        let g = &scene.geometry;
        let tris = g.triangles.len() as u64;
        let mut e = MemoryEstimate::default();
        e.add("the program: code, libraries, thread stacks".into(), 64 << 20, &["threads"]);
        e.add(
            format!("scene: {tris} triangles × {} B + BVH", size_of::<TriangleData>() + 48),
            tris * (size_of::<TriangleData>() as u64 + 48) + g.shading_normals.len() as u64 * 36 + scene.lights.len() as u64 * 64,
            &["scene"],
        );
        e
    }

    /// One path-traced image of `size`: mean and standard error, and the
    /// per-tile results they are gathered from.
    pub fn path_tracer(scene: &Scene, size: (u32, u32)) -> MemoryEstimate {
        let mut e = Self::scene(scene);
        let px = size.0 as u64 * size.1 as u64;
        e.add(format!("images: {}×{} pixels × 48 B", size.0, size.1), px * 48, &["size"]);
        e.sorted()
    }

    /// One VPL frame of `size` with `vpls` VPLs: the G-buffer, the frame's
    /// images (sum, indirect, direct, interleaved sub-images and filter),
    /// the VPL set with the sampler's working memory (up to 16 candidates of
    /// 64 bytes per VPL, SMC's resampling ratio), and the visibility: one
    /// paraboloid map of `res²` f32 depths per VPL, or one point per VPL.
    pub fn vpl_frame(scene: &Scene, size: (u32, u32), vpls: usize, shadow_map_res: Option<u32>) -> MemoryEstimate {
        let mut e = Self::scene(scene);
        let px = size.0 as u64 * size.1 as u64;
        let (w, h) = size;
        e.add(format!("G-buffer: {w}×{h} × {} B", size_of::<GSample>()), px * size_of::<GSample>() as u64, &["size"]);
        e.add(format!("images: {w}×{h} × 8 RGB buffers"), px * 8 * 12, &["size"]);
        let v = vpls as u64;
        e.add(
            format!("VPLs: {vpls} × ({} B + 1 KiB of sampler state)", 2 * size_of::<Option<Vpl>>()),
            v * (2 * size_of::<Option<Vpl>>() as u64 + 1024),
            &["vpls"],
        );
        match shadow_map_res {
            Some(res) => {
                let r = res as u64;
                e.add(
                    format!("shadow maps: {vpls} VPLs × {res}² texels × 4 B"),
                    v.saturating_mul(r * r * 4 + 96),
                    &["vpls", "shadowmap-res"],
                );
            }
            None => e.add(format!("shadow-ray origins: {vpls} × 16 B"), v * 16, &["vpls"]),
        }
        e.sorted()
    }

    /// The progressive renderer at `size`: its accumulated image and error
    /// buffers, the pass's caustic photons (up to `max_depth` a path) and its
    /// VPLs (up to `max_depth` a path), `vpl_bytes` each as the renderer
    /// holds them (`vpl_progressive::bytes_per_vpl`).
    pub fn progressive(
        scene: &Scene,
        size: (u32, u32),
        caustic_paths: usize,
        vpl_paths: usize,
        max_depth: u32,
        vpl_bytes: u64,
    ) -> MemoryEstimate {
        let mut e = Self::scene(scene);
        let px = size.0 as u64 * size.1 as u64;
        e.add(format!("images: {}×{} × 8 RGB buffers", size.0, size.1), px * 8 * 12, &["size"]);
        let d = max_depth.max(1) as u64;
        e.add(format!("caustic photons: {caustic_paths} paths × {d} × 48 B"), caustic_paths as u64 * d * 48, &["caustic-paths"]);
        e.add(format!("VPLs: {vpl_paths} paths × {d} × {vpl_bytes} B"), vpl_paths as u64 * d * vpl_bytes, &["vpl-paths"]);
        e.sorted()
    }
}

/// The machine's physical memory in bytes (`MemTotal` of `/proc/meminfo`),
/// `None` where it cannot be read.
pub fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The peak resident memory of this process so far (`VmHWM` of
/// `/proc/self/status`), `None` where it cannot be read.
pub fn peak_resident() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = text.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_largest_part_is_named() {
        let setup = vpl_core::SceneSetup::builtin("cornell").unwrap();
        // The case of a 2048-VPL atlas of 4096² maps: 128 GiB of maps.
        let e = MemoryEstimate::vpl_frame(&setup.scene, (640, 360), 2048, Some(4096));
        assert!(e.total() > 128 << 30 && e.items[0].driver == ["vpls", "shadowmap-res"], "{e:?}");
        let err = e.check(12 << 30).unwrap_err();
        let line = err.to_string();
        assert!(line.contains("128.0 GiB") && line.contains("shadowmap-res") && line.contains("12.0 GiB"), "{line}");
        // Ten million VPLs.
        let e = MemoryEstimate::vpl_frame(&setup.scene, (64, 64), 10_000_000, None);
        assert_eq!(e.items[0].driver, &["vpls"]);
        assert!(e.total() > 10_000_000 * 1024);
        // A modest render passes.
        assert!(MemoryEstimate::path_tracer(&setup.scene, (256, 256)).check(128 << 20).is_ok());
    }
}
