//! Recording the camera-and-light path of a session as a scene file's
//! animation (`[sequence]`), so that a sequence for Table 1 can be authored
//! by flying through the scene.
//!
//! The window hands the recorder the pose (camera origin and target, and
//! each `[[lights]]` entry's position and direction) at every tick. A key
//! is kept at most every 1/fps seconds while the pose changes; when it
//! starts changing after standing still, a key at the last still instant
//! is kept first, so that the linear interpolation of the keys holds still
//! where the session did. Lights that never moved get no keys.
//!
//! ```
//! use vpl_core::glam::Vec3;
//! use vpl_viewer::record::{Pose, Recorder};
//!
//! let mut r = Recorder::new(10.0);
//! let at = |x: f32| Pose { origin: Vec3::new(x, 1.0, 5.0), target: Vec3::ZERO, lights: vec![] };
//! r.push(0.0, at(0.0));
//! r.push(0.5, at(0.0)); // standing still
//! r.push(1.0, at(1.0)); // moving
//! let seq = r.finish(1.2).unwrap();
//! assert_eq!(seq.camera.len(), 3);
//! assert_eq!(seq.camera[1].t, 0.5);
//! assert_eq!(seq.duration, 1.2);
//! ```

use glam::Vec3;
use vpl_core::scene_file::{CameraKeySpec, LightKeySpec, SequenceSpec};

/// Where the camera and the lights are at an instant.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// Camera position.
    pub origin: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Per `[[lights]]` entry: its position (point, spot) and direction
    /// (spot, sun), `None` where the light has none.
    pub lights: Vec<(Option<Vec3>, Option<Vec3>)>,
}

/// Collects poses into keys.
#[derive(Clone, Debug)]
pub struct Recorder {
    fps: f32,
    keys: Vec<(f32, Pose)>,
    /// The pose of the last tick, when it was not kept as a key.
    still: Option<(f32, Pose)>,
}

impl Recorder {
    /// A recorder whose animation plays at `fps` frames per second (keys at
    /// most that often); a rate that is not positive is 30.
    pub fn new(fps: f32) -> Recorder {
        Recorder { fps: if fps.is_finite() && fps > 0.0 { fps } else { 30.0 }, keys: Vec::new(), still: None }
    }

    /// Keys so far.
    pub fn len(&self) -> usize {
        self.keys.len()
    }

    /// Whether no pose has been given.
    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    /// The pose at `t` seconds since the recording began (times must not
    /// go back; a pose with a non-finite value is ignored).
    pub fn push(&mut self, t: f32, pose: Pose) {
        let finite = pose.origin.is_finite()
            && pose.target.is_finite()
            && pose.lights.iter().all(|(p, d)| p.is_none_or(|p| p.is_finite()) && d.is_none_or(|d| d.is_finite()));
        if !finite || !t.is_finite() {
            return;
        }
        let Some((t_last, last)) = self.keys.last() else {
            self.keys.push((t.max(0.0), pose));
            return;
        };
        if t < *t_last {
            return;
        }
        if pose == *last {
            self.still = Some((t, pose));
            return;
        }
        // It moves again after standing still: hold the still pose until then.
        if let Some((ts, p)) = self.still.take()
            && p == *last
            && ts > *t_last
        {
            self.keys.push((ts, p));
        }
        let t_last = self.keys.last().map_or(0.0, |k| k.0);
        if t - t_last >= 1.0 / self.fps - 1e-6 {
            self.keys.push((t, pose));
        } else {
            self.still = Some((t, pose));
        }
    }

    /// The animation up to `t_end` seconds, in the frame the poses were
    /// given in (`None` before the first pose). The last pose given is its
    /// last key.
    pub fn finish(mut self, t_end: f32) -> Option<SequenceSpec> {
        if let Some((t, p)) = self.still.take()
            && self.keys.last().is_some_and(|(_, last)| *last != p)
        {
            self.keys.push((t, p));
        }
        let t_last = self.keys.last()?.0;
        // The file wants a positive length: at least one frame.
        let duration = t_end.max(t_last).max(1.0 / self.fps);
        let camera = self.keys.iter().map(|(t, p)| CameraKeySpec { t: *t, origin: p.origin.into(), target: p.target.into() }).collect();
        let n_lights = self.keys.iter().map(|(_, p)| p.lights.len()).min().unwrap_or(0);
        let mut lights = Vec::new();
        for l in 0..n_lights {
            let first = self.keys[0].1.lights[l];
            if self.keys.iter().all(|(_, p)| p.lights[l] == first) {
                continue;
            }
            for (t, p) in &self.keys {
                let (position, direction) = p.lights[l];
                lights.push(LightKeySpec { light: l, t: *t, position: position.map(Into::into), direction: direction.map(Into::into) });
            }
        }
        Some(SequenceSpec { fps: self.fps, duration, camera, lights })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(x: f32, light: Vec3) -> Pose {
        Pose { origin: Vec3::new(x, 0.0, 0.0), target: Vec3::Z, lights: vec![(Some(light), None), (None, Some(Vec3::Y))] }
    }

    #[test]
    fn keys_follow_the_moves_and_hold_the_stops() {
        let mut r = Recorder::new(10.0);
        // Moving at 60 ticks a second: keys at most every 0.1 s.
        for i in 0..=30 {
            r.push(i as f32 / 60.0, pose(i as f32, Vec3::ZERO));
        }
        assert!(r.len() <= 6 && r.len() >= 5, "{} keys", r.len());
        // Still for a second, then the light moves.
        for i in 31..=90 {
            r.push(i as f32 / 60.0, pose(30.0, Vec3::ZERO));
        }
        r.push(1.6, pose(30.0, Vec3::X));
        let seq = r.finish(2.0).unwrap();
        assert_eq!(seq.duration, 2.0);
        let last = seq.camera.last().unwrap();
        assert_eq!(last.origin, [30.0, 0.0, 0.0]);
        // The key at the end of the stop: t = 1.5, before the light moved.
        assert!(seq.camera.iter().any(|k| k.t == 1.5 && k.origin == [30.0, 0.0, 0.0]));
        // Light 0 moved and has keys; light 1 did not and has none.
        assert!(seq.lights.iter().all(|k| k.light == 0));
        assert_eq!(seq.lights.last().unwrap().position, Some([1.0, 0.0, 0.0]));
        assert_eq!(seq.lights.len(), seq.camera.len());
        // The keys interpolate to the session's path at the stop.
        let s = vpl_core::sequence::Sequence {
            fps: seq.fps,
            duration: seq.duration,
            camera: seq
                .camera
                .iter()
                .map(|k| vpl_core::sequence::CameraKey { t: k.t, origin: k.origin.into(), target: k.target.into() })
                .collect(),
            lights: vec![],
        };
        assert_eq!(s.camera_at(1.2).unwrap().0.x, 30.0);
    }

    #[test]
    fn nothing_recorded_is_no_animation_and_bad_poses_are_ignored() {
        assert!(Recorder::new(30.0).finish(1.0).is_none());
        let mut r = Recorder::new(f32::NAN);
        r.push(0.0, pose(f32::NAN, Vec3::ZERO));
        assert!(r.is_empty());
        r.push(0.0, pose(1.0, Vec3::ZERO));
        let seq = r.finish(0.0).unwrap();
        assert_eq!((seq.fps, seq.camera.len()), (30.0, 1));
        assert!(seq.duration > 0.0);
    }
}
