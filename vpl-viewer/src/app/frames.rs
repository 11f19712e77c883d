//! The frames: the scene of the current animation frame and lights, jobs
//! to the render thread and its replies, and the view composed from them
//! (on the device when the frames stay there).

use super::*;

/// The render thread: the jobs sent to it, its replies, and the frame in flight.
pub(super) struct Link {
    pub(super) jobs: Sender<Job>,
    pub(super) replies: Receiver<Reply>,
    pub(super) generation: u64,
    pub(super) in_flight: Option<(u64, Arc<AtomicBool>, Instant)>,
    pub(super) stalled: bool,
}

/// The last frame and what shows it: the composed view, its textures, and the plots' history.
pub(super) struct Picture {
    pub(super) last: Vec<SideResult>,
    pub(super) composite: Option<Composite>,
    pub(super) recompose: bool,
    pub(super) texture: Option<egui::TextureHandle>,
    /// What the view draws: `texture`'s id, or the device view's.
    pub(super) view_texture: Option<egui::TextureId>,
    /// The window presents from the renderer's device: frames stay there.
    pub(super) resident: bool,
    /// Frames composed on the device.
    pub(super) device_frames: u64,
    pub(super) view_rect: Option<egui::Rect>,
    pub(super) pixels_per_point: f32,
    pub(super) history: [History; 2],
}

impl State {
    pub(super) fn scene(&mut self) -> Result<Arc<Scene>, ViewerError> {
        let key = (self.anim.anim_frame, self.anim.lights_version);
        if let Some((k, s)) = &self.anim.scene_cache
            && *k == key
        {
            return Ok(s.clone());
        }
        let (mut scene, _) = self.world.setup.frame(self.anim.anim_frame)?;
        if let Some(l) = &self.anim.manual_lights {
            scene = scene.with_lights(l.clone())?;
        }
        let scene = Arc::new(scene);
        self.anim.scene_cache = Some((key, scene.clone()));
        Ok(scene)
    }

    /// Sends the next job when none is in flight: frames render continuously.
    pub(super) fn submit(&mut self) {
        if self.link.in_flight.is_some() || self.link.stalled || self.session.quit {
            return;
        }
        let scene = match self.scene() {
            Ok(s) => s,
            Err(e) => {
                self.report.error_line = Some(e.to_string());
                self.link.stalled = true;
                return;
            }
        };
        let camera = match self.world.cam.camera(&self.world.setup.camera, self.resolution()) {
            Ok(c) => c,
            Err(e) => {
                self.report.error_line = Some(format!("camera: {e}"));
                self.link.stalled = true;
                return;
            }
        };
        let time = self.world.setup.sequence.as_ref().map_or(0.0, |s| s.time(self.anim.anim_frame));
        let cancel = Arc::new(AtomicBool::new(false));
        let reference = self.inspect.reference_on.then_some(ReferenceSpec {
            mode: self.shown.mode,
            max_depth: vpl_core::Budget::default().max_depth,
            budget: REFERENCE_BUDGET,
        });
        let job = Job { scene, camera, time, sides: self.specs(), cancel: cancel.clone(), reference, resident: self.picture.resident };
        if self.link.jobs.send(job).is_ok() {
            self.link.in_flight = Some((self.link.generation, cancel, Instant::now()));
        } else {
            self.fail(ViewerError::Render("the render thread stopped".into()));
        }
    }

    /// Takes the render thread's replies.
    pub(super) fn poll(&mut self) {
        loop {
            let reply = match self.link.replies.try_recv() {
                Ok(r) => r,
                Err(mpsc::TryRecvError::Empty) => break,
                Err(mpsc::TryRecvError::Disconnected) => {
                    self.link.in_flight = None;
                    self.fail(ViewerError::Render("the render thread stopped".into()));
                    break;
                }
            };
            let Some((generation, _, _)) = self.link.in_flight.take() else { continue };
            match reply {
                Reply::Frame { sides, reference } => {
                    let now = Instant::now();
                    self.report.first_frame_at.get_or_insert(now);
                    self.report.last_frame_at = Some(now);
                    self.report.frames_shown += 1;
                    if generation == self.link.generation {
                        self.session.waiting = self.session.waiting.saturating_sub(1);
                    }
                    for (h, s) in self.picture.history.iter_mut().zip(&sides) {
                        h.push(s);
                    }
                    self.picture.last = sides;
                    self.report.error_line = None;
                    self.picture.recompose = true;
                    match reference {
                        Some(Ok(r)) => self.inspect.reference = Some(r),
                        Some(Err(e)) => {
                            self.inspect.reference = None;
                            self.report.error_line = Some(e);
                        }
                        None => self.inspect.reference = None,
                    }
                    self.refresh_map();
                }
                Reply::Cancelled => {}
                Reply::Failed(e) => {
                    if self.session.scripted {
                        self.fail(ViewerError::Render(e.clone()));
                    }
                    self.report.error_line = Some(e);
                    if generation == self.link.generation {
                        self.link.stalled = true;
                    }
                }
            }
        }
    }

    /// The last frame's sides with their G-buffers on the host (read back
    /// where they stayed on the device).
    pub(super) fn on_host(&self) -> Vec<(SideResult, vpl_core::GBuffer)> {
        self.picture
            .last
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
            channel: self.shown.channel,
            overlay: self.shown.overlay,
            exposure: self.shown.exposure,
            reference: self.inspect.reference.as_ref().map(|r| &r.image),
            picked: self.pick(),
        }
    }

    /// Composes the last frame on the device it was rendered on, when the
    /// window shares that device and every side stayed there.
    #[cfg(feature = "gpu")]
    pub(super) fn compose_on_device(&mut self, gfx: &mut Gfx) {
        let Some(view) = gfx.device_view.as_mut().filter(|_| self.picture.recompose) else { return };
        let look = self.look();
        match view.show(&gfx.device, &mut gfx.painter, &self.picture.last, &look) {
            Ok(Some((id, c))) => {
                self.picture.view_texture = Some(id);
                self.picture.composite = Some(c);
                self.picture.recompose = false;
                self.picture.device_frames += 1;
            }
            Ok(None) => {}
            Err(e) => self.report.error_line = Some(format!("view on the device: {e}")),
        }
    }

    pub(super) fn compose(&mut self, ctx: &egui::Context) {
        if !self.picture.recompose {
            return;
        }
        self.picture.recompose = false;
        let Some(left) = self.picture.last.first() else { return };
        let right =
            self.picture.last.get(1).filter(|r| r.out.image.width == left.out.image.width && r.out.image.height == left.out.image.height);
        let c = compose(side(left), right.map(side), &self.look());
        let image = egui::ColorImage::from_rgba_unmultiplied([c.width as usize, c.height as usize], &c.rgba);
        match &mut self.picture.texture {
            Some(t) => t.set(image, egui::TextureOptions::NEAREST),
            None => self.picture.texture = Some(ctx.load_texture("vpl-view", image, egui::TextureOptions::NEAREST)),
        }
        self.picture.view_texture = self.picture.texture.as_ref().map(|t| t.id());
        self.picture.composite = Some(c);
    }
}
