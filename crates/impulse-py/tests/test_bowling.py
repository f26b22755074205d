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
