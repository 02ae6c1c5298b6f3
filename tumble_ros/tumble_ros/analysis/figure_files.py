"""
Figure files: drawn figures (name, PNG bytes) written into a directory, safely; no matplotlib.

Files are never written through a symbolic link and, unless ``overwrite=True``, never replace an
existing file: all the names are checked first, and only if none is taken
(:class:`FigureExistsError` names them) or a symbolic link (:class:`FigurePathError`) are the
files written. The output directory itself must not be a symbolic link. Files are created with
O_CREAT | O_EXCL | O_NOFOLLOW relative to the directory's descriptor; with ``overwrite=True`` a
file is written to a new temporary file and renamed over the old one (a rename replaces a link,
never what it points to). Used by :mod:`.figures` (which re-exports these names), by
:mod:`.figure_pool` (the main process writes what its workers drew, without matplotlib) and by
the encounter command.
"""
from __future__ import annotations

import errno
import os
from pathlib import Path
import stat

from tumble_ros.errors import AnalysisError

__all__ = ['Drawing', 'FigureExistsError', 'FigurePathError', 'check_outputs', 'write_files']


#: A drawn figure: (file name, PNG bytes).
Drawing = tuple[str, bytes]


class FigurePathError(AnalysisError):
    """A figure path that is refused: a symbolic link, or not a regular file (an AnalysisError)."""


class FigureExistsError(FigurePathError):
    """Figure files that already exist and are not overwritten (``overwrite=False``)."""


def _link_refused(path: Path) -> FigurePathError:
    return FigurePathError(f'{path}: is a symbolic link: figures are not written through links')


def _open_dir(out_dir: Path) -> int:
    """Open ``out_dir`` (created if needed) as a descriptor; refuse a symbolic link."""
    if out_dir.is_symlink():
        raise _link_refused(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    try:
        return os.open(out_dir, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
    except OSError as err:
        if err.errno == errno.ELOOP:            # replaced by a link since the check
            raise _link_refused(out_dir) from None
        raise


def _check_names(out_dir: Path, dir_fd: int, names: list[str], overwrite: bool) -> None:
    """
    Refuse links and non-regular files at the figure paths.

    Without ``overwrite``, refuse any existing file too.
    """
    taken = []
    for name in names:
        try:
            mode = os.stat(name, dir_fd=dir_fd, follow_symlinks=False).st_mode
        except FileNotFoundError:
            continue
        if stat.S_ISLNK(mode):
            raise _link_refused(out_dir / name)
        if not stat.S_ISREG(mode):
            raise FigurePathError(f'{out_dir / name}: exists and is not a regular file')
        taken.append(name)
    if taken and not overwrite:
        raise FigureExistsError(f'{", ".join(str(out_dir / n) for n in taken)}: '
                                f'{"exists" if len(taken) == 1 else "exist"}, not overwritten')


_CREATE = os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | getattr(os, 'O_CLOEXEC', 0)


def _create(dir_fd: int, name: str, data: bytes) -> None:
    """Write a new file ``name`` (never an existing one, never through a link)."""
    fd = os.open(name, _CREATE, 0o666, dir_fd=dir_fd)
    try:
        with os.fdopen(fd, 'wb') as stream:
            stream.write(data)
    except BaseException:
        os.unlink(name, dir_fd=dir_fd)
        raise


def _write_one(out_dir: Path, dir_fd: int, name: str, data: bytes, overwrite: bool) -> Path:
    if overwrite:
        temporary = f'.{name}.{os.getpid()}-{os.urandom(4).hex()}.tmp'
        _create(dir_fd, temporary, data)
        try:
            os.replace(temporary, name, src_dir_fd=dir_fd, dst_dir_fd=dir_fd)
        except BaseException:
            os.unlink(temporary, dir_fd=dir_fd)
            raise
        return out_dir / name
    try:
        _create(dir_fd, name, data)
    except FileExistsError:        # created since the check
        raise FigureExistsError(f'{out_dir / name}: exists, not overwritten') from None
    return out_dir / name


def _write(drawings: list[Drawing], out_dir, overwrite: bool) -> list[Path]:
    """Write the drawn figures into ``out_dir`` if none of their paths is refused."""
    if not drawings:
        return []
    out_dir = Path(out_dir)
    dir_fd = _open_dir(out_dir)
    try:
        _check_names(out_dir, dir_fd, [name for name, _ in drawings], overwrite)
        return [_write_one(out_dir, dir_fd, name, data, overwrite) for name, data in drawings]
    finally:
        os.close(dir_fd)


def check_outputs(out_dir: str | os.PathLike[str], names: list[str], overwrite: bool) -> None:
    """
    Refuse before any work what :func:`write_files` would refuse at the end (FigurePathError).

    ``out_dir`` a symbolic link or not a directory, a name that is a link or not a regular
    file, an existing name without ``overwrite`` (FigureExistsError), or a directory that
    cannot be written or created.
    """
    out_dir = Path(out_dir)
    if out_dir.is_symlink():
        raise _link_refused(out_dir)
    if out_dir.exists():
        if not out_dir.is_dir():
            raise FigurePathError(f'{out_dir}: exists and is not a directory')
        dir_fd = os.open(out_dir, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
        try:
            _check_names(out_dir, dir_fd, names, overwrite)
        finally:
            os.close(dir_fd)
        if not os.access(out_dir, os.W_OK | os.X_OK):
            raise FigurePathError(f'{out_dir}: cannot write into it (permission denied)')
        return
    parent = out_dir.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise FigurePathError(f'{out_dir}: cannot be created ({parent} is not a writable '
                              'directory)')


def write_files(files: list[Drawing], out_dir: str | os.PathLike[str],
                overwrite: bool) -> list[Path]:
    """
    Write ``files`` ((name, bytes) pairs) into ``out_dir``, created if needed.

    Never through a symbolic link, never over an existing file unless ``overwrite`` (then
    each is replaced atomically); nothing is written if any path is refused.
    """
    return _write(files, out_dir, overwrite)
