"""
Reading a file a user names: refused by kind, by size and by encoding before it costs.

The one check of every text file a user hands to tumble_ros (a params file, a shape file, a
photometry table): :func:`read_user_bytes` opens the path without blocking and refuses, in one
line starting with the caller's ``what`` (``params file F.yaml``, ``shape_file: F.obj``)::

    no such file
    is a FIFO (named pipe), not a <kind> (only regular files are read)
    is a directory / a character device / a block device / a socket, ...
    61,000,000 bytes, above the limit of 4,194,304 (MAX_PARAMS_FILE_BYTES)

and :func:`decode_user_text` refuses what is not UTF-8 text, naming the encoding it recognises
(UTF-16 and UTF-32 by their byte-order mark or their NUL bytes, other binary data by its NUL
bytes) instead of reading it as an empty or garbled file.

A FIFO, a device or a socket is refused before any read: the file is opened with O_NONBLOCK
(opening a FIFO for reading blocks until a writer comes) and checked on the open descriptor
(``tumble_ros.io.mcap_reader`` opens a recording the same way); a device such as /dev/zero has
no size and would be read for ever. Raises ``error`` (default :class:`~.limits.ScenarioError`).
What a path that is not a regular file is comes from the one table of every reader,
:mod:`tumble_ros.file_kinds` (``file_kind`` re-exported here).
"""
from __future__ import annotations

import codecs
import os
from pathlib import Path
import stat

from tumble_ros.core.model.limits import ScenarioError
from tumble_ros.file_kinds import file_kind

__all__ = ['read_user_bytes', 'decode_user_text', 'read_user_text', 'file_kind']

#: Byte-order marks of the encodings recognised by name (the UTF-32 ones first: they begin with
#: the UTF-16 ones).
_BOMS = ((codecs.BOM_UTF32_LE, 'UTF-32'), (codecs.BOM_UTF32_BE, 'UTF-32'),
         (codecs.BOM_UTF16_LE, 'UTF-16'), (codecs.BOM_UTF16_BE, 'UTF-16'))


def _one_line(text: object) -> str:
    return ' '.join(str(text).split())


def read_user_bytes(path: str | os.PathLike[str], what: str, limit: int, limit_name: str,
                    kind: str = 'file', error: type[Exception] = ScenarioError) -> bytes:
    """
    Return the bytes of the regular file ``path``, never blocking, at most ``limit`` bytes.

    ``what`` starts every message (``params file F.yaml``); ``limit_name`` names the constant
    of the limit; ``kind`` what the file should be (``params file``, ``shape file``). Raises
    ``error`` for a missing file, a path that is not a regular file (before any read), a file
    above ``limit`` bytes (before it is read) or one that cannot be read.
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
                        f'({limit_name}, docs/ros.md "Limits of the inputs")')
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


def _encoding(data: bytes) -> str | None:
    """Name the non-UTF-8 encoding ``data`` is in (UTF-16, UTF-32, binary), or None."""
    for bom, name in _BOMS:
        if data.startswith(bom):
            return f'{name} text'
    head = data[:4096]
    if b'\0' not in head:
        return None
    if head[1::2].count(0) > len(head) // 4 or head[0::2].count(0) > len(head) // 4:
        zeros = head.count(0)
        return 'UTF-32 text' if zeros > 2 * len(head) // 3 else 'UTF-16 text'
    return 'binary data'


def decode_user_text(data: bytes, what: str, error: type[Exception] = ScenarioError) -> str:
    """
    Return ``data`` decoded as UTF-8 (a leading byte-order mark dropped).

    Raises ``error``, starting with ``what``, for UTF-16 or UTF-32 text, binary data (NUL
    bytes), or bytes that are not UTF-8 (naming the first offset).
    """
    found = _encoding(data)
    if found is not None:
        raise error(f'{what}: cannot read it as text: it holds {found}, not UTF-8 (save it as '
                    'UTF-8 text)')
    try:
        return data.decode('utf-8-sig')
    except UnicodeDecodeError as err:
        raise error(f'{what}: cannot read it as text ({err.__class__.__name__}: {err})') \
            from None


def read_user_text(path: str | os.PathLike[str], what: str, limit: int, limit_name: str,
                   kind: str = 'file', error: type[Exception] = ScenarioError) -> str:
    """:func:`read_user_bytes` then :func:`decode_user_text`: a user's UTF-8 text file."""
    return decode_user_text(read_user_bytes(path, what, limit, limit_name, kind, error), what,
                            error)
