//! The error type of this crate.

/// Why a model could not be built, a URDF could not be imported, or a computation could not be
/// carried out. Every variant that concerns a part of the model names the link or joint.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MultibodyError {
    /// A link's mass properties are unusable: non-finite, negative or zero mass where a moving
    /// body needs mass, a centre of mass that is not finite, or a rotational inertia that is not
    /// symmetric positive (semi-)definite.
    #[error("link `{link}`: invalid inertia: {reason}")]
    InvalidInertia {
        /// The link's name.
        link: String,
        /// What is wrong.
        reason: String,
    },
    /// A joint's data is unusable: a non-finite or zero-length axis, a non-finite origin, or a
    /// negative or non-finite spring, damper or friction constant.
    #[error("joint `{joint}`: {reason}")]
    InvalidJoint {
        /// The joint's name.
        joint: String,
        /// What is wrong.
        reason: String,
    },
    /// A joint names a parent or child link that does not exist.
    #[error("joint `{joint}` refers to unknown link `{link}`")]
    UnknownLink {
        /// The joint's name.
        joint: String,
        /// The missing link's name.
        link: String,
    },
    /// Two links or two joints share a name.
    #[error("duplicate {kind} name `{name}`")]
    DuplicateName {
        /// `"link"` or `"joint"`.
        kind: &'static str,
        /// The repeated name.
        name: String,
    },
    /// A link is the child of more than one joint (the structure is not a tree).
    #[error("link `{link}` is the child of two joints, `{first}` and `{second}`")]
    MultipleParents {
        /// The link's name.
        link: String,
        /// The first joint naming it as child.
        first: String,
        /// The second joint naming it as child.
        second: String,
    },
    /// The joints contain a closed loop (the structure is not a tree); the link is on it.
    #[error("kinematic loop through link `{link}`: multibodies must be trees")]
    Cycle {
        /// A link on the loop.
        link: String,
    },
    /// The model has no link at all, or every link has a parent (no root).
    #[error("the model has no root link")]
    NoRoot,
    /// More than one link has no parent joint: the links do not form one connected tree.
    #[error("the model has several root links (`{first}`, `{second}`): links must form one tree")]
    MultipleRoots {
        /// One root link.
        first: String,
        /// Another root link.
        second: String,
    },
    /// A URDF feature this crate does not model (e.g. a floating, planar or mimic joint).
    #[error("joint `{joint}`: unsupported {what}")]
    Unsupported {
        /// The joint's name.
        joint: String,
        /// What is unsupported.
        what: String,
    },
    /// The URDF text could not be read or parsed.
    #[error("URDF: {0}")]
    Urdf(String),
    /// A vector argument has the wrong length.
    #[error("{what}: expected {expected} values, got {got}")]
    DimensionMismatch {
        /// Which argument.
        what: &'static str,
        /// The length the model needs.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// A link, joint or controller index or name that the model does not have.
    #[error("unknown {kind} `{name}`")]
    UnknownName {
        /// `"link"`, `"joint"` or `"controller"`.
        kind: &'static str,
        /// The name or index given.
        name: String,
    },
    /// An argument is out of its valid range (non-finite, negative step, zero period, ...).
    #[error("invalid {what}: {reason}")]
    InvalidArgument {
        /// Which argument.
        what: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// A 6×6 articulated inertia (floating base) was not numerically positive definite; only
    /// possible for non-finite states or inertias far outside the validated range.
    #[error("articulated inertia of link `{link}` is not positive definite")]
    SingularInertia {
        /// The link's name.
        link: String,
    },
    /// The adaptive integrator needed a step below its minimum (the system is stiff or the state
    /// became non-finite).
    #[error("step size {step:e} s fell below the minimum {min_step:e} s at t = {time} s")]
    StepSizeUnderflow {
        /// Simulation time (s).
        time: f64,
        /// The step that would have been needed (s).
        step: f64,
        /// The configured minimum (s).
        min_step: f64,
    },
    /// Joint stops struck at one instant kept driving each other
    /// ([`crate::limit::MAX_STOPS_PER_INSTANT`] stops without time advancing).
    #[error("joint `{joint}`: {count} stops at t = {time} s without time advancing")]
    LimitStall {
        /// The joint of the last stop.
        joint: String,
        /// Simulation time (s).
        time: f64,
        /// Stops resolved at that instant.
        count: usize,
    },
    /// The state became non-finite during integration.
    #[error("the state became non-finite at t = {time} s")]
    NonFiniteState {
        /// Simulation time (s).
        time: f64,
    },
}
