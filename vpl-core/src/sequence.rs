//! Animated sequences: camera and light keyframes, linearly interpolated.

use glam::Vec3;

/// A camera keyframe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraKey {
    /// Time in seconds.
    pub t: f32,
    /// Eye position.
    pub origin: Vec3,
    /// Point looked at.
    pub target: Vec3,
}

/// A light keyframe: a new position (point, spot) and/or direction (spot, sun).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightKey {
    /// Index into the scene's non-area lights (the `[[lights]]` entries).
    pub light: usize,
    /// Time in seconds.
    pub t: f32,
    /// New position, if the key moves the light.
    pub position: Option<Vec3>,
    /// New direction, if the key turns the light.
    pub direction: Option<Vec3>,
}

/// The most frames a scene file's sequence may have: 10⁶, over nine hours
/// at 30 fps (the SMC paper's sequences have 720–750).
pub const MAX_FRAMES: u32 = 1_000_000;

/// An animation: frames at `fps` for `duration` seconds.
#[derive(Clone, Debug, PartialEq)]
pub struct Sequence {
    /// Frames per second.
    pub fps: f32,
    /// Length in seconds.
    pub duration: f32,
    /// Camera keys sorted by time (may be empty: the camera stays).
    pub camera: Vec<CameraKey>,
    /// Light keys sorted by time.
    pub lights: Vec<LightKey>,
}

/// Linear interpolation of `f` over keys sorted by `t`, clamped at the ends.
fn interpolate<K>(keys: &[&K], t: f32, time: impl Fn(&K) -> f32, value: impl Fn(&K) -> Vec3) -> Option<Vec3> {
    let first = keys.first()?;
    if t <= time(first) {
        return Some(value(first));
    }
    for w in keys.windows(2) {
        let (a, b) = (w[0], w[1]);
        if t <= time(b) {
            let span = time(b) - time(a);
            let s = if span > 0.0 { (t - time(a)) / span } else { 1.0 };
            return Some(value(a).lerp(value(b), s));
        }
    }
    keys.last().map(|k| value(k))
}

impl Sequence {
    /// Number of frames: the first at t = 0, then one every 1/fps, and the
    /// last at t = `duration` exactly, so `⌈duration · fps⌉ + 1` (a
    /// duration of 3 s at 2 fps has 7 frames, t = 0, 0.5, …, 3; the last
    /// interval is shorter when duration · fps is not a whole number).
    pub fn frame_count(&self) -> u32 {
        let n = self.duration * self.fps;
        // A whole number that rounding put a hair above itself stays whole.
        let intervals = if (n - n.round()).abs() <= 1e-4 * n.max(1.0) { n.round() } else { n.ceil() };
        (intervals.max(0.0) as u32).saturating_add(1)
    }

    /// Time of frame `f` in seconds: f/fps, and `duration` for the last.
    pub fn time(&self, frame: u32) -> f32 {
        (frame as f32 / self.fps).min(self.duration)
    }

    /// Camera (origin, target) at time `t`, if the sequence moves the camera.
    pub fn camera_at(&self, t: f32) -> Option<(Vec3, Vec3)> {
        let keys: Vec<&CameraKey> = self.camera.iter().collect();
        let o = interpolate(&keys, t, |k| k.t, |k| k.origin)?;
        let g = interpolate(&keys, t, |k| k.t, |k| k.target)?;
        Some((o, g))
    }

    /// Position and direction of light `light` at time `t` (each `None` if no key sets it).
    pub fn light_at(&self, light: usize, t: f32) -> (Option<Vec3>, Option<Vec3>) {
        let pos: Vec<&LightKey> = self.lights.iter().filter(|k| k.light == light && k.position.is_some()).collect();
        let dir: Vec<&LightKey> = self.lights.iter().filter(|k| k.light == light && k.direction.is_some()).collect();
        let p = interpolate(&pos, t, |k| k.t, |k| k.position.unwrap_or_default());
        let d = interpolate(&dir, t, |k| k.t, |k| k.direction.unwrap_or_default()).map(|d| d.normalize_or_zero());
        (p, d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The last frame reaches the last key: 3 s at 2 fps is t = 0 … 3.
    #[test]
    fn the_last_frame_is_at_the_end() {
        let key = |t, x| CameraKey { t, origin: Vec3::new(x, 0.0, 0.0), target: Vec3::Z };
        let s = Sequence { fps: 2.0, duration: 3.0, camera: vec![key(0.0, 0.0), key(3.0, 6.0)], lights: vec![] };
        assert_eq!(s.frame_count(), 7);
        let times: Vec<f32> = (0..7).map(|f| s.time(f)).collect();
        assert_eq!(times, [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0]);
        assert_eq!(s.camera_at(s.time(6)).unwrap().0.x, 6.0);
        // 2.2 s at 2 fps: t = 0, 0.5, …, 2.0 and 2.2.
        let odd = Sequence { duration: 2.2, ..s.clone() };
        assert_eq!(odd.frame_count(), 6);
        assert_eq!(odd.time(5), 2.2);
        // 20 s at 30 fps: 601 frames, though 20 · 30 in f32 is not exactly 600.
        let long = Sequence { fps: 30.0, duration: 20.0, ..s };
        assert_eq!(long.frame_count(), 601);
        assert_eq!(long.time(600), 20.0);
    }

    #[test]
    fn interpolates_and_clamps() {
        let s = Sequence {
            fps: 30.0,
            duration: 2.0,
            camera: vec![
                CameraKey { t: 0.0, origin: Vec3::ZERO, target: Vec3::Z },
                CameraKey { t: 2.0, origin: Vec3::new(2.0, 0.0, 0.0), target: Vec3::Z },
            ],
            lights: vec![LightKey { light: 0, t: 1.0, position: Some(Vec3::Y), direction: None }],
        };
        assert_eq!(s.frame_count(), 61);
        assert_eq!(s.time(60), 2.0);
        assert_eq!(s.camera_at(1.0).unwrap().0, Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(s.camera_at(5.0).unwrap().0, Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(s.light_at(0, 0.0).0, Some(Vec3::Y));
        assert_eq!(s.light_at(1, 0.0), (None, None));
    }
}
