"""``--video``: a GIF from highway-env's renderer, written atomically; bad paths refused."""

import pytest
from PIL import Image

from ego.highway_env.video import MAX_FRAMES, VideoWriter, check_video_path
from ego.params import ConfigError
from ego.runner import RunSpec, run


@pytest.mark.highway_env
def test_a_run_writes_a_gif_of_every_traffic_step(tmp_path):
    path = tmp_path / "videos" / "cut-in.gif"
    m = run(RunSpec("cut-in", "pid", 0, {"duration": "4"}, backend="highway-env", video=str(path))).metrics
    assert m["status"] == "completed"
    assert path.stat().st_size > 10_000
    with Image.open(path) as gif:
        assert gif.n_frames == 41  # t = 0 and each 0.1 s step
        assert gif.size == (900, 200)
        assert gif.info["duration"] == 100  # ms: real time
        gif.seek(20)
        colours = gif.convert("RGB").getcolors(maxcolors=10_000)
    assert len(colours) > 3  # a drawn road and cars, not a black frame
    assert sorted(p.name for p in path.parent.iterdir()) == ["cut-in.gif"]  # no temp file left


def test_a_long_run_keeps_every_kth_frame_at_a_lower_rate(tmp_path):
    writer = VideoWriter(tmp_path / "v.gif", fps=10.0, frames_expected=3 * MAX_FRAMES + 1)
    assert (writer.stride, writer.fps) == (4, 2.5)


@pytest.mark.parametrize(
    "path, why",
    [
        ("run.avi", "expected a file ending in .gif or .mp4"),
        ("run", "expected a file ending in .gif or .mp4"),
    ],
)
def test_bad_video_paths_are_refused(path, why):
    with pytest.raises(ConfigError, match=why):
        check_video_path(path)


def test_mp4_without_any_ffmpeg_suggests_a_gif(monkeypatch):
    from ego.highway_env import video

    monkeypatch.setattr(video, "ffmpeg_exe", lambda: None)  # a machine with neither
    with pytest.raises(ConfigError, match=r"needs ffmpeg \(pip install imageio-ffmpeg.*write a \.gif instead"):
        check_video_path("run.mp4")


def test_mp4_is_written_with_imageio_ffmpegs_own_binary(tmp_path, monkeypatch):
    import imageio_ffmpeg
    import numpy as np

    monkeypatch.setenv("PATH", str(tmp_path))  # no system ffmpeg: the wheel's binary must do
    path = check_video_path(str(tmp_path / "v.mp4"))
    writer = VideoWriter(path, fps=10.0, frames_expected=12)
    for k in range(12):
        frame = np.zeros((31, 40, 3), dtype=np.uint8)  # odd height: padded to even
        frame[:, : 3 * k + 1] = (200, 30, 30)
        writer.add(frame)
    writer.close()
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    frames = list(reader)
    assert meta["size"] == (40, 32) and meta["fps"] == 10.0 and len(frames) == 12
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.mp4"]


def test_video_needs_the_highway_env_backend(tmp_path):
    with pytest.raises(ConfigError, match="--video needs --backend highway-env"):
        run(RunSpec("cut-in", "pid", video=str(tmp_path / "v.gif")))
    assert not (tmp_path / "v.gif").exists()


@pytest.mark.sumo
def test_ctrl_c_keeps_the_mp4_and_the_trace(tmp_path):
    """A terminal's Ctrl-C reaches the whole process group: the mp4 encoder runs in a session
    of its own, so the run stops at its next step and writes the video of what it simulated
    and its trace (the encoder died with the run's group before: exit 1, neither written)."""
    import os
    import signal
    import subprocess
    import sys

    from process_group import wait_for

    video, trace = tmp_path / "v.mp4", tmp_path / "v.csv"
    args = ["run", "emergency-brake", "-c", "pid", "--backend", "highway-env", "--set", "duration=3000"]
    args += ["--set", "traffic_density=0", "--video", str(video), "--trace", str(trace)]
    p = subprocess.Popen(
        [sys.executable, "-m", "ego", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        env={**os.environ, "MPLCONFIGDIR": str(tmp_path)},
    )
    wait_for(lambda: any(tmp_path.glob(".v.mp4.part*")), p, "the encoder's partial file")
    os.killpg(p.pid, signal.SIGINT)  # the whole process group, as a terminal does
    out, err = p.communicate(timeout=120)
    assert p.returncode == 130, err
    assert video.stat().st_size > 1000 and trace.stat().st_size > 1000
