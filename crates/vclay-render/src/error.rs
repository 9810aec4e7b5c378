//! The error type of `vclay-render`.

use std::path::PathBuf;
use thiserror::Error;

/// Everything that can go wrong while rendering or encoding a picture.
#[derive(Debug, Error)]
pub enum RenderError {
    /// Image size out of range (zero, or larger than [`crate::MAX_IMAGE_SIDE`]).
    #[error("invalid image size {width}x{height}: each side must be between 1 and {max}")]
    Size {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// Largest allowed side.
        max: u32,
    },
    /// A mesh of the scene is invalid (non-finite vertex, bad index, normal count).
    #[error("mesh {index}: {source}")]
    Mesh {
        /// 0-based index of the mesh in the scene.
        index: usize,
        /// What [`vclay_core::TriMesh::validate`] found.
        #[source]
        source: vclay_core::MeshError,
    },
    /// A point, polyline vertex or camera parameter is NaN or infinite.
    #[error("{what} is not finite")]
    NonFinite {
        /// What was not finite, e.g. `polyline 2, point 5`.
        what: String,
    },
    /// A camera that cannot produce a picture (eye at the target, up parallel to the view, ...).
    #[error("invalid camera: {0}")]
    Camera(String),
    /// The scene has nothing to draw, so no camera can frame it.
    #[error("the scene is empty: nothing to frame")]
    EmptyScene,
    /// An animation with no frames, or frames of different sizes.
    #[error("invalid animation: {0}")]
    Animation(String),
    /// Invalid plot data (no series, non-finite values, non-positive values on a log axis).
    #[error("invalid plot: {0}")]
    Plot(String),
    /// The PNG or GIF encoder failed.
    #[error("{}: cannot encode {format}: {message}", path.display())]
    Encode {
        /// The target file (or `<memory>`).
        path: PathBuf,
        /// `PNG` or `GIF`.
        format: &'static str,
        /// What the encoder said.
        message: String,
    },
    /// Writing the file failed (the previous file, if any, is untouched).
    #[error(transparent)]
    Io(#[from] vclay_io::IoError),
}
