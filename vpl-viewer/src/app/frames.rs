//! The frames: the scene of the current animation frame and lights, jobs
//! to the render thread and its replies, and the view composed from them
//! (on the device when the frames stay there).

use super::*;

impl State {
    pub(super) fn scene(&mut self) -> Result<Arc<Scene>, ViewerError> {
        let key = (self.anim_frame, self.lights_version);
        if let Some((k, s)) = &self.scene_cache
            && *k == key
        {
            return Ok(s.clone());
        }
        let (mut scene, _) = self.setup.frame(self.anim_frame)?;
        if let Some(l) = &self.manual_lights {
            scene = scene.with_lights(l.clone())?;
        }
        let scene = Arc::new(scene);
        self.scene_cache = Some((key, scene.clone()));
        Ok(scene)
    }

    /// Sends the next job when none is in flight: frames render continuously.
    pub(super) fn submit(&mut self) {
        if self.in_flight.is_some() || self.stalled || self.quit {
            return;
        }
        let scene = match self.scene() {
            Ok(s) => s,
            Err(e) => {
                self.error_line = Some(e.to_string());
                self.stalled = true;
                return;
            }
        };
        let camera = match self.cam.camera(&self.setup.camera, self.resolution()) {
            Ok(c) => c,
            Err(e) => {
                self.error_line = Some(format!("camera: {e}"));
                self.stalled = true;
                return;
            }
        };
        let time = self.setup.sequence.as_ref().map_or(0.0, |s| s.time(self.anim_frame));
        let cancel = Arc::new(AtomicBool::new(false));
        let reference = self.reference_on.then_some(ReferenceSpec {
            mode: self.mode,
            max_depth: vpl_core::Budget::default().max_depth,
            budget: REFERENCE_BUDGET,
        });
        let job = Job { scene, camera, time, sides: self.specs(), cancel: cancel.clone(), reference, resident: self.resident };
        if self.jobs.send(job).is_ok() {
            self.in_flight = Some((self.generation, cancel, Instant::now()));
        } else {
            self.fail(ViewerError::Render("the render thread stopped".into()));
        }
    }

    /// Takes the render thread's replies.
    pub(super) fn poll(&mut self) {
        loop {
            let reply = match self.replies.try_recv() {
                Ok(r) => r,
                Err(mpsc::TryRecvError::Empty) => break,
                Err(mpsc::TryRecvError::Disconnected) => {
                    self.in_flight = None;
                    self.fail(ViewerError::Render("the render thread stopped".into()));
                    break;
                }
            };
            let Some((generation, _, _)) = self.in_flight.take() else { continue };
            match reply {
                Reply::Frame { sides, reference } => {
                    let now = Instant::now();
                    self.first_frame_at.get_or_insert(now);
                    self.last_frame_at = Some(now);
                    self.frames_shown += 1;
                    if generation == self.generation {
                        self.waiting = self.waiting.saturating_sub(1);
                    }
                    for (h, s) in self.history.iter_mut().zip(&sides) {
                        h.push(s);
                    }
                    self.last = sides;
                    self.error_line = None;
                    self.recompose = true;
                    match reference {
                        Some(Ok(r)) => self.reference = Some(r),
                        Some(Err(e)) => {
                            self.reference = None;
                            self.error_line = Some(e);
                        }
                        None => self.reference = None,
                    }
                    self.refresh_map();
                }
                Reply::Cancelled => {}
                Reply::Failed(e) => {
                    if self.scripted {
                        self.fail(ViewerError::Render(e.clone()));
                    }
                    self.error_line = Some(e);
                    if generation == self.generation {
                        self.stalled = true;
                    }
                }
            }
        }
    }

    /// The last frame's sides with their G-buffers on the host (read back
    /// where they stayed on the device).
    pub(super) fn on_host(&self) -> Vec<(SideResult, vpl_core::GBuffer)> {
        self.last
            .iter()
            .map(|s| {
                #[cfg(feature = "gpu")]
                if let Some((image, gbuffer)) = host_frame(s) {
                    let out = vpl_render::FrameOutput { image, ..s.out.clone() };
                    return (SideResult { out, device: None, gpu: None, ..s.clone() }, gbuffer);
                }
                (s.clone(), s.out.gbuffer.clone())
            })
            .collect()
    }

    /// How the view is drawn now.
    pub(super) fn look(&self) -> Look<'_> {
        Look {
            channel: self.channel,
            overlay: self.overlay,
            exposure: self.exposure,
            reference: self.reference.as_ref().map(|r| &r.image),
            picked: self.pick(),
        }
    }

    /// Composes the last frame on the device it was rendered on, when the
    /// window shares that device and every side stayed there.
    #[cfg(feature = "gpu")]
    pub(super) fn compose_on_device(&mut self, gfx: &mut Gfx) {
        let Some(view) = gfx.device_view.as_mut().filter(|_| self.recompose) else { return };
        let look = self.look();
        match view.show(&gfx.device, &mut gfx.painter, &self.last, &look) {
            Ok(Some((id, c))) => {
                self.view_texture = Some(id);
                self.composite = Some(c);
                self.recompose = false;
                self.device_frames += 1;
            }
            Ok(None) => {}
            Err(e) => self.error_line = Some(format!("view on the device: {e}")),
        }
    }

    pub(super) fn compose(&mut self, ctx: &egui::Context) {
        if !self.recompose {
            return;
        }
        self.recompose = false;
        let Some(left) = self.last.first() else { return };
        let right = self.last.get(1).filter(|r| r.out.image.width == left.out.image.width && r.out.image.height == left.out.image.height);
        let c = compose(side(left), right.map(side), &self.look());
        let image = egui::ColorImage::from_rgba_unmultiplied([c.width as usize, c.height as usize], &c.rgba);
        match &mut self.texture {
            Some(t) => t.set(image, egui::TextureOptions::NEAREST),
            None => self.texture = Some(ctx.load_texture("vpl-view", image, egui::TextureOptions::NEAREST)),
        }
        self.view_texture = self.texture.as_ref().map(|t| t.id());
        self.composite = Some(c);
    }
}
