//! The README's two commands are the ones the project runs: its test command is exactly what
//! `.ci/run` (CI's entry point) executes, and `cargo xtask` goes through the launcher, which
//! gets the prerequisites. A README that documents one command while CI runs another would let
//! a new user's run fail where CI's passes.

use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .nth(2)
        .unwrap()
        .to_path_buf()
}

fn read(path: &str) -> String {
    std::fs::read_to_string(root().join(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The one-line `sh` code blocks of the README section headed `## The two commands`.
fn readme_commands(readme: &str) -> Vec<String> {
    let section = readme
        .split("\n## ")
        .find(|s| s.starts_with("The two commands"))
        .expect("README has a `## The two commands` section");
    let mut commands = Vec::new();
    let mut lines = section.lines();
    while let Some(line) = lines.next() {
        if line.trim() == "```sh" {
            let body: Vec<&str> = lines.by_ref().take_while(|l| l.trim() != "```").collect();
            assert_eq!(body.len(), 1, "a command block of one line: {body:?}");
            commands.push(body[0].trim().to_owned());
        }
    }
    commands
}

/// The commands `.ci/run` executes: every line but comments, blank lines, `set` and `cd`.
fn ci_run_commands(script: &str) -> Vec<String> {
    script
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .filter(|l| !l.starts_with("set ") && !l.starts_with("cd "))
        .map(str::to_owned)
        .collect()
}

#[test]
fn ci_runs_exactly_the_readme_test_command_and_nothing_else() {
    let commands = readme_commands(&read("README.md"));
    assert_eq!(
        commands.len(),
        2,
        "the main job, then the test suite: {commands:?}"
    );
    let test_command = &commands[1];
    assert_eq!(
        ci_run_commands(&read(".ci/run")),
        [format!("exec {test_command}")],
        ".ci/run must run the README's test command and install nothing itself \
         (prerequisites go through xtask/launcher)"
    );
}

#[test]
fn cargo_xtask_goes_through_the_launcher() {
    let config = read(".cargo/config.toml");
    let alias = config
        .lines()
        .find_map(|l| l.trim().strip_prefix("xtask = "))
        .expect("an xtask alias");
    assert_eq!(alias, r#""run --quiet --package xtask-launcher --""#);
}

#[test]
fn the_main_job_runs_a_bundled_scene() {
    let commands = readme_commands(&read("README.md"));
    let words: Vec<&str> = commands[0].split_whitespace().collect();
    assert_eq!(
        words[..6],
        ["cargo", "run", "-p", "impulse-cli", "--", "run"]
    );
    assert!(
        root().join(words[6]).is_file(),
        "{} is not a file",
        words[6]
    );
}

#[test]
fn the_parsers_read_what_they_should() {
    let readme = "# x\n\n## The two commands\n\ntext\n\n```sh\na b\n```\n\n```sh\nc d\n```\n\n## Next\n\n```sh\ne\n```\n";
    assert_eq!(readme_commands(readme), ["a b", "c d"]);
    let script = "#!/bin/bash\n# c\nset -e\ncd x\napt-get install y\nexec c d\n";
    assert_eq!(ci_run_commands(script), ["apt-get install y", "exec c d"]);
}
