//! The `features` step of `cargo xtask ci`: the three builds CI makes share their compiled
//! dependencies.
//!
//! A fresh `cargo xtask ci` compiles the workspace's libraries in three cargo invocations: `cargo
//! run -p xtask` (the launcher, before any step), `cargo test --workspace`, and `maturin
//! develop` (the Python extension, `crates/impulse-py`). Cargo resolves features per
//! invocation, over the packages it was asked for, and a package built with other features is
//! another build of it and of everything above it. One differing feature low in the graph
//! (`num-complex`'s `default`, which only NumPy's crate asks for; `syn`'s `extra-traits`, which
//! only PyO3's macros ask for) and every impulse crate, faer and serde are compiled again:
//! measured on a fresh clone, the test step rebuilt 114 crates and `maturin develop` took
//! 113 s. So `xtask` and `impulse-py` declare, for feature unification only, the features the
//! whole workspace turns on (their manifests say which and why), and this step checks that no
//! dependency change has broken that: every package of the `xtask` graph and of the
//! `impulse-py` graph must have exactly the features it has in the workspace's graph (with
//! dev-dependencies, as `cargo test --workspace` builds it). It asks `cargo tree` (no build,
//! about a second) and fails naming each package whose features differ.
//!
//! Owns: the comparison. Must not know: why a crate turns a feature on (the manifests say).

use std::collections::BTreeMap;
use std::process::Command;

use crate::{Result, cargo, workspace_root};

/// The packages whose own dependency graph must match the workspace's: each is built by a
/// cargo invocation of its own in CI (`cargo run -p xtask`, `maturin develop`).
pub const SEPARATE_BUILDS: &[&str] = &["xtask", "impulse-py"];

/// Features per package (`name vX.Y.Z`), as `cargo tree` resolves them.
type Graph = BTreeMap<String, String>;

/// Runs the check (module documentation).
pub fn run() -> Result<()> {
    let whole = tree(&["--workspace", "-e", "normal,build,dev"])?;
    let mut problems = Vec::new();
    let mut checked = Vec::new();
    for package in SEPARATE_BUILDS {
        let own = tree(&["-p", package, "-e", "normal,build"])?;
        checked.push(format!("{package}'s {}", own.len()));
        problems.extend(
            differences(&whole, &own)
                .into_iter()
                .map(|d| format!("{package}: {d}")),
        );
    }
    if problems.is_empty() {
        println!(
            "features: ok ({} packages have the features the workspace's build gives them)",
            checked.join(" and ")
        );
        Ok(())
    } else {
        Err(format!(
            "{} package(s) would be compiled twice on a fresh clone, with other features than \
             `cargo test --workspace` gives them (declare the missing features in the \
             manifest's feature-unification list; xtask/src/unify.rs says why):\n  {}",
            problems.len(),
            problems.join("\n  ")
        ))
    }
}

/// `cargo tree <args>` as a map from package to its features.
fn tree(args: &[&str]) -> Result<Graph> {
    let out = Command::new(cargo())
        .arg("tree")
        .args(args)
        .args(["--prefix", "none", "-f", "{p}|{f}"])
        .current_dir(workspace_root())
        .output()
        .map_err(|e| format!("could not run `cargo tree`: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "`cargo tree {}` failed: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    Ok(parse(&String::from_utf8_lossy(&out.stdout)))
}

/// Parses `cargo tree --prefix none -f "{p}|{f}"` output: one `name vX (source)|a,b` line per
/// appearance of a package. The source (a path, for workspace members) and the markers
/// `(*)` and `(proc-macro)` are dropped.
fn parse(text: &str) -> Graph {
    let mut graph = Graph::new();
    for line in text.lines() {
        let Some((package, features)) = line.split_once('|') else {
            continue;
        };
        let mut words = package.split_whitespace();
        let (Some(name), Some(version)) = (words.next(), words.next()) else {
            continue;
        };
        let features = features
            .trim_end_matches(" (*)")
            .trim_end_matches(" (proc-macro)")
            .trim();
        graph.insert(format!("{name} {version}"), features.to_owned());
    }
    graph
}

/// Each package of `own` whose features differ from `whole`'s, described.
fn differences(whole: &Graph, own: &Graph) -> Vec<String> {
    own.iter()
        .filter_map(|(package, features)| match whole.get(package) {
            Some(w) if w == features => None,
            Some(w) => Some(format!(
                "{package} has [{features}] where the workspace has [{w}]"
            )),
            None => Some(format!("{package} is not in the workspace's graph")),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_package_with_other_features_is_named_with_both_sets() {
        let whole = parse(
            "faer v0.24.4|default,std\nnum-complex v0.4.6|bytemuck,default,std\n\
             impulse-geom v0.1.0 (/w/crates/impulse-geom)|\nsyn v3.0.9|full (proc-macro)\n",
        );
        let own = parse(
            "faer v0.24.4|default,std (*)\nnum-complex v0.4.6|bytemuck,std\n\
             impulse-geom v0.1.0 (/w/crates/impulse-geom)|\nsyn v3.0.9|full (proc-macro)\n",
        );
        assert_eq!(
            differences(&whole, &own),
            [
                "num-complex v0.4.6 has [bytemuck,std] where the workspace has [bytemuck,default,std]"
            ]
        );
    }
}
