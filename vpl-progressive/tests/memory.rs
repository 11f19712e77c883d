//! The accumulation buffer has constant size: memory does not grow with
//! passes. A counting global allocator measures the bytes alive between
//! passes and the peak during each pass.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use vpl_core::SceneSetup;
use vpl_progressive::{Progressive, ProgressiveConfig};

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

// A global allocator is unsafe by the trait's contract; this one forwards
// to the system allocator and only counts bytes.
#[allow(unsafe_code)]
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let now = LIVE.fetch_add(layout.size(), Ordering::SeqCst) + layout.size();
            PEAK.fetch_max(now, Ordering::SeqCst);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::SeqCst);
    }
}

#[global_allocator]
static A: Counting = Counting;

#[test]
fn memory_does_not_grow_with_passes() {
    let setup = SceneSetup::builtin("glass").unwrap();
    let camera = setup.camera.with_resolution((48, 36)).unwrap();
    let config = ProgressiveConfig { caustic_paths: 20_000, ..Default::default() };
    // One worker thread, so no pool threads allocate on their own schedule.
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let mut r = Progressive::new(&setup.scene, camera, config).unwrap();
    // Room for every measurement up front, so the test's own vectors do not grow.
    let mut live = Vec::with_capacity(40);
    let mut peaks = Vec::with_capacity(40);
    pool.install(|| r.pass()); // warm-up: the pool's own buffers
    for _ in 0..40 {
        let before = LIVE.load(Ordering::SeqCst);
        PEAK.store(before, Ordering::SeqCst);
        pool.install(|| r.pass());
        peaks.push(PEAK.load(Ordering::SeqCst) - before);
        live.push(LIVE.load(Ordering::SeqCst));
    }
    eprintln!(
        "bytes alive after passes 2..41: {:?} … {:?}; per-pass peak: first ten {:?}, last ten {:?}",
        &live[..3],
        &live[37..],
        &peaks[..10],
        &peaks[30..]
    );
    // Nothing stays behind after a pass.
    assert!(live.iter().all(|&l| l == live[0]), "memory alive between passes changed: {live:?}");
    // The working set of a pass does not creep up (it varies with the random
    // number of VPLs and photon deposits, well within 25 %).
    let first = *peaks[..10].iter().max().unwrap();
    let last = *peaks[30..].iter().max().unwrap();
    assert!(last as f64 <= 1.25 * first as f64, "per-pass peak grew from {first} to {last} bytes");
    assert!(r.buffer_bytes() == 2 * 48 * 36 * 24);
}
