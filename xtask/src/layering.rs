//! The layering check: workspace crates against the layer table of `docs/architecture.md`.
//!
//! The table under `## Layers` is the source of truth (columns `Layer | Crate | Status | …`,
//! crate names in backticks, status `built` or `planned`). The check fails when
//! - a workspace package is not in the table;
//! - a row with status `built` names no workspace package;
//! - a package has a dependency of any kind (normal, build, dev) on a workspace package whose
//!   layer is not strictly lower than its own.
//!
//! [`parse_table`], [`parse_metadata`] and [`check`] are pure functions of the table text and
//! of the JSON of `cargo metadata --format-version 1 --no-deps`, so they are unit-tested on
//! small inline fixtures; [`run`] only gathers the two inputs.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::process::Command;

use serde_json::Value;

use crate::{Result, cargo, workspace_root};

/// The heading above the layer table.
const HEADING: &str = "## Layers";

/// Whether a crate of the table exists yet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// The crate exists and must be a workspace package.
    Built,
    /// The crate is designed but not written yet.
    Planned,
}

/// One row of the layer table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Row {
    /// The layer: a crate may depend only on crates of a strictly lower layer.
    pub layer: u32,
    /// The package name, without backticks.
    pub krate: String,
    /// Whether the crate exists yet.
    pub status: Status,
}

/// The kind of a dependency edge, as `cargo metadata` reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum DepKind {
    /// `[dependencies]`.
    Normal,
    /// `[build-dependencies]`.
    Build,
    /// `[dev-dependencies]`.
    Dev,
}

impl fmt::Display for DepKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DepKind::Normal => "normal",
            DepKind::Build => "build",
            DepKind::Dev => "dev",
        })
    }
}

/// A workspace package and its dependencies on other workspace packages.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Package {
    /// The package name.
    pub name: String,
    /// Dependencies on workspace packages: (package name, kind).
    pub deps: Vec<(String, DepKind)>,
}

/// Runs the check on the real workspace and prints a one-line result.
pub fn run() -> Result<()> {
    let root = workspace_root();
    let doc_path = root.join("docs/architecture.md");
    let doc = std::fs::read_to_string(&doc_path)
        .map_err(|e| format!("cannot read {}: {e}", doc_path.display()))?;
    let rows = parse_table(&doc).map_err(|e| format!("{}: {e}", doc_path.display()))?;

    let output = Command::new(cargo())
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--manifest-path",
        ])
        .arg(root.join("Cargo.toml"))
        .current_dir(&root)
        .output()
        .map_err(|e| format!("could not start `cargo metadata`: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "`cargo metadata` failed ({}):\n{}",
            output.status,
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    let json = std::str::from_utf8(&output.stdout)
        .map_err(|e| format!("`cargo metadata` printed invalid UTF-8: {e}"))?;
    let packages = parse_metadata(json)?;

    let errors = check(&rows, &packages);
    if errors.is_empty() {
        let edges: usize = packages.iter().map(|p| p.deps.len()).sum();
        println!(
            "layering: ok ({} workspace packages, {} table rows, {} workspace dependency edges)",
            packages.len(),
            rows.len(),
            edges
        );
        Ok(())
    } else {
        Err(format!(
            "layering check failed against {}:\n  - {}",
            doc_path.display(),
            errors.join("\n  - ")
        ))
    }
}

/// Parses the layer table under `## Layers` of the architecture document.
///
/// `Err` names the line (1-based) and what is wrong: a missing heading, table or column, a
/// layer that is not a number, a crate name without backticks, an unknown status, a crate
/// listed twice.
pub fn parse_table(doc: &str) -> Result<Vec<Row>> {
    let mut lines = doc
        .lines()
        .enumerate()
        .map(|(i, line)| (i + 1, line.trim()));
    lines
        .by_ref()
        .find(|(_, line)| *line == HEADING)
        .ok_or_else(|| format!("no `{HEADING}` heading"))?;
    let mut table = lines
        .skip_while(|(_, line)| line.is_empty() || !line.starts_with('|') && !line.starts_with('#'))
        .take_while(|(_, line)| line.starts_with('|'));

    let (header_line, header) = table
        .next()
        .ok_or_else(|| format!("no table under `{HEADING}`"))?;
    let header = cells(header);
    let column = |name: &str| {
        header
            .iter()
            .position(|cell| cell.eq_ignore_ascii_case(name))
            .ok_or_else(|| format!("line {header_line}: the layer table has no `{name}` column"))
    };
    let (layer_col, crate_col, status_col) =
        (column("Layer")?, column("Crate")?, column("Status")?);
    if !table.next().is_some_and(|(_, line)| is_separator(line)) {
        let n = header_line + 1;
        return Err(format!(
            "line {n}: no `|---|` separator row under the table header"
        ));
    }

    let mut rows: Vec<Row> = Vec::new();
    for (n, line) in table {
        let cells = cells(line);
        let cell = |col: usize, name: &str| {
            cells
                .get(col)
                .copied()
                .ok_or_else(|| format!("line {n}: no `{name}` cell"))
        };
        let layer = cell(layer_col, "Layer")?;
        let layer = layer
            .parse::<u32>()
            .map_err(|_| format!("line {n}: layer `{layer}` is not a non-negative integer"))?;
        let krate = cell(crate_col, "Crate")?;
        let krate = krate
            .strip_prefix('`')
            .and_then(|k| k.strip_suffix('`'))
            .filter(|k| !k.is_empty() && !k.contains('`'))
            .ok_or_else(|| format!("line {n}: crate `{krate}` is not one name in backticks"))?
            .to_owned();
        let status = match cell(status_col, "Status")? {
            "built" => Status::Built,
            "planned" => Status::Planned,
            other => {
                return Err(format!(
                    "line {n}: status `{other}` of `{krate}` is neither `built` nor `planned`"
                ));
            }
        };
        if rows.iter().any(|r| r.krate == krate) {
            return Err(format!("line {n}: `{krate}` is listed twice"));
        }
        rows.push(Row {
            layer,
            krate,
            status,
        });
    }
    if rows.is_empty() {
        return Err(format!("line {header_line}: the layer table has no rows"));
    }
    Ok(rows)
}

/// Whether a table line is the header separator, e.g. `|---|:--|`.
fn is_separator(line: &str) -> bool {
    cells(line)
        .iter()
        .all(|c| !c.is_empty() && c.chars().all(|ch| ch == '-' || ch == ':'))
}

/// The trimmed cells of a markdown table line, without the outer pipes.
fn cells(line: &str) -> Vec<&str> {
    let line = line.trim();
    let line = line.strip_prefix('|').unwrap_or(line);
    let line = line.strip_suffix('|').unwrap_or(line);
    line.split('|').map(str::trim).collect()
}

/// Extracts the workspace packages and their dependencies on each other from the JSON of
/// `cargo metadata --format-version 1 --no-deps`.
///
/// A dependency counts when it names a workspace package and has no registry or git source.
pub fn parse_metadata(json: &str) -> Result<Vec<Package>> {
    let metadata: Value = serde_json::from_str(json)
        .map_err(|e| format!("cannot parse `cargo metadata` JSON: {e}"))?;
    let members: BTreeSet<&str> = metadata["workspace_members"]
        .as_array()
        .ok_or("`cargo metadata`: no `workspace_members` array")?
        .iter()
        .map(|id| {
            id.as_str()
                .ok_or("`cargo metadata`: a workspace member id is not a string")
        })
        .collect::<std::result::Result<_, _>>()?;
    let packages: Vec<&Value> = metadata["packages"]
        .as_array()
        .ok_or("`cargo metadata`: no `packages` array")?
        .iter()
        .filter(|p| p["id"].as_str().is_some_and(|id| members.contains(id)))
        .collect();
    let names: BTreeSet<&str> = packages.iter().filter_map(|p| p["name"].as_str()).collect();

    packages
        .iter()
        .map(|p| {
            let name = p["name"]
                .as_str()
                .ok_or("`cargo metadata`: a package has no name")?;
            let deps = p["dependencies"]
                .as_array()
                .ok_or_else(|| format!("`cargo metadata`: `{name}` has no `dependencies` array"))?
                .iter()
                .filter(|d| d["source"].is_null())
                .filter_map(|d| {
                    let dep = d["name"].as_str().filter(|dep| names.contains(dep))?;
                    let kind = match d["kind"].as_str() {
                        None => Ok(DepKind::Normal),
                        Some("build") => Ok(DepKind::Build),
                        Some("dev") => Ok(DepKind::Dev),
                        Some(other) => Err(format!(
                            "`cargo metadata`: `{name}` → `{dep}` has kind `{other}`"
                        )),
                    };
                    Some(kind.map(|kind| (dep.to_owned(), kind)))
                })
                .collect::<Result<Vec<_>>>()?;
            Ok(Package {
                name: name.to_owned(),
                deps,
            })
        })
        .collect()
}

/// Checks the packages against the table; returns one message per violation (empty: passes).
pub fn check(rows: &[Row], packages: &[Package]) -> Vec<String> {
    let layer_of: BTreeMap<&str, u32> = rows.iter().map(|r| (r.krate.as_str(), r.layer)).collect();
    let mut errors = Vec::new();
    for package in packages {
        if !layer_of.contains_key(package.name.as_str()) {
            errors.push(format!(
                "workspace package `{}` is not in the layer table of docs/architecture.md",
                package.name
            ));
        }
    }
    for row in rows.iter().filter(|r| r.status == Status::Built) {
        if !packages.iter().any(|p| p.name == row.krate) {
            errors.push(format!(
                "`{}` (layer {}) is marked `built` in the layer table but is no workspace package",
                row.krate, row.layer
            ));
        }
    }
    for package in packages {
        let Some(&layer) = layer_of.get(package.name.as_str()) else {
            continue;
        };
        for (dep, kind) in &package.deps {
            let Some(&dep_layer) = layer_of.get(dep.as_str()) else {
                continue;
            };
            if dep_layer >= layer {
                let direction = if dep_layer == layer {
                    "the same layer"
                } else {
                    "a higher layer"
                };
                errors.push(format!(
                    "`{}` (layer {layer}) has a {kind} dependency on `{dep}` (layer {dep_layer}), \
                     which is {direction}: a crate may depend only on lower layers",
                    package.name
                ));
            }
        }
    }
    errors
}

#[cfg(test)]
mod tests {
    use super::*;

    const TABLE: &str = "\
# Doc

Intro | with a pipe.

## Layers

| Layer | Crate | Status | Owns | Must not know |
|---|---|---|---|---|
| 0 | `geom` | built | math | mass |
| 1 | `mass` | built | integrals | files |
| 1 | `broad` | planned | hashing | — |
| 5 | `cli` | built | the program | — |

## Code map
";

    /// A dependency of a fixture package: (name, kind, source).
    type Dep<'a> = (&'a str, Option<&'a str>, Option<&'a str>);

    /// A `cargo metadata` document of packages with their dependencies.
    fn metadata(packages: &[(&str, &[Dep])]) -> String {
        let packages: Vec<Value> = packages
            .iter()
            .map(|(name, deps)| {
                let deps: Vec<Value> = deps
                    .iter()
                    .map(|(dep, kind, source)| {
                        serde_json::json!({ "name": dep, "kind": kind, "source": source })
                    })
                    .collect();
                serde_json::json!({ "name": name, "id": format!("path+file:///ws#{name}"), "dependencies": deps })
            })
            .collect();
        let members: Vec<Value> = packages.iter().map(|p| p["id"].clone()).collect();
        serde_json::json!({ "packages": packages, "workspace_members": members }).to_string()
    }

    fn errors(packages: &[(&str, &[Dep])]) -> Vec<String> {
        let rows = parse_table(TABLE).expect("the fixture table parses");
        let packages = parse_metadata(&metadata(packages)).expect("the fixture metadata parses");
        check(&rows, &packages)
    }

    const REGISTRY: Option<&str> = Some("registry+https://github.com/rust-lang/crates.io-index");

    #[test]
    fn table_parses() {
        let rows = parse_table(TABLE).unwrap();
        let row = |layer, krate: &str, status| Row {
            layer,
            krate: krate.to_owned(),
            status,
        };
        assert_eq!(
            rows,
            [
                row(0, "geom", Status::Built),
                row(1, "mass", Status::Built),
                row(1, "broad", Status::Planned),
                row(5, "cli", Status::Built),
            ]
        );
    }

    #[test]
    fn real_architecture_doc_parses() {
        let path = workspace_root().join("docs/architecture.md");
        let doc = std::fs::read_to_string(&path).unwrap();
        let rows = parse_table(&doc).unwrap();
        let find = |name: &str| {
            rows.iter()
                .find(|r| r.krate == name)
                .map(|r| (r.layer, r.status))
        };
        assert_eq!(find("impulse-geom"), Some((0, Status::Built)));
        assert_eq!(find("impulse-massprops"), Some((1, Status::Built)));
        assert_eq!(find("impulse-cli"), Some((5, Status::Built)));
        assert_eq!(find("xtask"), Some((5, Status::Built)));
        assert_eq!(find("impulse-broadphase"), Some((1, Status::Built)));
        assert_eq!(find("impulse-reduced"), Some((3, Status::Built)));
    }

    #[test]
    fn valid_graph_passes() {
        let errors = errors(&[
            ("geom", &[("glam", None, REGISTRY)]),
            ("mass", &[("geom", None, None), ("geom", Some("dev"), None)]),
            (
                "cli",
                &[("geom", None, None), ("mass", Some("build"), None)],
            ),
        ]);
        assert_eq!(errors, Vec::<String>::new());
    }

    #[test]
    fn registry_crate_with_a_workspace_name_is_ignored() {
        let errors = errors(&[
            ("geom", &[("mass", None, REGISTRY)]),
            ("mass", &[]),
            ("cli", &[]),
        ]);
        assert_eq!(errors, Vec::<String>::new());
    }

    #[test]
    fn same_layer_dependency_fails() {
        let errors = errors(&[
            ("geom", &[]),
            ("mass", &[("broad", None, None)]),
            ("broad", &[]),
            ("cli", &[]),
        ]);
        assert_eq!(
            errors,
            [
                "`mass` (layer 1) has a normal dependency on `broad` (layer 1), which is the same \
              layer: a crate may depend only on lower layers"
            ]
        );
    }

    #[test]
    fn upward_dependency_fails() {
        let errors = errors(&[
            ("geom", &[("mass", Some("build"), None)]),
            ("mass", &[]),
            ("cli", &[]),
        ]);
        assert_eq!(
            errors,
            [
                "`geom` (layer 0) has a build dependency on `mass` (layer 1), which is a higher \
              layer: a crate may depend only on lower layers"
            ]
        );
    }

    #[test]
    fn upward_dev_dependency_fails() {
        let errors = errors(&[
            ("geom", &[]),
            ("mass", &[("cli", Some("dev"), None)]),
            ("cli", &[]),
        ]);
        assert_eq!(
            errors,
            [
                "`mass` (layer 1) has a dev dependency on `cli` (layer 5), which is a higher layer: \
              a crate may depend only on lower layers"
            ]
        );
    }

    #[test]
    fn unlisted_crate_fails() {
        let errors = errors(&[
            ("geom", &[]),
            ("mass", &[]),
            ("cli", &[]),
            ("extra", &[("geom", None, None)]),
        ]);
        assert_eq!(
            errors,
            ["workspace package `extra` is not in the layer table of docs/architecture.md"]
        );
    }

    #[test]
    fn built_row_without_package_fails() {
        let errors = errors(&[("geom", &[]), ("cli", &[])]);
        assert_eq!(
            errors,
            ["`mass` (layer 1) is marked `built` in the layer table but is no workspace package"]
        );
    }

    #[test]
    fn planned_row_without_package_passes() {
        assert!(errors(&[("geom", &[]), ("mass", &[]), ("cli", &[])]).is_empty());
    }

    #[test]
    fn malformed_tables_fail_precisely() {
        let bad = |from: &str, to: &str| parse_table(&TABLE.replace(from, to)).unwrap_err();
        assert_eq!(bad("## Layers", "## Strata"), "no `## Layers` heading");
        assert!(bad("| 1 | `mass`", "| one | `mass`").starts_with("line 10: layer `one`"));
        assert!(bad("`mass`", "mass").starts_with("line 10: crate `mass` is not one name"));
        assert!(bad("| built | integrals", "| done | integrals").contains("status `done`"));
        assert!(bad("`broad`", "`geom`").contains("`geom` is listed twice"));
        assert!(bad("| Status |", "| State |").contains("no `Status` column"));
        assert!(bad("|---|---|---|---|---|", "").contains("line 8: no `|---|` separator"));
        assert!(
            parse_table("## Layers\n\ntext\n")
                .unwrap_err()
                .contains("no table")
        );
    }

    #[test]
    fn bad_metadata_fails() {
        assert!(parse_metadata("{").unwrap_err().contains("cannot parse"));
        assert!(
            parse_metadata("{}")
                .unwrap_err()
                .contains("workspace_members")
        );
    }

    /// The real workspace obeys its own table, so plain `cargo test -p xtask` enforces layering.
    #[test]
    fn workspace_is_layered() {
        run().unwrap();
    }
}
