"""Writes rendered frames: an MP4 through imageio-ffmpeg (the ``video`` extra) when it is
installed, otherwise numbered PNG frames; screenshots as PNG. Encoding runs on a background
thread so recording does not stall the window."""
from __future__ import annotations

import queue
import threading
from pathlib import Path

import numpy as np
from PIL import Image

NO_ENCODER = "no MP4 encoder installed (pip install -e '.[video]' adds imageio-ffmpeg)"


def mp4_encoder_available() -> bool:
    try:
        import imageio_ffmpeg
        imageio_ffmpeg.get_ffmpeg_exe()
    except (ImportError, RuntimeError):
        return False
    return True


def save_png(pixels: np.ndarray, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(pixels).save(path)
    return path


class FrameWriter:
    """``add`` frames, then ``close``. ``path`` ending in .mp4 asks for a video; without an encoder
    (or for any other path) the frames go as PNGs into a folder, and ``note`` says which happened."""

    def __init__(self, path: str | Path, fps: float):
        path = Path(path)
        self.fps = fps
        self.frames = 0
        self.is_video = path.suffix.lower() == ".mp4" and mp4_encoder_available()
        if path.suffix.lower() == ".mp4" and not self.is_video:
            self.path = path.with_name(path.stem + "_frames")
            self.note = f"{NO_ENCODER}: writing PNG frames to {self.path}/"
        else:
            self.path = path
            self.note = f"writing {'MP4 video' if self.is_video else 'PNG frames'} to {path}"
        (self.path.parent if self.is_video else self.path).mkdir(parents=True, exist_ok=True)
        self._encoder = None
        self._queue: queue.Queue = queue.Queue(maxsize=120)
        self._error: Exception | None = None
        self._thread = threading.Thread(target=self._work, daemon=True)
        self._thread.start()

    def add(self, pixels: np.ndarray) -> None:
        if self._error is not None:
            raise OSError(f"{self.path}: {self._error}")
        self._queue.put((self.frames, pixels))
        self.frames += 1

    def _work(self) -> None:
        try:
            while (item := self._queue.get()) is not None:
                index, pixels = item
                if self.is_video:
                    self._encode(pixels)
                else:
                    Image.fromarray(pixels).save(self.path / f"frame_{index:05d}.png")
        except Exception as err:  # reported to the caller on its next add() or close()
            self._error = err
            while self._queue.get() is not None:   # keep draining so add() never blocks forever
                pass
        finally:
            if self._encoder is not None:
                self._encoder.close()

    def _encode(self, pixels: np.ndarray) -> None:
        if self._encoder is None:
            import imageio_ffmpeg
            height, width = pixels.shape[:2]
            self._encoder = imageio_ffmpeg.write_frames(str(self.path), (width, height), fps=self.fps, quality=7,
                                                        macro_block_size=2, ffmpeg_log_level="error")
            self._encoder.send(None)
        self._encoder.send(np.ascontiguousarray(pixels).tobytes())

    def close(self) -> Path:
        self._queue.put(None)
        self._thread.join()
        if self._error is not None:
            raise OSError(f"{self.path}: {self._error}")
        return self.path
