//! # impulse-geom — layer 0 of the `impulse` workspace
//!
//! **Owns** the f64 mathematics every other crate stands on:
//! - rigid motions: [`Pose`], the SE(3) exponential and logarithm, adjoints ([`pose`], [`se3`]);
//! - spatial algebra for twists, wrenches and spatial inertias, one set of types shared by the
//!   impulse-based and the articulated-body code ([`se3`], [`spatial`]);
//! - shapes: the exact [`Sphere`] and [`Ellipsoid`], closed polygon meshes ([`PolyMesh`]) and convex polyhedra with
//!   the full feature topology a closest-features algorithm walks ([`ConvexPolyhedron`]), built
//!   from a convex hull ([`hull`]), from explicit faces, or as primitives;
//! - bounding volumes ([`Aabb`]) and reading/writing Wavefront OBJ meshes ([`obj`]).
//!
//! **Must not know** about mass, bodies, time, collisions, worlds or threads. It depends on glam,
//! thiserror and robust (exact orientation predicates for the hull) only. Mass properties live in
//! `impulse-massprops`, collision queries in `impulse-collide`.
//!
//! Conventions: SI units are not assumed (any consistent length unit works); every length
//! tolerance is relative to the size of the object it applies to (see [`tol`]). Twists and
//! wrenches are packed linear on top, angular below (Murray, Li & Sastry).
#![forbid(unsafe_code)]

pub mod aabb;
pub mod ellipsoid;
pub mod error;
pub mod hull;
pub mod mesh;
pub mod obj;
pub mod plane;
pub mod polyhedron;
pub mod pose;
pub mod primitives;
pub mod se3;
pub mod spatial;
pub mod sphere;
pub mod tol;

pub use aabb::Aabb;
pub use ellipsoid::Ellipsoid;
pub use error::GeomError;
pub use glam::{DMat3, DMat4, DQuat, DVec3};
pub use mesh::PolyMesh;
pub use plane::Plane;
pub use polyhedron::{ConvexPolyhedron, Edge};
pub use pose::Pose;
pub use se3::{Mat6, Twist, Wrench};
pub use spatial::SpatialInertia;
pub use sphere::Sphere;
