//! The registry of validation cases run by `cargo xtask validate`.
//!
//! One module per library crate under test, each exposing `cases()`; [`all`] concatenates them
//! in a fixed order. A case's name is also its snapshot file name in `fixtures/snapshots/`, so
//! names are unique and stable (ASCII letters, digits, `-`, `_`, `.`).

mod forks;
mod massprops;
mod poses;
pub mod scenes;

use crate::validate::case::Case;

/// Every validation case, in registry order.
pub fn all() -> Vec<Case> {
    let mut cases = Vec::new();
    cases.extend(massprops::cases());
    cases.extend(poses::cases());
    cases.extend(scenes::cases());
    cases.extend(forks::cases());
    cases
}
