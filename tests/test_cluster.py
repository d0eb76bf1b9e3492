"""The cluster path: jobs submitted through Snakemake's executor plugins give the same bytes as a local run."""

import shutil

import pytest

from conftest import DEMO_RAW
from workflow_run import copy_project, digest, one_variant, run


def small_project(work):
    """One demo video, one variant: every rule of the workflow, few jobs."""
    return one_variant(copy_project(work, raw_files=[DEMO_RAW / "demo_p20.mp4"]))


@pytest.mark.slow
def test_local_cluster_profile_gives_the_local_runs_bytes(tmp_path):
    local = small_project(tmp_path / "local")
    cluster = small_project(tmp_path / "cluster")
    run(["-c2"], local)
    proc = run(["--profile", "profiles/local-cluster"], cluster)
    assert "Submitted job" in proc.stdout + proc.stderr, "jobs did not go through the cluster executor"
    produced = digest(cluster / "results")
    assert len(produced) > 10 and produced == digest(local / "results")
    shutil.rmtree(cluster / ".snakemake", ignore_errors=True)


@pytest.mark.slow
def test_slurm_profile_plans_the_workflow(tmp_path):
    work = small_project(tmp_path / "slurm")
    proc = run(["--profile", "profiles/slurm", "-n"], work)
    assert "rule tracks" in proc.stdout
