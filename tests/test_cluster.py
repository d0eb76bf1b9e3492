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


def test_the_local_cluster_profile_cancels_its_jobs_as_the_plugin_calls_the_command():
    """A helper pressed Ctrl-C on a run through the profile: the plugin runs the cancel command as one program with
    no shell ([command, job id, ...]), so "python3 profiles/local-cluster/cancel.py" was no file; the run crashed and
    its two running jobs were left to finish without metadata. Called as the plugin calls it, it stops the job."""
    import subprocess
    import sys

    import yaml

    from workflow_run import ROOT

    command = yaml.safe_load((ROOT / "profiles/local-cluster/config.yaml").read_text())["cluster-generic-cancel-cmd"]
    job = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"], start_new_session=True)
    try:
        subprocess.check_call([command, str(job.pid)], shell=False, cwd=ROOT)
        assert job.wait(timeout=10) != 0  # ended by the signal, not by its 60 s
    finally:
        job.kill()
