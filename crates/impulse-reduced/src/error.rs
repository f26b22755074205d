//! The error type of `impulse-reduced`: every failure names what is wrong and where (the link,
//! joint or end effector by its name).

use thiserror::Error;

/// Everything that can go wrong while reading, validating or reducing a mechanism.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum Error {
    /// The RON text could not be parsed into a `Mechanism(...)`.
    #[error("mechanism file: {0}")]
    Parse(String),
    /// Two links share a name.
    #[error("link `{0}` is declared twice")]
    DuplicateLink(String),
    /// Two joints share a name.
    #[error("joint `{0}` is declared twice")]
    DuplicateJoint(String),
    /// A joint names a link that does not exist.
    #[error("joint `{joint}`: unknown {side} link `{link}`")]
    UnknownLink {
        /// The joint.
        joint: String,
        /// "parent" or "child".
        side: &'static str,
        /// The missing name.
        link: String,
    },
    /// A joint connects a link to itself.
    #[error("joint `{0}` connects a link to itself")]
    SelfJoint(String),
    /// A number is NaN or infinite.
    #[error("{owner}: `{field}` is not finite")]
    NonFinite {
        /// "link `a`", "joint `j`", "load" …
        owner: String,
        /// The field.
        field: &'static str,
    },
    /// A value is out of its range (negative mass, zero axis, non-positive radius …).
    #[error("{owner}: `{field}` {reason}")]
    OutOfRange {
        /// "link `a`", "joint `j`" …
        owner: String,
        /// The field.
        field: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// A joint declares a free direction with zero or negative compliance.
    #[error(
        "joint `{joint}`: direction {direction} is declared free but its compliance is {value} \
         (must be > 0; make the direction rigid by choosing another joint kind)"
    )]
    NonPositiveCompliance {
        /// The joint.
        joint: String,
        /// Index of the free direction (0-based, in the joint's order).
        direction: usize,
        /// The offending compliance.
        value: f64,
    },
    /// A per-direction list has the wrong length.
    #[error(
        "joint `{joint}`: `{field}` has {got} values, the joint has {expected} free directions (give 1 or {expected})"
    )]
    CountMismatch {
        /// The joint.
        joint: String,
        /// The field.
        field: &'static str,
        /// The joint's number of free directions.
        expected: usize,
        /// The number given.
        got: usize,
    },
    /// Damping is zero on some free directions and positive on others.
    #[error(
        "joint `{0}`: damping must be positive on every free direction of every joint, or zero everywhere"
    )]
    MixedDamping(String),
    /// No link is without a parent, or more than one is.
    #[error("the mechanism needs exactly one base (a link that is no joint's child); found {0}")]
    Base(String),
    /// A link cannot be reached from the base.
    #[error("link `{0}` cannot be reached from the base")]
    Unreachable(String),
    /// The joint graph has a directed cycle: the walk from the base cannot order it.
    #[error(
        "unwalkable loop: joint `{0}` closes a directed cycle (orient the loop's joints away from the base)"
    )]
    Cycle(String),
    /// An end effector is unknown, repeated, the base, or not a leaf of the walk.
    #[error("end effector `{link}`: {reason}")]
    EndEffector {
        /// The link.
        link: String,
        /// What is wrong.
        reason: String,
    },
    /// The rank found by the truncated SVD disagrees with the rank expected from the joints.
    #[error(
        "rank check failed at {at}: truncated SVD gives rank {found}, the joints give {expected} \
         (threshold {tolerance:e}; set it with `impulse reduce --tsvd` or `Tsvd::with_relative`, \
         or check the mechanism)"
    )]
    Rank {
        /// Where (e.g. "end-effector compliance").
        at: String,
        /// Rank found.
        found: usize,
        /// Rank expected.
        expected: usize,
        /// The tolerance used.
        tolerance: f64,
    },
    /// The threshold keeps an end-effector direction whose compliance is below the round-off
    /// of the walk's compliance: the model cannot resolve it.
    #[error(
        "end-effector compliance: at this threshold the joints' motions keep {rank} directions, \
         but the smallest has compliance {compliance:.2e} of the largest, at or below the \
         round-off of C ({floor:.2e} of it): the walk cannot resolve it; use --tsvd above \
         {floor:.2e} to treat it as rigid"
    )]
    Unresolved {
        /// Directions the threshold keeps.
        rank: usize,
        /// The smallest kept direction's compliance, relative to the largest.
        compliance: f64,
        /// The round-off of C relative to its largest singular value.
        floor: f64,
    },
    /// A dense factorisation failed (non-finite input).
    #[error("linear algebra failed: {0}")]
    LinearAlgebra(String),
    /// The nonlinear static solver did not converge.
    #[error(
        "static solve did not converge: residual {residual:e} after {iterations} Newton iterations"
    )]
    NoConvergence {
        /// Final residual norm.
        residual: f64,
        /// Iterations used.
        iterations: usize,
    },
    /// The nonlinear statics could not follow the equilibrium to the full load.
    #[error(
        "static solve found no equilibrium: {reason}; stopped at load fraction {fraction:.6} \
         (increment {step:.3e} refused); worst equation: {worst}; relative residual of the \
         last attempt, per Newton iteration: [{}]",
        scientific(.history)
    )]
    NoEquilibrium {
        /// Fraction of the load path reached (0 = the start's loads, 1 = the full load).
        fraction: f64,
        /// The last load increment tried (fraction of the path).
        step: f64,
        /// Why the last increment failed.
        reason: String,
        /// The equation furthest from balance: a joint coordinate's force or a loop's
        /// closure, named.
        worst: String,
        /// The relative residual after each Newton iteration of the last attempt.
        history: Vec<f64>,
    },
    /// An argument of a call is malformed (wrong length, unknown name, NaN).
    #[error("{0}")]
    Argument(String),
    /// The mechanism is larger than the limit a build was given
    /// ([`crate::desc::MAX_DOF`] by default), checked before any work.
    #[error(
        "the mechanism has {links} links and {dof} joint degrees of freedom, over the limit of \
         {limit}: its reduction builds dense matrices of dof² entries and factorises them in \
         time growing as dof³; raise the limit with `impulse reduce --max-dof N` or \
         `MechanismDesc::build_with_max_dof`"
    )]
    TooLarge {
        /// Links declared.
        links: usize,
        /// Joint degrees of freedom declared (saturating sum).
        dof: usize,
        /// The limit the build was given.
        limit: usize,
    },
}

/// `[1.234e-3, …]`-style list of the numbers (three decimals of mantissa).
fn scientific(values: &[f64]) -> String {
    values
        .iter()
        .map(|x| format!("{x:.3e}"))
        .collect::<Vec<_>>()
        .join(", ")
}
