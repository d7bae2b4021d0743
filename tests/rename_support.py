"""Watching and failing the renames that ``aibo_sim.files`` makes, for the tests."""

from __future__ import annotations

import os
from pathlib import Path


def _full(name, folder_fd: int | None) -> Path:
    """The path ``name`` names inside the folder open at ``folder_fd`` (aibo-sim renames so)."""
    return Path(name) if folder_fd is None else Path(os.readlink(f"/proc/self/fd/{folder_fd}"), name)


def watch_renames(monkeypatch, fail=lambda source, target: None) -> list[tuple[Path, Path]]:
    """The (source, target) full paths of each ``os.replace`` from now on; where ``fail(source,
    target)`` gives an OSError, that is raised instead of renaming."""
    renamed, real_replace = [], os.replace

    def replace(source, target, **folders):
        paths = _full(source, folders.get("src_dir_fd")), _full(target, folders.get("dst_dir_fd"))
        error = fail(*paths)
        if error is not None:
            raise error
        renamed.append(paths)
        real_replace(source, target, **folders)

    monkeypatch.setattr(os, "replace", replace)
    return renamed
