"""Pose and bowling studies spread over a Dask cluster: one task per shard, merged by the
library.

A pose study (thesis §7.5) of ``drops`` drops is cut into ``shards`` shards (shard K runs drops
K, K + N, K + 2N, ...); each shard is one Dask task calling :func:`impulse.run_pose_shard` on a
worker, and one last task merges their files with :func:`impulse.merge_pose_studies`, the
library's own merge. A drop's outcome depends only on (seed, drop index), so the merged file is
byte for byte the file ``impulse poses PART --drops DROPS --seed SEED --out FILE`` writes on one
machine, whatever the number of shards, workers or threads.

Example (a local cluster of two worker processes)::

    from dask.distributed import Client, LocalCluster
    import impulse
    from impulse.distributed import pose_study

    part = impulse.PosePart.from_file("fixtures/parts/box-1x2x3.ron")
    with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
        text = pose_study(part, drops=2000, shards=8, client=client)
    table = impulse.pose_summary(part, text)

A bowling study (thesis §7.4) of ``throws`` throws of each kind is spread the same way with
:func:`bowling_study` (shard K runs throws K, K + N, ...; :func:`impulse.run_bowling_shard` per
task, :func:`impulse.merge_bowling_studies` to merge): the merged file is byte for byte the
file ``impulse bowling --throws THROWS --seed SEED --out FILE`` writes on one machine::

    with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
        text = bowling_study(throws=320, shards=16, client=client)
    bins = impulse.bowling_summary(text)

With ``out``, each shard keeps its drops as ``impulse poses --shard K/N --out`` keeps them: in
the file ``OUT.shard-K-of-N`` and, while it runs, its journal ``OUT.shard-K-of-N.partial``. A
study whose cluster was killed, run again with the same arguments and ``out``, does only the
drops (or throws) no shard had finished: a shard whose file is written returns it, a shard
with a journal runs only the drops it lacks. The shard files are removed once ``out`` is
written. Workers write them, so ``out`` must be on a file system every worker sees.

Without Dask, the same shards run as a Slurm job array of ``impulse poses --shard K/N`` and
``impulse poses merge`` (the README's "impulse poses" section has the script), or of
``impulse bowling --shard K/N`` and ``impulse bowling merge``.

Dask is imported only when these functions are called: ``pip install "dask[distributed]"``.
"""

from __future__ import annotations

import os
from typing import Any, Optional, Union

from . import _impulse

__all__ = [
    "bowling_study",
    "bowling_study_graph",
    "pose_study",
    "pose_study_graph",
    "shard_path",
]

_PathLike = Union[str, "os.PathLike[str]"]


def shard_path(out: _PathLike, k: int, shards: int) -> str:
    """The file (absolute) in which shard ``k`` of ``shards`` of a study written to ``out`` is kept:
    ``OUT.shard-K-of-N`` (its journal is that name with ``.partial`` added)."""
    return f"{os.path.abspath(os.fspath(out))}.shard-{k}-of-{shards}"


def _shard_outs(out: Optional[_PathLike], shards: int) -> list:
    return [None if out is None else shard_path(out, k, shards) for k in range(shards)]


def pose_study_graph(
    part: _impulse.PosePart,
    drops: int,
    shards: int,
    *,
    seed: int = 1,
    threads_per_shard: int = 1,
    out: Optional[_PathLike] = None,
    **settings: Any,
):
    """The study as a Dask graph: a ``dask.delayed`` object whose value is the merged file text.

    One task per shard (``impulse.run_pose_shard(part, drops, seed=seed, shard=(k, shards),
    threads=threads_per_shard, out=shard_path(out, k, shards), **settings)``) and one merge
    task. ``settings`` are the drop settings of :func:`impulse.run_pose_shard` (``height``,
    ``exit_speed``, ``friction``, ``restitution``, ``epsilon``, ``jitter``, ``uniform_only``,
    ``max_time``). With ``out``, each shard is kept in its file (:func:`shard_path`) and a
    graph computed again resumes the shards; nothing writes ``out`` itself. The part is shipped
    to the workers pickled (by its file path, which must be readable there, or by its
    description). Compute it with any Dask scheduler.
    """
    import dask

    shards = _shards_checked(shards)
    if not isinstance(drops, int) or drops < 1:
        raise _impulse.ImpulseError(f"drops = {drops!r}: a study needs at least one drop")
    run = dask.delayed(_impulse.run_pose_shard, pure=True)
    parts = [
        run(
            part,
            drops,
            seed=seed,
            shard=(k, shards),
            threads=threads_per_shard,
            out=kept,
            **settings,
        )
        for k, kept in enumerate(_shard_outs(out, shards))
    ]
    return dask.delayed(_impulse.merge_pose_studies, pure=True)(parts)


def _shards_checked(shards: Any) -> int:
    if not isinstance(shards, int) or shards < 1:
        raise _impulse.ImpulseError(f"shards = {shards!r}: need a whole number ≥ 1")
    return shards


def _compute(graph: Any, client: Optional[Any], out: Optional[_PathLike], shards: int) -> str:
    """The graph's value on ``client`` (default: the current client, else Dask's default
    scheduler), also written to ``out`` if given, as the CLI's ``--out`` writes it; then the
    shards' files (:func:`shard_path`) are removed."""
    if client is None:
        try:
            from dask.distributed import get_client

            client = get_client()
        except (ImportError, ValueError):
            client = None
    text = client.compute(graph).result() if client is not None else graph.compute()
    if out is not None:
        with open(out, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
        for kept in _shard_outs(out, shards):
            if os.path.exists(kept):
                os.remove(kept)
    return text


def pose_study(
    part: _impulse.PosePart,
    drops: int,
    shards: int,
    *,
    client: Optional[Any] = None,
    seed: int = 1,
    threads_per_shard: int = 1,
    out: Optional[_PathLike] = None,
    **settings: Any,
) -> str:
    """Runs a pose study as ``shards`` Dask tasks and returns the merged study file's text.

    ``client``: a ``dask.distributed.Client`` (default: the current client if there is one,
    else Dask's default scheduler). ``out``: also write the text to this file, as ``impulse
    poses --out`` does, and keep each shard's drops on the way (:func:`shard_path`), so that
    the same call made again after a kill runs only the drops not yet done. The text equals, byte for byte, the file of the same study run in one
    process (``impulse.run_pose_shard(part, drops, seed=seed)``) or by ``impulse poses``.
    Read the estimates with :func:`impulse.pose_summary`. A failed shard raises its
    :class:`impulse.ImpulseError` here.
    """
    graph = pose_study_graph(
        part, drops, shards, seed=seed, threads_per_shard=threads_per_shard, out=out, **settings
    )
    return _compute(graph, client, out, shards)


def bowling_study_graph(
    throws: int,
    shards: int,
    *,
    seed: int = 1,
    threads_per_shard: int = 1,
    out: Optional[_PathLike] = None,
    **settings: Any,
):
    """The bowling study as a Dask graph: a ``dask.delayed`` whose value is the merged file text.

    One task per shard (``impulse.run_bowling_shard(throws, seed=seed, shard=(k, shards),
    threads=threads_per_shard, out=shard_path(out, k, shards), **settings)``) and one merge
    task (:func:`impulse.merge_bowling_studies`). With ``out``, shards are kept and resumed as
    in :func:`pose_study_graph`. ``settings`` are the keywords of
    :func:`impulse.run_bowling_shard` (``speed``, ``spin``, ``angle``, ``center``, ``width``,
    ``settle``, ``alley``: an alley file's path, which must be readable on the workers).
    Compute it with any Dask scheduler.
    """
    import dask

    shards = _shards_checked(shards)
    if not isinstance(throws, int) or throws < 1:
        raise _impulse.ImpulseError(
            f"throws = {throws!r}: a study needs at least one throw of each kind"
        )
    run = dask.delayed(_impulse.run_bowling_shard, pure=True)
    parts = [
        run(throws, seed=seed, shard=(k, shards), threads=threads_per_shard, out=kept, **settings)
        for k, kept in enumerate(_shard_outs(out, shards))
    ]
    return dask.delayed(_impulse.merge_bowling_studies, pure=True)(parts)


def bowling_study(
    throws: int,
    shards: int,
    *,
    client: Optional[Any] = None,
    seed: int = 1,
    threads_per_shard: int = 1,
    out: Optional[_PathLike] = None,
    **settings: Any,
) -> str:
    """Runs a bowling study (thesis §7.4) as ``shards`` Dask tasks; returns the merged file's text.

    ``throws`` of each kind (straight and hook) in the whole study; ``settings`` as
    :func:`impulse.run_bowling_shard`'s keywords. ``client``: a ``dask.distributed.Client``
    (default: the current client if there is one, else Dask's default scheduler). ``out``: also
    write the text to this file, as ``impulse bowling --out`` does, and keep each shard's throws
    on the way (:func:`shard_path`), so that the same call made again after a kill throws only
    what was not yet thrown. The text equals, byte for
    byte, the file of the same study run in one process (``impulse.run_bowling_shard(throws,
    seed=seed, **settings)``) or by ``impulse bowling``. Read the pins felled per bin with
    :func:`impulse.bowling_summary`. A failed shard raises its :class:`impulse.ImpulseError`
    here.
    """
    graph = bowling_study_graph(
        throws, shards, seed=seed, threads_per_shard=threads_per_shard, out=out, **settings
    )
    return _compute(graph, client, out, shards)
