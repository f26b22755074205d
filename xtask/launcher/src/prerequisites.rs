//! What the checks need beyond the Rust toolchain, how to tell whether this machine has it, and
//! how to get it.
//!
//! [`PREREQUISITES`] is the one list: a program that a new check needs (Python, maturin, a
//! fuzzer's toolchain) is added here, with the subcommands that need it, and nowhere else.
//! Finding ([`find`]) and planning an install ([`plan`]) are separate: [`plan`] is a pure
//! function of the machine's description ([`Host`]), so every case (root, passwordless sudo,
//! neither; which package manager) is unit-tested without touching the machine.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How long a program may take to answer `--version` before it counts as not working.
const PROBE_TIMEOUT: Duration = Duration::from_secs(20);

/// Something a subcommand needs that the Rust toolchain does not bring.
#[derive(Debug)]
pub struct Prerequisite {
    /// The name a user knows it by, as in messages ("chromium").
    pub name: &'static str,
    /// Why it is needed, said in messages ("the viewer step opens … in it").
    pub purpose: &'static str,
    /// The `cargo xtask` subcommands that need it.
    pub needed_by: &'static [&'static str],
    /// How to tell that the machine has it.
    pub probe: Probe,
    /// How to get it.
    pub install: Install,
}

/// How to tell that a prerequisite is present.
#[derive(Debug)]
pub enum Probe {
    /// A program: `$env` if set, else the first of `programs` found (a bare name is looked up on
    /// `PATH`, an absolute path taken as it is); it must answer `--version` with exit code 0.
    Program {
        /// The environment variable that names the program, overriding the search.
        env: &'static str,
        /// Names or absolute paths tried in order.
        programs: &'static [&'static str],
    },
    /// A cargo subcommand: `cargo <name> --version` exits 0.
    CargoSubcommand(&'static str),
}

/// How to get a prerequisite.
#[derive(Debug)]
pub enum Install {
    /// A package of the system's package manager: the package name for each manager that has
    /// it. Needs root, or `sudo` without a password.
    SystemPackage(&'static [(Manager, &'static str)]),
    /// A component of the rustup toolchain (`rustup component add <name>`); no root needed.
    RustupComponent(&'static str),
}

/// A system package manager that [`Install::SystemPackage`] knows how to drive
/// non-interactively.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Manager {
    /// Debian and its derivatives.
    Apt,
    /// Fedora, RHEL.
    Dnf,
    /// Arch.
    Pacman,
    /// openSUSE.
    Zypper,
    /// Alpine.
    Apk,
}

impl Manager {
    /// Every manager, in the order they are looked for.
    pub const ALL: [Manager; 5] = [
        Manager::Apt,
        Manager::Dnf,
        Manager::Pacman,
        Manager::Zypper,
        Manager::Apk,
    ];

    /// The program, looked up on `PATH`.
    pub fn program(self) -> &'static str {
        match self {
            Manager::Apt => "apt-get",
            Manager::Dnf => "dnf",
            Manager::Pacman => "pacman",
            Manager::Zypper => "zypper",
            Manager::Apk => "apk",
        }
    }

    /// The commands that install `package` without asking anything, in order: apt's package
    /// lists are empty on a fresh Debian image, so it updates them first.
    fn commands(self, package: &str) -> Vec<Cmd> {
        let cmd = |args: &[&str]| Cmd {
            program: self.program().to_owned(),
            args: args.iter().map(|a| (*a).to_owned()).collect(),
            env: if self == Manager::Apt {
                vec![("DEBIAN_FRONTEND".to_owned(), "noninteractive".to_owned())]
            } else {
                Vec::new()
            },
        };
        match self {
            Manager::Apt => vec![
                cmd(&["update", "-qq"]),
                cmd(&["install", "-y", "-qq", "--no-install-recommends", package]),
            ],
            Manager::Dnf => vec![cmd(&["install", "-y", package])],
            Manager::Pacman => vec![cmd(&["-S", "--noconfirm", "--needed", package])],
            Manager::Zypper => vec![cmd(&["--non-interactive", "install", package])],
            Manager::Apk => vec![cmd(&["add", package])],
        }
    }

    /// The command a person would type, for messages: `apt-get install chromium`.
    fn shown(self, package: &str) -> String {
        match self {
            Manager::Apt => format!("apt-get install {package}"),
            Manager::Dnf => format!("dnf install {package}"),
            Manager::Pacman => format!("pacman -S {package}"),
            Manager::Zypper => format!("zypper install {package}"),
            Manager::Apk => format!("apk add {package}"),
        }
    }
}

/// The prerequisites of every subcommand.
pub const PREREQUISITES: &[Prerequisite] = &[
    Prerequisite {
        name: "rustfmt",
        purpose: "the first step of `ci` checks the formatting with `cargo fmt`",
        needed_by: &["ci"],
        probe: Probe::CargoSubcommand("fmt"),
        install: Install::RustupComponent("rustfmt"),
    },
    Prerequisite {
        name: "clippy",
        purpose: "the second step of `ci` runs `cargo clippy`",
        needed_by: &["ci"],
        probe: Probe::CargoSubcommand("clippy"),
        install: Install::RustupComponent("clippy"),
    },
    Prerequisite {
        name: "chromium",
        purpose: "the viewer step opens the replay pages of `impulse run --html` in headless \
                  Chromium",
        needed_by: &["ci", "viewer"],
        probe: Probe::Program {
            env: "CHROMIUM",
            programs: &[
                "chromium",
                "chromium-browser",
                "google-chrome",
                "google-chrome-stable",
                "/Applications/Chromium.app/Contents/MacOS/Chromium",
                "/Applications/Google Chrome.app/Contents/MacOS/Google Chrome",
            ],
        },
        install: Install::SystemPackage(&[
            (Manager::Apt, "chromium"),
            (Manager::Dnf, "chromium"),
            (Manager::Pacman, "chromium"),
            (Manager::Zypper, "chromium"),
            (Manager::Apk, "chromium"),
        ]),
    },
    Prerequisite {
        name: "python3",
        purpose: "the python step builds the `impulse` Python package into a virtual \
                  environment (`python3 -m venv`, target/py-venv) and runs its pytest suite",
        needed_by: &["ci", "python"],
        probe: Probe::Program {
            env: "PYTHON",
            programs: &["python3", "python"],
        },
        // Debian splits `venv` out of python3; its package pulls python3 in.
        install: Install::SystemPackage(&[
            (Manager::Apt, "python3-venv"),
            (Manager::Dnf, "python3"),
            (Manager::Pacman, "python"),
            (Manager::Zypper, "python3"),
            (Manager::Apk, "python3"),
        ]),
    },
];

/// The prerequisites of a subcommand (none for one that needs nothing beyond Rust).
pub fn needed_by(subcommand: &str) -> impl Iterator<Item = &'static Prerequisite> + '_ {
    PREREQUISITES
        .iter()
        .filter(move |p| p.needed_by.contains(&subcommand))
}

/// A command to run: program, arguments and extra environment.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Cmd {
    /// The program (a name looked up on `PATH`).
    pub program: String,
    /// Its arguments.
    pub args: Vec<String>,
    /// Variables added to its environment.
    pub env: Vec<(String, String)>,
}

impl Cmd {
    /// The command as a shell would show it.
    pub fn shown(&self) -> String {
        let mut words: Vec<String> = self.env.iter().map(|(k, v)| format!("{k}={v}")).collect();
        words.push(self.program.clone());
        words.extend(self.args.iter().cloned());
        words.join(" ")
    }

    /// Runs it with inherited output; `Err` says how it failed.
    pub fn run(&self) -> Result<(), String> {
        let status = Command::new(&self.program)
            .args(&self.args)
            .envs(self.env.iter().map(|(k, v)| (k, v)))
            .stdin(Stdio::null())
            .status()
            .map_err(|e| format!("`{}` could not start: {e}", self.shown()))?;
        if status.success() {
            Ok(())
        } else {
            Err(format!("`{}` failed ({status})", self.shown()))
        }
    }

    /// The same command run through `sudo -n` (never asks for a password: it fails instead).
    fn with_sudo(self) -> Cmd {
        let mut args = vec!["-n".to_owned()];
        // sudo resets the environment; variables go on its command line.
        args.extend(self.env.iter().map(|(k, v)| format!("{k}={v}")));
        args.push(self.program);
        args.extend(self.args);
        Cmd {
            program: "sudo".to_owned(),
            args,
            env: Vec::new(),
        }
    }
}

/// What matters about this machine for installing things.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Host {
    /// The process runs as root.
    pub root: bool,
    /// What `sudo` can do for us.
    pub sudo: Sudo,
    /// The package managers found on `PATH`, in [`Manager::ALL`] order.
    pub managers: Vec<Manager>,
    /// `rustup` is on `PATH`.
    pub rustup: bool,
}

impl Host {
    /// Looks at this machine: who we are, what is on `PATH`.
    pub fn detect() -> Host {
        let root = Command::new("id")
            .arg("-u")
            .stderr(Stdio::null())
            .output()
            .is_ok_and(|out| out.status.success() && out.stdout.trim_ascii() == b"0");
        let sudo = if root || on_path("sudo").is_none() {
            Sudo::Absent
        } else if Command::new("sudo")
            .args(["-n", "true"])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
        {
            Sudo::Passwordless
        } else {
            Sudo::AsksPassword
        };
        Host {
            root,
            sudo,
            managers: Manager::ALL
                .into_iter()
                .filter(|m| on_path(m.program()).is_some())
                .collect(),
            rustup: on_path("rustup").is_some(),
        }
    }
}

/// Whether `sudo` can run a command as root without a person at the keyboard.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sudo {
    /// No `sudo` on `PATH`.
    #[default]
    Absent,
    /// `sudo -n true` fails: it would ask for a password.
    AsksPassword,
    /// `sudo -n true` succeeds.
    Passwordless,
}

/// How a missing prerequisite can be got on a host.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Plan {
    /// These commands, in order, install it.
    Run(Vec<Cmd>),
    /// It cannot be installed from here: what the user should do instead.
    Manual(String),
}

/// How to get `prerequisite` on `host`.
pub fn plan(prerequisite: &Prerequisite, host: &Host) -> Plan {
    match &prerequisite.install {
        Install::RustupComponent(component) => {
            let cmd = Cmd {
                program: "rustup".to_owned(),
                args: vec!["component".into(), "add".into(), (*component).to_owned()],
                env: Vec::new(),
            };
            if host.rustup {
                Plan::Run(vec![cmd])
            } else {
                Plan::Manual(format!(
                    "No rustup on PATH: add the `{component}` component to your Rust toolchain \
                     with the tool that installed it (with rustup: `{}`)",
                    cmd.shown()
                ))
            }
        }
        Install::SystemPackage(packages) => {
            let found = host.managers.iter().find_map(|manager| {
                packages
                    .iter()
                    .find(|(m, _)| m == manager)
                    .map(|(m, package)| (*m, *package))
            });
            let Some((manager, package)) = found else {
                let known: Vec<String> = packages.iter().map(|(m, p)| m.shown(p)).collect();
                return Plan::Manual(format!(
                    "No package manager this check knows is on PATH ({}): install {} with the \
                     system's own (for example `{}`)",
                    Manager::ALL.map(Manager::program).join(", "),
                    prerequisite.name,
                    known.join("`, `")
                ));
            };
            if host.root {
                Plan::Run(manager.commands(package))
            } else if host.sudo == Sudo::Passwordless {
                Plan::Run(
                    manager
                        .commands(package)
                        .into_iter()
                        .map(Cmd::with_sudo)
                        .collect(),
                )
            } else if host.sudo == Sudo::AsksPassword {
                Plan::Manual(format!(
                    "Installing it needs root; this is not root and sudo asks for a password: \
                     run `sudo {}`",
                    manager.shown(package)
                ))
            } else {
                Plan::Manual(format!(
                    "Installing it needs root; this is not root and there is no sudo: run `{}` \
                     as root",
                    manager.shown(package)
                ))
            }
        }
    }
}

/// Finds a prerequisite on this machine: `Ok(Some(path))` for a program (the path to hand to
/// the check), `Ok(None)` for a cargo subcommand that works; `Err` says what was tried.
pub fn find(prerequisite: &Prerequisite, cargo: &Path) -> Result<Option<PathBuf>, String> {
    match &prerequisite.probe {
        Probe::CargoSubcommand(sub) => {
            let mut command = Command::new(cargo);
            command.arg(sub);
            if answers(command) {
                Ok(None)
            } else {
                Err(format!("`cargo {sub} --version` does not answer"))
            }
        }
        Probe::Program { env, programs } => {
            if let Some(named) = std::env::var_os(env).filter(|v| !v.is_empty()) {
                let path = PathBuf::from(named);
                return if answers(Command::new(&path)) {
                    Ok(Some(path))
                } else {
                    Err(format!(
                        "${env} is {}, which does not answer `--version`",
                        path.display()
                    ))
                };
            }
            for name in *programs {
                let candidate = if Path::new(name).is_absolute() {
                    Some(PathBuf::from(name)).filter(|p| p.is_file())
                } else {
                    on_path(name)
                };
                if let Some(path) = candidate
                    && answers(Command::new(&path))
                {
                    return Ok(Some(path));
                }
            }
            Err(format!(
                "not found (tried ${env}, then {} on PATH, then the usual macOS application \
                 paths)",
                programs
                    .iter()
                    .filter(|p| !Path::new(p).is_absolute())
                    .copied()
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        }
    }
}

/// Whether `command --version` exits 0 within [`PROBE_TIMEOUT`].
fn answers(mut command: Command) -> bool {
    let Ok(mut child) = command
        .arg("--version")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
    else {
        return false;
    };
    let start = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(status)) => return status.success(),
            Ok(None) if start.elapsed() < PROBE_TIMEOUT => {
                std::thread::sleep(Duration::from_millis(10));
            }
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                return false;
            }
        }
    }
}

/// The first executable file called `name` in a directory of `PATH`.
pub fn on_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|dir| dir.join(name))
        .find(|candidate| is_executable(candidate))
}

#[cfg(unix)]
fn is_executable(path: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt as _;
    path.metadata()
        .is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

#[cfg(not(unix))]
fn is_executable(path: &Path) -> bool {
    path.is_file()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chromium() -> &'static Prerequisite {
        PREREQUISITES.iter().find(|p| p.name == "chromium").unwrap()
    }

    fn host(root: bool, sudo: Sudo, managers: &[Manager]) -> Host {
        Host {
            root,
            sudo,
            managers: managers.to_vec(),
            rustup: true,
        }
    }

    fn shown(plan: &Plan) -> Vec<String> {
        match plan {
            Plan::Run(cmds) => cmds.iter().map(Cmd::shown).collect(),
            Plan::Manual(text) => panic!("expected commands, got: {text}"),
        }
    }

    #[test]
    fn root_with_apt_updates_then_installs_without_questions() {
        let plan = plan(chromium(), &host(true, Sudo::Absent, &[Manager::Apt]));
        assert_eq!(
            shown(&plan),
            [
                "DEBIAN_FRONTEND=noninteractive apt-get update -qq",
                "DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
                 chromium"
            ]
        );
    }

    #[test]
    fn passwordless_sudo_goes_through_sudo_n_with_the_environment_on_its_line() {
        let plan = plan(
            chromium(),
            &host(false, Sudo::Passwordless, &[Manager::Dnf]),
        );
        assert_eq!(shown(&plan), ["sudo -n dnf install -y chromium"]);
        let plan = super::plan(
            chromium(),
            &host(false, Sudo::Passwordless, &[Manager::Apt]),
        );
        assert_eq!(
            shown(&plan)[1],
            "sudo -n DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
             --no-install-recommends chromium"
        );
    }

    #[test]
    fn neither_root_nor_sudo_names_the_command_to_run() {
        match plan(
            chromium(),
            &host(false, Sudo::AsksPassword, &[Manager::Apt]),
        ) {
            Plan::Manual(text) => assert!(
                text.contains("sudo asks for a password: run `sudo apt-get install chromium`"),
                "{text}"
            ),
            Plan::Run(cmds) => panic!("no way to install, yet planned {cmds:?}"),
        }
        match plan(chromium(), &host(false, Sudo::Absent, &[Manager::Apt])) {
            Plan::Manual(text) => assert!(
                text.contains("no sudo: run `apt-get install chromium` as root"),
                "{text}"
            ),
            Plan::Run(cmds) => panic!("no way to install, yet planned {cmds:?}"),
        }
    }

    #[test]
    fn no_known_package_manager_lists_the_usual_commands() {
        match plan(chromium(), &host(true, Sudo::Absent, &[])) {
            Plan::Manual(text) => {
                assert!(text.contains("apt-get install chromium"), "{text}");
                assert!(text.contains("dnf install chromium"), "{text}");
            }
            Plan::Run(cmds) => panic!("no manager, yet planned {cmds:?}"),
        }
    }

    #[test]
    fn the_first_manager_found_is_used() {
        let plan = plan(
            chromium(),
            &host(true, Sudo::Absent, &[Manager::Pacman, Manager::Apk]),
        );
        assert_eq!(shown(&plan), ["pacman -S --noconfirm --needed chromium"]);
    }

    #[test]
    fn rust_components_need_rustup_not_root() {
        let rustfmt = PREREQUISITES.iter().find(|p| p.name == "rustfmt").unwrap();
        let plan = plan(rustfmt, &host(false, Sudo::Absent, &[]));
        assert_eq!(shown(&plan), ["rustup component add rustfmt"]);
        let no_rustup = Host {
            rustup: false,
            ..Host::default()
        };
        assert!(matches!(super::plan(rustfmt, &no_rustup), Plan::Manual(_)));
    }

    #[test]
    fn every_subcommand_named_exists_and_ci_needs_everything() {
        // `ci` runs every step, so it needs every prerequisite of every other subcommand.
        for p in PREREQUISITES {
            assert!(
                p.needed_by.contains(&"ci"),
                "{} is not needed by ci",
                p.name
            );
        }
        assert_eq!(needed_by("ci").count(), PREREQUISITES.len());
        assert_eq!(needed_by("validate").count(), 0);
        assert_eq!(
            needed_by("viewer").map(|p| p.name).collect::<Vec<_>>(),
            ["chromium"]
        );
        assert_eq!(
            needed_by("python").map(|p| p.name).collect::<Vec<_>>(),
            ["python3"]
        );
    }
}
