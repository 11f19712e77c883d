//! The scripted session: its steps, run one a frame, and the screenshots
//! it writes.

use super::*;

/// The scripted session: its steps, the frames it waits for, its screenshots, and whether it ends.
pub(super) struct Session {
    pub(super) scripted: bool,
    pub(super) script: VecDeque<Step>,
    pub(super) waiting: u32,
    pub(super) pending_shot: Option<PathBuf>,
    pub(super) shots: u32,
    pub(super) quit: bool,
}

impl State {
    /// Runs the script's steps up to the next wait (after the first frame).
    pub(super) fn advance_script(&mut self) {
        if !self.session.scripted || self.report.frames_shown == 0 || self.session.pending_shot.is_some() || self.session.quit {
            return;
        }
        while self.session.waiting == 0 {
            let Some(step) = self.session.script.pop_front() else {
                self.session.quit = true;
                return;
            };
            match step {
                Step::Frames(n) => self.session.waiting = n,
                Step::Sampler(name) => {
                    if !self.check_sampler(&name) {
                        return;
                    }
                    self.shown.sides[0] = name;
                    self.changed(true);
                }
                Step::Split(name) => {
                    if let Some(name) = name {
                        if !self.check_sampler(&name) {
                            return;
                        }
                        self.shown.sides[1] = name;
                        self.shown.split = true;
                    } else {
                        self.shown.split = false;
                    }
                    self.changed(true);
                }
                Step::Overlay(o) => {
                    self.shown.overlay = o;
                    self.picture.recompose = true;
                }
                Step::Show(c) => {
                    self.shown.channel = c;
                    self.picture.recompose = true;
                }
                Step::Mode(m) => {
                    self.shown.mode = m;
                    self.changed(true);
                }
                Step::Vpls(n) => {
                    self.shown.vpls = n;
                    self.changed(true);
                }
                Step::Orbit(yaw, pitch) => {
                    self.world.cam.orbit(yaw.to_radians(), pitch.to_radians());
                    self.changed(true);
                }
                Step::Reference(on) => self.set_reference(on),
                Step::Pick(None) => {
                    self.inspect.picked = None;
                    self.refresh_map();
                }
                Step::Pick(Some((fx, fy))) => {
                    let Some(left) = self.picture.last.first() else { continue };
                    let (w, h) = (left.out.image.width as f32, left.out.image.height as f32);
                    self.pick_at(fx * w, fy * h, f32::INFINITY);
                    if self.inspect.picked.is_none() {
                        self.fail(ViewerError::Render(format!("pick {fx} {fy}: the view shows no VPL")));
                        return;
                    }
                }
                Step::RecordStart => self.record_start(),
                Step::RecordStop(path) => {
                    if let Err(e) = self.record_stop(&path) {
                        self.fail(e);
                        return;
                    }
                }
                Step::Screenshot(path) => {
                    self.session.pending_shot = Some(path);
                    return;
                }
                Step::Quit => {
                    self.session.script.clear();
                    self.session.quit = true;
                    return;
                }
            }
        }
    }

    pub(super) fn check_sampler(&mut self, name: &str) -> bool {
        if self.world.names.iter().any(|n| n == name) {
            return true;
        }
        self.fail(ViewerError::UnknownSampler { name: name.into(), known: self.world.names.join(", ") });
        false
    }

    /// Writes a screenshot: the window's pixels, the view's values, and
    /// where the view and the split lie in the window.
    pub(super) fn write_shot(&self, path: &Path, window: (u32, u32, Vec<u8>)) -> Result<PathBuf, ViewerError> {
        let with = |ext: &str| {
            let mut s = OsString::from(path.as_os_str());
            s.push(ext);
            PathBuf::from(s)
        };
        let write_err = |p: &Path, e: &dyn std::fmt::Display| ViewerError::Write { path: p.to_path_buf(), reason: e.to_string() };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| write_err(dir, &e))?;
        }
        let (w, h, rgb) = window;
        let png = with(".png");
        vpl_scene_io::write_png_rgb8(&png, w, h, &rgb)?;
        let exr = with(".exr");
        match &self.picture.composite {
            Some(c) if c.hdr.on_host() => c.hdr.write_exr(&exr)?,
            // Composed on the device: the values come from the frames read back.
            Some(_) => {
                let hosted = self.on_host();
                if let Some((left, lg)) = hosted.first() {
                    let right = hosted.get(1).map(|(s, g)| SideFrame { gbuffer: g, ..side(s) });
                    let c = compose(SideFrame { gbuffer: lg, ..side(left) }, right, &self.look());
                    c.hdr.write_exr(&exr)?;
                }
            }
            None => {}
        }
        let ppp = self.picture.pixels_per_point;
        let view = self.picture.view_rect.map_or([0.0; 4], |r| [r.min.x * ppp, r.min.y * ppp, r.max.x * ppp, r.max.y * ppp]);
        let split =
            self.picture.composite.as_ref().and_then(|c| c.split_x.map(|s| view[0] + (s as f32 / c.width as f32) * (view[2] - view[0])));
        let quoted = |t: &str| format!("\"{}\"", t.replace('\\', "\\\\").replace('"', "\\\""));
        let sides: Vec<String> = self.picture.last.iter().map(|s| quoted(&s.spec.sampler)).collect();
        let pipelines: Vec<String> = self.picture.last.iter().map(|s| quoted(&s.pipeline)).collect();
        let res = self.picture.composite.as_ref().map_or((0, 0), |c| (c.width, c.height));
        let json = format!(
            "{{\n  \"window\": [{w}, {h}],\n  \"view\": [{:.1}, {:.1}, {:.1}, {:.1}],\n  \"split_x\": {},\n  \"render\": [{}, {}],\n  \"sides\": [{}],\n  \"pipelines\": [{}],\n  \"channel\": \"{}\",\n  \"overlay\": \"{}\",\n  \"frames\": {},\n  \"reference_passes\": {},\n  \"picked\": {},\n  \"shadow_map\": {}\n}}\n",
            view[0],
            view[1],
            view[2],
            view[3],
            split.map_or("null".to_string(), |s| format!("{s:.1}")),
            res.0,
            res.1,
            sides.join(", "),
            pipelines.join(", "),
            self.shown.channel.name(),
            self.shown.overlay.name(),
            self.report.frames_shown,
            self.inspect.reference.as_ref().map_or(0, |r| r.passes),
            self.inspect.picked.map_or("null".to_string(), |(k, slot)| format!("[{k}, {slot}]")),
            self.inspect.map_rect.map_or("null".to_string(), |r| format!(
                "[{:.1}, {:.1}, {:.1}, {:.1}]",
                r.min.x * ppp,
                r.min.y * ppp,
                r.max.x * ppp,
                r.max.y * ppp
            ))
        );
        let j = with(".json");
        vpl_core::image::write_atomic(&j, json.as_bytes())?;
        Ok(png)
    }
}
