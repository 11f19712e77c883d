//! Recording the camera's and the lights' path as a scene's sequence.

use super::*;

/// A path being recorded, and how many were written.
pub(super) struct Recordings {
    pub(super) recording: Option<(Instant, Recorder)>,
    pub(super) recordings: u32,
}

impl State {
    /// The camera and the `[[lights]]` entries now.
    pub(super) fn pose(&mut self) -> Pose {
        let lights = match &self.anim.manual_lights {
            Some(l) => l.clone(),
            None => self.scene().map_or_else(|_| self.world.setup.scene.extra_lights(), |s| s.extra_lights()),
        };
        let lights = lights
            .iter()
            .map(|l| match l {
                Light::Point { position, .. } => (Some(*position), None),
                Light::Spot { position, direction, .. } => (Some(*position), Some(*direction)),
                Light::Directional { direction, .. } => (None, Some(*direction)),
                _ => (None, None),
            })
            .collect();
        Pose { origin: self.world.cam.origin, target: self.world.cam.target(), lights }
    }

    pub(super) fn record_start(&mut self) {
        let fps = self.world.setup.sequence.as_ref().map_or(30.0, |s| s.fps);
        let mut r = Recorder::new(fps);
        r.push(0.0, self.pose());
        self.rec.recording = Some((Instant::now(), r));
        self.report.status_line = Some("recording the camera and the lights".into());
    }

    /// Ends the recording and writes the scene file with it as its
    /// animation; model paths are made relative to the file's folder.
    pub(super) fn record_stop(&mut self, path: &Path) -> Result<PathBuf, ViewerError> {
        let Some((start, mut r)) = self.rec.recording.take() else {
            return Err(ViewerError::Invalid("record stop: nothing is being recorded".into()));
        };
        let t = start.elapsed().as_secs_f32();
        r.push(t, self.pose());
        let spec = r.finish(t).ok_or_else(|| ViewerError::Invalid("record stop: nothing was recorded".into()))?;
        let setup = self.world.setup.clone().with_world_sequence(spec)?;
        let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir).map_err(|e| ViewerError::Write { path: dir.to_path_buf(), reason: e.to_string() })?;
        let file = setup.description.relocated(&self.world.scene_dir, dir);
        let text = format!(
            "# Recorded by vpl view on {}: {} camera keys, {} light keys.\n{}",
            self.world.scene_name,
            file.sequence.as_ref().map_or(0, |s| s.camera.len()),
            file.sequence.as_ref().map_or(0, |s| s.lights.len()),
            vpl_scene_io::scene_toml(&file)
        );
        vpl_core::image::write_atomic(path, text.as_bytes())?;
        self.report.status_line = Some(format!("wrote {}", path.display()));
        Ok(path.to_path_buf())
    }
}
