//! The device for the GPU tests. Without an adapter a test says it skipped,
//! unless VPL_REQUIRE_GPU=1 (CI), where a missing adapter fails it.

use vpl_gpu::GpuContext;

pub fn context() -> Option<GpuContext> {
    match GpuContext::new() {
        Ok(c) => {
            eprintln!("adapter: {}", c.describe());
            Some(c)
        }
        Err(e) if std::env::var("VPL_REQUIRE_GPU").is_ok_and(|v| v == "1") => panic!("VPL_REQUIRE_GPU=1 but {e}"),
        Err(e) => {
            eprintln!("skipped: {e}");
            None
        }
    }
}
