"""The bowling study (thesis §7.4) from Python: a shard, shards merged and a study spread over
a Dask LocalCluster of two workers, each against the file `impulse bowling --out` writes, byte
for byte; the binned pins felled against the CLI's `--csv`."""

import csv
import json
import math

import numpy as np
import pytest

import impulse

# Tiny on purpose: 4 throws of each kind, a quarter second after the crossing (a throw's
# roll down the lane is most of its cost), so each study runs in about two seconds.
THROWS, SEED, SETTLE = 4, 3, 0.25
ARGS = ("--throws", THROWS, "--seed", SEED, "--settle", SETTLE)


@pytest.fixture(scope="module")
def cli_study(cli, tmp_path_factory):
    """The file `impulse bowling` writes for the study, run unsharded in one process."""
    out = tmp_path_factory.mktemp("bowling") / "bowling.json"
    cli("bowling", *ARGS, "--out", out)
    return out.read_text()


def test_one_process_equals_impulse_bowling_byte_for_byte(cli_study):
    text = impulse.run_bowling_shard(THROWS, seed=SEED, settle=SETTLE, threads=2)
    assert text == cli_study
    study = json.loads(text)
    assert [o["index"] for o in study["outcomes"]] == list(range(2 * THROWS))
    assert [o["kind"] for o in study["outcomes"][:2]] == ["Straight", "Hook"]


def test_four_shards_merged_equal_the_unsharded_file(cli_study, cli, tmp_path):
    shards = [impulse.run_bowling_shard(THROWS, seed=SEED, settle=SETTLE, shard=(k, 4),
                                        threads=1)
              for k in range(4)]
    # A shard's text is the CLI's `--shard K/4 --out` file.
    out = tmp_path / "shard1.json"
    cli("bowling", *ARGS, "--shard", "1/4", "--out", out)
    assert shards[1] == out.read_text()
    assert [o["index"] for o in json.loads(shards[1])["outcomes"]] == [1, 5]
    assert impulse.merge_bowling_studies(shards[::-1]) == cli_study


def test_a_dask_cluster_of_two_workers_gives_the_same_file(cli_study, tmp_path):
    from dask import distributed

    from impulse.distributed import bowling_study

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        text = bowling_study(THROWS, shards=4, seed=SEED, settle=SETTLE, client=client,
                             out=tmp_path / "merged.json")
        assert len(client.run(lambda: 1)) == 2
    assert text == cli_study
    assert (tmp_path / "merged.json").read_text() == cli_study


def test_the_summary_bins_are_the_clis_csv(cli_study, cli, tmp_path):
    path, table = tmp_path / "study.json", tmp_path / "bins.csv"
    path.write_text(cli_study)
    cli("bowling", "--from", path, "--csv", table)
    with open(table) as f:
        rows = list(csv.DictReader(f))
    s = impulse.bowling_summary(cli_study)
    b = len(rows)
    assert b == 80  # the 40 cm window in 5 mm bins
    assert s["lo"].shape == s["hi"].shape == (b,)
    assert s["mean"].shape == s["se"].shape == s["n"].shape == (b, 2)
    assert s["mean"].dtype == np.float64
    np.testing.assert_allclose(s["lo"], [float(r["lo_m"]) for r in rows], atol=5e-5)
    np.testing.assert_allclose(s["hi"], [float(r["hi_m"]) for r in rows], atol=5e-5)
    for k, (kind, col) in enumerate([("straight", 0), ("hook", 1)]):
        assert s["n"][:, col].tolist() == [int(r[f"{kind}_n"]) for r in rows]
        # The CSV writes each mean in full (shortest round-trip digits), an empty bin blank.
        want = [float(r[f"{kind}_mean"]) if r[f"{kind}_mean"] else math.nan for r in rows]
        np.testing.assert_array_equal(s["mean"][:, col], want)
    # The window's means recounted from the file: throws crossing in [-0.2, 0.2) m.
    outcomes = json.loads(cli_study)["outcomes"]
    for col, kind in enumerate(["Straight", "Hook"]):
        felled = [o["felled"] for o in outcomes
                  if o["kind"] == kind and o["crossing"] is not None
                  and -0.2 <= o["crossing"] < 0.2]
        assert s["window"]["n"][col] == len(felled) == s["n"][:, col].sum()
        assert s["window"]["mean"][col] == pytest.approx(np.mean(felled), rel=1e-12)
    assert s["throws"] == 2 * THROWS and s["throws_per_kind"] == THROWS


def test_bad_arguments_raise_impulse_error_with_the_message(tmp_path, cli_study):
    with pytest.raises(impulse.ImpulseError, match="cannot read .*nowhere-alley.ron"):
        impulse.run_bowling_shard(2, alley=tmp_path / "nowhere-alley.ron")
    with pytest.raises(impulse.ImpulseError, match="throws.*at least one throw of each kind"):
        impulse.run_bowling_shard(0)
    with pytest.raises(impulse.ImpulseError, match="settle_time.*-1"):
        impulse.run_bowling_shard(2, settle=-1.0)
    with pytest.raises(impulse.ImpulseError, match="shard `4/4`"):
        impulse.run_bowling_shard(2, shard=(4, 4))
    with pytest.raises(impulse.ImpulseError, match=r"studies\[1\]: not a bowling study"):
        impulse.merge_bowling_studies([cli_study, "{}"])
    with pytest.raises(impulse.ImpulseError, match="throw 0"):
        impulse.merge_bowling_studies([cli_study, cli_study])  # a throw held twice
    with pytest.raises(impulse.ImpulseError, match="bin_width"):
        impulse.bowling_summary(cli_study, bin_width=0.0)


def test_a_throws_scene_is_the_clis_byte_for_byte(cli, tmp_path):
    text = impulse.bowling_throw_scene(5, throws=THROWS, seed=SEED, settle=SETTLE)
    assert text == cli("bowling", *ARGS, "--scene", 5)  # its standard output, newline and all
    assert text.startswith("// Throw 5 of a bowling study (seed 3, 4 throws of each kind)")
    path = tmp_path / "throw5.ron"
    path.write_text(text)
    w = impulse.World.from_scene(path)  # the saved scene replays the throw
    assert "ball" in w.names()
    # Throw 5 of 8 is a hook: its ball spins about +y at −spin (rad/s) at release.
    ball = w.names().index("ball")
    assert w.angular_velocities()[ball][1] == pytest.approx(-12.0, rel=1e-12)
    with pytest.raises(impulse.ImpulseError, match="throw 8: the study has throws 0 to 7"):
        impulse.bowling_throw_scene(8, throws=THROWS)


def journal_lines(path):
    return path.read_text().splitlines()


def test_a_study_the_cli_stopped_is_finished_by_python(cli_study, cli, tmp_path):
    out = tmp_path / "study.json"
    partial = tmp_path / "study.json.partial"
    # Stopped before its first throw: the CLI's journal holds its header only.
    cli("bowling", *ARGS, "--max-wall", "1e-9", "--out", out)
    assert not out.exists() and len(journal_lines(partial)) == 1
    # Three throws done before, one of them marked: it must be read back, not run again.
    whole = json.loads(cli_study)
    done = [dict(o) for o in whole["outcomes"] if o["index"] in (0, 2, 5)]
    done[2]["felled"] = 11  # no throw fells 11 of 10 pins
    with open(partial, "a") as f:
        for o in done:
            f.write(json.dumps(o) + "\n")
    text = impulse.run_bowling_shard(THROWS, seed=SEED, settle=SETTLE, threads=2, out=out)
    expected = dict(whole, outcomes=[done[2] if o["index"] == 5 else o
                                     for o in whole["outcomes"]])
    assert json.loads(text) == expected
    assert out.read_text() == text and not partial.exists()
    # Unmarked (all throws but one read back), the finished file is the CLI's whole study
    # byte for byte.
    out.unlink()
    cli("bowling", *ARGS, "--max-wall", "1e-9", "--out", out)
    with open(partial, "a") as f:
        for o in whole["outcomes"]:
            if o["index"] != 3:
                f.write(json.dumps(o) + "\n")
    assert impulse.run_bowling_shard(THROWS, seed=SEED, settle=SETTLE, threads=2,
                                     out=out) == cli_study
    assert out.read_text() == cli_study


def test_a_study_python_stopped_is_finished_by_the_cli(cli_study, cli, tmp_path):
    out = tmp_path / "study.json"
    partial = tmp_path / "study.json.partial"
    with pytest.raises(impulse.ImpulseError, match=r"after 0 of 8 throws; they are kept in"):
        impulse.run_bowling_shard(THROWS, seed=SEED, settle=SETTLE, out=out, max_wall=1e-9)
    assert not out.exists() and len(journal_lines(partial)) == 1
    # Stopped after a throw or two (one thread, 0.3 s), if this machine is not much faster.
    try:
        impulse.run_bowling_shard(THROWS, seed=SEED, settle=SETTLE, out=out, max_wall=0.3,
                                  threads=1)
        kept = 8  # a machine fast enough to throw all 8 in 0.3 s
    except impulse.ImpulseError as e:
        kept = int(str(e).split("after ")[1].split(" ")[0])
        assert 0 < kept < 8 and not out.exists()
        assert len(journal_lines(partial)) == 1 + kept  # the header, a line per throw
        report = cli("bowling", *ARGS, "--out", out)  # the CLI reads Python's journal
        assert f"resumed:          {kept} throws read back" in report
    assert out.read_text() == cli_study and not partial.exists()
    # A journal of another study is refused, naming it.
    cli("bowling", *ARGS, "--max-wall", "1e-9", "--out", out)
    with pytest.raises(impulse.ImpulseError, match=r"study\.json\.partial holds the runs of "
                                                   r"another study"):
        impulse.run_bowling_shard(THROWS, seed=SEED + 1, settle=SETTLE, out=out)
    with pytest.raises(impulse.ImpulseError, match="max_wall 0"):
        impulse.run_bowling_shard(THROWS, out=out, max_wall=0.0)
