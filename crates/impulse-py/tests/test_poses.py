"""Pose studies (thesis §7.5) from Python: shards and merge against `impulse poses`, byte for
byte, and a study spread over a Dask LocalCluster of two workers."""

import json
import pathlib

import numpy as np
import pytest

import impulse

DROPS, SEED = 40, 5


@pytest.fixture(scope="module")
def part(root):
    return impulse.PosePart.from_file(root / "fixtures/parts/box-1x2x3.ron")


@pytest.fixture(scope="module")
def cli_study(cli, root, tmp_path_factory):
    """The file `impulse poses` writes for the study, run in one process."""
    out = tmp_path_factory.mktemp("poses") / "poses.json"
    cli("poses", root / "fixtures/parts/box-1x2x3.ron", "--drops", DROPS, "--seed", SEED,
        "--out", out)
    return out.read_text()


def test_one_process_equals_impulse_poses_byte_for_byte(part, cli_study):
    text = impulse.run_pose_shard(part, DROPS, seed=SEED, threads=2)
    assert text == cli_study
    study = json.loads(text)
    assert [o["index"] for o in study["outcomes"]] == list(range(DROPS))


def test_shards_merged_equal_the_whole_study(part, cli_study, cli, tmp_path):
    shards = [impulse.run_pose_shard(part, DROPS, seed=SEED, shard=(k, 3), threads=1)
              for k in range(3)]
    # Each shard's text is the CLI's `--shard K/3 --out` file.
    out = tmp_path / "shard1.json"
    cli("poses", "fixtures/parts/box-1x2x3.ron", "--drops", DROPS, "--seed", SEED,
        "--shard", "1/3", "--out", out)
    assert shards[1] == out.read_text()
    assert [o["index"] for o in json.loads(shards[1])["outcomes"]] == list(range(1, DROPS, 3))
    assert impulse.merge_pose_studies(shards[::-1]) == cli_study


def test_the_summary_counts_every_drop(part, cli_study):
    s = impulse.pose_summary(part, cli_study)
    assert s["drops"] == DROPS and s["uniform_drops"] == DROPS // 2
    # Each pose's count recounted from the file: uniform drops (no `start`) resting on one of
    # its facets.
    outcomes = json.loads(cli_study)["outcomes"]
    for r in s["rows"]:
        recount = sum(1 for o in outcomes if "start" not in o and o.get("facet") in r["facets"])
        assert r["uniform_count"] == recount
    assert sum(r["uniform_count"] for r in s["rows"]) > 0
    # The quasi-static estimates of the 1 × 2 × 3 box (thesis Table 7.5's part): 64.50 %,
    # 24.27 %, 11.23 % on the 2 × 3, 1 × 3 and 1 × 2 faces.
    qs = sorted((r["quasi_static"] for r in s["rows"]), reverse=True)
    np.testing.assert_allclose(qs, [0.6450, 0.2427, 0.1123], atol=5e-5)
    # The uniform drops' shares are counts over the uniform drops classified.
    for r in s["rows"]:
        assert r["interval"][0] <= r["uniform"] <= r["interval"][1]


def test_a_part_from_a_numpy_hull_pickles_and_runs(tmp_path):
    import pickle

    rng = np.random.default_rng(2)
    pts = rng.normal(size=(30, 3)) * [0.01, 0.015, 0.02]
    part = impulse.PosePart.new("pebble", points=pts, density=2500.0)
    again = pickle.loads(pickle.dumps(part))
    assert again.name == "pebble" and again.stable_facets() == part.stable_facets()
    a = impulse.run_pose_shard(part, 6, seed=1, threads=1)
    assert impulse.run_pose_shard(again, 6, seed=1, threads=1) == a


def test_a_dask_cluster_of_two_workers_gives_the_same_file(part, cli_study, tmp_path):
    from dask import distributed

    from impulse.distributed import pose_study

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        text = pose_study(part, DROPS, shards=4, seed=SEED, client=client,
                          out=tmp_path / "merged.json")
        # Each shard ran as its own task, on the cluster's workers.
        assert len(client.run(lambda: 1)) == 2
    assert text == cli_study
    assert (tmp_path / "merged.json").read_text() == cli_study
    single = impulse.pose_summary(part, impulse.run_pose_shard(part, DROPS, seed=SEED))
    spread = impulse.pose_summary(part, text)
    assert [r["uniform_count"] for r in spread["rows"]] == \
        [r["uniform_count"] for r in single["rows"]]


MARK = 1234.5  # a drop's `time` no drop can have (max_time is 10 s): read back, not run


def journal_lines(path):
    return path.read_text().splitlines()


def append_outcomes(path, outcomes):
    with open(path, "a") as f:
        for o in outcomes:
            f.write(json.dumps(o) + "\n")


def test_a_stopped_study_resumes_from_its_journal_byte_for_byte(part, cli_study, cli, root,
                                                                tmp_path):
    out = tmp_path / "study.json"
    partial = tmp_path / "study.json.partial"
    whole = json.loads(cli_study)
    with pytest.raises(impulse.ImpulseError, match=r"after 0 of 40 drops; they are kept in"):
        impulse.run_pose_shard(part, DROPS, seed=SEED, out=out, max_wall=1e-9)
    assert not out.exists() and len(journal_lines(partial)) == 1  # the header only
    # Every drop but two done before, one of them marked: read back, not dropped again; the
    # rerun drops only the two missing.
    done = [dict(o) for o in whole["outcomes"] if o["index"] not in (3, 17)]
    done[5]["time"] = MARK
    append_outcomes(partial, done)
    text = impulse.run_pose_shard(part, DROPS, seed=SEED, threads=2, out=out)
    marked = [o for o in json.loads(text)["outcomes"] if o["time"] == MARK]
    assert [o["index"] for o in marked] == [done[5]["index"]]
    assert json.loads(text) == dict(whole, outcomes=[
        done[5] if o["index"] == done[5]["index"] else o for o in whole["outcomes"]])
    assert out.read_text() == text and not partial.exists()
    # A journal cut by hand in the middle of a line (a kill while writing): the cut line is
    # dropped and its drop run again; the file is the uninterrupted run's, byte for byte.
    out.unlink()
    with pytest.raises(impulse.ImpulseError, match="after 0 of 40 drops"):
        impulse.run_pose_shard(part, DROPS, seed=SEED, out=out, max_wall=1e-9)
    append_outcomes(partial, whole["outcomes"][:30])
    cut = partial.read_text()
    partial.write_text(cut[: len(cut) - 25])
    assert impulse.run_pose_shard(part, DROPS, seed=SEED, threads=2, out=out) == cli_study
    assert out.read_text() == cli_study and not partial.exists()
    # Stopped by the wall-time limit after some drops (one thread, 0.5 s) and resumed by the
    # CLI, which reads Python's journal, or by Python: the uninterrupted run's file.
    out.unlink()
    try:
        impulse.run_pose_shard(part, DROPS, seed=SEED, threads=1, out=out, max_wall=0.5)
        kept = DROPS  # a machine fast enough to drop all 40 in 0.5 s
    except impulse.ImpulseError as e:
        kept = int(str(e).split("after ")[1].split(" ")[0])
        assert 0 < kept < DROPS and not out.exists()
        assert len(journal_lines(partial)) == 1 + kept
        report = cli("poses", root / "fixtures/parts/box-1x2x3.ron", "--drops", DROPS,
                     "--seed", SEED, "--out", out)
        assert f"resumed:          {kept} drops read back" in report
    assert out.read_text() == cli_study and not partial.exists()


def test_a_finished_shard_file_is_returned_without_dropping_again(part, cli, tmp_path):
    out = tmp_path / "shard.json"
    text = impulse.run_pose_shard(part, DROPS, seed=SEED, shard=(2, 8), threads=1, out=out)
    marked = json.loads(text)
    marked["outcomes"][1]["time"] = MARK
    out.write_text(json.dumps(marked))
    again = json.loads(impulse.run_pose_shard(part, DROPS, seed=SEED, shard=(2, 8), out=out))
    assert again == marked  # read, not dropped again
    # A file of another shard or study at `out` is not taken: the shard runs, as the CLI's
    # --out would, and overwrites it.
    fresh = impulse.run_pose_shard(part, DROPS, seed=SEED, shard=(3, 8), threads=1, out=out)
    assert [o["index"] for o in json.loads(fresh)["outcomes"]] == list(range(3, DROPS, 8))
    assert out.read_text() == fresh
    with pytest.raises(impulse.ImpulseError, match="max_wall -1"):
        impulse.run_pose_shard(part, DROPS, out=out, max_wall=-1.0)


def test_a_killed_dask_study_rerun_does_only_the_missing_drops(part, cli_study, tmp_path):
    from dask import distributed

    from impulse.distributed import pose_study, shard_path

    whole = json.loads(cli_study)
    owned = lambda k: [o for o in whole["outcomes"] if o["index"] % 4 == k]  # noqa: E731

    def killed(out, mark):
        """The files a 4-shard study killed midway leaves: shard 0 finished, shard 1 half
        journaled, shards 2 and 3 not started. With `mark`, one drop of each kept shard is
        marked, to show it is read back."""
        first = impulse.run_pose_shard(part, DROPS, seed=SEED, shard=(0, 4), threads=1,
                                       out=shard_path(out, 0, 4))
        kept = []
        if mark:
            study = json.loads(first)
            study["outcomes"][2]["time"] = MARK
            kept.append(study["outcomes"][2])
            with open(shard_path(out, 0, 4), "w") as f:
                json.dump(study, f)
        with pytest.raises(impulse.ImpulseError, match="after 0 of 10 drops"):
            impulse.run_pose_shard(part, DROPS, seed=SEED, shard=(1, 4),
                                   out=shard_path(out, 1, 4), max_wall=1e-9)
        half = [dict(o) for o in owned(1)[:5]]
        if mark:
            half[4]["time"] = MARK
            kept.append(half[4])
        append_outcomes(pathlib.Path(shard_path(out, 1, 4) + ".partial"), half)
        return kept

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        out = tmp_path / "marked.json"
        kept = killed(out, mark=True)
        text = pose_study(part, DROPS, shards=4, seed=SEED, client=client, out=out)
        marks = {o["index"]: o for o in kept}
        assert json.loads(text) == dict(whole, outcomes=[marks.get(o["index"], o)
                                                         for o in whole["outcomes"]])
        out = tmp_path / "merged.json"
        killed(out, mark=False)
        text = pose_study(part, DROPS, shards=4, seed=SEED, client=client, out=out)
    assert text == cli_study and out.read_text() == cli_study
    # The shards' files and journals are gone once the study's file is written.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["marked.json", "merged.json"]
