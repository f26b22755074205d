"""Type stub of the extension module ``impulse._impulse`` (crates/impulse-py/src).

Arrays are NumPy ``float64``; shapes are in each docstring: n bodies, nq configuration and nv
velocity coordinates of a multibody model.
"""

import os
from typing import Any, Callable, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, "os.PathLike[str]"]
_Vec = npt.ArrayLike
_F64 = npt.NDArray[np.float64]

__version__: str
"""The package's version (the workspace's, as Cargo.toml gives it)."""

class ImpulseError(ValueError):
    """An error of the library; the message names what is wrong and where."""

# Mass properties (thesis ch. 6)

class MassProperties:
    """Exact mass properties of a solid of uniform density."""

    @property
    def volume(self) -> float: ...
    @property
    def mass(self) -> float: ...
    @property
    def com(self) -> _F64:
        """Centre of mass, shape (3,)."""
    @property
    def inertia(self) -> _F64:
        """Inertia about the centre of mass, shape (3, 3)."""
    @property
    def principal_moments(self) -> _F64:
        """Principal moments, increasing, shape (3,)."""
    @property
    def principal_axes(self) -> _F64:
        """Shape (3, 3): row k is the axis of principal_moments[k]."""

def mass_properties(
    vertices: _Vec,
    faces: Union[npt.ArrayLike, Sequence[Sequence[int]]],
    density: Optional[float] = None,
    mass: Optional[float] = None,
) -> MassProperties:
    """vertices (n, 3); faces (m, k) ints or index lists, counter-clockwise from outside."""

def convex_hull(points: _Vec) -> Tuple[_F64, list[list[int]]]:
    """Hull of points (n, 3): vertices (v, 3) and faces (index lists, counter-clockwise)."""

def mass_properties_obj(
    path: _Path, density: Optional[float] = None, mass: Optional[float] = None
) -> MassProperties:
    """The mass properties `impulse massprops PATH` prints."""

# Worlds (thesis ch. 1-3, 7)

class Shape:
    """A body's shape, as a scene file's `shape:` field."""

    @staticmethod
    def box(half_extents: _Vec) -> Shape: ...
    @staticmethod
    def sphere(radius: float) -> Shape: ...
    @staticmethod
    def hull(points: _Vec) -> Shape:
        """Convex hull of points, shape (n, 3)."""
    @staticmethod
    def obj(path: _Path) -> Shape: ...
    @staticmethod
    def prism(sides: int, radius: float, half_height: float) -> Shape: ...
    @staticmethod
    def ellipsoid(semi_axes: _Vec, level: Optional[int] = None) -> Shape: ...
    @staticmethod
    def compound(parts: Sequence[Tuple[Shape, _Vec, _Vec]]) -> Shape:
        """Parts (shape, position (3,), quaternion x, y, z, w (4,))."""
    @staticmethod
    def from_ron(text: str) -> Shape: ...
    def to_ron(self) -> str: ...

class World:
    """A world of rigid bodies; arrays have one row per body, in `names()` order."""

    def __init__(
        self,
        collision_epsilon: float = 1e-4,
        gravity: Optional[_Vec] = None,
        friction: float = 0.3,
        restitution: float = 0.5,
        contact_model: str = "switching",
        base_dir: Optional[_Path] = None,
    ) -> None: ...
    @staticmethod
    def from_scene(path: _Path, contact_model: Optional[str] = None) -> World: ...
    def add_body(
        self,
        name: str,
        shape: Shape,
        position: Optional[_Vec] = None,
        rotation: Optional[_Vec] = None,
        velocity: Optional[_Vec] = None,
        angular_velocity: Optional[_Vec] = None,
        density: Optional[float] = None,
        mass: Optional[float] = None,
        material: Optional[str] = None,
        fixed: bool = False,
    ) -> int:
        """Returns the body's row; rotation is a quaternion (x, y, z, w)."""
    def add_multibody(self, desc: str) -> list[int]:
        """A scene file's `Multibody(...)` entry (RON); returns its links' rows."""
    def add_urdf(
        self,
        name: str,
        path: _Path,
        position: Optional[_Vec] = None,
        rotation: Optional[_Vec] = None,
        floating: bool = False,
        q: Optional[dict[str, float]] = None,
        qd: Optional[dict[str, float]] = None,
        self_collision: bool = False,
    ) -> list[int]:
        """A URDF robot as multibody `name`; q, qd by joint name; returns its links' rows."""
    def joint_state(self, name: str) -> Tuple[_F64, _F64]:
        """Multibody `name`'s q (nq,) and v (nv,)."""
    def multibody_names(self) -> list[str]:
        """The multibodies' names, in the order they were added."""
    def set_material_pair(self, a: str, b: str, friction: float, restitution: float) -> None: ...
    def step(self, dt: float) -> dict[str, Any]: ...
    def step_until(self, t: float) -> dict[str, Any]: ...
    @property
    def time(self) -> float: ...
    @property
    def contact_model(self) -> str:
        """"switching" or "impulse"."""
    def __len__(self) -> int: ...
    def names(self) -> list[str]: ...
    def positions(self) -> _F64:
        """Shape (n, 3)."""
    def orientations(self) -> _F64:
        """Quaternions (x, y, z, w), shape (n, 4)."""
    def velocities(self) -> _F64:
        """Shape (n, 3)."""
    def angular_velocities(self) -> _F64:
        """Shape (n, 3)."""
    def centres_of_mass(self) -> _F64:
        """Shape (n, 3)."""
    def states(self) -> _F64:
        """Shape (n, 16): position, quaternion, velocity, angular velocity, centre of mass."""
    def kinetic_energy(self) -> float: ...
    def impacts(self) -> dict[str, Any]:
        """Contacts resolved by the last step call, k of them: `time`, `normal_speed_before`,
        `normal_speed_after`, `energy_before`, `energy_after` (k,); `a`, `b` (k,) int rows;
        `kind` list of k strings ("collision", "microcollision", "reversing", "fallback");
        `impulse` (on `a`), `point`, `normal` (from `b` toward `a`) (k, 3)."""
    def held_pairs(self) -> npt.NDArray[np.int64]:
        """Pairs held as constraints now (switching model), shape (p, 2) int rows."""
    def held_contacts(self) -> dict[str, Any]:
        """The held pairs' points, k of them: `a`, `b` (k,) int rows; `point`, `normal` (from
        `a` toward `b`), `impulse` (on `b` over the last island step) (k, 3); `span` (k,), that
        step's length (s)."""
    def set_pose(self, name: str, position: _Vec, rotation: _Vec) -> None: ...
    def set_velocity(self, name: str, velocity: _Vec, angular_velocity: _Vec) -> None: ...
    def apply_impulse(self, name: str, impulse: _Vec, point: _Vec) -> None: ...
    def set_force(self, name: str, force: _Vec) -> None:
        """Force (3,) through the centre of mass, kept until changed."""
    def set_load(
        self,
        name: str,
        force: Optional[_Vec] = None,
        torque: Optional[_Vec] = None,
        point: Optional[_Vec] = None,
    ) -> None:
        """Constant force (3,) at `point` (3,, world; default the centre of mass) and torque
        (3,) about the centre of mass, world, kept until changed."""
    def set_load_function(
        self,
        name: str,
        function: Callable[[float, dict[str, _F64]], Sequence[_Vec]],
        rate: float,
    ) -> None:
        """`function(t, state)` -> (force, torque) or (force, torque, point), world, called
        every 1/rate s and held in between; `state`: `position`, `rotation`, `velocity`,
        `angular_velocity`, `com`. Its exception is raised by `step` (world unchanged)."""
    def clear_load(self, name: str) -> None: ...

# Articulated dynamics (thesis ch. 4)

class Model:
    """A URDF multibody model with its workspace."""

    @staticmethod
    def from_urdf(
        path: _Path, floating_base: bool = False, gravity: Optional[_Vec] = None
    ) -> Model: ...
    @property
    def nq(self) -> int: ...
    @property
    def nv(self) -> int: ...
    def joint_names(self) -> list[str]: ...
    def neutral_configuration(self) -> _F64:
        """Shape (nq,)."""

def aba(model: Model, q: _Vec, v: _Vec, tau: _Vec) -> _F64:
    """Forward dynamics: qdd, shape (nv,)."""

def rnea(model: Model, q: _Vec, v: _Vec, a: _Vec) -> _F64:
    """Inverse dynamics: tau, shape (nv,)."""

def crba(model: Model, q: _Vec) -> _F64:
    """Mass matrix, shape (nv, nv)."""

# Pose studies (thesis §7.5)

class PosePart:
    """A part with its stable poses; pickles for Dask."""

    @staticmethod
    def from_file(path: _Path) -> PosePart: ...
    @staticmethod
    def from_ron(text: str, base_dir: Optional[_Path] = None) -> PosePart: ...
    @staticmethod
    def new(
        name: str,
        points: Optional[_Vec] = None,
        shape: Optional[Shape] = None,
        density: Optional[float] = None,
        mass: Optional[float] = None,
    ) -> PosePart: ...
    @property
    def name(self) -> str: ...
    @property
    def diameter(self) -> float: ...
    def stable_facets(self) -> list[int]: ...
    def facet_normal(self, face: int) -> _F64:
        """Shape (3,)."""

def run_pose_shard(
    part: PosePart,
    drops: int,
    seed: int = 1,
    shard: Tuple[int, int] = (0, 1),
    threads: Optional[int] = None,
    height: float = 0.12,
    exit_speed: float = 0.05,
    friction: float = 0.3,
    restitution: float = 0.3,
    epsilon: Optional[float] = None,
    jitter: float = 1.5,
    uniform_only: bool = False,
    max_time: float = 10.0,
    out: Optional[_Path] = None,
    max_wall: Optional[float] = None,
) -> str:
    """The study file text `impulse poses --shard K/N --out FILE` writes; with `out`, kept in
    and resumed from the CLI's journal `OUT.partial`."""

def merge_pose_studies(studies: Sequence[str]) -> str:
    """The text `impulse poses merge ... --out FILE` writes."""

def pose_summary(
    part: PosePart, study: str, cone: float = 20.0, confidence: float = 0.95
) -> dict[str, Any]: ...

# The bowling study (thesis §7.4)

def run_bowling_shard(
    throws: int = 320,
    seed: int = 1,
    shard: Tuple[int, int] = (0, 1),
    threads: Optional[int] = None,
    alley: Optional[_Path] = None,
    speed: float = 8.0,
    spin: float = 12.0,
    angle: float = 2.0,
    center: float = 0.0,
    width: float = 0.40,
    settle: float = 4.0,
    out: Optional[_Path] = None,
    max_wall: Optional[float] = None,
) -> str:
    """The study file text `impulse bowling --shard K/N --out FILE` writes; with `out`, kept
    in the journal OUT.partial and resumed from it as the CLI does."""

def bowling_throw_scene(
    index: int,
    throws: int = 320,
    seed: int = 1,
    alley: Optional[_Path] = None,
    speed: float = 8.0,
    spin: float = 12.0,
    angle: float = 2.0,
    center: float = 0.0,
    width: float = 0.40,
    settle: float = 4.0,
) -> str:
    """The scene text `impulse bowling --scene INDEX` prints."""

def merge_bowling_studies(studies: Sequence[str]) -> str:
    """The text `impulse bowling merge ... --out FILE` writes."""

def bowling_summary(study: str, bin_width: float = 0.005) -> dict[str, Any]:
    """B bins: `lo`, `hi` (B,); `mean`, `se` (B, 2) float64 and `n` (B, 2) int, columns
    straight, hook; `window`, `pocket`, `head_on`, `shoulders`: dicts of `mean`, `se`, `n`
    (2,); `throws`, `throws_per_kind`, `outside`, `no_crossing`, `unsettled`."""

# Reduced compliant mechanisms (FORK⁻¹S)

class ReducedMechanism:
    """A FORK⁻¹S reduced model built at rest; E end effectors."""

    @staticmethod
    def from_file(path: _Path, tsvd: Optional[float] = None) -> ReducedMechanism: ...
    @property
    def name(self) -> str: ...
    @property
    def rank(self) -> int: ...
    def end_effectors(self) -> list[str]: ...
    def compliance(self) -> _F64:
        """C, shape (6E, 6E)."""
    def stiffness(self) -> _F64:
        """K = C⁺, shape (6E, 6E)."""
    def mass(self) -> _F64:
        """M, shape (6E, 6E)."""
    def reference_positions(self) -> _F64:
        """Shape (E, 3)."""
    def static_positions(self, loads: dict[str, _Vec]) -> _F64:
        """Reduced static response, shape (E, 3); loads: link -> force (3,) or wrench (6,)."""
    def full_static_positions(self, loads: dict[str, _Vec]) -> _F64:
        """Full nonlinear statics, shape (E, 3)."""
    def simulation(
        self,
        dt: float = 1e-3,
        loads: Optional[dict[str, _Vec]] = None,
        ground: Optional[float] = None,
        threads: Optional[int] = None,
    ) -> ReducedSimulation:
        """A reduced simulation at rest, to step (FORK⁻¹S §6)."""
    def simulate(
        self,
        until: float,
        dt: float = 1e-3,
        loads: Optional[dict[str, _Vec]] = None,
        ground: Optional[float] = None,
        threads: Optional[int] = None,
        every: int = 1,
    ) -> dict[str, Any]:
        """The run of `impulse reduce --until --dt --out`, F frames of L links: `links` (L
        names), `time` (F,), `positions` (F, L, 3), `orientations` (F, L, 4),
        `constraint_error` (F,)."""

class ReducedSimulation:
    """A running reduced simulation; L links: E end effectors, then internal links."""

    def step(self, steps: int = 1) -> _F64:
        """Advances `steps` steps; end-effector positions after them, shape (E, 3)."""
    def set_loads(self, loads: dict[str, _Vec]) -> None: ...
    @property
    def dt(self) -> float: ...
    @property
    def time(self) -> float: ...
    @property
    def steps(self) -> int: ...
    @property
    def contacts(self) -> int:
        """End-effector contacts with the ground in the last step."""
    def links(self) -> list[str]: ...
    def positions(self) -> _F64:
        """Shape (L, 3)."""
    def orientations(self) -> _F64:
        """Quaternions (x, y, z, w), shape (L, 4)."""
    def end_effector_positions(self) -> _F64:
        """Shape (E, 3)."""
    def state(self) -> Tuple[_F64, _F64]:
        """ξ and φ, each shape (E, 6), linear on top."""
    def energy(self) -> float: ...
    def constraint_error(self) -> float: ...
