//! Errors of the progressive renderer.

/// What can go wrong setting up a progressive render.
#[derive(Debug, thiserror::Error)]
pub enum ProgressiveError {
    /// The scene has no light.
    #[error("scene '{0}' has no light: nothing to render")]
    NoLights(String),
    /// A setting is out of range.
    #[error("{0}")]
    Config(String),
}
