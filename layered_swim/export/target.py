"""The file an export writes, checked before any work: its suffix picks the format, it is never
a symbolic link, and an existing file is replaced only when asked."""
from __future__ import annotations

from dataclasses import dataclass
from importlib.util import find_spec
from pathlib import Path

from layered_swim.config import ConfigError

# Suffix: (format, the modules writing it needs).
FORMATS = {".bvh": ("BVH", ()), ".glb": ("glTF binary", ("pygltflib",)), ".usda": ("USD ascii", ("pxr",))}


@dataclass(frozen=True)
class ExportTarget:
    path: Path
    overwrite: bool

    @property
    def suffix(self) -> str:
        return self.path.suffix.lower()


def check_target(path: str | Path, overwrite: bool = False) -> ExportTarget:
    """``path`` fit to be written (by these rules), without touching the disk; else one ConfigError."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise ConfigError(f"{path}: cannot tell the format from '{suffix or 'no suffix'}'; "
                          f"name a {', '.join(FORMATS)} file")
    if path.is_symlink():
        raise ConfigError(f"{path}: is a symbolic link; give the file it points to, if it is meant")
    if path.exists() and not path.is_file():
        raise ConfigError(f"{path}: exists and is not a file")
    if path.exists() and not overwrite:
        raise ConfigError(f"{path}: exists; add --overwrite to replace it")
    if not path.parent.is_dir():
        raise ConfigError(f"{path.parent}: no such folder")
    missing = [module for module in FORMATS[suffix][1] if find_spec(module) is None]
    if missing:
        raise ConfigError(f"writing {FORMATS[suffix][0]} needs the export extra (no module {missing[0]}): "
                          "pip install 'layered-swim[export]'")
    return ExportTarget(path, overwrite)
