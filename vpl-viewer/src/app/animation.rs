//! The animation: playing the sequence, its frames, and a light moved by
//! hand.

use super::*;

/// The animation: the sequence's frames, playing them, and lights moved by hand.
pub(super) struct Animation {
    pub(super) frame_count: u32,
    pub(super) anim_frame: u32,
    pub(super) playing: bool,
    pub(super) play_clock: f64,
    pub(super) follow_camera: bool,
    pub(super) manual_lights: Option<Vec<Light>>,
    pub(super) lights_version: u64,
    pub(super) scene_cache: Option<((u32, u64), Arc<Scene>)>,
}

impl State {
    /// Advances the animation and the keyboard flight by the time since the last tick.
    pub(super) fn tick(&mut self, ctx: &egui::Context) {
        let now = Instant::now();
        let dt = (now - self.report.last_tick).as_secs_f32().min(0.1);
        self.report.last_tick = now;
        if self.rec.recording.is_some() {
            let pose = self.pose();
            if let Some((start, r)) = &mut self.rec.recording {
                r.push((now - *start).as_secs_f32(), pose);
            }
        }
        if self.anim.playing
            && let Some(seq) = &self.world.setup.sequence
        {
            self.anim.play_clock += dt as f64;
            let f = ((self.anim.play_clock * seq.fps as f64) as u64 % self.anim.frame_count as u64) as u32;
            if f != self.anim.anim_frame {
                self.set_anim_frame(f);
            }
        }
        if ctx.wants_keyboard_input() {
            return;
        }
        let (mut f, mut r, mut u, fast) = ctx.input(|i| {
            let k = |key| if i.key_down(key) { 1.0f32 } else { 0.0 };
            (k(egui::Key::W) - k(egui::Key::S), k(egui::Key::D) - k(egui::Key::A), k(egui::Key::E) - k(egui::Key::Q), i.modifiers.shift)
        });
        if f != 0.0 || r != 0.0 || u != 0.0 {
            let step = self.world.speed * dt * if fast { 4.0 } else { 1.0 };
            f *= step;
            r *= step;
            u *= step;
            self.world.cam.fly(f, r, u);
            self.changed(false);
        }
    }

    pub(super) fn set_anim_frame(&mut self, f: u32) {
        self.anim.anim_frame = f.min(self.anim.frame_count - 1);
        if self.anim.follow_camera
            && let Ok(c) = self.world.setup.camera_at_frame(self.anim.anim_frame)
        {
            self.world.cam = FlyCamera::from_camera(&c);
        }
        self.changed(false);
    }

    /// Keeps redrawing without input: keys held, an animation playing, a
    /// frame in flight is answered by a wake-up instead.
    pub(super) fn wants_ticks(&self, ctx: &egui::Context) -> bool {
        self.anim.playing
            || ctx.input(|i| {
                [egui::Key::W, egui::Key::A, egui::Key::S, egui::Key::D, egui::Key::Q, egui::Key::E].iter().any(|k| i.key_down(*k))
            })
    }

    /// Moves the first point or spot light in the view plane by a drag of
    /// `(dx, dy)` view pixels (turns a directional light).
    pub(super) fn move_light(&mut self, dx: f32, dy: f32) {
        let view_w = self.view_pixels().0.max(1.0);
        let lights = self.anim.manual_lights.get_or_insert_with(|| {
            self.anim.scene_cache.as_ref().map_or_else(|| self.world.setup.scene.extra_lights(), |(_, s)| s.extra_lights())
        });
        let right = self.world.cam.right();
        let up = right.cross(self.world.cam.forward).normalize_or(Vec3::Y);
        let fov = self.world.setup.camera.fov_deg.to_radians();
        let moved = lights.iter_mut().find_map(|l| match l {
            Light::Point { position, .. } | Light::Spot { position, .. } => {
                let dist = (*position - self.world.cam.origin).dot(self.world.cam.forward).abs().max(1e-3);
                let per_px = 2.0 * dist * (0.5 * fov).tan() / view_w;
                *position += (right * dx - up * dy) * per_px;
                Some(())
            }
            Light::Directional { direction, .. } => {
                let turn = vpl_core::glam::Quat::from_axis_angle(self.world.cam.up, -dx * 0.005)
                    * vpl_core::glam::Quat::from_axis_angle(right, -dy * 0.005);
                *direction = (turn * *direction).normalize_or(*direction);
                Some(())
            }
            _ => None,
        });
        if moved.is_some() {
            self.anim.lights_version += 1;
            self.changed(false);
        } else {
            self.report.status_line = Some("the scene has no point, spot or directional light to move".into());
        }
    }
}
