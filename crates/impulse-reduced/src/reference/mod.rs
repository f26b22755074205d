//! The full nonlinear reference model of a [`Mechanism`](crate::Mechanism): the truth for every
//! error figure, the source of linearisation points, and the speed baseline (the paper used
//! Vortex).
//!
//! - [`kinematics`]: joint motions, link poses of a configuration θ, exact body Jacobians, the
//!   loop-closure residual and its Jacobian;
//! - [`linear`]: the linearised constrained statics (joint springs + loop closure) and its
//!   Schur complement at the end effectors, the exact operational-space accelerability
//!   `J M⁻¹ Jᵀ` (projected on the loop-closure null space);
//! - [`dynamics`]: the full nonlinear dynamics, backward Euler in joint coordinates (free base
//!   included) with loop closure at position level, solved by Newton;
//! - [`statics`]: the nonlinear static equilibrium under end-effector loads, by Newton on the
//!   force balance with loop-closure constraints (KKT, truncated SVD for redundant loops);
//! - `tangent`: the statics' equations and their exact Newton tangent (second-order
//!   kinematics from the joints' spatial screws).

pub mod dynamics;
pub mod kinematics;
pub mod linear;
pub mod statics;
pub(crate) mod tangent;

pub use dynamics::{FullOptions, FullSim, FullStepReport};
pub use kinematics::{Configuration, joint_motion};
pub use linear::{JointMatrix, LinearStatics};
pub use statics::{Load, StaticOptions, StaticSolution, solve_statics};
