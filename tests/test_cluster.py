"""The cluster path: jobs submitted through Snakemake's executor plugins give the same bytes as a local run."""

import shutil

import pytest

from workflow_run import digest, only_the_bad_videos_failed, run, small_project


def test_local_cluster_profile_gives_the_local_runs_bytes(tmp_path, small_build):
    """Also where trials fail: the same failed documents, the others built, the end non-zero."""
    cluster = small_project(tmp_path / "cluster")
    proc = run(["--profile", "profiles/local-cluster"], cluster, check=False)
    assert "Submitted job" in proc.stdout + proc.stderr, "jobs did not go through the cluster executor"
    assert proc.returncode != 0 and small_build.returncode != 0, "the two failed trials must end the build non-zero"
    assert only_the_bad_videos_failed(cluster) and only_the_bad_videos_failed(small_build.work)
    produced = digest(cluster / "results")
    assert len(produced) > 10 and produced == digest(small_build.work / "results")
    shutil.rmtree(cluster / ".snakemake", ignore_errors=True)


@pytest.mark.slow
def test_slurm_profile_plans_the_workflow(tmp_path):
    work = small_project(tmp_path / "slurm")
    proc = run(["--profile", "profiles/slurm", "-n"], work)
    assert "rule tracks" in proc.stdout
