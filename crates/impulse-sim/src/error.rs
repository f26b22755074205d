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
    /// A value in the scene, or given to a world, is out of range.
    #[error("{what}: field `{field}`: {problem}")]
    Invalid {
        /// The body, material pair, `scene`, `world` or the call.
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
    /// Two bodies overlap by more than the collision epsilon (placed so at the start, added
    /// or moved so by a program). Touching, or overlapping by less, is contact.
    #[error(
        "bodies \"{a}\" and \"{b}\" overlap by {depth:.3e}, more than ε_c = {collision_epsilon:.3e}; \
         move them apart (touching is fine)"
    )]
    Overlap {
        /// First body.
        a: String,
        /// Second body.
        b: String,
        /// Penetration depth (the smallest translation that separates them).
        depth: f64,
        /// The world's ε_c.
        collision_epsilon: f64,
    },
    /// A body handle whose body has been removed (or that belongs to another world).
    #[error("no body {handle} in this world (removed?)")]
    UnknownBody {
        /// The handle, as `#slot.generation`.
        handle: String,
    },
    /// A collision involving a multibody link could not be resolved (`crate::articulated`).
    #[error("link collision: {0}")]
    LinkCollision(String),
    /// The simulation cannot continue.
    #[error("t = {time}: {message}")]
    Runtime {
        /// Simulated time.
        time: f64,
        /// What went wrong (naming the bodies).
        message: String,
    },
}
