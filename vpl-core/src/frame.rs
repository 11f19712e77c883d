//! The per-frame context that the stages of a VPL renderer read.

use crate::camera::Camera;
use crate::gbuffer::GBuffer;
use crate::image::Image;
use crate::scene::Scene;

/// What a frame's stages read: the scene and camera at this frame's time,
/// the frame index and seed that key random streams, the G-buffer of
/// camera-visible points, and the previous frame's image, if any.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// The scene, lights placed for this frame.
    pub scene: &'a Scene,
    /// The camera of this frame.
    pub camera: &'a Camera,
    /// Time in seconds since the start of the sequence.
    pub time: f32,
    /// Frame index (part of random-stream keys where a sampler wants fresh numbers per frame).
    pub index: u64,
    /// Seed of all random streams.
    pub seed: u64,
    /// Camera-visible points of this frame.
    pub gbuffer: &'a GBuffer,
    /// The image of the previous frame (samplers that adapt to it read it).
    pub previous: Option<&'a Image>,
}
