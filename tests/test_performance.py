"""Thread budgets and the pipelined decoder (issue 13): what a job asks the scheduler for is what it uses.

Speed itself is measured by tests/benchmarks/record.py, not here.
"""

import json
import os
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

from pendulum.camera import video

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = ROOT / "workflow" / "scripts"
FPS = 25
LEVELS = [40 + 12 * k for k in range(16)]  # each frame one flat grey level


@pytest.fixture(scope="module")
def graded_clip(tmp_path_factory):
    """16 frames of 96×64 H.264 at 25 fps, frame k flat at grey LEVELS[k] (known content and order)."""
    import av

    path = tmp_path_factory.mktemp("clip") / "graded.mp4"
    with av.open(str(path), "w") as out:
        stream = out.add_stream("libx264", rate=FPS)
        stream.width, stream.height, stream.pix_fmt = 96, 64, "yuv420p"
        stream.options = {"crf": "10", "bframes": "2", "g": "8"}
        for level in LEVELS:
            rgb = np.full((64, 96, 3), level, np.uint8)
            for packet in stream.encode(av.VideoFrame.from_ndarray(rgb, format="rgb24")):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)
    return path


def _luma_level(rgb_level: int) -> float:
    """BT.601 limited-range luma of a grey RGB level (what libswscale writes): 16 + 219·v/255."""
    return 16 + 219 * rgb_level / 255


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_decoder_uses_exactly_the_threads_asked_for(graded_clip, monkeypatch, threads):
    opened = []
    real_open = video._open

    def spy(path):
        container = real_open(path)
        opened.append(container)
        return container

    monkeypatch.setattr(video, "_open", spy)
    frames = video.iter_luma(graded_clip, threads=threads)
    next(frames)
    assert opened[0].streams.video[0].codec_context.thread_count == threads
    frames.close()
    # the module-level setting (what a workflow job's _setup gives) is the default
    monkeypatch.setattr(video, "DECODER_THREADS", threads + 1)
    frames = video.iter_luma(graded_clip)
    next(frames)
    assert opened[1].streams.video[0].codec_context.thread_count == threads + 1
    frames.close()


def test_pipelined_decode_gives_every_frame_in_order_with_its_time(graded_clip):
    """Decoding ahead in a thread changes nothing: 16 frames, times k/25 s, each at its own grey level."""
    for threads in (1, 2):
        got = [(index, t, float(y.mean())) for index, t, y in video.iter_luma(graded_clip, threads=threads)]
        assert [g[0] for g in got] == list(range(len(LEVELS)))
        assert np.allclose([g[1] for g in got], np.arange(len(LEVELS)) / FPS, atol=1e-9)
        assert np.allclose([g[2] for g in got], [_luma_level(v) for v in LEVELS], atol=1.5)


def test_a_consumer_that_stops_early_leaves_no_decoder_thread(graded_clip):
    frames = video.iter_luma(graded_clip, threads=2)
    first = [next(frames)[2].copy() for _ in range(3)]
    frames.close()  # as `break` out of a for loop does
    assert not [t for t in threading.enumerate() if t.name == "pendulum-decoder"]
    assert [round(f.mean()) for f in first] == [round(_luma_level(v)) for v in LEVELS[:3]]


def test_decode_ahead_holds_a_few_frames_not_the_video(graded_clip, monkeypatch):
    """A stalled consumer: the decoder thread stops DECODE_AHEAD_FRAMES (+ the one in hand) ahead."""
    monkeypatch.setattr(video, "DECODE_AHEAD_FRAMES", 2)
    decoded = []
    real = video._decoded_frames

    def counting(*args):
        for item in real(*args):
            decoded.append(item)
            yield item

    monkeypatch.setattr(video, "_decoded_frames", counting)
    frames = video.iter_luma(graded_clip, threads=1)
    next(frames)
    for _ in range(100):  # let the decoder run ahead as far as it may
        threading.Event().wait(0.01)
    assert 2 <= len(decoded) <= 1 + 2 + 1  # in hand, queued, and one waiting to be queued
    frames.close()


def _run_setup(threads):
    """Import workflow/scripts/_setup.py as a Snakemake script does (``snakemake`` in __main__)."""
    code = (
        "import sys, types, json, os\n"
        f"if {threads!r} is not None:\n"
        f"    sys.modules['__main__'].snakemake = types.SimpleNamespace(threads={threads!r})\n"
        f"sys.path.insert(0, {str(SCRIPTS)!r})\n"
        "import _setup\n"
        "numpy_before = 'numpy' in sys.modules\n"
        "from pendulum.camera import video\n"
        "import cv2\n"
        "keys = ['OMP_NUM_THREADS', 'OPENBLAS_NUM_THREADS', 'MKL_NUM_THREADS', 'OPENCV_FOR_THREADS_NUM',"
        " 'PENDULUM_DECODER_THREADS']\n"
        "print(json.dumps({'env': {k: os.environ.get(k) for k in keys}, 'numpy_before': numpy_before,"
        " 'decoder': video.DECODER_THREADS, 'opencv': cv2.getNumThreads()}))\n"
    )
    env = {k: v for k, v in os.environ.items() if "THREADS" not in k}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    return json.loads(proc.stdout)


@pytest.mark.parametrize("threads", [1, 3])
def test_setup_ties_blas_and_decoder_threads_to_the_rule(threads):
    result = _run_setup(threads)
    assert result["env"] == dict.fromkeys(result["env"], str(threads))
    assert result["numpy_before"] is False  # set before any BLAS library loads
    assert result["decoder"] == threads
    assert result["opencv"] == threads  # OpenCV's loops too (before, 2 threads in a 1-thread job on 2 cores)


def test_setup_outside_snakemake_leaves_threads_alone():
    result = _run_setup(None)
    assert result["env"] == dict.fromkeys(result["env"])
    assert result["decoder"] is None


def test_every_rule_declares_threads_memory_and_runtime():
    sys.path.insert(0, str(ROOT / "tests" / "benchmarks"))
    from workflow_rules import rule_declarations

    rules = rule_declarations()
    assert {"frames", "tracks", "angles", "fit_trial", "fit_joint", "report"} <= set(rules)
    missing = {name: d for name, d in rules.items() if name != "all" and None in (d["threads"], d["mem_mb"])}
    missing |= {name: d for name, d in rules.items() if name != "all" and d["runtime"] is None}
    assert not missing
    assert rules["tracks"]["threads"] == 1  # two tracks jobs side by side beat one with two decoder threads


def test_the_tracks_job_declares_memory_and_time_by_the_clip_s_size():
    """A 4K clip's tracks job peaked at 4.3 GB before its scene was taken a band of rows at a time, 2.2 GB after
    (75 samples held; up to 119: ~2.9 GB), against a fixed 2000 MB declared: a cluster would have killed it. The
    rule now declares by the picture (the frames stage's summary), 2000 MB up to 1080p as before."""
    from pendulum.tracking.settings import job_resources

    assert job_resources(1280, 720, 660) == (2000, 60)
    assert job_resources(1920, 1080, 1200) == (2000, 60)
    mem_mb, runtime = job_resources(3840, 2160, 600)
    assert mem_mb == 3400 and mem_mb > 2900 and runtime == 60  # measured: 2.2 GB and 81 s
    assert job_resources(3840, 2160, 18000)[1] == 250  # five minutes at 60 fps: 0.13 s per frame measured: 40 min


def test_a_group_fit_declares_memory_by_its_trials_and_samples():
    """Discovery on copies of the demo's records (~630 samples each) peaked at 0.31 GB for 20 trials, 1.05 GB for
    80 and 3.34 GB for 160 while it held the dense Jacobian, against a fixed 2000 MB declared: a cluster would
    have killed the last. From SPARSE_FROM_TRIALS trials it holds the sparse one: 0.29 GB for 40, 0.41 GB for
    160 (2026-12-03). The joint, body and discovery rules declare by their trials' samples."""
    from pendulum.fit import output_error
    from pendulum.groups import SPARSE_FROM_TRIALS, group_job_mem_mb

    assert SPARSE_FROM_TRIALS == output_error.SPARSE_FROM_TRIALS  # one threshold, two modules' copies
    assert group_job_mem_mb([630] * 5) == 2000
    assert group_job_mem_mb([630] * 160) == 2000  # measured 0.41 GB
    assert group_job_mem_mb([100_000] * 10) > 2900  # ten records of 28 min at 60 fps: a dense Jacobian of 2.9 GB
    assert 2000 < group_job_mem_mb([630] * 1000) < 5000  # its compressed rows 216 MB, a square matrix 72 MB
