//! The simulator's error type.

use std::path::PathBuf;

/// Why a scene could not be loaded or a world could not go on.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A scene file could not be read.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's message.
        message: String,
    },
    /// The text is not a valid scene (RON syntax, unknown or missing field, wrong type).
    #[error("{source_name}: {message}")]
    Parse {
        /// The file or text the scene came from.
        source_name: String,
        /// RON's message, with line and column.
        message: String,
    },
    /// A value in the scene is out of range.
    #[error("{what}: field `{field}`: {problem}")]
    Invalid {
        /// The body, material pair or `scene`.
        what: String,
        /// The field.
        field: String,
        /// What is wrong with it.
        problem: String,
    },
    /// A body's geometry or mass could not be built (non-convex hull input, degenerate mesh…).
    #[error("body \"{body}\": {message}")]
    Geometry {
        /// The body.
        body: String,
        /// What went wrong.
        message: String,
    },
    /// Two bodies overlap or lie closer than the collision epsilon at the start.
    #[error("bodies \"{a}\" and \"{b}\" {problem} at the start; move them apart")]
    InitialOverlap {
        /// First body.
        a: String,
        /// Second body.
        b: String,
        /// "overlap" or "are closer than ε_c (distance …)".
        problem: String,
    },
    /// The simulation cannot continue.
    #[error("t = {time}: {message}")]
    Runtime {
        /// Simulated time.
        time: f64,
        /// What went wrong (naming the bodies).
        message: String,
    },
}
