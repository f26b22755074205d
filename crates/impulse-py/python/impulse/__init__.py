"""impulse: physically accurate rigid-body simulation, NumPy in and out.

The simulator of Mirtich's impulse-based thesis (1996) as a Python package, built from the Rust
crates of this workspace (``crates/impulse-py``). Every array is ``float64``; shapes are given
in each docstring and in the type stub (``_impulse.pyi``). Long calls release the GIL. Every
error of the library is raised as :class:`ImpulseError` (a ``ValueError``) carrying the
library's message, which names what is wrong and where.

- :func:`mass_properties`, :func:`mass_properties_obj`: exact mass properties (thesis ch. 6);
- :class:`World`, :class:`Shape`: worlds from scene files or built in code, stepped, read as
  arrays, pushed by loads and by Python load functions (thesis ch. 1-3, 7);
- :class:`Model`, :func:`aba`, :func:`rnea`, :func:`crba`: articulated dynamics of URDF
  models (thesis ch. 4);
- :class:`PosePart`, :func:`run_pose_shard`, :func:`merge_pose_studies`,
  :func:`pose_summary`: pose studies (thesis §7.5), in shards; :mod:`impulse.distributed`
  runs them as Dask tasks;
- :func:`run_bowling_shard`, :func:`merge_bowling_studies`, :func:`bowling_summary`: the
  bowling study (thesis §7.4), in shards, kept in the CLI's journal to resume a stopped one;
  :func:`bowling_throw_scene` the scene of one throw; :mod:`impulse.distributed` runs it as
  Dask tasks;
- :class:`ReducedMechanism`, :class:`ReducedSimulation`: FORK⁻¹S reduced compliant
  mechanisms, their matrices and static response beside the full nonlinear statics, and their
  reduced dynamics, stepped or run as ``impulse reduce`` runs them.
"""

from ._impulse import (
    ImpulseError,
    __version__,
    MassProperties,
    Model,
    PosePart,
    ReducedMechanism,
    ReducedSimulation,
    Shape,
    World,
    aba,
    bowling_summary,
    bowling_throw_scene,
    convex_hull,
    crba,
    mass_properties,
    mass_properties_obj,
    merge_bowling_studies,
    merge_pose_studies,
    pose_summary,
    rnea,
    run_bowling_shard,
    run_pose_shard,
)

__all__ = [
    "__version__",
    "ImpulseError",
    "MassProperties",
    "Model",
    "PosePart",
    "ReducedMechanism",
    "ReducedSimulation",
    "Shape",
    "World",
    "aba",
    "bowling_summary",
    "bowling_throw_scene",
    "convex_hull",
    "crba",
    "mass_properties",
    "mass_properties_obj",
    "merge_bowling_studies",
    "merge_pose_studies",
    "pose_summary",
    "rnea",
    "run_bowling_shard",
    "run_pose_shard",
]
