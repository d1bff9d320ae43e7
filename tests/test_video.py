"""``sigcore run WORLD --video out.mp4``: an MP4 at the simulated pace (frame count and duration probed with
imageio-ffmpeg, the encoder's own reader), the overview or a robot's camera, the time and score in a corner, clear
errors for bad options, and a video that stays readable when the run is interrupted."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import imageio_ffmpeg
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
WORLD = ROOT / "tests" / "data" / "sim" / "camera.xml"


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "sigcore", "run", str(WORLD), "--transport", "none", "-q", *args],
                          capture_output=True, text=True, cwd=ROOT, timeout=300)


def _first_frame(path: Path) -> np.ndarray:
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    frame = np.frombuffer(next(reader), dtype=np.uint8).reshape(meta["size"][1], meta["size"][0], 3)
    reader.close()
    return frame


@pytest.mark.slow
def test_overview_video_has_one_frame_per_period_and_the_run_s_duration(tmp_path: Path) -> None:
    """2 simulated seconds at 25 fps (one frame every 20 steps of 2 ms): 50 frames lasting 2.00 s, 640x480 H.264;
    the first frame has the dark band with white text (time, score) in its top-left corner and the room below."""
    out = tmp_path / "run.mp4"
    r = _run("--duration", "2", "--video", str(out), "--video-fps", "25")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "video:    " in r.stdout and "(50 frames, 2.00 s at 25 fps)" in r.stdout
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(out))
    assert (frames, seconds) == (50, 2.0)
    first = _first_frame(out)
    assert first.shape == (480, 640, 3)
    corner = first[2:14, 2:60].astype(int).sum(axis=2)
    assert (corner < 100).mean() > 0.5 and (corner > 500).any()  # a dark band with light letters
    assert first[200:400].std() > 5  # the scene, not a blank image


@pytest.mark.slow
def test_robot_camera_video_keeps_the_simulated_pace(tmp_path: Path) -> None:
    """The robot's head camera at 30 fps asked: 30 fps is not a whole number of 2 ms steps, so a frame comes every
    17 steps (29.41 fps); 1.5 s (750 steps) give 44 frames and a video within one frame of 1.5 s."""
    out = tmp_path / "head.mp4"
    r = _run("--steps", "750", "--video", str(out), "--video-camera", "bot/head")
    assert r.returncode == 0, r.stdout + r.stderr
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(out))
    assert frames == 750 // 17
    assert abs(frames * 17 * 0.002 - 1.5) < 17 * 0.002 and abs(seconds - 1.5) <= 17 * 0.002 + 0.01
    assert _first_frame(out).shape == (120, 160, 3)


@pytest.mark.slow
@pytest.mark.parametrize(("args", "says"), [
    (["--video-camera", "eyes"], "--video-camera 'eyes' is not a camera of this world; valid: overview, bot/head"),
    (["--video-fps", "0"], "--video-fps 0 is out of range; valid: 0.1 <= fps <= 240"),
])
def test_bad_video_options_are_refused_before_the_run(tmp_path: Path, args: list[str], says: str) -> None:
    """An unknown camera or frame rate: exit code 2, a message naming what is valid, no file."""
    out = tmp_path / "bad.mp4"
    r = _run("--steps", "10", "--video", str(out), *args)
    assert r.returncode == 2 and says in r.stderr, r.stdout + r.stderr
    assert not out.exists()


@pytest.mark.slow
def test_a_missing_folder_or_suffix_is_refused(tmp_path: Path) -> None:
    r = _run("--steps", "10", "--video", str(tmp_path / "nowhere" / "x.mp4"))
    assert r.returncode == 2 and f"no folder {tmp_path / 'nowhere'}" in r.stderr
    r = _run("--steps", "10", "--video", str(tmp_path / "x.avi"))
    assert r.returncode == 2 and "the file must end in .mp4" in r.stderr


@pytest.mark.slow
def test_an_interrupted_run_leaves_a_readable_video(tmp_path: Path) -> None:
    """SIGINT in the middle of a long run: the run reports and the video holds the frames rendered until then,
    readable, with a duration of frames / fps."""
    out = tmp_path / "cut.mp4"
    proc = subprocess.Popen([sys.executable, "-m", "sigcore", "run", str(WORLD), "--transport", "none",
                             "--duration", "600", "--video", str(out), "--video-fps", "25"], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and (not out.exists() or out.stat().st_size < 20_000):
            time.sleep(0.2)
        os.kill(proc.pid, signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert "stopped:  by SIGINT" in stdout, stdout + stderr
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(out))
    assert frames > 0 and seconds == pytest.approx(frames / 25, abs=0.05)
    assert f"({frames} frames" in stdout
