"""
What a path that is not a regular file is, and reading a user's file without blocking: one place.

A reader opens the path a user names without blocking and refuses anything but a regular file
before any read (opening a FIFO blocks until a writer comes, a device such as /dev/zero has no
size): core's user files (params and shape files, ``core.model.user_files``), io's recordings
(``io.mcap_reader``) and the analysis' photometry tables say what the path is by
:func:`file_kind`, and the bytes of a regular file come from :func:`read_regular_bytes`
(opened with O_NONBLOCK, checked on the open descriptor, its size bounded before the read; the
caller names its error class: ``ScenarioError`` for core's model files, ValueError for the
ephemeris tables of the torques, ``AnalysisError`` for photometry). A fact of the operating
system that imports nothing of tumble_ros: the bottom layer, beside ``errors`` and ``topics``,
so that core and io both reach it.
"""
from __future__ import annotations

import os
from pathlib import Path
import stat
from typing import Callable

__all__ = ['FILE_KINDS', 'file_kind', 'read_regular_bytes']

#: (test of ``st_mode``, what such a path is), in order: the first test that holds names it.
FILE_KINDS: tuple[tuple[Callable[[int], bool], str], ...] = (
    (stat.S_ISDIR, 'is a directory'), (stat.S_ISFIFO, 'is a FIFO (named pipe)'),
    (stat.S_ISCHR, 'is a character device'), (stat.S_ISBLK, 'is a block device'),
    (stat.S_ISSOCK, 'is a socket'))


def file_kind(mode: int) -> str:
    """Say what a non-regular file of ``st_mode`` ``mode`` is: ``is a FIFO (named pipe)``, ..."""
    return next((text for test, text in FILE_KINDS if test(mode)), 'is not a regular file')


def _one_line(text: object) -> str:
    return ' '.join(str(text).split())


def read_regular_bytes(path: str | os.PathLike[str], what: str, limit: int, limit_name: str,
                       kind: str = 'file', error: type[Exception] = ValueError,
                       limit_hint: str = '') -> bytes:
    """
    Return the bytes of the regular file ``path``, never blocking, at most ``limit`` bytes.

    ``what`` starts every message (``params file F.yaml``); ``limit_name`` names the constant
    of the limit, ``limit_hint`` (optional) says where it is explained or what to do; ``kind``
    what the file should be (``params file``, ``shape file``). Raises ``error`` for a missing
    file, a path that is not a regular file (before any read), a file above ``limit`` bytes
    (before it is read) or one that cannot be read.
    """
    path = Path(os.fspath(path))
    regular_only = f'not a {kind} (only regular files are read)'
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except FileNotFoundError:
        raise error(f'{what}: no such file') from None
    except OSError as err:
        try:
            mode = os.stat(path).st_mode          # a socket or a directory fails to open
        except OSError:
            mode = stat.S_IFREG
        if not stat.S_ISREG(mode):
            raise error(f'{what}: {file_kind(mode)}, {regular_only}') from None
        raise error(f'{what}: cannot open it: {_one_line(err.strerror or err)}') from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise error(f'{what}: {file_kind(info.st_mode)}, {regular_only}')
        if info.st_size > limit:
            raise error(f'{what}: {info.st_size:,} bytes, above the limit of {limit:,} '
                        f'({limit_name}{limit_hint})')
        os.set_blocking(fd, True)
        with os.fdopen(fd, 'rb', closefd=False) as stream:
            data = stream.read(limit + 1)
    except OSError as err:
        raise error(f'{what}: cannot read it: {_one_line(err.strerror or err)}') from None
    finally:
        os.close(fd)
    if len(data) > limit:                  # grew since the fstat
        raise error(f'{what}: above the limit of {limit:,} bytes ({limit_name})')
    return data
