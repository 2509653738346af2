"""Writes rendered frames: an MP4 through imageio-ffmpeg (the ``video`` extra) when it is
installed, otherwise numbered PNG frames; screenshots and stills as PNG. Encoding runs on a
background thread so recording does not stall the window."""
from __future__ import annotations

import os
import queue
import shutil
import threading
from pathlib import Path

import numpy as np
from PIL import Image

from layered_swim.config import ConfigError

NO_ENCODER = "no MP4 encoder installed (pip install -e '.[video]' adds imageio-ffmpeg)"


def mp4_encoder_available() -> bool:
    try:
        import imageio_ffmpeg
        imageio_ffmpeg.get_ffmpeg_exe()
    except (ImportError, RuntimeError):
        return False
    return True


def save_png(pixels: np.ndarray, path: Path) -> Path:
    """Written under a temporary name and moved into place: never half a picture."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp.png")
    try:
        Image.fromarray(pixels).save(tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def check_png_out(path: Path, overwrite: bool) -> None:
    """Before a still is drawn: ``path`` may take it (an existing file only with ``overwrite``)."""
    if path.is_symlink():
        raise ConfigError(f"{path}: is a symbolic link; give the real path, if it is meant")
    if path.is_dir():
        raise ConfigError(f"{path}: is a folder; choose another --out")
    if path.exists() and not overwrite:
        raise ConfigError(f"{path}: exists; choose another --out or add --overwrite to replace it")
    _check_folder_of(path)


def _check_folder_of(path: Path) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ConfigError(f"{path.parent}: cannot create it ({err.strerror})") from None
    if not os.access(path.parent, os.W_OK):
        raise ConfigError(f"{path.parent}: cannot write there")


class FrameWriter:
    """``add`` frames, then ``close`` (or ``abort``). ``path`` ending in .mp4 asks for a video;
    without an encoder (or for any other path) the frames go as PNGs into a folder, and ``note``
    says which happened. Frames go to a temporary name first and move into place on ``close``: a
    failed render leaves nothing behind. A frame folder must be empty or hold only frames (which
    the new ones replace); an existing video is replaced only with ``overwrite``."""

    def __init__(self, path: str | Path, fps: float, overwrite: bool = False):
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
        self._check_out(overwrite)
        self._tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.tmp{self.path.suffix}")
        if not self.is_video:
            self._tmp.mkdir()
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
                    Image.fromarray(pixels).save(self._tmp / f"frame_{index:05d}.png")
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
            self._encoder = imageio_ffmpeg.write_frames(str(self._tmp), (width, height), fps=self.fps, quality=7,
                                                        macro_block_size=2, ffmpeg_log_level="error")
            self._encoder.send(None)
        self._encoder.send(np.ascontiguousarray(pixels).tobytes())

    def _check_out(self, overwrite: bool) -> None:
        """Before any frame is drawn: the folder it goes into is writable, and the target is not
        something else's (see the class)."""
        if self.path.is_symlink():
            raise ConfigError(f"{self.path}: is a symbolic link; give the real path, if it is meant")
        if self.path.exists() and self.is_video == self.path.is_dir():
            raise ConfigError(f"{self.path}: is a {'folder' if self.is_video else 'file'}; choose another --out")
        if self.is_video and self.path.exists() and not overwrite:
            raise ConfigError(f"{self.path}: exists; choose another --out or add --overwrite to replace it")
        if not self.is_video and self.path.is_dir() and not all(
                f.is_file() and not f.is_symlink() and f.name.startswith("frame_") and f.suffix == ".png"
                for f in self.path.iterdir()):
            raise ConfigError(f"{self.path}: holds files that are not rendered frames; refusing to touch them, "
                              "choose another --out")
        _check_folder_of(self.path)

    def _finish(self) -> None:
        self._queue.put(None)
        self._thread.join()

    def close(self) -> Path:
        """Finish encoding and move the frames into place."""
        self._finish()
        if self._error is not None:
            self.abort()
            raise OSError(f"{self.path}: {self._error}")
        if not self.is_video and self.path.exists():
            shutil.rmtree(self.path)
        os.replace(self._tmp, self.path)
        return self.path

    def abort(self) -> None:
        """Stop and remove everything written."""
        if self._thread.is_alive():
            self._finish()
        if self._tmp.is_dir():
            shutil.rmtree(self._tmp, ignore_errors=True)
        else:
            self._tmp.unlink(missing_ok=True)
