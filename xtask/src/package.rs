//! The packaging check of `cargo xtask ci`: every crate under `crates/` can be packaged for
//! crates.io, so that a user can depend on any of them.
//!
//! The crates are those of the layer table of `docs/architecture.md` (status `built`) whose
//! directory is under `crates/`, in layer order: the eight libraries, the `impulse` program and
//! the Python extension `impulse-py`
//! (`xtask` is `publish = false`). What is checked:
//! - **files**: each crate's `LICENSE-MIT` and `LICENSE-APACHE` equal the workspace root's
//!   (cargo packages only files under a crate's own directory, so each crate carries a copy);
//!   each library crate's `README.md` shows its example `examples/readme_<name>.rs` (`<name>`
//!   without `impulse-`) verbatim after the file's `//!` header, in a `rust` block: the README's
//!   example is a program `cargo test` and clippy build (not for `impulse-py`, a Python
//!   extension: its README's Python example is run by its pytest suite);
//! - **metadata** (`cargo metadata`): a description, a license, keywords, categories and a
//!   readme;
//! - **contents** (`cargo package --list -p <crate>`, one crate at a time): README.md and both
//!   license files are in the package;
//! - **packaging** (`cargo package --no-verify --offline -p …`, all crates in one call, into
//!   `target/package-check/`): each manifest normalised for crates.io — every dependency has a
//!   version, as a path alone is refused —, its lockfile resolved, its `.crate` file written. A
//!   crate's dependencies on workspace crates resolve against the crates packaged in the same
//!   call (cargo's local overlay of them): packaged alone, `impulse-massprops` fails with "no
//!   matching package named `impulse-geom` found", since no impulse crate is on crates.io yet.
//!
//! Not checked: building the packaged sources (`cargo package` without `--no-verify`). That
//! builds each crate from its `.crate` file as a workspace of its own, without this
//! workspace's profiles, so every dependency (faer, rayon, serde, …) is compiled again in
//! another configuration: minutes on two cores, against this step's budget of seconds (it takes
//! about one). The same sources are built by the clippy and test steps. `--offline`: the
//! lockfiles are resolved from the registry index cargo cached for the steps before, so the check
//! needs no network and reads nothing newer than what the workspace was built with. Nothing is
//! written to the source tree (`--allow-dirty` only lets uncommitted changes be packaged).

use std::path::Path;
use std::process::Command;

use serde_json::Value;

use crate::layering::{self, Status};
use crate::{Result, cargo, workspace_root};

/// Where `cargo package` writes (`--target-dir`), relative to the workspace root.
const TARGET_DIR: &str = "target/package-check";

/// The license files every crate must carry, equal to the workspace root's.
const LICENSE_FILES: [&str; 2] = ["LICENSE-MIT", "LICENSE-APACHE"];

/// A crate to package.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Crate {
    /// The package name, also its directory under `crates/`.
    pub name: String,
    /// Its layer in `docs/architecture.md`.
    pub layer: u32,
}

/// Runs the check on the real workspace and prints one line per crate.
pub fn run() -> Result<()> {
    let root = workspace_root();
    let doc_path = root.join("docs/architecture.md");
    let doc = std::fs::read_to_string(&doc_path)
        .map_err(|e| format!("cannot read {}: {e}", doc_path.display()))?;
    let rows = layering::parse_table(&doc).map_err(|e| format!("{}: {e}", doc_path.display()))?;
    let crates = crates_in_layer_order(&rows, |name| root.join("crates").join(name).is_dir());
    if crates.is_empty() {
        return Err("package: no crate of the layer table is under crates/".to_owned());
    }

    let mut problems = Vec::new();
    for krate in &crates {
        problems.extend(check_files(&root, &krate.name));
    }
    let (metadata_problems, versions) = check_metadata(&root, &crates)?;
    problems.extend(metadata_problems);
    let mut file_counts = Vec::with_capacity(crates.len());
    for krate in &crates {
        let listing = cargo_output(
            &root,
            &[
                "package",
                "--list",
                "--offline",
                "--allow-dirty",
                "-p",
                &krate.name,
            ],
        )?;
        let files: Vec<&str> = listing.lines().collect();
        for needed in ["README.md", LICENSE_FILES[0], LICENSE_FILES[1]] {
            if !files.contains(&needed) {
                problems.push(format!(
                    "{}: the package does not contain {needed}",
                    krate.name
                ));
            }
        }
        file_counts.push(files.len());
    }
    if !problems.is_empty() {
        return Err(format!(
            "package check failed:\n  - {}",
            problems.join("\n  - ")
        ));
    }

    let target = root.join(TARGET_DIR);
    let mut args: Vec<&str> = vec!["package", "--no-verify", "--offline", "--allow-dirty"];
    for krate in &crates {
        args.extend(["-p", &krate.name]);
    }
    let status = Command::new(cargo())
        .args(&args)
        .arg("--target-dir")
        .arg(&target)
        .arg("--quiet")
        .current_dir(&root)
        .status()
        .map_err(|e| format!("could not start `cargo package`: {e}"))?;
    if !status.success() {
        return Err(format!(
            "`cargo {}` failed ({status}); with --offline, a dependency missing from cargo's \
             index cache fails too: build the workspace once (`cargo build`) and retry",
            args.join(" ")
        ));
    }
    for ((krate, files), version) in crates.iter().zip(&file_counts).zip(&versions) {
        let file = target
            .join("package")
            .join(format!("{}-{version}.crate", krate.name));
        let size = std::fs::metadata(&file)
            .map_err(|e| format!("{}: not written by `cargo package`: {e}", file.display()))?
            .len();
        println!(
            "  layer {}  {:<20} {files:>3} files, {:>6.1} KiB",
            krate.layer,
            krate.name,
            size as f64 / 1024.0
        );
    }
    println!(
        "package: ok ({} crates packaged in layer order into {TARGET_DIR}/package; not built \
         from the package, see `xtask/src/package.rs`)",
        crates.len()
    );
    Ok(())
}

/// The built crates of the layer table for which `is_crate_dir` holds, ordered by layer (the
/// table's order within a layer).
pub fn crates_in_layer_order(
    rows: &[layering::Row],
    is_crate_dir: impl Fn(&str) -> bool,
) -> Vec<Crate> {
    let mut crates: Vec<Crate> = rows
        .iter()
        .filter(|r| r.status == Status::Built && is_crate_dir(&r.krate))
        .map(|r| Crate {
            name: r.krate.clone(),
            layer: r.layer,
        })
        .collect();
    crates.sort_by_key(|c| c.layer);
    crates
}

/// The license copies and, for a library crate, the README's example: one message per
/// problem.
fn check_files(root: &Path, name: &str) -> Vec<String> {
    let dir = root.join("crates").join(name);
    let mut problems = Vec::new();
    for license in LICENSE_FILES {
        match (
            std::fs::read(root.join(license)),
            std::fs::read(dir.join(license)),
        ) {
            (Ok(a), Ok(b)) if a == b => {}
            (Ok(_), Ok(_)) => problems.push(format!(
                "crates/{name}/{license} differs from the workspace root's {license} \
                 (copy it: `cp {license} crates/{name}/`)"
            )),
            (Err(e), _) => problems.push(format!("cannot read {license}: {e}")),
            (_, Err(e)) => problems.push(format!("cannot read crates/{name}/{license}: {e}")),
        }
    }
    if !dir.join("src/lib.rs").is_file() || dir.join("pyproject.toml").is_file() {
        // A program, or the Python extension (impulse-py: its README shows Python, which its
        // pytest suite runs): no Rust example to show.
        return problems;
    }
    let short = name.strip_prefix("impulse-").unwrap_or(name);
    let example_path = format!("crates/{name}/examples/readme_{short}.rs");
    let read = |path: &str| {
        std::fs::read_to_string(root.join(path)).map_err(|e| format!("cannot read {path}: {e}"))
    };
    match (
        read(&format!("crates/{name}/README.md")),
        read(&example_path),
    ) {
        (Ok(readme), Ok(example)) => {
            if let Err(e) = readme_shows_example(&readme, &example) {
                problems.push(format!("crates/{name}/README.md and {example_path}: {e}"));
            }
        }
        (Err(e), _) | (_, Err(e)) => problems.push(e),
    }
    problems
}

/// `Ok` if the first `rust` code block of `readme` is `example` without its leading `//!`
/// lines and the blank line after them; `Err` says where they first differ.
pub fn readme_shows_example(readme: &str, example: &str) -> Result<()> {
    let block: Vec<&str> = readme
        .lines()
        .skip_while(|l| l.trim_end() != "```rust")
        .skip(1)
        .take_while(|l| l.trim_end() != "```")
        .collect();
    if block.is_empty() {
        return Err("the README has no ```rust block".to_owned());
    }
    let body: Vec<&str> = example
        .lines()
        .skip_while(|l| l.starts_with("//!"))
        .skip_while(|l| l.trim().is_empty())
        .collect();
    for (n, (shown, real)) in block.iter().zip(&body).enumerate() {
        if shown != real {
            return Err(format!(
                "line {} of the example differs: the README has `{shown}`, the file `{real}`",
                n + 1
            ));
        }
    }
    if block.len() != body.len() {
        return Err(format!(
            "the README's example has {} lines, the file {} (after its header)",
            block.len(),
            body.len()
        ));
    }
    Ok(())
}

/// The crates.io fields each crate must have, from `cargo metadata`: the problems found, and
/// each crate's version (in the order of `crates`; empty when unknown).
fn check_metadata(root: &Path, crates: &[Crate]) -> Result<(Vec<String>, Vec<String>)> {
    let json = cargo_output(
        root,
        &[
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ],
    )?;
    let metadata: Value = serde_json::from_str(&json)
        .map_err(|e| format!("cannot parse `cargo metadata` JSON: {e}"))?;
    let packages = metadata["packages"]
        .as_array()
        .ok_or("`cargo metadata`: no `packages` array")?;
    let (mut problems, mut versions) = (Vec::new(), Vec::new());
    for krate in crates {
        let Some(p) = packages.iter().find(|p| p["name"] == krate.name.as_str()) else {
            problems.push(format!("{}: not a workspace package", krate.name));
            versions.push(String::new());
            continue;
        };
        versions.push(p["version"].as_str().unwrap_or_default().to_owned());
        let filled = |field: &str| match &p[field] {
            Value::String(s) => !s.trim().is_empty(),
            Value::Array(a) => !a.is_empty(),
            _ => false,
        };
        for field in ["description", "license", "keywords", "categories", "readme"] {
            if !filled(field) {
                problems.push(format!("{}: no `{field}` in Cargo.toml", krate.name));
            }
        }
    }
    Ok((problems, versions))
}

/// Runs `cargo <args>` in `root` and returns its standard output; `Err` carries its stderr.
fn cargo_output(root: &Path, args: &[&str]) -> Result<String> {
    let shown = format!("cargo {}", args.join(" "));
    let output = Command::new(cargo())
        .args(args)
        .current_dir(root)
        .output()
        .map_err(|e| format!("could not start `{shown}`: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "`{shown}` failed ({}):\n{}",
            output.status,
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    String::from_utf8(output.stdout).map_err(|e| format!("`{shown}` printed invalid UTF-8: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    const EXAMPLE: &str = "//! Header.\n//! More header.\n\nfn main() {\n    run();\n}\n";

    fn readme(code: &str) -> String {
        format!("# crate\n\n```toml\nx = 1\n```\n\n```rust\n{code}```\n\nText.\n")
    }

    #[test]
    fn a_readme_with_the_example_passes() {
        assert_eq!(
            readme_shows_example(&readme("fn main() {\n    run();\n}\n"), EXAMPLE),
            Ok(())
        );
    }

    #[test]
    fn a_changed_line_is_named() {
        let e =
            readme_shows_example(&readme("fn main() {\n    walk();\n}\n"), EXAMPLE).unwrap_err();
        assert!(e.contains("line 2") && e.contains("walk()"), "{e}");
    }

    #[test]
    fn a_missing_or_extra_line_fails() {
        let e = readme_shows_example(&readme("fn main() {\n    run();\n"), EXAMPLE).unwrap_err();
        assert!(e.contains("has 2 lines, the file 3"), "{e}");
        let e = readme_shows_example(&readme("fn main() {\n    run();\n}\n// more\n"), EXAMPLE)
            .unwrap_err();
        assert!(e.contains("has 4 lines"), "{e}");
        let e = readme_shows_example("# crate\n\nNo code.\n", EXAMPLE).unwrap_err();
        assert!(e.contains("no ```rust block"), "{e}");
    }

    /// The real workspace: every directory under crates/ is packaged, libraries first by
    /// layer, and `impulse-geom` (layer 0) comes first.
    #[test]
    fn every_crate_directory_is_packaged_in_layer_order() {
        let root = workspace_root();
        let doc = std::fs::read_to_string(root.join("docs/architecture.md")).unwrap();
        let rows = layering::parse_table(&doc).unwrap();
        let crates = crates_in_layer_order(&rows, |n| root.join("crates").join(n).is_dir());
        let mut dirs: Vec<String> = std::fs::read_dir(root.join("crates"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        dirs.sort();
        let mut names: Vec<String> = crates.iter().map(|c| c.name.clone()).collect();
        names.sort();
        assert_eq!(names, dirs);
        assert_eq!(crates[0].name, "impulse-geom");
        assert!(crates.windows(2).all(|w| w[0].layer <= w[1].layer));
        assert!(!crates.iter().any(|c| c.name == "xtask"));
    }

    /// The real crates' license copies and README examples are as the step requires.
    #[test]
    fn the_workspace_files_pass() {
        let root = workspace_root();
        for name in ["impulse-geom", "impulse-sim", "impulse-cli", "impulse-py"] {
            assert_eq!(check_files(&root, name), Vec::<String>::new());
        }
    }
}
