"""
What a path that is not a regular file is: the one table every reader of a user's file uses.

A reader opens the path a user names without blocking and refuses anything but a regular file
before any read (opening a FIFO blocks until a writer comes, a device such as /dev/zero has no
size): core's user files (params and shape files, ``core.model.user_files``), io's recordings
(``io.mcap_reader``) and the analysis' photometry tables say what the path is by
:func:`file_kind`. A fact of the operating system that imports nothing of tumble_ros: the
bottom layer, beside ``errors`` and ``topics``, so that core and io both reach it.
"""
from __future__ import annotations

import stat
from typing import Callable

__all__ = ['FILE_KINDS', 'file_kind']

#: (test of ``st_mode``, what such a path is), in order: the first test that holds names it.
FILE_KINDS: tuple[tuple[Callable[[int], bool], str], ...] = (
    (stat.S_ISDIR, 'is a directory'), (stat.S_ISFIFO, 'is a FIFO (named pipe)'),
    (stat.S_ISCHR, 'is a character device'), (stat.S_ISBLK, 'is a block device'),
    (stat.S_ISSOCK, 'is a socket'))


def file_kind(mode: int) -> str:
    """Say what a non-regular file of ``st_mode`` ``mode`` is: ``is a FIFO (named pipe)``, ..."""
    return next((text for test, text in FILE_KINDS if test(mode)), 'is not a regular file')
