//! `--tev HOST:PORT`: a render shown in the tev viewer as it converges.

use super::tev_ipc::TevClient;
use std::sync::Mutex;
use vpl_core::Image;
use vpl_pathtrace::Tile;

/// One image in tev, fed by a render. A connection that fails mid-render
/// stops the streaming, not the render: the error is kept and reported once
/// at the end, beside the files written as usual.
pub(super) struct TevSink {
    client: Mutex<Option<TevClient>>,
    name: String,
    failed: Mutex<Option<String>>,
}

impl TevSink {
    /// Connects to tev at `address` and creates the black `width`×`height`
    /// image `name` there; a tev that cannot be reached is a bad argument.
    pub(super) fn open(address: &str, name: String, (width, height): (u32, u32)) -> Result<TevSink, String> {
        let mut client = TevClient::connect(address).map_err(|e| format!("--tev: {e}"))?;
        client.create_rgb(&name, width, height).map_err(|e| format!("--tev: {e}"))?;
        Ok(TevSink { client: Mutex::new(Some(client)), name, failed: Mutex::new(None) })
    }

    fn with(&self, send: impl FnOnce(&mut TevClient, &str) -> Result<(), super::tev_ipc::TevError>) {
        // A poisoned lock means a sending thread panicked: stop streaming.
        let Ok(mut guard) = self.client.lock() else { return };
        if let Some(c) = guard.as_mut()
            && let Err(e) = send(c, &self.name)
        {
            *guard = None;
            if let Ok(mut f) = self.failed.lock() {
                f.get_or_insert_with(|| e.to_string());
            }
        }
    }

    /// A finished tile of a path-traced image.
    pub(super) fn tile(&self, t: Tile<'_>) {
        self.with(|c, n| c.update_tile(n, (t.x, t.y, t.width, t.height), t.mean));
    }

    /// The whole image (a VPL frame, a progressive pass, the final image).
    pub(super) fn image(&self, img: &Image) {
        self.with(|c, n| c.update_whole(n, img));
    }

    /// Says, unless `quiet`, where the image went or why streaming stopped.
    pub(super) fn finish(self, address: &str, quiet: bool) {
        let failed = self.failed.into_inner().ok().flatten();
        match failed {
            Some(e) => eprintln!("vpl: warning: streaming to tev at {address} stopped: {e}"),
            None if !quiet => eprintln!("vpl: streamed to tev at {address} as '{}'", self.name),
            None => {}
        }
    }
}
