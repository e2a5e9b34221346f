"""A video of a run from highway-env's renderer: GIF (Pillow) or MP4 (ffmpeg).

MP4 is encoded by the ffmpeg binary the ``imageio-ffmpeg`` wheel ships (installed with
``ego[highway]`` and ``ego[gym]``), so no system ffmpeg is needed; without that package an
``ffmpeg`` on PATH is used.

Frames are RGB arrays (height, width, 3) from ``render_mode="rgb_array"``. The file is
written next to its final path and moved there when complete (``os.replace``), so a broken
run never leaves half a video under the asked name.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np

from ego.outputs import final_path
from ego.params import ConfigError

FORMATS = (".gif", ".mp4")
#: at most this many frames are kept (every k-th frame of a longer run): GIF frames are
#: held in memory until the file is written
MAX_FRAMES = 1500


def ffmpeg_exe() -> str | None:
    """The ffmpeg binary: imageio-ffmpeg's own, else one on PATH, else None."""
    try:
        import imageio_ffmpeg

        return imageio_ffmpeg.get_ffmpeg_exe()
    except (ImportError, RuntimeError):
        return shutil.which("ffmpeg")


def check_video_path(text: str | None) -> Path:
    """The ``--video`` path: a writable file ending in .gif or .mp4; .mp4 needs ffmpeg."""
    from ego.checks import check_output_file

    suffix = Path(str(text)).suffix.lower() if text else ""
    if suffix not in FORMATS:
        raise ConfigError(f"bad --video path {text!r} (expected a file ending in .gif or .mp4)")
    if suffix == ".mp4" and ffmpeg_exe() is None:
        raise ConfigError(
            f"bad --video path {text!r}: writing mp4 needs ffmpeg (pip install "
            "imageio-ffmpeg, or ffmpeg on PATH); write a .gif instead"
        )
    return check_output_file(text, "--video path", Path(text).suffix)


class VideoWriter:
    """Collect frames at ``fps`` (frames per simulated second) and write ``path`` on close.

    ``frames_expected`` (the run's traffic steps) sets the stride that keeps at most
    :data:`MAX_FRAMES` frames; the frame rate is lowered to match, so the video still plays
    in real time.
    """

    def __init__(self, path: str | os.PathLike, fps: float, frames_expected: int) -> None:
        self.path = final_path(path)
        self.stride = max(1, -(-int(frames_expected) // MAX_FRAMES))
        self.fps = fps / self.stride
        self._count = 0
        self._frames: list = []
        self._tmp = self.path.with_name(f".{self.path.name}.part{self.path.suffix}")
        self._ffmpeg: subprocess.Popen | None = None

    def add(self, frame: np.ndarray) -> None:
        """Offer one frame (every frame of the run, in order; the stride picks)."""
        k = self._count
        self._count += 1
        if k % self.stride:
            return
        if self.path.suffix.lower() == ".gif":
            from PIL import Image

            # a palette image is a quarter of the RGB frame's memory
            self._frames.append(Image.fromarray(frame).quantize(colors=64))
        else:
            if self._ffmpeg is None:
                self._start_ffmpeg(frame.shape[1], frame.shape[0])
            self._ffmpeg.stdin.write(np.ascontiguousarray(frame, dtype=np.uint8).tobytes())

    def _start_ffmpeg(self, width: int, height: int) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._ffmpeg = subprocess.Popen(
            [
                ffmpeg_exe() or "ffmpeg",
                "-loglevel",
                "error",
                "-y",
                "-f",
                "rawvideo",
                "-pix_fmt",
                "rgb24",
                "-s",
                f"{width}x{height}",
                "-r",
                f"{self.fps:g}",
                "-i",
                "-",
                # yuv420p needs even sides; most players need yuv420p
                "-vf",
                "pad=ceil(iw/2)*2:ceil(ih/2)*2",
                "-pix_fmt",
                "yuv420p",
                "-f",
                "mp4",
                str(self._tmp),
            ],
            stdin=subprocess.PIPE,
            # its own session: a Ctrl-C to the run's process group must not end the encoder
            # (the run stops at its next step and then closes the video); it ends at the end
            # of its input whenever ego does
            start_new_session=True,
        )

    def close(self) -> None:
        """Write the file (nothing when no frame came)."""
        try:
            if self._ffmpeg is not None:
                self._ffmpeg.stdin.close()
                code = self._ffmpeg.wait()
                if code != 0:
                    from ego.outputs import OutputError

                    raise OutputError(f"cannot write {self.path}: ffmpeg ended with status {code} (its message above)")
            elif self._frames:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                first, *rest = self._frames
                first.save(
                    self._tmp,
                    format="GIF",
                    save_all=True,
                    append_images=rest,
                    duration=round(1000.0 / self.fps),
                    loop=0,
                )
            else:
                return
            os.replace(self._tmp, self.path)
        except OSError as exc:  # a full disk: one line naming the file (ego.outputs.OutputError)
            from ego.outputs import output_error

            raise output_error(self.path, exc) from None
        finally:
            self._frames = []
            self._ffmpeg = None
            if self._tmp.exists():
                self._tmp.unlink()


def check_options(options) -> None:
    """The highway-env backend's options (``ego.sim.registry``): ``video``, a .gif/.mp4 path."""
    if options.get("video") is not None:
        check_video_path(options["video"])
